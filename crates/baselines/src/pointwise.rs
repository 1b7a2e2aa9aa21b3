//! Pointwise path-traced radiosity (MATH.md §8): `B(y) = E(y) + ρ(y)·mean_k B(hit(y, ω_k))` with
//! cosine-weighted directions ω_k, recursively with Russian roulette. Unbiased and independent
//! of any mesh; every probe reports its standard error.

use glam::DVec3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use scene_sampler::{Scene, SceneBvh, SurfacePoint, cosine_hemisphere};

/// Radiosity estimate at one point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Estimate {
    /// Mean B per band.
    pub mean: [f64; 3],
    /// Standard error of the mean per band.
    pub std_error: [f64; 3],
    /// Paths used.
    pub paths: usize,
}

/// One path's radiosity contribution leaving `p` (emission included).
fn path(scene: &Scene, bvh: &SceneBvh, p: SurfacePoint, rng: &mut ChaCha8Rng) -> [f64; 3] {
    let mut out = [0.0; 3];
    let mut throughput = [1.0; 3];
    let mut at = p;
    for depth in 0.. {
        let f = &scene.faces[at.face as usize];
        for b in 0..3 {
            out[b] += throughput[b] * f.emission.0[b];
            throughput[b] *= f.rho.0[b];
        }
        // Russian roulette after three bounces, survival ∝ the largest throughput.
        let q = throughput.iter().cloned().fold(0.0, f64::max).min(0.95);
        if q <= 0.0 {
            break;
        }
        if depth >= 3 {
            if rng.random::<f64>() >= q {
                break;
            }
            throughput.iter_mut().for_each(|t| *t /= q);
        }
        let dir = cosine_hemisphere(at.normal, [rng.random(), rng.random()]);
        let Some(hit) = bvh.trace_from(&at, dir) else {
            break;
        };
        let next = bvh.surface_point(&hit);
        // Only the front side radiates.
        if next.normal.dot(-dir) <= 0.0 {
            break;
        }
        at = next;
    }
    out
}

/// Estimates B at each point with `paths` paths, in parallel; deterministic per `seed`
/// (each point has its own random stream, so the thread count does not matter).
pub fn radiosity_at(
    scene: &Scene,
    bvh: &SceneBvh,
    points: &[SurfacePoint],
    paths: usize,
    seed: u64,
) -> Vec<Estimate> {
    points
        .par_iter()
        .enumerate()
        .map(|(i, &p)| {
            let mut rng =
                ChaCha8Rng::seed_from_u64(seed ^ (i as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15));
            let (mut sum, mut sq) = ([0.0; 3], [0.0; 3]);
            for _ in 0..paths.max(2) {
                let v = path(scene, bvh, p, &mut rng);
                for b in 0..3 {
                    sum[b] += v[b];
                    sq[b] += v[b] * v[b];
                }
            }
            let n = paths.max(2) as f64;
            let mean = sum.map(|s| s / n);
            let std_error =
                [0, 1, 2].map(|b| ((sq[b] / n - mean[b] * mean[b]).max(0.0) / (n - 1.0)).sqrt());
            Estimate {
                mean,
                std_error,
                paths: paths.max(2),
            }
        })
        .collect()
}

/// Convenience: the point on `face` at `position`.
pub fn surface_point(scene: &Scene, face: u32, position: DVec3) -> SurfacePoint {
    SurfacePoint {
        point: position,
        normal: scene.faces[face as usize].normal,
        face,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use scene_sampler::{AnyScene, builtin};

    #[test]
    fn furnace_gives_e_over_one_minus_rho_within_the_error_bar() {
        let AnyScene::ThreeD(scene) = builtin("furnace").unwrap() else {
            panic!()
        };
        let bvh = SceneBvh::new(&scene);
        let f = &scene.faces[0];
        let (e, rho) = (f.emission.0[0], f.rho.0[0]);
        let points: Vec<SurfacePoint> = (0..4)
            .map(|i| surface_point(&scene, i * 2, scene.faces[(i * 2) as usize].centroid()))
            .collect();
        for est in radiosity_at(&scene, &bvh, &points, 4000, 5) {
            let want = e / (1.0 - rho);
            assert!(
                (est.mean[0] - want).abs() < 4.0 * est.std_error[0] + 1e-9,
                "{est:?} vs {want}"
            );
            assert!(est.std_error[0] < 0.05 * want);
        }
    }
}
