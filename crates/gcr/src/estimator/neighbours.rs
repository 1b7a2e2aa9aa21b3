//! Paths shared between neighbouring output points (beyond the dissertation; issue "Fast and
//! accurate": "reuse of the smooth indirect part between neighbouring output points").
//!
//! The paths gather spends most of its rays on the path continued from each cosine ray's hit x,
//! L̂(x). Neighbouring points y₁ … y_m see nearly the same hemisphere, so one path can serve them
//! all: every member casts its own cosine rays (its own Sobol points), and each hit x with its
//! path L̂(x) is used by every member k through a visibility ray y_k → x. With c cosine rays per
//! member, the hits are drawn from the mixture of the members' cosine densities in area measure,
//! p_a(x) = G(y_a, x)·V(y_a, x) (G = cos θ_a cos θ_x/(π r²)), and member k's estimate of its
//! reflected-light integral ∫ L(x) G(y_k, x) V(y_k, x) dA is the multi-sample balance heuristic
//! (Veach 1997, eq. 9.4 with the balance weights)
//!
//! ```text
//! Î_k = Σ_hits L̂(x)·G(y_k, x)·V(y_k, x) / (c · Σ_a G(y_a, x)·V(y_a, x)),
//! ```
//!
//! unbiased for every member (its own rays are in the mixture, so the density is positive
//! wherever its integrand is), with weights at most 1/c (the member's own term bounds the sum):
//! near a corner, where one member's G grows as 1/r², the others' weights stay small. For m = 1 it
//! is the single-point gather. The visibility rays to x are the ones needed for the sum anyway.
//!
//! Direct light: each member keeps its own shadow rays; the cosine hits on an emitter count for
//! member k with the power heuristic between its n_e emitter samples (a = n_e·p_e(x)) and the
//! shared technique (b = c·Σ_a G(y_a, x), visibility left out: MIS weights need only sum to one),
//! so shadow-ray and shared-hit weights partition unity at every emitter point. Lights other than
//! faces (the sun, a sky, point lights: [`scene_sampler::lights`]) are not shared: a member's
//! shadow rays to them are weighted against its own c cosine rays, and a cosine ray that escapes
//! the scene brings the infinite lights' light to the member that cast it alone.
//!
//! Cost: each hit needs m − 1 visibility rays (one per other member) but only one path, so a
//! hit seen by a member costs (m − 1 + path)/m rays instead of 1 + path (a path with its shadow rays
//! is 4–6 rays at these albedos); each member therefore casts only about `SHARE_FACTOR / m` of a
//! lone point's cosine rays ([`cosine_share`]) and still sees about twice as many hits. The price
//! is a mixture that fits a member's own cosine density less well the farther apart the members
//! are. Members are grouped ([`groups`]) by position (a Morton order of the points, runs within
//! a radius set by the points' density, [`GROUP_RADIUS`]) and facing (normals within 25°), at most
//! `PathSettings::neighbours` per group, deterministically from the point set (not from the input
//! order). Irradiance probes in the air share as surface points do; Flatland and points that do not
//! reflect are gathered alone.
//!
//! Guided rounds ([`super::guide`]): a member's cosine rays have density q_a·cos θ/π (q_a its
//! group's guide toward the direction), so the mixture's density at x is Σ_a G(y_a, x)·V·q_a(x)
//! and the MIS weights count q_a cosine rays; a group of one takes the same road.

use super::guide::{GroupGuide, Guide, Learner, Record, SpatialGuides};
use super::paths::{PathGather, PointEstimate, REPLICATES, SobolRay, Vertex};
use crate::config::GatherSamples;
use crate::domain::Domain;
use crate::element::{BANDS, Bands};
use crate::gather::{Mis, emitter_geometry, geometry_3d, light_ray_scaled};
use glam::DVec3;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use scene_sampler::{
    KernelSampler, LightSet, NO_FACE, Pick, Receiver, SceneBvh, SurfacePoint, cosine_hemisphere,
};
use std::f64::consts::PI;

/// A group's members lie within twice the radius of a disc that holds a full group at the points'
/// mean density, and at most this fraction of the scene's diagonal, of its first member (a fixed
/// small radius left sparse point sets ungrouped; docs/design/estimator.md has the measurements).
pub(crate) const GROUP_RADIUS: f64 = 0.25;
/// A member of a group of m casts about `SHARE_FACTOR / m` of a lone point's cosine rays
/// ([`cosine_share`]), so that it still sees about twice as many hits as alone (1, 2, 4 and 8
/// measured within noise of each other, 2 the cheapest rounds; docs/design/estimator.md).
const SHARE_FACTOR: f64 = 2.0;
/// Members' normals within this cosine of the first member's (25°).
const GROUP_FACING: f64 = 0.9;

/// Groups of neighbouring output points (indices into `points`), each at most `max` points of
/// similar normal near its first point (the radius: [`GROUP_RADIUS`]); every point in exactly one
/// group. The grouping depends only on the set of points: they are walked in a Morton order of
/// their positions (ties by coordinates), a group closed when the next point is too far or faces
/// away. Points that cannot share (Flatland, ρ = 0, `max` ≤ 1) are singletons; points on no face
/// ([`NO_FACE`]: irradiance probes in the air) share with each other.
pub(crate) fn groups(
    domain: &Domain,
    points: &[(DVec3, DVec3, u32)],
    max: usize,
) -> Vec<Vec<usize>> {
    // a point on no face is an irradiance probe (a white receiver); others must reflect
    let shareable = |&(y, _, face): &(DVec3, DVec3, u32)| {
        max > 1
            && matches!(domain, Domain::ThreeD(_))
            && (face == NO_FACE || domain.reflectance_at(face, y).iter().any(|r| *r > 0.0))
    };
    let (origin, diagonal) = domain.frame();
    let key = |y: DVec3| {
        let q = ((y - origin) / diagonal.max(f64::MIN_POSITIVE)).clamp(DVec3::ZERO, DVec3::ONE);
        let scale = ((1u64 << 21) - 1) as f64;
        morton([q.x, q.y, q.z].map(|c| (c * scale) as u64))
    };
    let (mut order, alone): (Vec<usize>, Vec<usize>) =
        (0..points.len()).partition(|&i| shareable(&points[i]));
    order.sort_by_cached_key(|&i| {
        let (y, n, _) = points[i];
        (key(y), [y.x, y.y, y.z, n.x, n.y, n.z].map(f64::to_bits))
    });
    // a disc that holds `max` points at the set's mean density (N points over the scene's area A)
    // has radius √(max·A/(πN)); twice that, at most GROUP_RADIUS·diagonal
    let area = match domain {
        Domain::ThreeD(k) => k.scene.total_area(),
        Domain::Flat(_) => 0.0,
    };
    let radius = (2.0 * (max as f64 * area / (PI * order.len().max(1) as f64)).sqrt())
        .min(GROUP_RADIUS * diagonal);
    let mut out: Vec<Vec<usize>> = Vec::new();
    for i in order {
        let (y, n, _) = points[i];
        match out.last_mut() {
            Some(g)
                if g.len() < max && {
                    let (y0, n0, _) = points[g[0]];
                    y.distance(y0) <= radius && n.dot(n0) >= GROUP_FACING
                } =>
            {
                g.push(i)
            }
            _ => out.push(vec![i]),
        }
    }
    out.extend(alone.into_iter().map(|i| vec![i]));
    out
}

/// Each member's cosine rays in a group of `m` when a lone point would cast `n_c` from Sobol index
/// `first` on (per replicate), and the index its own sequence continues from: the group's hits
/// reach every member, so a member needs about `SHARE_FACTOR / m` as many (a power-of-two
/// fraction, so rounds continue the sequences at integer indices), at least one per replicate.
fn cosine_share(m: usize, n_c: usize, first: usize, replicates: usize) -> (usize, usize) {
    let halvings = (m as f64 / SHARE_FACTOR).log2().floor().max(0.0) as u32;
    let ratio = 0.5f64.powi(halvings as i32);
    let c = ((n_c as f64 * ratio / replicates as f64).ceil() as usize).max(1) * replicates;
    (c, (first as f64 * ratio).floor() as usize)
}

/// Interleaves the low 21 bits of three coordinates.
fn morton(c: [u64; 3]) -> u64 {
    let spread = |mut v: u64| {
        v &= 0x1f_ffff;
        v = (v | v << 32) & 0x1f_0000_0000_ffff;
        v = (v | v << 16) & 0x1f_0000_ff00_00ff;
        v = (v | v << 8) & 0x100f_00f0_0f00_f00f;
        v = (v | v << 4) & 0x10c3_0c30_c30c_30c3;
        (v | v << 2) & 0x1249_2492_4924_9249
    };
    spread(c[0]) | spread(c[1]) << 1 | spread(c[2]) << 2
}

/// One round of a group ([`PathGather::estimate_group`]): the members, their random numbers and
/// the counts of their rays.
struct Group<'g> {
    members: &'g [(DVec3, DVec3, u32)],
    seeds: &'g [u64],
    /// Shadow rays per member, and the first Sobol index of this round (per replicate).
    n_e: usize,
    first: usize,
    /// Cosine rays per member ([`cosine_share`]), and their first Sobol index.
    c: usize,
    first_c: usize,
    replicates: usize,
    /// The round's guide of the cosine rays (`None`: cosine-distributed; module docs of
    /// [`super::guide`]).
    guide: Option<&'g Guide>,
}

impl Group<'_> {
    /// Member k's Sobol point i from index `first` of its replicate's sequence.
    fn qmc(&self, first: usize, k: usize, i: usize) -> SobolRay {
        SobolRay::new(self.seeds[k], self.replicates, first, i)
    }

    /// b̃(x) = c·Σ_a G(y_a, x)·q_a(x): the shared cosine technique's count density at x,
    /// unoccluded (q_a the guide's density toward x from member a, 1 unguided).
    fn shared_density(&self, x: DVec3, nx: DVec3) -> f64 {
        let g: f64 = (self.members.iter())
            .map(|&(y, n, _)| {
                let geo = geometry_3d(y, n, x, nx);
                if geo > 0.0 {
                    geo * self.q(n, x - y)
                } else {
                    geo
                }
            })
            .sum();
        self.c as f64 * g
    }

    /// G·V from every member to a point x (into `weight`), and the cosine technique's mixture
    /// density there, Σ G·V·q (q the guide's toward x from each member). `caster`: the member
    /// whose cosine ray hit x and that ray's q (it sees x: no visibility ray); None for a point
    /// none of them cast a ray to (a draw from the table of secondary sources, `group_relays`).
    fn mixture(
        &self,
        bvh: &SceneBvh,
        hit: &SurfacePoint,
        caster: Option<(usize, f64)>,
        weight: &mut [f64],
    ) -> f64 {
        let (x, nx) = (hit.point, hit.normal);
        let mut total = 0.0;
        for (k, &(yk, nk, fk)) in self.members.iter().enumerate() {
            let geo = geometry_3d(yk, nk, x, nx);
            let cast = caster.filter(|&(a, _)| a == k);
            let seen = cast.is_some()
                || (geo > 0.0 && bvh.visible(hit, &Domain::surface_point_3d(yk, nk, fk)));
            weight[k] = if seen { geo } else { 0.0 };
            total += match (seen, self.guide, cast) {
                (false, _, _) => 0.0,
                (true, None, _) => weight[k],
                (true, Some(_), Some((_, q))) => weight[k] * q,
                (true, Some(_), None) => weight[k] * self.q(nk, x - yk),
            };
        }
        total
    }

    /// The power heuristic's weight, for member `k`, of the shared cosine technique (count
    /// density `shared` at the point) that hit a point of the emitting `face`, against k's own
    /// shadow rays (their density depends on the member: the light tree's choice); 0 where
    /// `shared` is 0.
    fn hit_weight(&self, lights: &LightSet, k: usize, face: u32, shared: f64) -> f64 {
        if shared == 0.0 {
            return 0.0;
        }
        let (p, n, _) = self.members[k];
        power(
            self.n_e as f64 * lights.face_density(&Receiver { p, n }, face),
            shared,
        )
    }

    /// The guide's density q for a ray along `d` (not necessarily unit) from a member with
    /// normal `n`; 1 unguided.
    fn q(&self, n: DVec3, d: DVec3) -> f64 {
        match self.guide {
            Some(g) => g.density_toward(n, d),
            None => 1.0,
        }
    }
}

/// The power heuristic's weight b²/(a² + b²) of the technique with count density b against a
/// (0 where b is 0).
fn power(a: f64, b: f64) -> f64 {
    if b > 0.0 {
        1.0 / (1.0 + (a / b).powi(2))
    } else {
        0.0
    }
}

/// The mean over the bands: what the guide learns of a ray's light.
fn luminance(t: &Bands) -> f64 {
    t.iter().sum::<f64>() / BANDS as f64
}

/// Adds ρ_k·t·scale to member k's share of replicate r.
fn add(out: &mut [PointEstimate], rho: &[Bands], (k, r): (usize, usize), t: Bands, scale: f64) {
    for b in 0..BANDS {
        out[k].share[r][b] += rho[k][b] * t[b] * scale;
    }
}

impl<C: Fn(DVec3, DVec3) -> Bands> PathGather<'_, C> {
    /// One round of the shared gather (module docs) at the group `members` (each `(y, n, face)`
    /// of a 3-D scene, a reflecting face or [`NO_FACE`]) with reflectance and emission `material`
    /// (an irradiance probe: ρ = 1, E = 0), seeded per member by `seeds`: `samples.direct` shadow
    /// rays and `samples.indirect` cosine rays per member, each cosine ray's hit continued as a
    /// path shared by all members. One estimate per member, in order; a group of one is the lone
    /// gather ([`PathGather::estimate`], [`PathGather::estimate_irradiance`]).
    ///
    /// `guiding`: the group's guide across rounds and the round's spatial guides
    /// ([`super::guide`]): this round's cosine rays are drawn from the group's guide (a group of
    /// one too), its paths' bounces from their cells' guides, and every ray is learned from for
    /// the next round; `None` unguided.
    pub(crate) fn estimate_group(
        &self,
        members: &[(DVec3, DVec3, u32)],
        material: &[(Bands, Bands)],
        seeds: &[u64],
        (first, samples): (usize, GatherSamples),
        guiding: Option<(&mut GroupGuide, &SpatialGuides)>,
    ) -> Vec<PointEstimate> {
        let alone = |k: usize| {
            let (p, n, face) = members[k];
            self.estimate_at(Vertex { p, n, face }, material[k], seeds[k], first, samples)
        };
        let Domain::ThreeD(kernel) = self.domain else {
            return (0..members.len()).map(alone).collect();
        };
        if (members.len() == 1 && guiding.is_none()) || self.settings.corrections < samples.indirect
        {
            return (0..members.len()).map(alone).collect();
        }
        let (n_e, n_c) = (samples.direct, samples.indirect);
        let replicates = REPLICATES.min(n_e.max(n_c)).max(1);
        // ⟨Each member's cosine rays: fewer as the group grows (module docs)⟩
        let (c, mut first_c) = cosine_share(members.len(), n_c, first, replicates);
        // ⟨Guided rounds: each round its own scrambling, from index 0. A round's guide was
        // learned from the earlier rounds' points, and later points of one scrambled sequence
        // fill the gaps the earlier ones left: not independent of the guide (measured: +1 % in
        // the furnace). Independent scramblings make each round unbiased given its guide.⟩
        let mut first = first;
        let round_seeds: Vec<u64>;
        let seeds = if guiding.is_some() {
            let round = (first as u64 + 1).wrapping_mul(0xA076_1D64_78BD_642F);
            round_seeds = seeds.iter().map(|s| s ^ round).collect();
            (first, first_c) = (0, 0);
            &round_seeds[..]
        } else {
            seeds
        };
        let (guide, learner, spatial) = match guiding {
            Some((g, spatial)) => (
                g.guide.as_deref(),
                Some(&mut g.learner),
                Some((spatial, &mut g.records)),
            ),
            None => (None, None, None),
        };
        let group = Group {
            members,
            seeds,
            n_e,
            first,
            c,
            first_c,
            replicates,
            guide,
        };
        let rho: Vec<Bands> = material.iter().map(|m| m.0).collect();
        let mut out: Vec<PointEstimate> = (material.iter())
            .map(|&(_, emission)| PointEstimate {
                emission,
                replicates,
                rays: n_e.max(n_c),
                reflects: true,
                ..PointEstimate::default()
            })
            .collect();
        self.group_direct(kernel, &group, &rho, &mut out);
        self.group_hits(kernel, &group, &rho, &mut out, (learner, spatial));
        self.group_relays(kernel, &group, &rho, &mut out);
        out
    }

    /// ⟨Direct light: each member's shadow rays, MIS against the shared cosine hits⟩
    fn group_direct(
        &self,
        kernel: &KernelSampler,
        g: &Group,
        rho: &[Bands],
        out: &mut [PointEstimate],
    ) {
        let lights = self.emitters.lights();
        // other lights than faces: MIS against the member's own c cosine rays (module docs)
        let own = Mis {
            emitters: self.emitters,
            n_e: g.n_e as f64,
            n_c: g.c as f64,
        };
        for (k, &(y, n, face)) in g.members.iter().enumerate() {
            for i in 0..g.n_e {
                let a = g.qmc(g.first, k, i).set(0);
                let (ef, density) = match lights.pick(&Receiver { p: y, n }, a[0]) {
                    Some(Pick::Face(ef, density)) => (ef, density),
                    Some(pick) => {
                        let u = [a[1], a[2]];
                        let q = |d: DVec3| g.q(n, d);
                        let receiver = (y, n, face);
                        if let Some(d) = light_ray_scaled(self.domain, &own, pick, u, receiver, q) {
                            add(out, rho, (k, i % g.replicates), d, 1.0);
                        }
                        continue;
                    }
                    None => continue,
                };
                if ef == face {
                    continue;
                }
                let u = [a[1], a[2]];
                let Some((x, geo)) = emitter_geometry(self.domain, ef, u, y, n, face) else {
                    continue;
                };
                let f = &kernel.scene.faces[ef as usize];
                let a = g.n_e as f64 * density;
                if a <= 0.0 {
                    continue;
                }
                let w = geo / a * (1.0 - power(a, g.shared_density(x, f.normal)));
                add(out, rho, (k, i % g.replicates), f.emission.0, w);
            }
        }
    }

    /// ⟨Shared cosine rays: every member's hits, with their paths, for every member⟩
    fn group_hits(
        &self,
        kernel: &KernelSampler,
        g: &Group,
        rho: &[Bands],
        out: &mut [PointEstimate],
        (mut learner, mut spatial): (
            Option<&mut Learner>,
            Option<(&SpatialGuides, &mut Vec<Record>)>,
        ),
    ) {
        let (scene, bvh) = (kernel.scene, kernel.bvh);
        // the group's paths: one random stream per group and round
        let group_seed = g.seeds.iter().fold(0x243F_6A88_85A3_08D3u64, |h, s| {
            (h ^ s).wrapping_mul(0x9E37_79B9_7F4A_7C15).rotate_left(29)
        });
        let mut rng = ChaCha8Rng::seed_from_u64(
            group_seed ^ (g.first as u64).wrapping_mul(0xD1B5_4A32_D192_ED03),
        );
        let mut weight = vec![0.0; g.members.len()];
        let lights = self.emitters.lights();
        let infinite = lights.has_infinite();
        let own = Mis {
            emitters: self.emitters,
            n_e: g.n_e as f64,
            n_c: g.c as f64,
        };
        for (a, &(y, n, face)) in g.members.iter().enumerate() {
            for i in 0..g.c {
                let sobol = g.qmc(g.first_c, a, i);
                let (sa, sb) = (sobol.set(0), sobol.set(1));
                let u = SobolRay::cosine(sa, sb);
                // ⟨The guided warp of the square: density q (1 unguided)⟩
                let (u, q) = g.guide.map_or((u, 1.0), |guide| guide.sample(u));
                let from = Domain::surface_point_3d(y, n, face);
                let dir = cosine_hemisphere(n, u);
                let Some(h) = bvh.trace_from(&from, dir) else {
                    // escaped: the infinite lights, for the caster alone (module docs)
                    if infinite {
                        let at = Receiver { p: y, n };
                        let t = if g.guide.is_some() {
                            lights.escaped(&at, dir, |g, p| own.cosine_density(g * q, p) / q)
                        } else {
                            lights.escaped(&at, dir, |g, p| own.cosine_density(g, p))
                        };
                        add(out, rho, (a, i % g.replicates), t, 1.0);
                        if let Some(l) = learner.as_deref_mut() {
                            l.add(u, q, luminance(&t) * g.c as f64 * q);
                        }
                    }
                    continue;
                };
                let hit = bvh.surface_point(&h);
                let (x, nx) = (hit.point, hit.normal);
                if nx.dot(y - x) <= 0.0 {
                    continue;
                }
                let total = g.mixture(bvh, &hit, Some((a, q)), &mut weight);
                if !(total > 0.0 && total.is_finite()) {
                    continue;
                }
                // an emitter's light at x for member k, weighted against k's own shadow rays
                let e = scene.faces[hit.face as usize].emission.0;
                let shared = if e.iter().any(|v| *v != 0.0) {
                    g.shared_density(x, nx)
                } else {
                    0.0
                };
                let mis = |k: usize| g.hit_weight(lights, k, hit.face, shared);
                let vertex = Vertex {
                    p: x,
                    n: nx,
                    face: hit.face,
                };
                let first = SobolRay::path_vertex(sb, sobol.set(2));
                let guides = spatial.as_mut().map(|(g, r)| (*g, &mut **r));
                // the table's draws: one per cosine ray of every member (`group_relays`)
                let arrival = (self.secondary.is_some()).then(|| total / g.members.len() as f64);
                let l = self.reflected(&vertex, Some(first), &mut rng, guides, arrival);
                let with_light = |m: f64| -> Bands { std::array::from_fn(|b| l[b] + m * e[b]) };
                if let Some(learn) = learner.as_deref_mut() {
                    learn.add(u, q, luminance(&with_light(mis(a))));
                }
                for (k, &w) in weight.iter().enumerate().filter(|(_, w)| **w > 0.0) {
                    let t = if shared == 0.0 { l } else { with_light(mis(k)) };
                    add(out, rho, (k, i % g.replicates), t, w / (g.c as f64 * total));
                }
            }
        }
    }
}

impl<C: Fn(DVec3, DVec3) -> Bands> PathGather<'_, C> {
    /// ⟨Secondary sources, shared (`secondary.rs`): each member draws a point z from the table
    /// per cosine ray, and every member that sees z takes F̂′(z)·G(y_k, z)/(A(z) + N·Q(z)), A the
    /// members' cosine mixture (count density, [`Group::mixture`]) and N the group's draws⟩
    fn group_relays(
        &self,
        kernel: &KernelSampler,
        g: &Group,
        rho: &[Bands],
        out: &mut [PointEstimate],
    ) {
        if self.secondary.is_none() {
            return;
        }
        let draws = (g.c * g.members.len()) as f64;
        let alone = self.lights_alone();
        let mut weight = vec![0.0; g.members.len()];
        for a in 0..g.members.len() {
            for i in 0..g.c {
                let sobol = g.qmc(g.first_c, a, i);
                let (s3, s4) = (sobol.set(3), sobol.set(4));
                let Some((z, q)) = self.table_draw([s3[0], s3[1], s3[2]]) else {
                    continue;
                };
                let f = self.direct_radiosity(&z, &alone, [s3[3], s4[0], s4[1]]);
                if f.iter().all(|v| *v == 0.0) {
                    continue;
                }
                let at = Domain::surface_point_3d(z.p, z.n, z.face);
                let total = g.c as f64 * g.mixture(kernel.bvh, &at, None, &mut weight);
                let density = total + draws * q;
                if !(density > 0.0 && density.is_finite()) {
                    continue;
                }
                for (k, &w) in weight.iter().enumerate().filter(|(_, w)| **w > 0.0) {
                    add(out, rho, (k, i % g.replicates), f, w / density);
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::config::PathSettings;
    use crate::emitters::Emitters;
    use scene_sampler::{KernelSampler, SceneBvh, SurfaceSampler, builtin};

    /// Clusters of 8 points within 1 cm on the faces of the Cornell box (by the blocks, at the
    /// walls' corners, in shadow), grouped by [`groups`] (at most 8 a group), each gathered 32
    /// times with independent seeds, shared and alone (64 rays per point): the means agree within
    /// their standard errors at every point and band (mean z² about 1: no bias), the replicates'
    /// standard error predicts the spread of the shared runs (mean σ̂² / variance about 1), and at
    /// equal rays per point the shared runs vary less (a member casts a quarter of the cosine rays
    /// in a group of 8 but sees twice as many hits). Checked to fail when the mixture's sum leaves
    /// out the caster or the visibility of the other members.
    #[test]
    fn shared_paths_agree_with_lone_points() {
        let scene = builtin("cornell-box").unwrap().into_3d().unwrap();
        let bvh = SceneBvh::new(&scene);
        let domain = Domain::ThreeD(KernelSampler::new(&scene, &bvh));
        let emitters = Emitters::new(&domain);
        let centres = SurfaceSampler::new(&scene)
            .spread(24, |q| scene.faces[q.face as usize].emission.is_zero());
        let mut points = Vec::new();
        for (c, q) in centres.iter().enumerate() {
            let f = &scene.faces[q.face as usize];
            let e1 = (f.v[1] - f.v[0]).normalize();
            let e2 = f.normal.cross(e1);
            for j in 0..8 {
                // up to 1 cm away in the face's plane, kept on the face
                let t = (c * 8 + j) as f64;
                let (s, u) = ((t * 0.618_034) % 1.0 - 0.5, (t * 0.754_878) % 1.0 - 0.5);
                let p = f.closest_point(q.point + 0.02 * (s * e1 + u * e2));
                points.push((p, f.normal, q.face));
            }
        }
        let groups = groups(&domain, &points, 8);
        let grouped: usize = groups.iter().filter(|g| g.len() > 1).map(Vec::len).sum();
        assert!(
            grouped > points.len() / 2,
            "{grouped} of {} grouped",
            points.len()
        );
        let samples = GatherSamples {
            direct: 64,
            indirect: 64,
        };
        let gather = PathGather::new(
            &domain,
            &emitters,
            |_: DVec3, _: DVec3| [0.0; BANDS],
            samples,
            PathSettings::default(),
        );
        const RUNS: usize = 32;
        // per point and band: Σ and Σ² of the shared runs, of the lone runs, and Σσ̂² of the shared
        let mut acc = vec![[[0.0f64; 5]; BANDS]; points.len()];
        for run in 0..RUNS as u64 {
            let seed = |i: usize| (i as u64 * 7919 + 1) ^ run.wrapping_mul(0x2545_F491_4F6C_DD1D);
            for g in &groups {
                let members: Vec<_> = g.iter().map(|&i| points[i]).collect();
                let seeds: Vec<u64> = g.iter().map(|&i| seed(i)).collect();
                let materials: Vec<_> = (members.iter())
                    .map(|&(y, _, f)| (domain.reflectance_at(f, y), domain.emission(f)))
                    .collect();
                let round = (0, samples);
                let shared = gather.estimate_group(&members, &materials, &seeds, round, None);
                for (k, &i) in g.iter().enumerate() {
                    let s = shared[k].gathered();
                    let a = gather.estimate(points[i], !seed(i), 0, samples).gathered();
                    for b in 0..BANDS {
                        let (x, y) = (s.radiosity[b], a.radiosity[b]);
                        let v = &mut acc[i][b];
                        *v = [
                            v[0] + x,
                            v[1] + x * x,
                            v[2] + y,
                            v[3] + y * y,
                            v[4] + s.std_error[b].powi(2),
                        ];
                    }
                }
            }
        }
        let n = RUNS as f64;
        let (mut z2, mut count, mut var_shared, mut var_alone, mut claimed) =
            (0.0, 0.0, 0.0, 0.0, 0.0);
        for v in acc.iter().flatten() {
            let (ms, ma) = (v[0] / n, v[2] / n);
            let vs = (v[1] / n - ms * ms).max(0.0) * n / (n - 1.0);
            let va = (v[3] / n - ma * ma).max(0.0) * n / (n - 1.0);
            if vs + va == 0.0 {
                continue; // a point no light reaches
            }
            z2 += (ms - ma).powi(2) / ((vs + va) / n);
            count += 1.0;
            var_shared += vs;
            var_alone += va;
            claimed += v[4] / n;
        }
        let (z2, predicted) = (z2 / count, claimed / var_shared);
        assert!((0.6..1.6).contains(&z2), "mean z² {z2} over {count} values");
        assert!(
            (0.7..1.4).contains(&predicted),
            "mean σ̂² / variance {predicted}"
        );
        assert!(
            var_shared < var_alone,
            "variance shared {var_shared} vs alone {var_alone}"
        );
    }

    #[test]
    fn morton_interleaves() {
        assert_eq!(morton([1, 0, 0]), 1);
        assert_eq!(morton([0, 1, 0]), 2);
        assert_eq!(morton([0, 0, 1]), 4);
        assert_eq!(morton([3, 0, 0]), 0b1001);
        assert_eq!(morton([0x1f_ffff; 3]), (1u64 << 63) - 1);
    }
}
