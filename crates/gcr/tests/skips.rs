//! Every skip of "what a scene doesn't need" must leave the answer unchanged. Here: skipping the
//! shading network and its base when neither the gather nor the strengths read them
//! (`SolveConfig::skip_unused_base`) gives bit-identical radiosity in the kernel and ray gathers.
//! The time it saves is measured by `cargo xtask bench --only gcr`.

use gcr::{Domain, Emitters, GatherMode, SolveConfig, radiosity_at_points};
use scene_sampler::{KernelSampler, SceneBvh};

#[test]
fn skipping_the_unused_base_changes_nothing() {
    let scene = scene_sampler::builtin("cornell-box")
        .unwrap()
        .into_3d()
        .unwrap();
    let bvh = SceneBvh::new(&scene);
    let domain = Domain::ThreeD(KernelSampler::new(&scene, &bvh));
    let emitters = Emitters::new(&domain);
    let sampler = scene_sampler::SurfaceSampler::new(&scene);
    let points: Vec<_> = (0..40)
        .map(|i| {
            let u = [
                (i as f64 * 0.618_034) % 1.0,
                (i as f64 * 0.414_214 + 0.1) % 1.0,
            ];
            sampler.sample(u)
        })
        .collect();

    let run = |skip: bool| {
        let config = SolveConfig {
            kernel_cells: 60,
            shading_cells: 30,
            skip_unused_base: skip,
            ..SolveConfig::default()
        };
        assert_eq!(config.needs_base(), !skip);
        let trained = gcr::solve(&domain, &config, &mut |_| {}).unwrap();
        let mut out = Vec::new();
        let at: Vec<_> = points.iter().map(|p| (p.point, p.normal, p.face)).collect();
        for gather in [GatherMode::Kernel, GatherMode::Rays] {
            let config = SolveConfig { gather, ..config };
            let b = radiosity_at_points(&domain, &trained, &emitters, &config, &at).unwrap();
            out.extend(b.iter().map(|g| g.radiosity));
        }
        (out, trained.metrics.fem_steps)
    };
    let (skipped, steps_skipped) = run(true);
    let (kept, steps_kept) = run(false);
    assert_eq!(
        steps_skipped, steps_kept,
        "the FEM schedule must not change"
    );
    assert!(skipped.iter().flatten().any(|b| *b > 0.0));
    assert_eq!(
        skipped, kept,
        "skipping the base changed the kernel's answer"
    );
}
