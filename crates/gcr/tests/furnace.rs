//! Converged bounces (issue 16, item 4): closed boxes with ρ near 1, where B = E/(1 − ρ)
//! (MATH.md §8) and the light makes ~1/(1 − ρ) bounces before it is absorbed.

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

#[test]
fn measure_rgb() {
    let scene = scene_sampler::builtin::furnace(Spectrum([1.0; 3]), Spectrum([0.5, 0.8, 0.95]));
    for cells in [100, 200] {
        report("rgb", &scene, &config(cells), [2.0, 5.0, 20.0]);
    }
}

#[test]
fn measure_grey() {
    let scene = scene_sampler::builtin::furnace(Spectrum([1.0; 3]), Spectrum([0.99; 3]));
    for cells in [100, 200] {
        report("grey99", &scene, &config(cells), [100.0; 3]);
    }
}
