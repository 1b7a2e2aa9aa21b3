//! Numerical stability of the whole solver (issue: "never NaN, never a blow-up, error reported"):
//! the same scene at three scales, a nearly non-absorbing furnace (ρ = 0.95), and geometry that
//! breaks naive code (a sliver triangle, a face coincident with another, corners where the kernel
//! is singular).

use gcr::{Domain, Emitters, GatherMode, NetworkTarget, SolveConfig, radiosity_at_points};
use glam::DVec3;
use scene_sampler::{Face, KernelSampler, Scene, SceneBvh, Spectrum, SurfacePoint};

/// Rebuilds `scene` with every vertex mapped by `f` and every face's (ρ, E) by `material`, plus
/// the `extra` faces.
fn rebuild(
    scene: &Scene,
    f: impl Fn(DVec3) -> DVec3,
    material: impl Fn(&Face) -> (Spectrum, Spectrum),
    extra: Vec<Face>,
) -> Scene {
    let mut faces: Vec<Face> = scene
        .faces
        .iter()
        .map(|face| {
            let (rho, e) = material(face);
            Face::new(face.v.map(&f), rho, e, face.object, face.surface)
        })
        .collect();
    faces.extend(extra);
    Scene::new(&scene.name, "test", faces, scene.objects.clone(), None).unwrap()
}

/// Area-uniform points on the non-emitting faces, or on every face when nothing else exists
/// (a Kronecker sequence: the same every run).
fn points(scene: &Scene, count: usize) -> Vec<SurfacePoint> {
    let sampler = scene_sampler::SurfaceSampler::new(scene);
    let all_emit = scene.faces.iter().all(|f| !f.emission.is_zero());
    (1..100 * count as u64)
        .map(|i| {
            sampler.sample([
                (i as f64 * 0.754_877_666).fract(),
                (i as f64 * 0.569_840_291).fract(),
            ])
        })
        .filter(|p| all_emit || scene.faces[p.face as usize].emission.is_zero())
        .take(count)
        .collect()
}

/// B by `gather` at `points` after a solve with `config`.
fn solve_at(
    scene: &Scene,
    config: &SolveConfig,
    gather: GatherMode,
    points: &[SurfacePoint],
) -> Vec<[f64; 3]> {
    let bvh = SceneBvh::new(scene);
    let domain = Domain::ThreeD(KernelSampler::new(scene, &bvh));
    let trained = gcr::solve(&domain, config, &mut |_| {}).unwrap();
    let emitters = Emitters::new(&domain);
    let config = SolveConfig { gather, ..*config };
    let at: Vec<_> = points.iter().map(|p| (p.point, p.normal, p.face)).collect();
    radiosity_at_points(&domain, &trained, &emitters, &config, &at)
        .unwrap()
        .into_iter()
        .zip(points)
        .map(|(g, p)| {
            assert!(
                g.radiosity.iter().all(|b| b.is_finite() && *b >= 0.0),
                "B = {:?} at {:?}",
                g.radiosity,
                p.point
            );
            g.radiosity
        })
        .collect()
}

fn relative_l2(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    let (mut num, mut den) = (0.0, 0.0);
    for (x, y) in a.iter().zip(b) {
        for k in 0..3 {
            num += (x[k] - y[k]).powi(2);
            den += y[k].powi(2);
        }
    }
    (num / den).sqrt()
}

fn small(cells: usize) -> SolveConfig {
    SolveConfig {
        kernel_cells: cells,
        shading_cells: cells / 2,
        ..SolveConfig::default()
    }
}

/// Radiosity is scale-free (form factors are): the Cornell box at 1e−3 and 1e3 of its size
/// gives the same B as at its own size, up to the solver's own run-to-run noise.
#[test]
fn radiosity_does_not_depend_on_the_scene_scale() {
    let base = scene_sampler::builtin("cornell-box")
        .unwrap()
        .into_3d()
        .unwrap();
    let pts = points(&base, 60);
    let unit = solve_at(&base, &small(80), GatherMode::Rays, &pts);
    for s in [1e-3, 1e3] {
        let scaled = rebuild(&base, |v| v * s, |f| (f.rho, f.emission), vec![]);
        let scaled_pts: Vec<SurfacePoint> = pts
            .iter()
            .map(|p| SurfacePoint {
                point: p.point * s,
                ..*p
            })
            .collect();
        for gather in [GatherMode::Rays, GatherMode::Kernel] {
            let at_scale = solve_at(&scaled, &small(80), gather, &scaled_pts);
            let own = if gather == GatherMode::Rays {
                unit.clone()
            } else {
                solve_at(&base, &small(80), gather, &pts)
            };
            let d = relative_l2(&at_scale, &own);
            eprintln!("scale {s:e} {}: relative difference {d:.2e}", gather.name());
            assert!(d < 1e-6, "scale {s}: {} differs by {d}", gather.name());
        }
    }
}

/// A furnace that hardly absorbs: ρ = 0.95 everywhere, E = 1, so B = E/(1 − ρ) = 20, of which
/// the networks carry 19. Many bounces; the projection's bounce loop must converge, not blow up
/// (without `energy_correction` it ran away to B ≈ 300). Measured at 200 cells: mean B 19.73
/// (kernel gather, 19 % pointwise) and 20.03 (ray gather, 5.9 %). At 80 cells the network
/// trained on the clamped kernel (the default) leaves the mean 17 % low (ray gather 17 %); trained
/// on the unclamped K·s it was 0.6 % (4.3 %): the furnace's K·s has no structure but G's.
#[test]
fn a_nearly_white_furnace_converges_to_e_over_one_minus_rho() {
    let furnace = scene_sampler::builtin("furnace")
        .unwrap()
        .into_3d()
        .unwrap();
    let white = rebuild(
        &furnace,
        |v| v,
        |_| (Spectrum([0.95; 3]), Spectrum([1.0; 3])),
        vec![],
    );
    let pts = points(&white, 40);
    for gather in [GatherMode::Kernel, GatherMode::Rays] {
        let b = solve_at(&white, &small(200), gather, &pts);
        let err = relative_l2(&b, &vec![[20.0; 3]; b.len()]);
        let mean = b.iter().map(|v| v[0]).sum::<f64>() / b.len() as f64;
        eprintln!(
            "white furnace {}: relative error {err:.4}, mean B {mean:.3} (exact 20)",
            gather.name()
        );
        // The mean is held by the energy correction; the pointwise error is the fit's ripple,
        // amplified by the many bounces (it is 3–6 % at ρ = 0.5, tests/accuracy.rs).
        assert!(
            (mean / 20.0 - 1.0).abs() < 0.02,
            "{}: mean {mean}",
            gather.name()
        );
        let bound = if gather == GatherMode::Rays {
            0.08
        } else {
            0.25
        };
        assert!(err < bound, "{}: {err}", gather.name());
    }
}

/// A sliver (aspect ratio 1e6), a face lying on the floor (coincident, same orientation) and
/// corners everywhere: no NaN, no negative or exploding B, and still close to the plain box.
#[test]
fn slivers_and_coincident_faces_stay_finite() {
    let base = scene_sampler::builtin("cornell-box")
        .unwrap()
        .into_3d()
        .unwrap();
    let grey = Spectrum([0.5; 3]);
    let (lo, hi) = base.bounds;
    let c = (lo + hi) * 0.5;
    let span = hi - lo;
    let floor_y = lo.y;
    let sliver = Face::new(
        [
            DVec3::new(c.x - 0.3 * span.x, c.y, c.z),
            DVec3::new(c.x + 0.3 * span.x, c.y, c.z),
            DVec3::new(c.x, c.y + 1e-6 * span.y, c.z),
        ],
        grey,
        Spectrum::ZERO,
        0,
        10_000,
    );
    let on_floor = Face::new(
        [
            DVec3::new(lo.x + 0.1 * span.x, floor_y, lo.z + 0.1 * span.z),
            DVec3::new(lo.x + 0.3 * span.x, floor_y, lo.z + 0.3 * span.z),
            DVec3::new(lo.x + 0.3 * span.x, floor_y, lo.z + 0.1 * span.z),
        ],
        grey,
        Spectrum::ZERO,
        0,
        10_001,
    );
    // Orient the copy like the floor (up).
    let on_floor = if on_floor.normal.y < 0.0 {
        Face::new(
            [on_floor.v[0], on_floor.v[2], on_floor.v[1]],
            grey,
            Spectrum::ZERO,
            0,
            10_001,
        )
    } else {
        on_floor
    };
    let odd = rebuild(
        &base,
        |v| v,
        |f| (f.rho, f.emission),
        vec![sliver, on_floor],
    );
    let pts = points(&base, 60);
    // Each against the path tracer on its own scene: the extra faces change the sampling, so
    // the two solves differ by the solver's noise at this budget, not by the geometry.
    let reference = |scene: &Scene| -> Vec<[f64; 3]> {
        let bvh = SceneBvh::new(scene);
        baselines::pointwise::radiosity_at(scene, &bvh, &pts, 4000, 3)
            .into_iter()
            .map(|e| e.mean)
            .collect()
    };
    let plain = relative_l2(
        &solve_at(&base, &small(80), GatherMode::Rays, &pts),
        &reference(&base),
    );
    let odd_error = relative_l2(
        &solve_at(&odd, &small(80), GatherMode::Rays, &pts),
        &reference(&odd),
    );
    eprintln!(
        "error against the path tracer: plain box {plain:.3}, with sliver and coincident face {odd_error:.3}"
    );
    assert!(
        odd_error < 0.2 && odd_error < 2.0 * plain,
        "{odd_error} vs {plain}"
    );
}

/// `wall-floor` at 400 kernel cells once ran its final bounces into B ≈ 1e51 (seed 1) and
/// 1e133 (seed 2): the projected kernel had a mode with gain above 1 that the first 30 bounces
/// hid. The bounce iteration now stops when its changes grow, and a projection that diverges is
/// redone with a higher rejection threshold (seed 2 needs it); B stays within the
/// maximum-principle bound and near the path tracer.
#[test]
fn a_projected_kernel_with_gain_above_one_does_not_blow_up() {
    let scene = scene_sampler::builtin("wall-floor")
        .unwrap()
        .into_3d()
        .unwrap();
    let pts = points(&scene, 40);
    let bvh = SceneBvh::new(&scene);
    let domain = Domain::ThreeD(KernelSampler::new(&scene, &bvh));
    let bound = domain.radiosity_bound();
    let reference: Vec<[f64; 3]> = baselines::pointwise::radiosity_at(&scene, &bvh, &pts, 4000, 3)
        .into_iter()
        .map(|e| e.mean)
        .collect();
    for seed in [1, 2] {
        let config = SolveConfig { seed, ..small(400) };
        let b = solve_at(&scene, &config, GatherMode::Kernel, &pts);
        assert!(
            b.iter().all(|v| (0..3).all(|k| v[k] <= bound[k])),
            "seed {seed}: B above E_max/(1 − ρ_max) = {bound:?}"
        );
        let err = relative_l2(&b, &reference);
        eprintln!("wall-floor at 400 cells, seed {seed}: kernel gather error {err:.3}");
        assert!(err < 0.5, "seed {seed}: kernel gather error {err}");
    }
}

/// The network grows tiny cells where surfaces meet (the kernel's singularity). A cell there
/// holds a fraction of a sample on average; when one sample's sender lies in both of its halves,
/// the projection feeds that sample's strength back to itself with a gain far above 1. On
/// cornell-box, seed 5, this made projections diverge from about 300 cells on (each was redone
/// with most cells rejected) and stopped the solve with the guard from 1000 cells. Leaving the
/// cells with less than two samples of support out of the projection (the default) removes it.
/// (Since the training projections run only at doublings up to half the budget, fewer of them
/// meet the edge cells: at 1200 cells one bounce iteration runs away without the rule.)
#[test]
fn cells_without_samples_do_not_feed_their_noise_back() {
    let scene = scene_sampler::builtin("cornell-box")
        .unwrap()
        .into_3d()
        .unwrap();
    let bvh = SceneBvh::new(&scene);
    let domain = Domain::ThreeD(KernelSampler::new(&scene, &bvh));
    let redone = |projection_min_support: f64| {
        let config = SolveConfig {
            seed: 5,
            projection_min_support,
            // the dissertation's target, which grows the edge cells (the default clamps G)
            network_target: NetworkTarget::KernelValue,
            ..small(1200)
        };
        let trained = gcr::solve(&domain, &config, &mut |_| {}).unwrap();
        let m = &trained.metrics;
        eprintln!(
            "min support {projection_min_support}: {} projections redone, {} diverging \
             iterations stopped, {} cells unsupported",
            m.stabilized_projections, m.diverging_bounces_stopped, m.unsupported_cells
        );
        (
            m.stabilized_projections + m.diverging_bounces_stopped,
            m.unsupported_cells,
        )
    };
    let (without, none) = redone(0.0);
    assert_eq!(none, 0);
    assert!(without > 0, "every cell projected: the edge cells run away");
    let (with, unsupported) = redone(SolveConfig::default().projection_min_support);
    assert_eq!(with, 0, "no projection redone, no bounce iteration stopped");
    assert!(unsupported > 0);
}
