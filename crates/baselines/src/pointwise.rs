//! Pointwise path-traced radiosity (MATH.md §8): `B(y) = E(y) + ρ(y)·mean_k B(hit(y, ω_k))` with
//! cosine-weighted directions ω_k, recursively with Russian roulette. Unbiased and independent
//! of any mesh; every probe reports its standard error.

use crate::error::BaselineError;
use crate::stats::{point_rng, run_fixed};
use glam::DVec3;
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use scene_sampler::{Scene, SceneBvh, SurfacePoint, cosine_hemisphere};

pub use crate::stats::{Adaptive, Estimate};

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

/// Estimates B at each point with `paths` paths (at least 2), in parallel; deterministic per `seed`
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
            let mut rng = point_rng(seed, i);
            run_fixed(paths, || path(scene, bvh, p, &mut rng))
        })
        .collect()
}

/// Adaptive mode: per point, batches of paths until the relative standard error of every band with a positive
/// mean is at most `adaptive.rel_error`, or `adaptive.max_paths` (see [`Adaptive`]). Parallel over points,
/// deterministic per seed. The first `k·batch` paths of a point are exactly those [`radiosity_at`] traces with
/// `k·batch` paths and the same seed.
///
/// # Errors
/// Invalid [`Adaptive`] parameters, or a point whose face index is not in the scene.
pub fn radiosity_adaptive(
    scene: &Scene,
    bvh: &SceneBvh,
    points: &[SurfacePoint],
    adaptive: &Adaptive,
) -> Result<Vec<Estimate>, BaselineError> {
    adaptive.validate()?;
    check_faces(scene, points)?;
    Ok(points
        .par_iter()
        .enumerate()
        .map(|(i, &p)| {
            let mut rng = point_rng(adaptive.seed, i);
            adaptive.run(|| path(scene, bvh, p, &mut rng))
        })
        .collect())
}

/// Error unless every point's face exists.
fn check_faces(scene: &Scene, points: &[SurfacePoint]) -> Result<(), BaselineError> {
    for (index, p) in points.iter().enumerate() {
        if p.face as usize >= scene.faces.len() {
            return Err(BaselineError::NoSuchElement {
                index,
                what: "face",
                id: p.face,
                count: scene.faces.len(),
            });
        }
    }
    Ok(())
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

    #[test]
    fn adaptive_reaches_the_target_and_is_deterministic() {
        let AnyScene::ThreeD(scene) = builtin("cornell-box").unwrap() else {
            panic!()
        };
        let bvh = SceneBvh::new(&scene);
        let floor = scene
            .faces
            .iter()
            .position(|f| f.normal.y > 0.9 && f.centroid().y < 0.01)
            .unwrap() as u32;
        let p = surface_point(&scene, floor, scene.faces[floor as usize].centroid());
        let a = Adaptive {
            rel_error: 0.03,
            batch: 200,
            max_paths: 200_000,
            seed: 3,
        };
        let e = radiosity_adaptive(&scene, &bvh, &[p, p], &a).unwrap();
        assert!(e[0].rel_error() <= 0.03, "{:?}", e[0]);
        assert!(e[0].paths < 200_000 && e[0].paths % 200 == 0);
        // same seed, same numbers; the fixed-count mode with as many paths agrees bit for bit
        let again = radiosity_adaptive(&scene, &bvh, &[p], &a).unwrap();
        assert_eq!(e[0], again[0]);
        let fixed = radiosity_at(&scene, &bvh, &[p], e[0].paths, 3);
        assert_eq!(fixed[0], e[0]);
        // a bad face index is an error, not a panic
        let bad = SurfacePoint { face: 9999, ..p };
        assert!(radiosity_adaptive(&scene, &bvh, &[bad], &a).is_err());
        assert!(radiosity_adaptive(&scene, &bvh, &[p], &Adaptive { batch: 0, ..a }).is_err());
    }
}
