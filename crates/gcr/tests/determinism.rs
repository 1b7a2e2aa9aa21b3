//! Same seed, same answer — on one thread or two. Every parallel sum in the solver runs over
//! fixed chunks combined in order, and every random stream is seeded per sample or per point, so
//! the output is bit-identical whatever the thread count.

use gcr::{Domain, Emitters, GatherMode, SolveConfig, radiosity_at_points};
use scene_sampler::{KernelSampler, SceneBvh};

fn run(threads: usize, seed: u64) -> Vec<[f64; 3]> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    pool.install(|| {
        let scene = scene_sampler::builtin("cornell-box")
            .unwrap()
            .into_3d()
            .unwrap();
        let bvh = SceneBvh::new(&scene);
        let domain = Domain::ThreeD(KernelSampler::new(&scene, &bvh));
        let config = SolveConfig {
            kernel_cells: 60,
            shading_cells: 30,
            seed,
            ..SolveConfig::default()
        };
        let trained = gcr::solve(&domain, &config, &mut |_| {}).unwrap();
        let emitters = Emitters::new(&domain);
        let sampler = scene_sampler::SurfaceSampler::new(&scene);
        let mut out = Vec::new();
        let at: Vec<_> = (0..30)
            .map(|i| {
                let p = sampler.sample([
                    (i as f64 * 0.754_877_666).fract(),
                    (i as f64 * 0.569_840_291).fract(),
                ]);
                (p.point, p.normal, p.face)
            })
            .collect();
        for gather in [GatherMode::Kernel, GatherMode::Rays] {
            let config = SolveConfig { gather, ..config };
            let b = radiosity_at_points(&domain, &trained, &emitters, &config, &at).unwrap();
            out.extend(b.iter().map(|g| g.radiosity));
        }
        out
    })
}

#[test]
fn same_seed_same_output_on_one_or_two_threads() {
    let two = run(2, 5);
    assert_eq!(run(2, 5), two, "two runs with the same seed differ");
    assert_eq!(run(1, 5), two, "one thread and two threads differ");
    assert_ne!(run(2, 6), two, "the seed is not used");
}
