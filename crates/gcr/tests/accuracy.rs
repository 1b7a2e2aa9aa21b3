//! End-to-end accuracy of `gcr` against exact and independent references: the furnace (exact
//! B = E/(1 − ρ)) and the Cornell box (the path-traced pointwise reference of `baselines`).
//! Budgets are small so that the tests run in seconds; `docs/gcr-algorithm.md` has the errors at
//! larger budgets.

use gcr::config::{GatherMode, OutputFit, SolveConfig};
use gcr::domain::Domain;
use gcr::gather::Emitters;
use gcr::pipeline::radiosity_at;
use scene_sampler::{KernelSampler, Scene, SceneBvh, SurfacePoint};

fn scene(name: &str) -> (Scene, Vec<SurfacePoint>) {
    let scene = scene_sampler::builtin(name).unwrap().into_3d().unwrap();
    let path = format!(
        "{}/../../scenes/{name}.probes.txt",
        env!("CARGO_MANIFEST_DIR")
    );
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
    let trained = gcr::solve::solve(&domain, config, &mut |_| {}).unwrap();
    let emitters = Emitters::new(&domain);
    [GatherMode::Kernel, GatherMode::Rays]
        .into_iter()
        .map(|gather| {
            let config = SolveConfig { gather, ..*config };
            let (mut num, mut den) = (0.0, 0.0);
            let mut scratch = Vec::new();
            for (i, (p, r)) in points.iter().zip(reference).enumerate() {
                if skip_emitters && !scene.faces[p.face as usize].emission.is_zero() {
                    continue;
                }
                let g = radiosity_at(
                    &domain,
                    &trained,
                    &emitters,
                    &config,
                    p.point,
                    p.normal,
                    p.face,
                    i as u64,
                    &mut scratch,
                );
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
/// networks carry the reflected half.
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
        assert!(e < 0.08, "furnace {}: {e}", gather.name());
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
    assert!(kernel < 0.65, "kernel gather {kernel}");
    assert!(kernel < delta[0].1 && rays < delta[1].1);
}
