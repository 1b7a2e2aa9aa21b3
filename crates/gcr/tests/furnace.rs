//! Converged bounces (issue 16, item 4): closed boxes with ρ near 1, where B = E/(1 − ρ)
//! (docs/design/math.md §8) and the light makes ~1/(1 − ρ) bounces before it is absorbed.

use gcr::{Domain, Emitters, GatherMode, SolveConfig, Trained, radiosity_at_points};
use scene_sampler::{KernelSampler, Scene, SceneBvh, Spectrum, SurfacePoint};

/// Area-uniform points on the box (a Kronecker sequence: the same every run).
fn points(scene: &Scene, count: usize) -> Vec<SurfacePoint> {
    let sampler = scene_sampler::SurfaceSampler::new(scene);
    (1..=count as u64)
        .map(|i| {
            sampler.sample([
                (i as f64 * 0.754_877_666).fract(),
                (i as f64 * 0.569_840_291).fract(),
            ])
        })
        .collect()
}

/// The solve and B by `gather` at `points`.
fn solve_at(
    scene: &Scene,
    config: &SolveConfig,
    gathers: &[GatherMode],
    points: &[SurfacePoint],
) -> (Trained, Vec<Vec<[f64; 3]>>) {
    let bvh = SceneBvh::new(scene);
    let domain = Domain::ThreeD(KernelSampler::new(scene, &bvh));
    let trained = gcr::solve(&domain, config, &mut |_| {}).unwrap();
    let emitters = Emitters::new(&domain);
    let at: Vec<_> = points.iter().map(|p| (p.point, p.normal, p.face)).collect();
    let b = gathers
        .iter()
        .map(|&gather| {
            let config = SolveConfig { gather, ..*config };
            radiosity_at_points(&domain, &trained, &emitters, &config, &at)
                .unwrap()
                .into_iter()
                .map(|g| {
                    assert!(g.radiosity.iter().all(|b| b.is_finite() && *b >= 0.0));
                    g.radiosity
                })
                .collect()
        })
        .collect();
    (trained, b)
}

/// Per band, the mean over the points and the relative L2 error against `exact`.
fn stats(b: &[[f64; 3]], exact: [f64; 3]) -> ([f64; 3], [f64; 3]) {
    let mut mean = [0.0; 3];
    let mut l2 = [0.0; 3];
    for k in 0..3 {
        mean[k] = b.iter().map(|v| v[k]).sum::<f64>() / b.len() as f64;
        let num: f64 = b.iter().map(|v| (v[k] - exact[k]).powi(2)).sum();
        l2[k] = (num / (b.len() as f64 * exact[k] * exact[k])).sqrt();
    }
    (mean, l2)
}

fn config(cells: usize) -> SolveConfig {
    SolveConfig {
        kernel_cells: cells,
        shading_cells: cells / 2,
        ..SolveConfig::default()
    }
}

fn report(
    label: &str,
    scene: &Scene,
    cfg: &SolveConfig,
    exact: [f64; 3],
) -> Vec<([f64; 3], [f64; 3])> {
    let pts = points(scene, 60);
    let gathers = [GatherMode::Kernel, GatherMode::Rays];
    let (trained, bs) = solve_at(scene, cfg, &gathers, &pts);
    let m = &trained.metrics;
    let mut strengths = [0.0; 3];
    for s in &trained.samples {
        for k in 0..3 {
            strengths[k] += s.s[k] / trained.samples.len() as f64;
        }
    }
    eprintln!(
        "{label}: {} cells, bounces {} (final {}), direct {}, balance {:?}, fem {:.2}s, mean sample strength {strengths:.3?}",
        m.kernel_cells,
        m.bounces,
        m.final_bounces,
        m.direct_solves,
        m.energy_balance,
        m.seconds.fem
    );
    gathers
        .iter()
        .zip(&bs)
        .map(|(g, b)| {
            let (mean, l2) = stats(b, exact);
            eprintln!("  {}: mean {mean:.3?}, rel L2 {l2:.4?}", g.name());
            (mean, l2)
        })
        .collect()
}

/// ρ = (0.5, 0.8, 0.95), E = 1: B = (2, 5, 20). The final propagation's direct solve lands on
/// the fixed point in one step (before: the blue band at 18.8, −6 %). Measured (seed 1, 200
/// cells, ray gather): mean (2.002, 4.999, 19.97), relative L2 (0.016, 0.042, 0.067); seeds 2–4
/// give blue means 19.58, 19.86, 20.24 (docs/design/gcr-algorithm.md).
#[test]
fn an_rgb_furnace_converges_per_band() {
    let scene = scene_sampler::builtin::furnace(Spectrum([1.0; 3]), Spectrum([0.5, 0.8, 0.95]));
    let exact = [2.0, 5.0, 20.0];
    let r = report("rgb", &scene, &config(200), exact);
    let (mean, l2) = r[1];
    for k in 0..3 {
        assert!(
            (mean[k] / exact[k] - 1.0).abs() < 0.01,
            "band {k}: mean {mean:?}"
        );
        assert!(l2[k] < [0.03, 0.06, 0.10][k], "band {k}: rel L2 {l2:?}");
    }
}

/// Grey ρ = 0.99, E = 1: B = 100 (before: 45 at 100 cells). Measured (seed 1, 100 cells, ray
/// gather): mean 99.6, relative L2 0.082.
#[test]
fn a_grey_099_furnace_converges() {
    let scene = scene_sampler::builtin::furnace(Spectrum([1.0; 3]), Spectrum([0.99; 3]));
    let r = report("grey", &scene, &config(100), [100.0; 3]);
    let (mean, l2) = r[1];
    assert!((mean[0] / 100.0 - 1.0).abs() < 0.02, "mean {mean:?}");
    assert!(l2[0] < 0.12, "rel L2 {l2:?}");
}

/// The default gather (paths, to a target error, no networks) in both furnaces: every band's
/// mean over 200 points within 1 % (ρ ≤ 0.95) and 2 % (grey 0.99) of E/(1 − ρ) — the issue's
/// targets — and within 4 of its standard errors, the per-point error (target 3 %) below 6 %.
/// Before the roulette followed max ρ without a cap and the paths' depth limit of 64 went, the
/// grey furnace gave about half of B (the light beyond 64 bounces is 0.99^65 = 52 % of it).
#[test]
fn the_default_gather_is_unbiased_at_high_albedo() {
    use gcr::{GatherSamples, PathSettings};
    let cases = [
        ([0.5, 0.8, 0.95], [2.0, 5.0, 20.0], 0.01),
        ([0.99; 3], [100.0; 3], 0.02),
    ];
    for (rho, exact, within) in cases {
        let scene = scene_sampler::builtin::furnace(Spectrum([1.0; 3]), Spectrum(rho));
        let bvh = SceneBvh::new(&scene);
        let domain = Domain::ThreeD(KernelSampler::new(&scene, &bvh));
        let config = SolveConfig {
            gather: GatherMode::Paths,
            gather_samples: GatherSamples {
                direct: 16,
                indirect: 16,
            },
            paths: PathSettings {
                target_error: Some(0.03),
                ..PathSettings::default()
            },
            ..SolveConfig::default()
        };
        let trained = Trained::without_networks(&domain, &config);
        let at: Vec<_> = points(&scene, 200)
            .iter()
            .map(|p| (p.point, p.normal, p.face))
            .collect();
        let g =
            radiosity_at_points(&domain, &trained, &Emitters::new(&domain), &config, &at).unwrap();
        let b: Vec<[f64; 3]> = g.iter().map(|g| g.radiosity).collect();
        let (mean, l2) = stats(&b, exact);
        eprintln!(
            "ρ {rho:?}: mean {mean:.3?}, rel L2 {l2:.4?}, {} rays",
            g[0].rays
        );
        for k in 0..3 {
            let se = g.iter().map(|g| g.std_error[k].powi(2)).sum::<f64>().sqrt() / g.len() as f64;
            assert!(
                (mean[k] / exact[k] - 1.0).abs() < within,
                "ρ {rho:?} band {k}: mean {mean:?}"
            );
            assert!(
                (mean[k] - exact[k]).abs() < 4.0 * se,
                "ρ {rho:?} band {k}: mean {} vs {} (±{se})",
                mean[k],
                exact[k]
            );
            assert!(l2[k] < 0.06, "ρ {rho:?} band {k}: rel L2 {l2:?}");
        }
    }
}

#[test]
#[ignore]
fn measure_seeds() {
    let rgb = scene_sampler::builtin::furnace(Spectrum([1.0; 3]), Spectrum([0.5, 0.8, 0.95]));
    let grey = scene_sampler::builtin::furnace(Spectrum([1.0; 3]), Spectrum([0.99; 3]));
    for direct in [0, 3000] {
        let cfg = SolveConfig {
            seed: 4,
            direct_solve_cells: direct,
            ..config(100)
        };
        let r = std::panic::catch_unwind(|| {
            report(&format!("grey direct {direct}"), &grey, &cfg, [100.0; 3])
        });
        eprintln!("ok: {}", r.is_ok());
    }
    for cells in [200] {
        for seed in 1..=4 {
            let cfg = SolveConfig {
                seed,
                ..config(cells)
            };
            report(&format!("rgb seed {seed}"), &rgb, &cfg, [2.0, 5.0, 20.0]);
            report(&format!("grey seed {seed}"), &grey, &cfg, [100.0; 3]);
        }
    }
}
