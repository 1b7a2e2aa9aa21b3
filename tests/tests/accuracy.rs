//! End-to-end accuracy of `gcr` against exact and independent references: the furnace (exact
//! B = E/(1 − ρ)) and the Cornell box (the path-traced pointwise reference of `baselines`).
//! Budgets are small so that the tests run in seconds; `docs/design/gcr-algorithm.md` has the errors at
//! larger budgets.

use gcr::{Domain, Emitters, GatherMode, OutputFit, SolveConfig, radiosity_at_points};
use scene_sampler::{KernelSampler, Scene, SceneBvh, SurfacePoint};

fn scene(name: &str) -> (Scene, Vec<SurfacePoint>) {
    let scene = scene_sampler::builtin(name).unwrap().into_3d().unwrap();
    let path = gcr_tests::workspace_path(&format!("scenes/{name}.probes.txt"));
    let probes = scene_sampler::read_probes(path).unwrap();
    let points = scene.snap_probes(&probes, name).unwrap();
    (scene, points)
}

/// Relative L2 error per gather mode at the probes (emitter probes left out when `skip_emitters`).
fn errors(
    scene: &Scene,
    points: &[SurfacePoint],
    reference: &[[f64; 3]],
    config: &SolveConfig,
    skip_emitters: bool,
) -> Vec<(GatherMode, f64)> {
    let bvh = SceneBvh::new(scene);
    let domain = Domain::ThreeD(KernelSampler::new(scene, &bvh));
    let trained = gcr::solve(&domain, config, &mut |_| {}).unwrap();
    let emitters = Emitters::new(&domain);
    [GatherMode::Kernel, GatherMode::Rays]
        .into_iter()
        .map(|gather| {
            let config = SolveConfig { gather, ..*config };
            let (mut num, mut den) = (0.0, 0.0);
            let at: Vec<_> = points.iter().map(|p| (p.point, p.normal, p.face)).collect();
            let gathered = radiosity_at_points(&domain, &trained, &emitters, &config, &at).unwrap();
            for ((p, r), g) in points.iter().zip(reference).zip(&gathered) {
                if skip_emitters && !scene.faces[p.face as usize].emission.is_zero() {
                    continue;
                }
                for b in 0..3 {
                    assert!(g.radiosity[b].is_finite());
                    num += (g.radiosity[b] - r[b]).powi(2);
                    den += r[b].powi(2);
                }
            }
            (gather, (num / den).sqrt())
        })
        .collect()
}

fn config(cells: usize, output_fit: OutputFit) -> SolveConfig {
    SolveConfig {
        kernel_cells: cells,
        shading_cells: cells / 2,
        output_fit,
        ..SolveConfig::default()
    }
}

/// Furnace: every face emits E = 1 and reflects ρ = 0.5, so B = 2 everywhere, of which the
/// networks carry the reflected half. The target is 1 %: the ray gather (measured 0.89 %)
/// meets it at 100 cells; the kernel gather (9.4 %; 6.5 % with the network trained on the
/// unclamped K·s, `NetworkTarget::KernelValue`) does not.
#[test]
fn furnace_radiosity_is_e_over_one_minus_rho() {
    let (scene, points) = scene("furnace");
    let exact = vec![[2.0; 3]; points.len()];
    let errs = errors(
        &scene,
        &points,
        &exact,
        &config(100, OutputFit::Projection),
        false,
    );
    eprintln!("furnace {errs:?}");
    for (gather, e) in errs {
        // The ray gather's 64 + 64 rays at 6 probes: its relative L2 is 1.06–1.63 % over eight
        // seedings of the per-point gathers (measured), so the bound leaves room for that noise.
        let bound = if gather == GatherMode::Rays {
            0.025
        } else {
            0.12
        };
        assert!(e < bound, "furnace {}: {e}", gather.name());
    }
}

/// Cornell box against the path tracer: the projected output layer at a small budget, and the
/// dissertation's delta rule, which it must beat.
#[test]
fn cornell_box_matches_the_path_traced_reference() {
    let (scene, points) = scene("cornell-box");
    let bvh = SceneBvh::new(&scene);
    let reference: Vec<[f64; 3]> =
        baselines::pointwise::radiosity_at(&scene, &bvh, &points, 20_000, 7)
            .into_iter()
            .map(|r| r.mean)
            .collect();
    let projected = errors(
        &scene,
        &points,
        &reference,
        &config(100, OutputFit::Projection),
        true,
    );
    let delta = errors(
        &scene,
        &points,
        &reference,
        &config(100, OutputFit::DeltaRule),
        true,
    );
    eprintln!("projection {projected:?}\ndelta rule {delta:?}");
    let (kernel, rays) = (projected[0].1, projected[1].1);
    assert!(rays < 0.2, "rays gather {rays}");
    // measured 0.315 (the ray gather 0.104)
    assert!(kernel < 0.45, "kernel gather {kernel}");
    assert!(kernel < delta[0].1 && rays < delta[1].1);
}

/// The base carries what the kernel collection predicts: on `wall-floor` the projection of
/// B_refl onto the base (Gaussians on the scene faces that face like their cell) stays within
/// 12 % (relative L2 over the surface) of B_refl itself. A projection that is inconsistent with
/// its Gram matrix fails this by orders of magnitude.
#[test]
fn base_reproduces_the_kernel_collection() {
    let scene = scene_sampler::builtin("wall-floor")
        .unwrap()
        .into_3d()
        .unwrap();
    let bvh = SceneBvh::new(&scene);
    let domain = Domain::ThreeD(KernelSampler::new(&scene, &bvh));
    let config = SolveConfig {
        skip_unused_base: false,
        ..config(200, OutputFit::Projection)
    };
    let trained = gcr::solve(&domain, &config, &mut |_| {}).unwrap();
    let sampler = scene_sampler::SurfaceSampler::new(&scene);
    let (mut num, mut den) = (0.0, 0.0);
    let mut scratch = Vec::new();
    for i in 0..5000 {
        // A Kronecker (golden-ratio) sequence: even coverage without a random generator.
        let u = [
            (i as f64 * 0.618_034) % 1.0,
            (i as f64 * 0.754_877_7 + 0.3) % 1.0,
        ];
        let p = sampler.sample(u);
        let kernel = trained.reflected_kernel(p.point, p.normal)[0];
        let base = trained
            .fem
            .reflected_from_base(p.point, p.normal, &mut scratch)[0];
        num += (kernel - base).powi(2);
        den += kernel.powi(2);
    }
    let err = (num / den).sqrt();
    eprintln!("base vs kernel collection: {err:.4}");
    assert!(err < 0.12, "{err}");
}
