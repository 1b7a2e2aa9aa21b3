//! The ray-traced final gather (`--gather rays`), beyond the dissertation: at a point y,
//!
//! ```text
//! B(y) = E(y) + ρ(y) · [ ∫_emitters E(x) G(x,y) V(x,y) dx  +  ∫_S B_refl(x) G(x,y) V(x,y) dx ]
//! ```
//!
//! The first integral (direct light) is estimated with shadow rays to points drawn on the emitters
//! in proportion to their power (stratified), so shadows are sharp; the second (indirect light)
//! with cosine-weighted rays whose hits take the reflected radiosity B_refl from the GCR solution.
//! It is one bounce: no recursive path tracing, all indirect light comes from the networks.
//!
//! The cosine-weighted rays that hit an emitter also estimate the direct light, and the two
//! estimates are combined by multiple importance sampling with the power heuristic (Veach &
//! Guibas 1995): with `a = n_e·p_e(x)` and `b = n_c·G(x,y)`, a sample x contributes
//!
//! ```text
//! E(x)·G·a / (a² + b²)     drawn on an emitter,      E(x)·b² / (n_c·(a² + b²))     hit by a cosine ray,
//! ```
//!
//! with `p_e` the area density of the emitter sampling, `n_e`, `n_c` the sample counts, and G the
//! area density of a cosine-weighted direction (G = cos θ_x cos θ_y/(π r²); Flatland
//! cos θ_x cos θ_y/(2r)). Emitter sampling alone has unbounded weights E·G/p_e where an emitter is
//! near y (G ∝ 1/r² at the edge where an emitting wall meets the receiver): in the furnace its
//! error at area-uniform points did not fall with the sample count (7.9 %, 15 %, 3.6 %, 6.2 % at
//! 64–4096 rays). With MIS every contribution is at most E/n_c. The power heuristic, not the
//! balance heuristic: at 64 + 64 rays per point (200 points, `gather_samples`) the balance
//! heuristic gave 7.6 % on `two-blockers` against 6.1 % without MIS, the power heuristic 6.2 %;
//! furnace 1.32 / 1.44 %, `cornell-box` 9.3 / 9.4 % (balance / power).

use crate::config::GatherSamples;
use crate::domain::Domain;
use crate::element::{BANDS, Bands};
use crate::emitters::Emitters;
use glam::{DVec2, DVec3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use scene_sampler::{
    Light, Pick, PowerHeuristic, Receiver, ShadowTarget, cosine_halfplane, cosine_hemisphere,
    uniform_triangle,
};
use std::f64::consts::PI;

/// Result of a gather at one point.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Gathered {
    /// B(y) = E + ρ·(direct + indirect).
    pub radiosity: Bands,
    /// The part ρ·indirect that came from the networks.
    pub from_networks: Bands,
    /// The estimate's standard error where the gather measures it (`paths`); 0 otherwise.
    pub std_error: Bands,
    /// The paths gather's two replicates' estimates A and B as their signed half-difference
    /// (A − B)/2 (so |spread| = std_error); 0 where nothing is measured. The product of two
    /// points' spreads estimates the covariance of their values without bias (neighbours share
    /// paths): what the lightmap denoiser's error estimate needs (`lightmap/denoise.rs`).
    pub spread: Bands,
    /// Shadow rays and cosine rays (each: the larger count) per point behind the value (`rays`,
    /// `paths`); 0 for the gathers that cast none.
    pub rays: usize,
    /// Whether the paths gather's rounds were guided (`--guiding`, `estimator/guide.rs`).
    pub guided: bool,
}

/// What `--guiding auto`'s trial measured before the rounds to a target (the table of secondary
/// sources, `estimator/relay.rs`; docs/design/estimator.md, "Secondary sources"): one ray's
/// relative variance without the table and, where that was high enough to try it, the ratio of
/// the variances per ray with and without it and whether it was kept (under 0.5, or 0.1 where
/// plain paths find the light fairly well).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct GuidingTrial {
    /// One ray's relative variance without the table (the trial's squared relative error × its
    /// rays per point).
    pub variance_per_ray: f64,
    /// The variance with the table over that without it; None where the table was not tried
    /// (plain paths find the light easily, `variance_per_ray` under 0.1, or fairly well in a job
    /// too small to pay for a table).
    pub table_ratio: Option<f64>,
    /// Whether the rounds drew from the table.
    pub table_kept: bool,
}

impl Gathered {
    /// B as RGB for a domain of `bands` bands: a grey domain's one band in all three.
    pub fn rgb(&self, bands: usize) -> [f64; 3] {
        match bands {
            1 => [self.radiosity[0]; 3],
            _ => self.radiosity,
        }
    }
}

/// Gathers B at the surface point (y, n, face) of `domain`. `b_refl(x, n_x, face_x)` returns the
/// networks' reflected radiosity at a hit. Deterministic for a given `seed`.
pub fn gather(
    domain: &Domain,
    emitters: &Emitters,
    y: DVec3,
    n: DVec3,
    face: u32,
    samples: GatherSamples,
    seed: u64,
    b_refl: &impl Fn(DVec3, DVec3, u32) -> Bands,
) -> Gathered {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mis = Mis {
        emitters,
        n_e: samples.direct as f64,
        n_c: samples.indirect as f64,
    };
    let mut direct = [0.0; BANDS];
    let mut indirect = [0.0; BANDS];
    // ⟨Direct light: shadow rays to light samples, stratified over the light choice⟩
    if !emitters.is_empty() && samples.direct > 0 {
        for i in 0..samples.direct {
            let u0 = (i as f64 + rng.random::<f64>()) / samples.direct as f64;
            // (a draw may find no light for this receiver where another draw does: go on)
            let Some(pick) = emitters.lights().pick(&Receiver { p: y, n }, u0) else {
                continue;
            };
            if matches!(pick, Pick::Face(ef, _) if ef == face) {
                continue;
            }
            let u = [rng.random::<f64>(), rng.random::<f64>()];
            if let Some(d) = light_ray(domain, &mis, pick, u, (y, n, face)) {
                for b in 0..BANDS {
                    direct[b] += d[b];
                }
            }
        }
    }
    // ⟨Indirect light: cosine rays with B_refl from the networks at their hits; hits on an
    // emitter, and rays that escape to a light at infinity, are the direct light's second
    // technique⟩
    for _ in 0..samples.indirect {
        let u = [rng.random::<f64>(), rng.random::<f64>()];
        let hit = match cosine_ray(domain, &mis, (y, n, face), u) {
            Cosine::Hit(hit) => hit,
            Cosine::Escaped(d) => {
                for band in 0..BANDS {
                    direct[band] += d[band];
                }
                continue;
            }
            Cosine::Lost => continue,
        };
        let b = b_refl(hit.x, hit.nx, hit.face);
        for band in 0..BANDS {
            indirect[band] += b[band].max(0.0) / mis.n_c;
            direct[band] += hit.direct[band];
        }
    }
    // ⟨B = E + ρ·(direct + indirect)⟩
    let (rho, e) = (domain.reflectance_at(face, y), domain.emission(face));
    let mut out = Gathered {
        rays: samples.direct.max(samples.indirect),
        ..Gathered::default()
    };
    for b in 0..BANDS {
        out.from_networks[b] = rho[b] * indirect[b];
        out.radiosity[b] = e[b] + rho[b] * (direct[b] + indirect[b]);
    }
    out
}

/// The direct light per unit ρ that one shadow ray to the point `u` of emitter `ef` (drawn with
/// area density `p_e`) brings to the receiver (y, n, face), weighted by [`Mis::light_density`]
/// with `mis.n_c·q(x − y)` cosine rays toward the emitter point x (q = 1 but for a guided
/// bounce); None when they do not see each other.
fn shadow_ray(
    domain: &Domain,
    mis: &Mis,
    (ef, p_e): (u32, f64),
    u: [f64; 2],
    (y, n, face): (DVec3, DVec3, u32),
    q: impl Fn(DVec3) -> f64,
) -> Option<Bands> {
    let (x, g) = emitter_geometry(domain, ef, u, y, n, face)?;
    let guided = Mis {
        n_c: mis.n_c * q(x - y),
        ..*mis
    };
    let (w, e) = (guided.light_density(g, p_e), domain.emission(ef));
    Some(e.map(|e| w * e))
}

/// The direct light per unit ρ that one shadow ray to the light `pick` (drawn by
/// [`scene_sampler::LightSet::pick`]), at its sample `u`, brings to the receiver (y, n, face),
/// MIS-weighted; None when the light does not reach the receiver. A face is [`shadow_ray`]; any
/// other light is sampled through the [`Light`] interface ([`other_light_ray`]).
pub(crate) fn light_ray(
    domain: &Domain,
    mis: &Mis,
    pick: Pick,
    u: [f64; 2],
    receiver: (DVec3, DVec3, u32),
) -> Option<Bands> {
    light_ray_scaled(domain, mis, pick, u, receiver, |_| 1.0)
}

/// [`light_ray`] where the cosine technique's density toward the light's sample is
/// `q(direction)` times cos θ/π (a guided bounce, `estimator::guide`): the MIS weight counts
/// `mis.n_c · q` cosine rays there.
pub(crate) fn light_ray_scaled(
    domain: &Domain,
    mis: &Mis,
    pick: Pick,
    u: [f64; 2],
    receiver: (DVec3, DVec3, u32),
    q: impl Fn(DVec3) -> f64,
) -> Option<Bands> {
    match pick {
        Pick::Face(ef, density) => shadow_ray(domain, mis, (ef, density), u, receiver, q),
        Pick::Light(light, probability) => {
            other_light_ray(domain, mis, light, probability, u, receiver, q)
        }
    }
}

/// One shadow ray to a sample of `light` (drawn with `probability`): E·g/(P·p) with the power
/// heuristic against the cosine rays (none for a delta light, which no cosine ray reaches); the
/// ray goes to the sample's point, or must escape the scene toward its direction. 3-D only.
fn other_light_ray(
    domain: &Domain,
    mis: &Mis,
    light: &dyn Light,
    probability: f64,
    u: [f64; 2],
    (y, n, face): (DVec3, DVec3, u32),
    q: impl Fn(DVec3) -> f64,
) -> Option<Bands> {
    let Domain::ThreeD(k) = domain else {
        return None;
    };
    let s = light.sample(&Receiver { p: y, n }, u)?;
    let from = Domain::surface_point_3d(y, n, face);
    let seen = k.bvh.reaches(&from, &s.target);
    if !seen {
        return None;
    }
    let p = probability * s.pdf;
    let w = if light.is_delta() {
        mis.delta(s.g, p)
    } else {
        let dir = match s.target {
            ShadowTarget::Direction(d) => d,
            ShadowTarget::Point { point, .. } => point - y,
        };
        let guided = Mis {
            n_c: mis.n_c * q(dir),
            ..*mis
        };
        guided.light_density(s.g, p)
    };
    Some(s.emission.map(|e| w * e))
}

/// What a cosine ray found: the front of a surface, light at infinity (it escaped the scene), or
/// nothing (the back of a face; or it escaped where no light is).
pub(crate) enum Cosine {
    /// It hit the front of a surface.
    Hit(CosineHit),
    /// It escaped; the direct light per unit ρ the infinite lights give it, weighted by
    /// [`Mis::cosine_density`].
    Escaped(Bands),
    /// It hit the back of a face.
    Lost,
}

/// The front of the surface a cosine ray hit, and the direct light per unit ρ it carries when it
/// is an emitter (weighted by [`Mis::cosine`]).
pub(crate) struct CosineHit {
    pub(crate) x: DVec3,
    pub(crate) nx: DVec3,
    pub(crate) face: u32,
    pub(crate) direct: Bands,
}

/// One cosine-weighted ray from the receiver (y, n, face) drawn with `u`: a hit on the front of a
/// face (only the front side radiates), or the light at infinity where it leaves the scene.
pub(crate) fn cosine_ray(
    domain: &Domain,
    mis: &Mis,
    (y, n, face): (DVec3, DVec3, u32),
    u: [f64; 2],
) -> Cosine {
    let (x, nx, fx) = match trace_cosine(domain, y, n, face, u) {
        Ok(hit) => hit,
        Err(dir) => {
            let at = Receiver { p: y, n };
            let lights = mis.emitters.lights();
            if !lights.has_infinite() {
                return Cosine::Lost;
            }
            return Cosine::Escaped(lights.escaped(&at, dir, |g, p| mis.cosine_density(g, p)));
        }
    };
    let d = y - x;
    let cx = nx.dot(d);
    if cx <= 0.0 {
        return Cosine::Lost;
    }
    let e = domain.emission(fx);
    let mut direct = [0.0; BANDS];
    if e.iter().any(|v| *v != 0.0) {
        let w = mis.cosine(
            geometry(domain, cx, -n.dot(d), d),
            &Receiver { p: y, n },
            fx,
        );
        if w > 0.0 {
            direct = e.map(|e| w * e);
        }
    }
    Cosine::Hit(CosineHit {
        x,
        nx,
        face: fx,
        direct,
    })
}

/// The power heuristic of the two direct-light techniques (module docs) at n_e emitter and n_c
/// cosine samples per point, [`PowerHeuristic`] with the emitter table's density of a face.
pub(crate) struct Mis<'a> {
    pub(crate) emitters: &'a Emitters,
    pub(crate) n_e: f64,
    pub(crate) n_c: f64,
}

impl Mis<'_> {
    /// The emitter technique's area density p_e at a point of `face` for the receiver `at` (0
    /// without emitters).
    fn p_e(&self, at: &Receiver, face: u32) -> f64 {
        if self.emitters.is_empty() {
            0.0
        } else {
            self.emitters.lights().face_density(at, face)
        }
    }

    fn heuristic(&self) -> PowerHeuristic {
        PowerHeuristic {
            light_samples: self.n_e,
            cosine_samples: self.n_c,
        }
    }

    /// Weight per unit emission of an emitter point hit by a cosine ray
    /// ([`PowerHeuristic::cosine`]; 1/n_c where g is infinite at an edge).
    pub(crate) fn cosine(&self, g: f64, at: &Receiver, face: u32) -> f64 {
        self.heuristic().cosine(g, self.p_e(at, face))
    }

    /// The weight per unit emission of a light sample ([`PowerHeuristic::light`]) with cosine
    /// density `g` and light density `p` in the light's own measure
    /// ([`scene_sampler::LightSample`]; an emitting face's area density from its pick).
    pub(crate) fn light_density(&self, g: f64, p: f64) -> f64 {
        self.heuristic().light(g, p)
    }

    /// [`Mis::cosine`] for a cosine ray with density `g` that reached a light whose own density
    /// there is `p` (0: a light that light sampling never draws there: full weight 1/n_c).
    pub(crate) fn cosine_density(&self, g: f64, p: f64) -> f64 {
        self.heuristic().cosine(g, p)
    }

    /// The weight of a delta light's sample (no cosine ray reaches it): g/(n_e·p).
    pub(crate) fn delta(&self, g: f64, p: f64) -> f64 {
        PowerHeuristic {
            light_samples: self.n_e,
            cosine_samples: 0.0,
        }
        .light(g, p)
    }
}

/// The point-to-point geometry term for cosines `cx`, `cy` and offset `d` = y − x: cos θx cos θy /
/// (π r²) in 3-D, cos θx cos θy / (2r) in Flatland (the cosines are unnormalised: d's length
/// divides out).
fn geometry(domain: &Domain, cx: f64, cy: f64, d: DVec3) -> f64 {
    match domain {
        Domain::ThreeD(_) => cx * cy / (PI * d.length_squared().powi(2)),
        Domain::Flat(_) => cx * cy / (2.0 * d.length().powi(3)),
    }
}

/// G(y, x) = cos θ_y cos θ_x/(π r²) of the receiver (y, n) and the surface point (x, n_x), 0
/// unless they face each other ([`scene_sampler::lights::geometry`]).
pub(crate) use scene_sampler::lights::geometry as geometry_3d;

/// An area-uniform point x on emitter `ef` at `u` ∈ [0,1)² (3-D: barycentrics (1 − √u1,
/// √u1(1 − u2), √u1·u2); Flatland: arc length u1, embedded at z = 0) and G(x, y), when x and the
/// receiver (y, n, face) face each other and see each other; None otherwise.
pub(crate) fn emitter_geometry(
    domain: &Domain,
    ef: u32,
    u: [f64; 2],
    y: DVec3,
    n: DVec3,
    face: u32,
) -> Option<(DVec3, f64)> {
    match domain {
        Domain::ThreeD(k) => {
            let f = &k.scene.faces[ef as usize];
            let [b1, b2] = uniform_triangle(u);
            let x = f.point(b1, b2);
            let g = geometry_3d(y, n, x, f.normal);
            if g == 0.0 {
                return None;
            }
            let xp = Domain::surface_point_3d(x, f.normal, ef);
            let yp = Domain::surface_point_3d(y, n, face);
            k.bvh.visible(&xp, &yp).then_some((x, g))
        }
        Domain::Flat(k) => {
            let s = &k.scene.segments[ef as usize];
            let x2 = s.point(u[0]);
            let d = DVec2::new(y.x, y.y) - x2;
            let r = d.length();
            let (cx, cy) = (s.normal.dot(d), -DVec2::new(n.x, n.y).dot(d));
            if cx <= 0.0 || cy <= 0.0 || r == 0.0 {
                return None;
            }
            let xp = Domain::flat_point(
                DVec3::new(x2.x, x2.y, 0.0),
                DVec3::new(s.normal.x, s.normal.y, 0.0),
                ef,
            );
            let yp = Domain::flat_point(y, n, face);
            (k.vis.visible(&xp, &yp))
                .then(|| (DVec3::new(x2.x, x2.y, 0.0), cx * cy / (2.0 * r * r * r)))
        }
    }
}

/// The first surface point (x, n_x, face_x) along a cosine-weighted direction from (y, n, face)
/// drawn with `u` (3-D: about the hemisphere; Flatland: the half-plane, from u[0]); `Err` with the
/// direction (3-D; zero in Flatland) when the ray leaves the scene.
fn trace_cosine(
    domain: &Domain,
    y: DVec3,
    n: DVec3,
    face: u32,
    u: [f64; 2],
) -> Result<(DVec3, DVec3, u32), DVec3> {
    match domain {
        Domain::ThreeD(k) => {
            let dir = cosine_hemisphere(n, u);
            let from = Domain::surface_point_3d(y, n, face);
            let h = k.bvh.trace_from(&from, dir).ok_or(dir)?;
            let p = k.bvh.surface_point(&h);
            Ok((p.point, p.normal, p.face))
        }
        Domain::Flat(k) => {
            let dir = cosine_halfplane(DVec2::new(n.x, n.y), u[0]);
            let from = Domain::flat_point(y, n, face);
            let h = k.vis.trace_from(&from, dir).ok_or(DVec3::ZERO)?;
            let p = k.vis.surface_point(&h);
            Ok((
                DVec3::new(p.point.x, p.point.y, 0.0),
                DVec3::new(p.normal.x, p.normal.y, 0.0),
                p.segment,
            ))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use scene_sampler::{AnyScene, FlatKernelSampler, KernelSampler, SceneBvh, builtin};

    /// A light rectangle a×b at height c over a floor corner (docs/design/math.md §8), the floor point at the
    /// rectangle's corner.
    fn parallel_rectangle() -> (Domain<'static>, f64) {
        use scene_sampler::{Face, Scene, Spectrum};
        let (a, b, c) = (1.0, 2.0, 1.5);
        let light = [
            DVec3::new(0.0, c, 0.0),
            DVec3::new(a, c, b),
            DVec3::new(0.0, c, b),
        ];
        let light2 = [
            DVec3::new(0.0, c, 0.0),
            DVec3::new(a, c, 0.0),
            DVec3::new(a, c, b),
        ];
        let floor = [
            DVec3::new(-3.0, 0.0, -3.0),
            DVec3::new(-3.0, 0.0, 3.0),
            DVec3::new(3.0, 0.0, 3.0),
        ];
        let e = Spectrum::grey(PI);
        let faces = vec![
            Face::new(light, Spectrum::ZERO, e, 0, 0),
            Face::new(light2, Spectrum::ZERO, e, 0, 0),
            Face::new(floor, Spectrum::grey(0.5), Spectrum::ZERO, 1, 1),
        ];
        let scene = Scene::new("pr", "test", faces, vec!["l".into(), "f".into()], None).unwrap();
        assert!(scene.faces[0].normal.y < 0.0, "light faces down");
        let scene: &'static Scene = Box::leak(Box::new(scene));
        let bvh: &'static SceneBvh = Box::leak(Box::new(SceneBvh::new(scene)));
        let (x, y) = (a / c, b / c);
        let f = 1.0 / (2.0 * PI)
            * (x / (1.0 + x * x).sqrt() * (y / (1.0 + x * x).sqrt()).atan()
                + y / (1.0 + y * y).sqrt() * (x / (1.0 + y * y).sqrt()).atan());
        // B = ρ·E·F with ρ = 0.5 and E = π.
        (Domain::ThreeD(KernelSampler::new(scene, bvh)), 0.5 * PI * f)
    }

    /// The parallel-rectangle configuration factor: the direct gather with zero indirect light
    /// must reproduce ρ·E·F, by emitter sampling alone and by both techniques with their MIS
    /// weights (mostly by cosine rays when those outnumber the shadow rays).
    #[test]
    fn direct_light_matches_the_analytic_configuration_factor() {
        let (d, want) = parallel_rectangle();
        let em = Emitters::new(&d);
        for (direct, indirect) in [(20000, 0), (2000, 20000), (200, 40000)] {
            let g = gather(
                &d,
                &em,
                DVec3::ZERO,
                DVec3::Y,
                2,
                GatherSamples { direct, indirect },
                7,
                &|_, _, _| [0.0; 3],
            );
            assert!(
                (g.radiosity[0] - want).abs() < 0.01 * want,
                "{direct} + {indirect} rays: {} vs {want}",
                g.radiosity[0]
            );
            assert_eq!(g.from_networks, [0.0; 3]);
        }
    }

    /// Next to an emitting wall (the furnace's edges) emitter sampling alone has unbounded weights
    /// E·G/p_e; with MIS every contribution is at most E/n_c, so the direct estimate is at most
    /// (n_e + n_c)/n_c·E whatever the seed.
    #[test]
    fn mis_bounds_the_direct_light_next_to_an_emitting_wall() {
        let AnyScene::ThreeD(scene) = builtin("furnace").unwrap() else {
            panic!()
        };
        let bvh = SceneBvh::new(&scene);
        let d = Domain::ThreeD(KernelSampler::new(&scene, &bvh));
        let em = Emitters::new(&d);
        let f = &scene.faces[0];
        // A point of face 0 a hair away from its first edge.
        let y = f.point(1e-7, 0.5);
        let samples = GatherSamples {
            direct: 16,
            indirect: 16,
        };
        let (e, rho) = (f.emission.0[0], f.rho.0[0]);
        for seed in 0..200 {
            let g = gather(&d, &em, y, f.normal, 0, samples, seed, &|_, _, _| [0.0; 3]);
            let direct = (g.radiosity[0] - e) / rho;
            assert!(
                direct.is_finite() && (0.0..=2.0 * e + 1e-12).contains(&direct),
                "seed {seed}: direct light {direct}"
            );
        }
    }

    #[test]
    fn indirect_light_of_a_unit_field_is_positive_and_at_most_rho() {
        let AnyScene::Flatland(scene) = builtin("flatland-corner").unwrap() else {
            panic!()
        };
        let d = Domain::Flat(FlatKernelSampler::new(&scene));
        let em = Emitters::new(&d);
        assert!(!em.is_empty());
        // A floor point: every indirect ray that hits a front face returns 1.
        let seg = scene
            .segments
            .iter()
            .position(|s| s.normal.y > 0.9)
            .unwrap() as u32;
        let s = &scene.segments[seg as usize];
        let p = s.point(0.5);
        let g = gather(
            &d,
            &em,
            DVec3::new(p.x, p.y, 0.0),
            DVec3::new(s.normal.x, s.normal.y, 0.0),
            seg,
            GatherSamples {
                direct: 0,
                indirect: 4000,
            },
            3,
            &|_, _, _| [1.0; 3],
        );
        assert!(g.from_networks[0] > 0.0 && g.from_networks[0] <= s.rho.0[0] + 1e-12);
        // Without shadow rays the cosine rays that hit the emitting wall carry the direct light
        // alone (MIS weight 1/n_c): B gains it on top of the networks' part.
        assert!(g.radiosity[0] > s.emission.0[0] + g.from_networks[0]);
    }
}
