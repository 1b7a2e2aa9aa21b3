//! Flatland references (docs/design/math.md §7): a pointwise path tracer ([`path_trace_at`], [`path_trace_adaptive`]) and
//! the converged fine-mesh solver with exact form factors ([`ExactSolver`]).
//!
//! The Flatland radiosity equation is `B(y) = E(y) + ρ(y) ∫ cos θx cos θy / (2 r) · V(x,y) · B(x) dx`
//! (eq. 1.4 with the 2-D kernel of docs/design/math.md §7). Sampling directions at `y` with density `cos θ / 2` per radian
//! ([`cosine_halfplane`]) cancels the kernel exactly, as in 3-D: `B(y) = E(y) + ρ(y)·E_ω[B(hit(y, ω))]`.
//! As in 3-D, every path vertex also sends a shadow ray to the emitters (next-event estimation, combined with
//! the cosine continuation's hits by the power heuristic).

use crate::error::BaselineError;
use crate::stats::{Adaptive, AdaptiveEstimate, Estimate, point_rng, run_fixed, survives_roulette};
use glam::DVec2;
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use scene_sampler::{
    EmitterTable, FlatPoint, FlatVisibility, FlatlandScene, PowerHeuristic, cosine_halfplane,
};

mod exact;
pub use exact::{ExactOptions, ExactSolver, crossed_strings, point_to_segment};

/// The length density of a cosine-weighted direction (density `cos θ / 2` per radian) from `y` (normal `ny`)
/// at the point `x` (normal `nx`): `G = cos θx cos θy / (2 r)`, 0 when they do not face each other.
fn geometry(y: DVec2, ny: DVec2, x: DVec2, nx: DVec2) -> f64 {
    let d = y - x;
    let (cx, cy) = (nx.dot(d), -ny.dot(d));
    if cx <= 0.0 || cy <= 0.0 {
        return 0.0;
    }
    cx * cy / (2.0 * d.length().powi(3))
}

/// One Flatland path's radiosity contribution leaving `p` (emission included): the estimator of docs/design/math.md §8
/// with next-event estimation and MIS as in 3-D (`crate::pointwise`): at every vertex a shadow ray to a point
/// drawn on the emitting segments (segment ∝ power, point uniform) and the cosine continuation, the two
/// weighted by the power heuristic; Russian roulette after three bounces (survival ∝ the largest
/// throughput, so no weight exceeds 1).
fn path(
    scene: &FlatlandScene,
    vis: &FlatVisibility,
    lights: &EmitterTable,
    p: FlatPoint,
    rng: &mut ChaCha8Rng,
) -> [f64; 3] {
    let mut out = scene.segments[p.segment as usize].emission.0;
    let mut throughput = [1.0; 3];
    let mut at = p;
    for depth in 0.. {
        let s = &scene.segments[at.segment as usize];
        for (t, r) in throughput.iter_mut().zip(s.rho.0) {
            *t *= r;
        }
        if !survives_roulette(&mut throughput, depth, rng) {
            break;
        }
        // ⟨next-event estimation: one shadow ray⟩
        let (u0, u1) = (rng.random::<f64>(), rng.random::<f64>());
        if !lights.is_empty() {
            let (ef, p_e) = lights
                .pick_by_power(u0)
                .map(|f| (f, lights.power_density(f)))
                .expect("a table with emitters");
            let e = &scene.segments[ef as usize];
            if ef != at.segment {
                let x = e.point(u1);
                let g = geometry(at.point, at.normal, x, e.normal);
                if g > 0.0 {
                    let xp = FlatPoint {
                        point: x,
                        normal: e.normal,
                        segment: ef,
                    };
                    if vis.visible(&xp, &at) {
                        let w = PowerHeuristic::ONE_EACH.light(g, p_e);
                        for b in 0..3 {
                            out[b] += throughput[b] * w * e.emission.0[b];
                        }
                    }
                }
            }
        }
        // ⟨the cosine continuation; emission at its hit is the second technique⟩
        let dir = cosine_halfplane(at.normal, rng.random());
        let Some(hit) = vis.trace_from(&at, dir) else {
            break;
        };
        let next = vis.surface_point(&hit);
        // only the front side radiates
        if next.normal.dot(-dir) <= 0.0 {
            break;
        }
        let ns = &scene.segments[next.segment as usize];
        if !ns.emission.is_zero() {
            let w = PowerHeuristic::ONE_EACH.cosine(
                geometry(at.point, at.normal, next.point, next.normal),
                lights.power_density(next.segment),
            );
            for b in 0..3 {
                out[b] += throughput[b] * w * ns.emission.0[b];
            }
        }
        at = next;
    }
    out
}

/// The random stream of point `p`: keyed by its position and normal (see `stats::point_rng`).
fn rng_of(seed: u64, p: &FlatPoint) -> ChaCha8Rng {
    point_rng(seed, &[p.point.x, p.point.y, p.normal.x, p.normal.y])
}

/// The bands in which B can be positive at a point on segment `segment` (as
/// [`crate::pointwise::live_bands`]).
pub fn live_bands(scene: &FlatlandScene, segment: u32) -> [bool; 3] {
    let s = &scene.segments[segment as usize];
    [0, 1, 2].map(|b| {
        s.emission.0[b] > 0.0
            || (s.rho.0[b] > 0.0 && scene.segments.iter().any(|g| g.emission.0[b] > 0.0))
    })
}

/// Error unless every point's segment exists.
fn check_segments(scene: &FlatlandScene, points: &[FlatPoint]) -> Result<(), BaselineError> {
    for (index, p) in points.iter().enumerate() {
        if p.segment as usize >= scene.segments.len() {
            return Err(BaselineError::NoSuchElement {
                index,
                what: "segment",
                id: p.segment,
                count: scene.segments.len(),
            });
        }
    }
    Ok(())
}

/// Pointwise path-traced B at Flatland points with `paths` paths each (at least 2), in parallel, deterministic
/// per `seed` whatever the thread count (every point has its own random stream). Grey scenes carry the same
/// value in all three bands.
///
/// # Errors
/// A point whose segment index is not in the scene.
pub fn path_trace_at(
    scene: &FlatlandScene,
    vis: &FlatVisibility,
    points: &[FlatPoint],
    paths: usize,
    seed: u64,
) -> Result<Vec<Estimate>, BaselineError> {
    check_segments(scene, points)?;
    let lights = EmitterTable::of_flatland(scene);
    Ok(points
        .par_iter()
        .map(|&p| {
            let mut rng = rng_of(seed, &p);
            run_fixed(paths, || path(scene, vis, &lights, p, &mut rng))
        })
        .collect())
}

/// Adaptive Flatland path tracing: batches per point until the relative standard error target (by the
/// stopping rule of [`Adaptive`], which never stops on a zero mean) or the path cap of `adaptive`; the first
/// `k·batch` paths equal those of [`path_trace_at`] with the same seed. [`reference_at`] also gives each
/// point's verdict.
///
/// # Errors
/// Invalid [`Adaptive`] parameters, or a point whose segment index is not in the scene.
pub fn path_trace_adaptive(
    scene: &FlatlandScene,
    vis: &FlatVisibility,
    points: &[FlatPoint],
    adaptive: &Adaptive,
) -> Result<Vec<Estimate>, BaselineError> {
    Ok(reference_at(scene, vis, points, adaptive)?
        .into_iter()
        .map(|a| a.estimate)
        .collect())
}

/// [`path_trace_adaptive`] with each point's bound on its relative standard error and whether it met the
/// target (see [`AdaptiveEstimate`]).
///
/// # Errors
/// Invalid [`Adaptive`] parameters, or a point whose segment index is not in the scene.
pub fn reference_at(
    scene: &FlatlandScene,
    vis: &FlatVisibility,
    points: &[FlatPoint],
    adaptive: &Adaptive,
) -> Result<Vec<AdaptiveEstimate>, BaselineError> {
    adaptive.validate()?;
    check_segments(scene, points)?;
    let lights = EmitterTable::of_flatland(scene);
    Ok(points
        .par_iter()
        .map(|&p| {
            let mut rng = rng_of(adaptive.seed, &p);
            adaptive.run(live_bands(scene, p.segment), || {
                path(scene, vis, &lights, p, &mut rng)
            })
        })
        .collect())
}

/// The point at fraction `t` along segment `segment` (a convenience for building probe lists).
pub fn point_on(scene: &FlatlandScene, segment: u32, t: f64) -> FlatPoint {
    let s = &scene.segments[segment as usize];
    FlatPoint {
        point: s.point(t),
        normal: s.normal,
        segment,
    }
}

/// A closed Flatland box (unit square, normals inward, counter-clockwise), every wall with emission `e` and
/// reflectance `rho`, each wall split into `split` segments: the Flatland furnace, `B = E/(1 − ρ)` (docs/design/math.md §8).
/// For tests and examples.
///
/// # Errors
/// `rho` outside `[0,1)`, negative `e` (from [`FlatlandScene::new`]), or `split == 0`.
pub fn flat_furnace(e: f64, rho: f64, split: usize) -> Result<FlatlandScene, BaselineError> {
    use scene_sampler::{Segment, Spectrum};
    if split == 0 {
        return Err(BaselineError::InvalidParameter {
            name: "split",
            value: 0.0,
            expected: "at least one segment per wall",
        });
    }
    let corners = [
        DVec2::new(0.0, 0.0),
        DVec2::new(1.0, 0.0),
        DVec2::new(1.0, 1.0),
        DVec2::new(0.0, 1.0),
    ];
    let mut segs = Vec::new();
    for k in 0..4 {
        let (a, b) = (corners[k], corners[(k + 1) % 4]);
        for s in 0..split {
            let (t0, t1) = (s as f64 / split as f64, (s + 1) as f64 / split as f64);
            segs.push(Segment::new(
                a.lerp(b, t0),
                a.lerp(b, t1),
                Spectrum::grey(rho),
                Spectrum::grey(e),
                0,
                k as u32,
            ));
        }
    }
    FlatlandScene::new(
        "flat-furnace",
        "flat_furnace()",
        segs,
        vec!["box".into()],
        None,
        false,
    )
    .map_err(|_| BaselineError::InvalidParameter {
        name: "rho/e",
        value: rho,
        expected: "0 <= rho < 1 and e > 0",
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use scene_sampler::{AnyScene, builtin};

    #[test]
    fn flatland_furnace_gives_e_over_one_minus_rho() {
        let scene = flat_furnace(1.0, 0.5, 2).unwrap();
        let vis = FlatVisibility::new(&scene);
        let pts: Vec<FlatPoint> = (0..8)
            .map(|k| point_on(&scene, k, 0.1 + 0.1 * k as f64))
            .collect();
        for e in path_trace_at(&scene, &vis, &pts, 4000, 11).unwrap() {
            assert!(
                (e.mean[0] - 2.0).abs() < 4.0 * e.std_error[0] + 1e-12,
                "{e:?}"
            );
            assert!(e.std_error[0] < 0.03 * 2.0);
        }
    }

    #[test]
    fn flatland_deterministic_and_independent_of_threads() {
        let AnyScene::Flatland(scene) = builtin("flatland-blocker").unwrap() else {
            panic!()
        };
        let vis = FlatVisibility::new(&scene);
        let pts: Vec<FlatPoint> = (0..6)
            .map(|k| point_on(&scene, 3, 0.05 + 0.15 * k as f64))
            .collect();
        let a = path_trace_at(&scene, &vis, &pts, 500, 4).unwrap();
        let one = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap();
        let b = one.install(|| path_trace_at(&scene, &vis, &pts, 500, 4).unwrap());
        assert_eq!(a, b);
        let c = path_trace_at(&scene, &vis, &pts, 500, 5).unwrap();
        assert_ne!(a, c);
    }

    #[test]
    fn flatland_adaptive_reaches_the_target() {
        let AnyScene::Flatland(scene) = builtin("flatland-corner").unwrap() else {
            panic!()
        };
        let vis = FlatVisibility::new(&scene);
        let pts = [point_on(&scene, 1, 0.3), point_on(&scene, 0, 0.5)];
        let ad = Adaptive {
            rel_error: 0.005,
            batch: 500,
            min_paths: 1000,
            max_paths: 1_000_000,
            seed: 9,
        };
        let e = path_trace_adaptive(&scene, &vis, &pts, &ad).unwrap();
        for est in &e {
            assert!(est.rel_error() <= 0.005, "{est:?}");
        }
        let fixed = path_trace_at(&scene, &vis, &pts[..1], e[0].paths, 9).unwrap();
        assert_eq!(fixed[0], e[0]);
        let bad = FlatPoint {
            segment: 7,
            ..pts[0]
        };
        assert!(path_trace_at(&scene, &vis, &[bad], 10, 0).is_err());
        assert!(
            path_trace_adaptive(
                &scene,
                &vis,
                &pts,
                &Adaptive {
                    rel_error: 2.0,
                    ..ad
                }
            )
            .is_err()
        );
    }
}
