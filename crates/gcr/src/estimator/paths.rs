//! The consistent gather (`--gather paths`, beyond the dissertation): the ray gather
//! ([`crate::gather`]) plus an unbiased correction of the networks' error by continued paths, so
//! that the estimate converges to B(y) whatever the networks' error, with a standard error per
//! point.
//!
//! The networks' reflected radiosity C(x) (the kernel collection, fig. 4.13c) is a control variate
//! for the reflected radiosity L(x) = B(x) − E(x) seen from y:
//!
//! ```text
//! B(y) = E(y) + ρ(y)·[ D(y) + ∫_Ω C(x(ω)) dω_cos + ∫_Ω (L − C)(x(ω)) dω_cos ]
//! ```
//!
//! with D the direct light and ω cosine-distributed. The first two terms are the ray gather:
//! `direct` shadow rays and `indirect` cosine rays, each of the latter costing one ray and one
//! evaluation of C. The third — the networks' error, which the ray gather never corrects — is
//! estimated at the hits of the first `corrections` of those rays by a path continued from there
//! (L̂: path tracing with one shadow ray and one cosine ray per vertex, MIS as in the ray gather,
//! Russian roulette from `PathSettings::roulette_depth` with continuation probability max ρ)
//! minus C at the same hit. When every ray is corrected (the default) C cancels exactly and is
//! not evaluated: the gather is then a path tracer split at its first vertex.
//!
//! The first vertex's shadow rays, cosine rays and the first vertex of each correction take
//! Owen-scrambled Sobol points (`sobol_burley`; a path's later vertices random numbers), in
//! `REPLICATES` (2) independently scrambled replicates whose spread gives the standard error.
//!
//! Measured (docs/design/estimator.md): fewer corrections, which read the networks, were less
//! accurate per second on cornell-box, and docs/design/math.md §9's kernel Ψ(x, y) as the pointwise control
//! variate of K·B (its integral is the collection in closed form) was worse than none — a sum of a
//! few hundred 6-D Gaussians does not follow K's 1/r² and cosines pointwise, and Ψ/p is large where
//! the cosine density p is small.

use super::guide::{Guide, Record, SpatialGuides};
use super::secondary::SecondarySources;
use crate::config::{GatherSamples, PathSettings};
use crate::domain::Domain;
use crate::element::{BANDS, Bands};
use crate::emitters::Emitters;
use crate::gather::{Cosine, Gathered, Mis, cosine_ray, light_ray_scaled};
use glam::DVec3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use scene_sampler::{NO_FACE, Pick, Receiver};

/// Path vertices beyond the output point at which a path stops whatever the roulette says: a
/// guard, not a budget (a grey ρ = 0.99 furnace loses 0.99^100000 of its light to it; 64, the
/// earlier value, lost 52 % there).
const MAX_DEPTH: usize = 100_000;
/// Independently scrambled Sobol replicates per point: the spread of their estimates gives the
/// standard error (randomized QMC: the sample variance of the rays themselves ignores the QMC
/// points' correlation and overstated the error 4× on two-blockers). Two: one degree of freedom
/// per point (a noisy error bar at one point, an unbiased variance, so an accurate ‖σ‖ over many),
/// and little of the QMC gain lost (8 replicates cost 1.3–2× in variance, measured).
pub(crate) const REPLICATES: usize = 2;
/// Mixed into a ray's scramble for the point in its pixel ([`SobolRay::padded`]).
const PIXEL_SALT: u32 = 0x7069_7865;

/// Ray i's Owen-scrambled Sobol point for a point seeded `seed`: ray i belongs to replicate
/// i mod `replicates`, each replicate its own scrambling of the sequence, continued from index
/// `first` (per replicate) so that rounds take disjoint points.
///
/// The dimensions, four at a time ([`SobolRay::set`]): 0 the emitter, 1–2 the point on it, 3–4
/// the cosine ray, 5–9 a path's first vertex (as 0–4), 10–11 the point in a pixel.
///
/// `sobol_burley` reads 16 bits of the index: index j and j + 2¹⁶ would be the same point, so
/// each block of 2¹⁶ indices takes its own scrambling (block 0 the replicate's): the blocks are
/// independent randomized nets, not one longer one.
#[derive(Clone, Copy)]
pub(crate) struct SobolRay {
    index: u32,
    scramble: u32,
}

impl SobolRay {
    pub(crate) fn new(seed: u64, replicates: usize, first: usize, i: usize) -> Self {
        let (r, j) = (i % replicates, first + i / replicates);
        let block = (j >> 16) as u64;
        let scramble = (seed
            ^ (r as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15)
            ^ block.wrapping_mul(0xD6E8_FEB8_6659_FD93)) as u32;
        Self {
            index: (j & 0xFFFF) as u32,
            scramble,
        }
    }

    /// Dimensions 4·set … 4·set + 3, in [0, 1): one SIMD evaluation, the same values as four of
    /// `sobol_burley::sample`.
    pub(crate) fn set(&self, set: u32) -> [f64; 4] {
        sobol_burley::sample_4d(self.index, set, self.scramble)
            .map(|v| f64::from(v).min(1.0 - f64::EPSILON))
    }

    /// Two dimensions padded in (Burley 2020, §4): the first two of the sequence seeded with
    /// this one's scramble and `salt`, shuffled and scrambled independently of every other
    /// dimension. The first two Sobol dimensions are a (0, 2)-sequence: any 2ᵏ consecutive
    /// points from 0 fill every elementary box of area 2⁻ᵏ once (16 points: each cell of a 4 × 4
    /// grid, and of 2 × 8 and 8 × 2), where higher pairs such as dimensions 10–11 stratify less.
    pub(crate) fn padded(&self, salt: u32) -> [f64; 2] {
        let [a, b, _, _] = sobol_burley::sample_4d(self.index, 0, self.scramble ^ salt);
        [a, b].map(|v| f64::from(v).min(1.0 - f64::EPSILON))
    }

    /// Dimensions 3–4 (the cosine ray) from sets 0 and 1.
    pub(crate) fn cosine(a: [f64; 4], b: [f64; 4]) -> [f64; 2] {
        [a[3], b[0]]
    }

    /// Dimensions 5–9 (a path's first vertex beyond the point, in [`PathGather::reflected`]'s
    /// order) from sets 1 and 2.
    pub(crate) fn path_vertex(b: [f64; 4], c: [f64; 4]) -> [f64; 5] {
        [b[1], b[2], b[3], c[0], c[1]]
    }
}

/// Everything the consistent gather needs, built once per set of output points.
pub struct PathGather<'a, C> {
    pub(crate) domain: &'a Domain<'a>,
    pub(crate) emitters: &'a Emitters,
    /// The networks' reflected radiosity C(x, n_x).
    networks: C,
    samples: GatherSamples,
    pub(crate) settings: PathSettings,
    /// The secondary sources drawn at every vertex (`secondary.rs`), if any.
    pub(crate) secondary: Option<std::sync::Arc<SecondarySources>>,
}

/// What a camera ray sees first ([`PathGather::estimate_footprint`]).
#[derive(Clone, Copy, Debug)]
pub(crate) enum FirstHit {
    /// The front of a face: the point, its normal, the face.
    Front(DVec3, DVec3, u32),
    /// Nothing: the ray leaves the scene in this unit direction (the sky, if any).
    Escaped(DVec3),
    /// The back of a face.
    Back,
}

/// A guided bounce of [`PathGather::reflected`], to learn from once its path ends: the vertex,
/// its square point, q·q_g, q_g, its hit's light, `out` after it, β after it, the hit.
type Bounce = (Vertex, [f64; 2], f64, f64, Bands, Bands, Bands, Vertex);

/// The branches of a bounce whose expected light is `r` times its path's start's
/// ([`PathGather::reflected`]): 1 up to [`SPLIT_ABOVE`], then ⌊r + ½⌋, at most [`SPLIT_MOST`].
fn branches(r: f64) -> usize {
    if r > SPLIT_ABOVE {
        (r + 0.5).min(SPLIT_MOST) as usize
    } else {
        1
    }
}

/// Records what each of a path's guided `bounces` brought, for the spatial guides: its hit's
/// emission (d·q·q_g undoes the 1/(q·q_g) in d) and L̂ beyond it ((`out` − out after the
/// bounce)/β after it).
fn record_bounces(
    guides: &SpatialGuides,
    records: &mut Vec<Record>,
    bounces: &[Bounce],
    out: Bands,
) {
    for &(v, u, qq, q_g, d, after, b, h) in bounces {
        if records.len() >= guides.cap() {
            break;
        }
        let mut l = 0.0;
        for k in 0..BANDS {
            l += d[k] * qq;
            if b[k] > 0.0 {
                l += (out[k] - after[k]) / b[k];
            }
        }
        guides.keep(
            records,
            guides.record((v.p, v.n), u, q_g, l / BANDS as f64, (h.p, h.n)),
        );
    }
}

/// Splitting ([`PathGather::reflected`]): a bounce splits where its expected light exceeds this
/// multiple of the path's start's,
const SPLIT_ABOVE: f64 = 2.0;
/// into at most this many branches,
const SPLIT_MOST: f64 = 8.0;
/// and a branch splits again at most this many times.
const MAX_SPLITS: usize = 4;

/// A surface point: position, unit normal, face ([`NO_FACE`] for a point in the air).
#[derive(Clone, Copy)]
pub(crate) struct Vertex {
    pub(crate) p: DVec3,
    pub(crate) n: DVec3,
    pub(crate) face: u32,
}

/// The paths gather's estimate at one point, per replicate, from one or more rounds of rays
/// ([`PathGather::estimate`]); [`PointEstimate::gathered`] turns it into B and its standard error.
#[derive(Clone, Copy, Debug, Default)]
pub struct PointEstimate {
    /// E at the point.
    pub(crate) emission: Bands,
    /// Per replicate, its estimate of the reflected part ρ·(D + ∫L), divided by the number of
    /// replicates (their sum is the estimate); rounds combined by their ray counts.
    pub(crate) share: [Bands; REPLICATES],
    /// The part of the sum that came from the networks.
    pub(crate) from_networks: Bands,
    /// Replicates used.
    pub(crate) replicates: usize,
    /// Shadow and cosine rays per point so far (the larger count of a round, summed over rounds).
    pub(crate) rays: usize,
    /// Whether the point reflects (else B = E exactly and the shares are 0).
    pub(crate) reflects: bool,
    /// Mean over the rays of the square of one ray's estimate (a footprint's,
    /// [`PathGather::estimate_footprint`]; 0 for the other estimators): with the mean, the
    /// variance of one ray, which allocates a pixel's rays (`estimator::pixel_rounds`).
    pub(crate) ray_square: Bands,
}

impl PointEstimate {
    /// Combines two independent rounds at the same point (their Sobol points disjoint), weighted
    /// by their ray counts: each replicate's combined estimate is still unbiased and independent
    /// of the others', so their spread still gives the standard error.
    pub fn merge(&mut self, other: &PointEstimate) {
        let total = (self.rays + other.rays) as f64;
        self.merge_weighted(other, other.rays as f64 / total);
    }

    /// [`PointEstimate::merge`] with weight `v` on `other` and 1 − v on `self` (v in [0, 1]).
    pub(crate) fn merge_weighted(&mut self, other: &PointEstimate, v: f64) {
        let w = 1.0 - v;
        for (a, b) in self.share.iter_mut().zip(&other.share) {
            for k in 0..BANDS {
                a[k] = w * a[k] + v * b[k];
            }
        }
        for k in 0..BANDS {
            self.from_networks[k] = w * self.from_networks[k] + v * other.from_networks[k];
            self.ray_square[k] = w * self.ray_square[k] + v * other.ray_square[k];
        }
        self.rays += other.rays;
        self.replicates = self.replicates.min(other.replicates);
    }

    /// B = E + the replicates' shares, with the standard error from their spread.
    pub fn gathered(&self) -> Gathered {
        let mut out = Gathered {
            radiosity: self.emission,
            rays: self.rays,
            ..Gathered::default()
        };
        if !self.reflects {
            return out;
        }
        let (e, share, replicates) = (self.emission, &self.share, self.replicates);
        let r = replicates as f64;
        for k in 0..BANDS {
            let total: f64 = share[..replicates].iter().map(|s| s[k]).sum();
            let mean = total / r;
            let spread: f64 = share[..replicates]
                .iter()
                .map(|s| (s[k] - mean).powi(2))
                .sum();
            out.from_networks[k] = self.from_networks[k];
            out.radiosity[k] = e[k] + total;
            out.std_error[k] = if replicates > 1 {
                (r / (r - 1.0) * spread).sqrt()
            } else {
                0.0
            };
            if replicates == 2 {
                out.spread[k] = share[0][k] - share[1][k];
            }
        }
        out
    }
}

impl<'a, C: Fn(DVec3, DVec3) -> Bands> PathGather<'a, C> {
    /// The gather with `samples` shadow and cosine rays per point and the networks' reflected
    /// radiosity `networks`.
    pub fn new(
        domain: &'a Domain<'a>,
        emitters: &'a Emitters,
        networks: C,
        samples: GatherSamples,
        settings: PathSettings,
    ) -> Self {
        Self {
            domain,
            emitters,
            networks,
            samples,
            settings,
            secondary: None,
        }
    }

    /// B at the surface point (y, n, face), deterministic for a given `seed`, with its standard
    /// error: one round of [`PathGather::estimate`] with the gather's ray counts.
    pub fn gather(&self, point: (DVec3, DVec3, u32), seed: u64) -> Gathered {
        self.estimate(point, seed, 0, self.samples).gathered()
    }

    /// One round of the gather at (y, n, face) with `samples` rays, its Sobol points taken from
    /// index `first` of each replicate's sequence on (a later round continues where the earlier
    /// ones stopped, [`PointEstimate::merge`] combines them). Deterministic for a given `seed`.
    pub fn estimate(
        &self,
        (y, n, face): (DVec3, DVec3, u32),
        seed: u64,
        first: usize,
        samples: GatherSamples,
    ) -> PointEstimate {
        let z = Vertex { p: y, n, face };
        let (rho, e) = (
            self.domain.reflectance_at(face, y),
            self.domain.emission(face),
        );
        self.estimate_at(z, (rho, e), seed, first, samples)
    }

    /// One round of the irradiance E(y, n) = ∫ L cos θ dω at any point y (on a surface or in the
    /// air) for the hemisphere about the unit normal n — what `rtrace -I` computes: the gather's
    /// estimate of ρ·(D + ∫ L) with ρ = 1 and no emission, its rays leaving from y itself (no
    /// face of the scene is skipped; a point on a surface sees the side n points to). Rounds and
    /// seeds as [`PathGather::estimate`].
    pub fn estimate_irradiance(
        &self,
        (y, n): (DVec3, DVec3),
        seed: u64,
        first: usize,
        samples: GatherSamples,
    ) -> PointEstimate {
        let z = Vertex {
            p: y,
            n,
            face: NO_FACE,
        };
        self.estimate_at(z, ([1.0; BANDS], [0.0; BANDS]), seed, first, samples)
    }

    /// [`PathGather::estimate`] at the vertex z with reflectance ρ and emission E.
    pub(crate) fn estimate_at(
        &self,
        z: Vertex,
        (rho, e): (Bands, Bands),
        seed: u64,
        first: usize,
        samples: GatherSamples,
    ) -> PointEstimate {
        // ⟨The paths' own random numbers: one stream per point and round⟩
        let mut rng = ChaCha8Rng::seed_from_u64(if first == 0 {
            seed
        } else {
            seed ^ (first as u64).wrapping_mul(0xD1B5_4A32_D192_ED03)
        });
        let (n_e, n_c) = (samples.direct, samples.indirect);
        let replicates = REPLICATES.min(n_e.max(n_c)).max(1);
        let mut out = PointEstimate {
            emission: e,
            replicates,
            rays: n_e.max(n_c),
            ..PointEstimate::default()
        };
        if rho.iter().all(|r| *r == 0.0) {
            return out;
        }
        let mis = Mis {
            emitters: self.emitters,
            n_e: n_e as f64,
            n_c: n_c as f64,
        };
        // ⟨Ray i belongs to replicate i mod R: each replicate is its own Owen scrambling⟩
        let qmc = |i: usize| SobolRay::new(seed, replicates, first, i);
        // Per replicate, its share of ρ·(D̂ + mean C + mean correction).
        let mut share = [[0.0; BANDS]; REPLICATES];
        let mut from_networks = [0.0; BANDS];
        let mut add = |i: usize, t: Bands, scale: f64| {
            for k in 0..BANDS {
                share[i % replicates][k] += rho[k] * t[k] * scale;
            }
        };
        // ⟨Direct light: shadow rays, MIS with the cosine rays⟩
        for i in 0..n_e {
            let a = qmc(i).set(0);
            add(i, self.next_event(&z, &mis, (a[0], [a[1], a[2]])), 1.0);
        }
        // ⟨Cosine rays: the networks' C at each hit, the correction L̂ − C at the first ones⟩
        let corrected = self.settings.corrections.min(n_c);
        // With every ray corrected C cancels exactly: not evaluated.
        let networks_read = corrected < n_c;
        for i in 0..n_c {
            let u = qmc(i);
            let (a, b) = (u.set(0), u.set(1));
            let (c, d, hit) = self.cosine_ray(&z, &mis, networks_read, SobolRay::cosine(a, b));
            add(i, d, 1.0);
            add(i, c, 1.0 / n_c as f64);
            for k in 0..BANDS {
                from_networks[k] += rho[k] * c[k] / n_c as f64;
            }
            if i < corrected {
                // ⟨Secondary sources: one draw per cosine ray (secondary.rs)⟩
                add(i, self.relay_from_point(&z, u), 1.0 / corrected as f64);
                if let Some(x) = hit {
                    let first = SobolRay::path_vertex(b, u.set(2));
                    let arrival = self.arrival(&z, &x, 1.0);
                    let l = self.reflected(&x, Some(first), &mut rng, None, arrival);
                    let t: Bands = std::array::from_fn(|k| l[k] - c[k]);
                    add(i, t, 1.0 / corrected as f64);
                }
            }
        }
        out.share = share;
        out.from_networks = from_networks;
        out.reflects = true;
        out
    }

    /// One round of `rays` samples of the mean B over a footprint (a pixel): sample i's receiver
    /// is `receiver(u)` at its own point u of a padded pair ([`SobolRay::padded`]), where it gets
    /// E, one shadow ray and one cosine ray continued as a path (every ray corrected: the networks
    /// are not read); a sample that sees the sky gets the infinite lights' π·L there, one that
    /// sees the back of a face 0. A path tracer whose first vertex is the receiver; replicates,
    /// rounds and seeds as [`PathGather::estimate`].
    ///
    /// The point in the pixel came from Sobol dimensions 10–11 before, a pair that stratifies
    /// less: padding it lowered two-blockers' per-pixel relative MSE at 64 rays a pixel from
    /// 3.2·10⁻⁴ to 2.2·10⁻⁴ (mean of 6 seeds; the same at 16 rays). Padding the shadow ray's and
    /// the cosine ray's pairs too made it worse (1.3–1.8× Mitsuba's instead of 0.8–0.96×): the
    /// main sequence's joint stratification of the light and the bounce is worth more there.
    pub fn estimate_footprint(
        &self,
        receiver: &impl Fn([f64; 2]) -> FirstHit,
        seed: u64,
        first: usize,
        rays: usize,
    ) -> PointEstimate {
        let mut rng =
            ChaCha8Rng::seed_from_u64(seed ^ (first as u64).wrapping_mul(0xD1B5_4A32_D192_ED03));
        let replicates = REPLICATES.min(rays).max(1);
        // One shadow ray and one cosine ray per sample.
        let mis = Mis {
            emitters: self.emitters,
            n_e: 1.0,
            n_c: 1.0,
        };
        let mut share = [[0.0; BANDS]; REPLICATES];
        let mut ray_square = [0.0; BANDS];
        for i in 0..rays {
            let u = SobolRay::new(seed, replicates, first, i);
            let pixel = u.set(2);
            // the point in the pixel from a padded pair: stratified as a (0, 2)-sequence
            let (y, n, face) = match receiver(u.padded(PIXEL_SALT)) {
                FirstHit::Front(y, n, face) => (y, n, face),
                FirstHit::Escaped(dir) => {
                    // the light at infinity seen directly: its full π·L
                    let at = Receiver {
                        p: DVec3::ZERO,
                        n: dir,
                    };
                    let b = self.emitters.lights().escaped(&at, dir, |_, _| 1.0);
                    for k in 0..BANDS {
                        share[i % replicates][k] += b[k] / rays as f64;
                        ray_square[k] += b[k] * b[k] / rays as f64;
                    }
                    continue;
                }
                FirstHit::Back => continue,
            };
            let z = Vertex { p: y, n, face };
            let (rho, e) = (
                self.domain.reflectance_at(face, y),
                self.domain.emission(face),
            );
            let mut b = e;
            if rho.iter().any(|r| *r != 0.0) {
                let (s0, s1) = (u.set(0), u.set(1));
                let mut light = self.next_event(&z, &mis, (s0[0], [s0[1], s0[2]]));
                let (_, d, hit) = self.cosine_ray(&z, &mis, false, SobolRay::cosine(s0, s1));
                let l = match hit {
                    Some(x) => {
                        let first = SobolRay::path_vertex(s1, pixel);
                        let arrival = self.arrival(&z, &x, 1.0);
                        self.reflected(&x, Some(first), &mut rng, None, arrival)
                    }
                    None => [0.0; BANDS],
                };
                let relay = self.relay_from_point(&z, u);
                for k in 0..BANDS {
                    light[k] += d[k] + l[k] + relay[k];
                    b[k] += rho[k] * light[k];
                }
            }
            for k in 0..BANDS {
                share[i % replicates][k] += b[k] / rays as f64;
                ray_square[k] += b[k] * b[k] / rays as f64;
            }
        }
        PointEstimate {
            share,
            replicates,
            rays,
            reflects: true,
            ray_square,
            ..PointEstimate::default()
        }
    }

    /// L̂(x): the reflected radiosity at a path vertex by path tracing: at each vertex one shadow
    /// ray and one cosine ray, MIS-combined for the direct light, continued with Russian roulette
    /// from `PathSettings::roulette_depth` with continuation probability q = max_k ρ_k at the
    /// vertex, so that the throughput ρ_k/q never grows (bounded weights, finite variance even
    /// at ρ = 0.99, where a 0.95 cap made the weights grow 4 % per bounce). With ρ < 1 every path
    /// ends; [`MAX_DEPTH`] only guards against a loop (its bias ρ^MAX_DEPTH).
    ///
    /// `L̂(x) = Σ_v β_v ρ_v (NEE_v + emitter hit_v)`, `β` the product of ρ/q over the earlier
    /// vertices: the recursion `L̂(x) = ρ·(NEE + hit + L̂(next)/q)` unrolled.
    ///
    /// `guiding`: the spatial guides of the round and the group's records
    /// ([`super::guide`]): each bounce's square point is warped by its cell's guide (density
    /// q_g, the throughput divided by it, the MIS weights counting q_g cosine rays), each
    /// bounce is recorded with the light it brought (its hit's emission and L̂ beyond it), and a
    /// bounce whose expected light outweighs the path's start's splits (below).
    ///
    /// **Splitting** (guided paths; a weight window after Vorba & Křivánek 2016, "Adjoint-driven
    /// Russian roulette and splitting"): at a vertex v whose cell's mean light is L_v, the path's
    /// expected remaining light relative to its start x's is r = w·β·L_v/L_x (w the weight of
    /// the branch, 1 for the path). Where r > 2 the bounce is cast m = min(⌊r + ½⌋, 8) times, each
    /// branch carrying β·ρ/(q·q_g·m) and continued on its own (the MIS weights count m·q cosine
    /// rays). A guide sends a path where the light is, at the price of weights that grow along
    /// the directions it neglects (up to 1/α per bounce); a path that then reaches a bright part
    /// of the scene carries its large weight into every light it finds there. Splitting averages
    /// those lights over m continuations: on the door gap's floor the standard deviation per
    /// path fell from 3.7–11 (guided, no splitting) to 2.2–4.6, at 2× the time per path
    /// (`guided_paths_vary_less_on_the_door_gaps_floor`). Unbiased: each branch is an
    /// independent estimate of the same continuation, averaged.
    pub(crate) fn reflected(
        &self,
        x: &Vertex,
        first: Option<[f64; 5]>,
        rng: &mut ChaCha8Rng,
        guiding: Option<(&SpatialGuides, &mut Vec<Record>)>,
        arrival: Option<f64>,
    ) -> Bands {
        self.walk(x, first, rng, guiding, (1.0, None, 0, arrival))
    }

    /// [`PathGather::reflected`] from `x` on a branch of weight `w` relative to its path, whose
    /// start's cell has mean light `start` (None: x is the start, its cell read at the first
    /// vertex), after `splits` splits.
    fn walk(
        &self,
        x: &Vertex,
        first: Option<[f64; 5]>,
        rng: &mut ChaCha8Rng,
        mut guiding: Option<(&SpatialGuides, &mut Vec<Record>)>,
        (w, mut start, splits, mut arrival): (f64, Option<f64>, usize, Option<f64>),
    ) -> Bands {
        let (mut out, mut beta) = ([0.0; BANDS], [1.0; BANDS]);
        let (mut x, mut first) = (*x, first);
        let mut bounces: Vec<Bounce> = Vec::new();
        for depth in 1..=MAX_DEPTH {
            let rho = self.domain.reflectance_at(x.face, x.p);
            let top = rho.iter().fold(0.0f64, |m, r| m.max(*r));
            if top == 0.0 {
                break;
            }
            let q = if depth == MAX_DEPTH {
                0.0
            } else if depth < self.settings.roulette_depth {
                1.0
            } else {
                top.min(1.0)
            };
            let u = first
                .take()
                .unwrap_or_else(|| std::array::from_fn(|_| rng.random()));
            let cell = guiding.as_ref().and_then(|(g, _)| g.at(x.p, x.n));
            let guide = cell.and_then(|c| c.guide);
            let start = *start.get_or_insert_with(|| cell.map_or(0.0, |c| c.light));
            // ⟨Splitting: the bounce's expected light against the start's (doc comment)⟩
            let m = match cell {
                Some(c) if start > 0.0 && q > 0.0 && splits < MAX_SPLITS => {
                    let b = beta.iter().fold(0.0f64, |m, b| m.max(*b));
                    branches(w * b * c.light / start)
                }
                _ => 1,
            };
            // The cosine ray is cast m times, each with probability q: its MIS count is m·q.
            let mis = Mis {
                emitters: self.emitters,
                n_e: 1.0,
                n_c: q * m as f64,
            };
            let mut light = match guide {
                None => self.next_event(&x, &mis, (u[0], [u[1], u[2]])),
                Some(g) => {
                    let q = |d: DVec3| g.density_toward(x.n, d);
                    self.next_event_scaled(&x, &mis, (u[0], [u[1], u[2]]), q)
                }
            };
            // ⟨Secondary sources (relay.rs): x's direct light weighted against the previous
            // vertex's draw from the table, and a draw of its own⟩
            let count = (guide, q * m as f64);
            let (w_a, relay) = self.vertex_relay(&x, arrival.take(), count, rng);
            for k in 0..BANDS {
                light[k] *= w_a;
                out[k] += beta[k] * rho[k] * relay[k];
            }
            if m > 1 {
                // ⟨m branches, each continued on its own; the path ends here⟩
                let step = (beta, rho, light, w_a);
                let branch = guiding.as_mut().map(|(g, r)| (*g, &mut **r));
                let split = self.branches(
                    &x,
                    u,
                    (guide, &mis, q, m),
                    step,
                    rng,
                    branch,
                    (w, start, splits),
                );
                for k in 0..BANDS {
                    out[k] += split[k];
                }
                break;
            }
            let (v, q_g, mut d, next) = self.bounce(&x, guide, (&mis, q, m), [u[3], u[4]], rng);
            for k in 0..BANDS {
                d[k] *= w_a;
                light[k] += d[k];
                out[k] += beta[k] * rho[k] * light[k];
            }
            let Some(n) = next else { break };
            for k in 0..BANDS {
                beta[k] *= rho[k] / (q * q_g);
            }
            if guiding.is_some() {
                bounces.push((x, v, q * q_g, q_g, d, out, beta, n));
            }
            arrival = self.arrival(&x, &n, q * q_g);
            x = n;
        }
        if let Some((guides, records)) = guiding.as_mut() {
            record_bounces(guides, records, &bounces, out);
        }
        out
    }

    /// A vertex x's light and its bounce cast m times ([`PathGather::reflected`]'s splitting),
    /// each branch continued on its own: β·ρ·(NEE + Σ hits) + Σ_j β·ρ/(q·q_g,j·m)·L̂(branch j),
    /// for a path at x with throughput β, reflectance ρ and the shadow ray's `light`; `u` the
    /// first branch's square points (the others random).
    #[allow(clippy::too_many_arguments)]
    fn branches(
        &self,
        x: &Vertex,
        u: [f64; 5],
        (guide, mis, q, m): (Option<&Guide>, &Mis, f64, usize),
        (beta, rho, light, w_a): (Bands, Bands, Bands, f64),
        rng: &mut ChaCha8Rng,
        mut guiding: Option<(&SpatialGuides, &mut Vec<Record>)>,
        (w, start, splits): (f64, f64, usize),
    ) -> Bands {
        let mut out: Bands = std::array::from_fn(|k| beta[k] * rho[k] * light[k]);
        for j in 0..m {
            let uj = if j == 0 {
                u
            } else {
                std::array::from_fn(|_| rng.random())
            };
            let (v, q_g, d, hit) = self.bounce(x, guide, (mis, q, m), [uj[3], uj[4]], rng);
            let d = d.map(|v| v * w_a);
            let qq = q * q_g * m as f64;
            let wj: Bands = std::array::from_fn(|k| beta[k] * rho[k] / qq);
            let mut beyond = [0.0; BANDS];
            if let Some(h) = hit {
                let wmax = wj.iter().fold(0.0f64, |m, b| m.max(*b));
                let branch = guiding.as_mut().map(|(g, r)| (*g, &mut **r));
                let at = (w * wmax, Some(start), splits + 1, self.arrival(x, &h, qq));
                beyond = self.walk(&h, None, rng, branch, at);
            }
            for k in 0..BANDS {
                out[k] += beta[k] * rho[k] * d[k] + wj[k] * beyond[k];
            }
            if let (Some((g, records)), Some(h)) = (guiding.as_mut(), hit)
                && records.len() < g.cap()
            {
                let l = (0..BANDS).map(|k| d[k] * qq + beyond[k]).sum::<f64>();
                g.keep(
                    records,
                    g.record((x.p, x.n), v, q_g, l / BANDS as f64, (h.p, h.n)),
                );
            }
        }
        out
    }

    /// One bounce from x, its square point `u` warped by the cell's `guide` (density q_g; 1
    /// unguided), cast with probability q as one of `m` (the MIS count m·q·q_g): (the warped
    /// point, q_g, the light the ray brought from an emitter per `mis`, the hit).
    fn bounce(
        &self,
        x: &Vertex,
        guide: Option<&Guide>,
        (mis, q, m): (&Mis, f64, usize),
        u: [f64; 2],
        rng: &mut ChaCha8Rng,
    ) -> ([f64; 2], f64, Bands, Option<Vertex>) {
        let (v, q_g) = guide.map_or((u, 1.0), |g| g.sample(u));
        if q > 0.0 && (q >= 1.0 || rng.random::<f64>() < q) {
            let mis = Mis {
                n_c: q * q_g * m as f64,
                ..*mis
            };
            let (_, d, hit) = self.cosine_ray(x, &mis, false, v);
            (v, q_g, d, hit)
        } else {
            (v, q_g, [0.0; BANDS], None)
        }
    }

    /// One shadow ray from z to a light drawn by power from `u0` and sampled from `u`: its
    /// direct light per unit ρ, MIS-weighted ([`crate::gather::light_ray`]).
    pub(crate) fn next_event(&self, z: &Vertex, mis: &Mis, (u0, u): (f64, [f64; 2])) -> Bands {
        self.next_event_scaled(z, mis, (u0, u), |_| 1.0)
    }

    /// [`PathGather::next_event`] where the cosine technique's density toward direction d is
    /// `q(d)`·cos θ/π (a guided bounce, [`light_ray_scaled`]).
    pub(crate) fn next_event_scaled(
        &self,
        z: &Vertex,
        mis: &Mis,
        (u0, u): (f64, [f64; 2]),
        q: impl Fn(DVec3) -> f64,
    ) -> Bands {
        match self
            .emitters
            .lights()
            .pick(&Receiver { p: z.p, n: z.n }, u0)
        {
            Some(Pick::Face(ef, _)) if ef == z.face => [0.0; BANDS],
            Some(pick) => light_ray_scaled(self.domain, mis, pick, u, (z.p, z.n, z.face), q)
                .unwrap_or_default(),
            None => [0.0; BANDS],
        }
    }

    /// One cosine-weighted ray from z ([`cosine_ray`]): (the networks' C at its hit, 0 unless
    /// `networks`; the direct light the hit carries — or the infinite lights' where the ray
    /// escapes — per one of `mis.n_c` rays; the hit).
    pub(crate) fn cosine_ray(
        &self,
        z: &Vertex,
        mis: &Mis,
        networks: bool,
        u: [f64; 2],
    ) -> (Bands, Bands, Option<Vertex>) {
        let hit = match cosine_ray(self.domain, mis, (z.p, z.n, z.face), u) {
            Cosine::Hit(hit) => hit,
            Cosine::Escaped(d) => return ([0.0; BANDS], d, None),
            Cosine::Lost => return ([0.0; BANDS], [0.0; BANDS], None),
        };
        let c = if networks {
            (self.networks)(hit.x, hit.nx).map(|v| v.max(0.0))
        } else {
            [0.0; BANDS]
        };
        let x = Vertex {
            p: hit.x,
            n: hit.nx,
            face: hit.face,
        };
        (c, hit.direct, Some(x))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use scene_sampler::{AnyScene, KernelSampler, SceneBvh, builtin};

    /// Four dimensions at once are `sobol_burley::sample`'s values; index j and j + 2¹⁶ of a
    /// replicate are different points (the library reads 16 bits of the index: without the
    /// block's own scrambling they were the same point), and within a block of 2¹⁶ the points of
    /// one replicate are a balanced net (each of 16 strata of dimension 3 gets 1/16 of them).
    #[test]
    fn sobol_rays_are_distinct_beyond_the_16_bit_index() {
        let (seed, reps) = (0x1234_5678_9ABC, 2);
        for i in [0, 1, 7, 1000] {
            let u = SobolRay::new(seed, reps, 3, i);
            let (r, j) = (i % reps, 3 + i / reps);
            let scramble = (seed ^ (r as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15)) as u32;
            for (d, v) in u.set(1).iter().enumerate() {
                let one = f64::from(sobol_burley::sample(j as u32, 4 + d as u32, scramble));
                assert_eq!(*v, one.min(1.0 - f64::EPSILON));
            }
        }
        let (a, b) = (
            SobolRay::new(seed, 1, 5, 0),
            SobolRay::new(seed, 1, 5 + (1 << 16), 0),
        );
        assert_ne!(a.set(0), b.set(0));
        let mut strata = [0usize; 16];
        for i in 0..1 << 12 {
            let v = SobolRay::new(seed, 1, 1 << 16, i).set(0)[3];
            strata[(v * 16.0) as usize] += 1;
        }
        assert!(strata.iter().all(|&c| c == 1 << 8), "{strata:?}");
    }

    /// The furnace as a domain (leaked: tests only), its emitters, the exact B = E/(1 − ρ) and E.
    fn furnace() -> (Domain<'static>, Emitters, f64, f64) {
        let AnyScene::ThreeD(scene) = builtin("furnace").unwrap() else {
            panic!()
        };
        let (e, rho) = (scene.faces[0].emission.0[0], scene.faces[0].rho.0[0]);
        assert!(
            scene
                .faces
                .iter()
                .all(|f| f.rho.0[0] == rho && f.emission.0[0] == e)
        );
        let scene: &'static scene_sampler::Scene = Box::leak(Box::new(scene));
        let bvh: &'static SceneBvh = Box::leak(Box::new(SceneBvh::new(scene)));
        let d = Domain::ThreeD(KernelSampler::new(scene, bvh));
        let em = Emitters::new(&d);
        (d, em, e / (1.0 - rho), e)
    }

    /// Whatever the networks say, the paths gather converges to the exact B: in the furnace (a
    /// closed box where every wall emits E and reflects ρ, B = E/(1 − ρ) everywhere) with a
    /// network that is 0, exact, or 3× too bright, the mean over 200 points is within 4 of its
    /// standard errors of the exact value, and the standard errors predict the spread: the sum of
    /// squared errors is about the sum of the variances.
    #[test]
    fn the_correction_removes_any_network_error_and_its_error_bar_is_right() {
        let (d, em, exact, e) = furnace();
        let (samples, settings) = counts(8, 32, 8);
        let points = SurfacePoints::of(d.scene_3d().unwrap(), 200);
        for scale in [0.0, 1.0, 3.0] {
            let net = move |_: DVec3, _: DVec3| [scale * (exact - e); BANDS];
            let g = PathGather::new(&d, &em, net, samples, settings);
            let (mut sum, mut var, mut sq) = (0.0, 0.0, 0.0);
            for (i, &(y, n, f)) in points.0.iter().enumerate() {
                let r = g.gather((y, n, f), i as u64);
                let (b, s) = (r.radiosity[0], r.std_error[0]);
                assert!(
                    b.is_finite() && s.is_finite(),
                    "scale {scale}: B {b}, σ {s}"
                );
                sum += b;
                var += s * s;
                sq += (b - exact).powi(2);
            }
            let n = points.0.len() as f64;
            let (mean, se) = (sum / n, var.sqrt() / n);
            assert!(
                (mean - exact).abs() < 4.0 * se,
                "scale {scale}: mean {mean} vs {exact} (standard error {se})"
            );
            // The squared errors against the variances the standard errors claim.
            let ratio = sq / var;
            assert!(
                (0.5..2.0).contains(&ratio),
                "scale {scale}: Σ error² / Σ σ² = {ratio}"
            );
        }
    }

    /// With no corrections the gather is the ray gather: its networks' part is ρ·C over the
    /// cosine rays, which in a closed box all hit a front face.
    #[test]
    fn without_corrections_it_is_the_ray_gather() {
        let (d, em, exact, e) = furnace();
        let (samples, settings) = counts(16, 16, 0);
        let net = |_: DVec3, _: DVec3| [exact - e; BANDS];
        let g = PathGather::new(&d, &em, net, samples, settings);
        for (i, &(y, n, f)) in SurfacePoints::of(d.scene_3d().unwrap(), 20)
            .0
            .iter()
            .enumerate()
        {
            let r = g.gather((y, n, f), i as u64);
            // With B_refl exact at every hit the indirect light is ρ·(B − E)·(fraction of
            // cosine rays that hit a front face) = ρ(B − E) in a closed box.
            let rho = d.scene_3d().unwrap().faces[0].rho.0[0];
            assert!((r.from_networks[0] - rho * (exact - e)).abs() < 1e-9);
        }
    }

    /// The default corrects every ray: the networks' value cancels and is never read (a network
    /// that panics when asked), and the gather is still exact in the furnace.
    #[test]
    fn with_every_ray_corrected_the_networks_are_not_read() {
        let (d, em, exact, _) = furnace();
        let (samples, _) = counts(8, 16, 0);
        let net = |_: DVec3, _: DVec3| -> Bands { panic!("the networks were read") };
        let g = PathGather::new(&d, &em, net, samples, PathSettings::default());
        let (mut sum, mut var) = (0.0, 0.0);
        let points = SurfacePoints::of(d.scene_3d().unwrap(), 100);
        for (i, &(y, n, f)) in points.0.iter().enumerate() {
            let r = g.gather((y, n, f), i as u64);
            assert_eq!(r.from_networks, [0.0; BANDS]);
            sum += r.radiosity[0];
            var += r.std_error[0].powi(2);
        }
        let n = points.0.len() as f64;
        let (mean, se) = (sum / n, var.sqrt() / n);
        assert!((mean - exact).abs() < 4.0 * se, "{mean} vs {exact} (±{se})");
    }

    /// Shadow rays, cosine rays and corrections per point.
    fn counts(direct: usize, indirect: usize, corrections: usize) -> (GatherSamples, PathSettings) {
        (
            GatherSamples { direct, indirect },
            PathSettings {
                corrections,
                ..PathSettings::default()
            },
        )
    }

    /// Area-uniform points of a scene with their normals and faces (an R2 set).
    struct SurfacePoints(Vec<(DVec3, DVec3, u32)>);

    impl SurfacePoints {
        fn of(scene: &scene_sampler::Scene, n: usize) -> Self {
            let s = scene_sampler::SurfaceSampler::new(scene);
            Self(
                s.spread(n, |_| true)
                    .into_iter()
                    .map(|q| (q.point, q.normal, q.face))
                    .collect(),
            )
        }
    }
}

#[cfg(test)]
mod guide_diagnostics {
    use super::*;
    use crate::estimator::guide::SpatialLearner;
    use scene_sampler::{KernelSampler, SceneBvh};

    /// The relative standard deviation of the values `v`.
    fn relative_std(v: &[f64]) -> f64 {
        let m = v.iter().sum::<f64>() / v.len() as f64;
        let var = v.iter().map(|a| (a - m).powi(2)).sum::<f64>() / v.len() as f64;
        var.sqrt() / m
    }

    /// [`paths_at`]'s relative standard deviations and seconds (paths split as they would be).
    fn path_spread(stem: &str, p: DVec3, normal: DVec3, n_paths: usize) -> [(f64, f64); 2] {
        let [(a, ta), (b, tb)] = paths_at(stem, (p, normal), n_paths, 1.0);
        [(relative_std(&a), ta), (relative_std(&b), tb)]
    }

    /// Per path L̂(x) at (p, n) of the shipped scene `stem` (with its lighting file): the values
    /// and the seconds of `n_paths` paths unguided, then of as many guided at every vertex by
    /// guides learned from twice as many earlier paths from the point, each path starting with
    /// weight `w` against its start (1: as `reflected`; more splits more).
    fn paths_at(
        stem: &str,
        (p, normal): (DVec3, DVec3),
        n_paths: usize,
        w: f64,
    ) -> [(Vec<f64>, f64); 2] {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes");
        let mut scene = scene_sampler::load(root.join(format!("{stem}.obj")))
            .unwrap()
            .into_3d()
            .unwrap();
        let lights = root.join(format!("{stem}.lights.json"));
        let lighting = scene_sampler::Lighting::read(&lights).unwrap();
        scene.add_lights(lighting.lights().unwrap());
        let bvh = SceneBvh::new(&scene);
        let d = Domain::ThreeD(KernelSampler::new(&scene, &bvh));
        let em = Emitters::new(&d);
        let samples = GatherSamples {
            direct: 1,
            indirect: 1,
        };
        let net = |_: DVec3, _: DVec3| [0.0; BANDS];
        let g = PathGather::new(&d, &em, net, samples, PathSettings::default());
        let face = (0..scene.faces.len() as u32)
            .find(|&f| {
                let fc = &scene.faces[f as usize];
                fc.normal.dot(normal) > 0.9 && fc.closest_point(p).distance(p) < 1e-9
            })
            .unwrap();
        let x = Vertex { p, n: normal, face };
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        let t = std::time::Instant::now();
        let plain: Vec<f64> = (0..n_paths)
            .map(|_| g.reflected(&x, None, &mut rng, None, None)[0])
            .collect();
        let plain = (plain, t.elapsed().as_secs_f64());
        // learn from unguided paths (guides that are empty), in batches as the rounds do
        let mut learner = SpatialLearner::new(d.frame(), 1);
        let empty = SpatialLearner::new(d.frame(), 1).guides();
        let mut records = Vec::new();
        for _ in 0..2 * n_paths {
            g.reflected(&x, None, &mut rng, Some((&empty, &mut records)), None);
            if records.len() >= empty.cap() {
                learner.learn(&records);
                records.clear();
            }
        }
        let guides = learner.guides();
        let t = std::time::Instant::now();
        let guided: Vec<f64> = (0..n_paths)
            .map(|_| {
                records.clear();
                let guiding = Some((&guides, &mut records));
                g.walk(&x, None, &mut rng, guiding, (w, None, 0, None))[0]
            })
            .collect();
        [plain, (guided, t.elapsed().as_secs_f64())]
    }

    /// Split paths stay unbiased: from a point of the door gap's floor, 20 000 guided paths that
    /// start with weight 3 (so that every path splits at its first vertex, and its branches
    /// again where they meet the lit room) agree with 20 000 unguided ones within 4 standard
    /// errors, and vary less.
    #[test]
    fn split_paths_agree_with_unguided_ones_on_the_door_gaps_floor() {
        let p = (DVec3::new(4.5, 0.0, 2.0), DVec3::Y);
        let [(a, _), (b, _)] = paths_at("door-gap", p, 20_000, 3.0);
        let stats = |v: &[f64]| {
            let n = v.len() as f64;
            let m = v.iter().sum::<f64>() / n;
            let var = v.iter().map(|a| (a - m).powi(2)).sum::<f64>() / (n - 1.0);
            (m, var / n)
        };
        let ((ma, va), (mb, vb)) = (stats(&a), stats(&b));
        assert!(
            (ma - mb).abs() < 4.0 * (va + vb).sqrt(),
            "unguided {ma} ± {}, split {mb} ± {}",
            va.sqrt(),
            vb.sqrt()
        );
        assert!(vb < va, "split paths vary more: {vb} vs {va}");
    }

    /// The spatial guides lower the variance of a path from a wall of the sun patch room (lit
    /// only by the patch the sun makes on the floor): 200 000 paths L̂(x) from one wall point,
    /// unguided, then guided at every vertex by guides learned from 400 000 earlier paths. A
    /// diagnostic (about 10 s in release: `cargo test --release -p gcr --lib
    /// guided_paths_vary_less -- --ignored --nocapture`); measured 2026-12-04: relative standard
    /// deviation per path 4.45 unguided, 2.63 guided (16 × 16 bins and 32 cells per diagonal
    /// with a 256-ray confidence gave 7.9: noisy guides cost more than they find).
    #[test]
    #[ignore]
    fn guided_paths_vary_less_at_a_wall_of_the_sun_patch_room() {
        // a point on the west wall (x = 0, facing +x)
        let [(a, _), (b, _)] = path_spread(
            "sun-patch-room",
            DVec3::new(0.0, 1.5, 4.0),
            DVec3::X,
            200_000,
        );
        println!("relative standard deviation per path: unguided {a:.3}, guided {b:.3}");
        assert!(b < 0.8 * a, "guided {b} vs unguided {a}");
    }

    /// The same at three points of the door gap's floor in the unlit room (1 000 000 paths
    /// each), with the seconds: the variance × time of a path, guided against unguided.
    /// Measured 2026-12-06 (relative standard deviation per path, unguided → guided; s):
    /// without splitting 7.6 → 3.7, 12.8 → 8.1, 17.1 → 11.0 at 1.9× the time per path; with it
    /// 7.6 → 2.2, 12.8 → 3.8, 17.1 → 4.6 at 4× (variance × time 2.8–3.3× lower).
    #[test]
    #[ignore]
    fn guided_paths_vary_less_on_the_door_gaps_floor() {
        for p in [
            DVec3::new(4.5, 0.0, 2.0),
            DVec3::new(6.0, 0.0, 1.5),
            DVec3::new(7.8, 0.0, 0.2),
        ] {
            let [(a, ta), (b, tb)] = path_spread("door-gap", p, DVec3::Y, 1_000_000);
            println!(
                "{p}: relative standard deviation per path: unguided {a:.3} ({ta:.2} s), \
                 guided {b:.3} ({tb:.2} s); variance × time {:.2}",
                (b * b * tb) / (a * a * ta)
            );
            assert!(b * b * tb < a * a * ta, "guided {b} vs unguided {a}");
        }
    }
}
