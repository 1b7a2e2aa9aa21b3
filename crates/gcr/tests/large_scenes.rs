//! Large scenes: the clustered surface integrals (the cluster tree, `SolveConfig::surface_clusters`)
//! must give the solve the exact integrals give. `tessellated-cornell-2000` (the Cornell box cut
//! into about 2000 triangles) is small enough to solve both ways in a test; forcing the cluster tree
//! on it (`min_elements = 0`) must move B by no more than the clustering's own error.

use gcr::{Domain, Emitters, GatherMode, SolveConfig, SurfaceClusters, radiosity_at_points};
use scene_sampler::{KernelSampler, SceneBvh};

#[test]
fn clustered_integrals_give_the_exact_solution_on_a_tessellated_cornell_box() {
    let scene = scene_sampler::builtin("tessellated-cornell-2000")
        .unwrap()
        .into_3d()
        .unwrap();
    assert!(scene.faces.len() > 1500);
    let bvh = SceneBvh::new(&scene);
    let domain = Domain::ThreeD(KernelSampler::new(&scene, &bvh));
    let emitters = Emitters::new(&domain);
    let sampler = scene_sampler::SurfaceSampler::new(&scene);
    let at: Vec<_> = (0..60)
        .map(|i| {
            let u = [
                (i as f64 * 0.618_034) % 1.0,
                (i as f64 * 0.414_214 + 0.1) % 1.0,
            ];
            let p = sampler.sample(u);
            (p.point, p.normal, p.face)
        })
        .collect();
    let run = |min_elements: usize| {
        let config = SolveConfig {
            kernel_cells: 50,
            shading_cells: 25,
            surface_clusters: SurfaceClusters {
                min_elements,
                ..SurfaceClusters::default()
            },
            gather: GatherMode::Kernel,
            ..SolveConfig::default()
        };
        let trained = gcr::solve(&domain, &config, &mut |_| {}).unwrap();
        radiosity_at_points(&domain, &trained, &emitters, &config, &at)
            .unwrap()
            .into_iter()
            .map(|g| g.radiosity)
            .collect::<Vec<_>>()
    };
    let exact = run(usize::MAX);
    let clustered = run(0);
    let (mut num, mut den) = (0.0, 0.0);
    for (a, b) in exact.iter().zip(&clustered) {
        for k in 0..3 {
            assert!(b[k].is_finite());
            num += (a[k] - b[k]).powi(2);
            den += a[k].powi(2);
        }
    }
    let rel = (num / den).sqrt();
    eprintln!("clustered vs exact: relative L2 {rel:.2e}");
    // Measured 5.9e-5 (kernel gather, 50 cells); the solution's own error is about 50 %.
    assert!(rel < 1e-3, "clustered vs exact: relative L2 {rel:.2e}");
    assert!(rel > 0.0, "the tree must actually have been used");
}
