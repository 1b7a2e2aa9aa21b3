//! Importance-sampled rays for the projected output layer (beyond the dissertation).
//!
//! The dissertation draws rays (x, y) area-uniformly on S × S (fig. B.2). The pair density is then
//! 1/A², and a single sample of the kernel `K(x,y)·s(x)` can be arbitrarily large near the edges
//! where two surfaces meet (`K ~ 1/r²`, docs/design/math.md §6): on `cornell-box`, 1 % of the samples carry
//! 96 % of the sum of squared targets. This module *shoots* rays instead:
//!
//! 1. x is drawn from the sender density `p_x = α/A + (1 − α)·[x on an emitter]/A_E`
//!    (half of the senders on the emitters, half anywhere, when the scene has emitters);
//! 2. a direction is drawn cosine-weighted about the normal at x (3-D: `cos θ/π` per steradian,
//!    Flatland: `cos θ/2` per radian);
//! 3. y is the first surface hit.
//!
//! The pair density becomes `p(x,y) = p_x(x) · G(x,y) · V(x,y)` with the point-to-point geometry
//! term `G = cos θx cos θy /(π r²)` (Flatland `cos θx cos θy /(2r)`), which is exactly the factor of
//! the kernel `K = ρ(y)·G·V` that is unbounded. So the importance weight of a sample,
//!
//! ```text
//! K(x,y)·s(x) / p(x,y) = ρ(y) · s(x) / p_x(x),
//! ```
//!
//! is bounded: the Monte-Carlo estimates of `∫∫ g_o(x,y) K(x,y) s(x) dx dy` that the projection
//! needs (see [`crate::projection`]) have finite, small variance, and no clamp of `r` is involved.

use crate::domain::{Domain, Endpoints, Ray};
use crate::emitters::Emitters;
use glam::DVec2;
use rand::Rng;
use scene_sampler::{
    FlatPoint, SurfacePoint, cosine_halfplane, cosine_hemisphere, uniform_triangle,
};

/// A shot ray with its sender density.
#[derive(Clone, Copy, Debug)]
pub struct Shot {
    /// The ray; its kernel is evaluated as for any other sample.
    pub ray: Ray,
    /// `1 / p_x(x)`: the sample's importance weight is `ρ(y)·s(x)/p_x(x)`.
    pub inv_px: f64,
}

/// The sender density `p_x` (module docs) over the scene's emitter table.
#[derive(Clone, Debug)]
pub struct SenderDensity {
    /// Share of the senders drawn area-uniformly over all of S.
    pub alpha: f64,
    total: f64,
    emitters: Emitters,
}

impl SenderDensity {
    /// The default density: α = 1/2 when the scene has emitters, α = 1 otherwise.
    pub fn new(domain: &Domain) -> Self {
        let emitters = Emitters::new(domain);
        Self {
            alpha: if emitters.table().is_empty() {
                1.0
            } else {
                0.5
            },
            total: domain.total_measure(),
            emitters,
        }
    }

    /// `p_x` on face (segment) `face`, per unit area (length).
    pub fn pdf(&self, face: u32) -> f64 {
        let mut p = self.alpha / self.total;
        if self.emitters.table().emits(face) {
            p += (1.0 - self.alpha) / self.emitters.table().area();
        }
        p
    }

    /// Shoots one ray (module docs). `None` when it leaves the scene (open scenes): such a ray
    /// still counts in the number of shots that normalizes the Monte-Carlo sums.
    pub fn shoot(&self, domain: &Domain, rng: &mut impl Rng) -> Option<Shot> {
        let on_emitter = rng.random::<f64>() >= self.alpha;
        let u: [f64; 4] = [rng.random(), rng.random(), rng.random(), rng.random()];
        // α < 1 only when the scene has emitters, so an emitter is there to pick.
        let emitter = |u0| {
            on_emitter
                .then(|| self.emitters.table().pick_by_area(u0))
                .flatten()
        };
        let ends = match domain {
            Domain::ThreeD(k) => {
                let x = if let Some(face) = emitter(u[0]) {
                    let f = &k.scene.faces[face as usize];
                    let [b1, b2] = uniform_triangle([u[1], u[2]]);
                    SurfacePoint {
                        point: f.point(b1, b2),
                        normal: f.normal,
                        face,
                    }
                } else {
                    k.sampler.sample([u[1], u[2]])
                };
                let dir = cosine_hemisphere(x.normal, [u[3], rng.random()]);
                let hit = k.bvh.trace_from(&x, dir)?;
                Endpoints::ThreeD(x, k.bvh.surface_point(&hit))
            }
            Domain::Flat(k) => {
                let x = if let Some(seg) = emitter(u[0]) {
                    let s = &k.scene.segments[seg as usize];
                    FlatPoint {
                        point: s.point(u[1]),
                        normal: s.normal,
                        segment: seg,
                    }
                } else {
                    k.sampler.sample(u[1])
                };
                let dir: DVec2 = cosine_halfplane(x.normal, u[2]);
                let hit = k.vis.trace_from(&x, dir)?;
                Endpoints::Flat(x, k.vis.surface_point(&hit))
            }
        };
        let ray = domain.evaluate(&ends);
        Some(Shot {
            inv_px: 1.0 / self.pdf(ray.face_x),
            ray,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;
    use scene_sampler::{AnyScene, FlatKernelSampler, KernelSampler, SceneBvh, builtin};

    /// ∫∫ K(x,y)·s(x) dx dy with s = E, estimated two ways: by shooting (importance weights
    /// ρ(y)E(x)/p_x) and by area-uniform pairs (A²·K·E); the two must agree. The exact value is
    /// Σ_emitters ρ-weighted power, i.e. for a closed box with one ρ per receiver it is bounded by
    /// max ρ · ∫E; we check against the uniform estimator with its standard error.
    #[test]
    fn shooting_and_uniform_pairs_estimate_the_same_transport() {
        let AnyScene::ThreeD(scene) = builtin("cornell-box").unwrap() else {
            panic!()
        };
        let bvh = SceneBvh::new(&scene);
        let domain = Domain::ThreeD(KernelSampler::new(&scene, &bvh));
        let density = SenderDensity::new(&domain);
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let n = 200_000;
        let mut shot = 0.0;
        for _ in 0..n {
            if let Some(s) = density.shoot(&domain, &mut rng) {
                if s.ray.kernel[0] > 0.0 {
                    shot += domain.reflectance_at(s.ray.face_y, s.ray.y)[0]
                        * s.ray.emission_x[0]
                        * s.inv_px;
                }
            }
        }
        shot /= n as f64;
        // Exact for a closed scene: every shot ray lands, so the transport of E is
        // Σ_x-faces E·A·(area-weighted mean ρ seen from x); bound it by ρ's range and compare
        // with the uniform-pair estimator below.
        let a = domain.total_measure();
        let (mut sum, mut sq) = (0.0, 0.0);
        let m = 400_000;
        for _ in 0..m {
            let u: [f64; 4] = [rng.random(), rng.random(), rng.random(), rng.random()];
            let r = domain.ray(&u);
            let v = a * a * r.kernel[0] * r.emission_x[0];
            sum += v;
            sq += v * v;
        }
        let mean = sum / m as f64;
        let se = ((sq / m as f64 - mean * mean) / m as f64).sqrt();
        assert!(
            (shot - mean).abs() < 4.0 * se + 0.01 * mean,
            "shooting {shot} vs uniform {mean} ± {se}"
        );
    }

    #[test]
    fn flatland_shots_land_and_weights_are_bounded() {
        let AnyScene::Flatland(scene) = builtin("flatland-blocker").unwrap() else {
            panic!()
        };
        let domain = Domain::Flat(FlatKernelSampler::new(&scene));
        let density = SenderDensity::new(&domain);
        assert!(density.alpha < 1.0, "the scene has an emitter");
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let bound = 1.0 / (density.alpha / domain.total_measure());
        let mut landed = 0;
        for _ in 0..2000 {
            if let Some(s) = density.shoot(&domain, &mut rng) {
                landed += 1;
                assert!(s.inv_px > 0.0 && s.inv_px <= bound * (1.0 + 1e-12));
                assert_eq!(s.ray.x.z, 0.0);
            }
        }
        assert!(landed > 100);
    }
}
