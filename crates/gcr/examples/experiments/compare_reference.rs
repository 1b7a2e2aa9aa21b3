//! Relative L2 error of `gcr solve` at a scene's non-emitting probes against the path-traced
//! reference, for both kernel output layers and every gather.
//!
//! `cargo run --release -p gcr --example compare_reference -- cornell-box 200 [seed] [samples-per-cell]`

use gcr::{Domain, Emitters, GatherMode, OutputFit, SolveConfig, radiosity_at_points};
use scene_sampler::{KernelSampler, SceneBvh};

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let name = args.get(1).map_or("cornell-box", |s| s.as_str());
    let cells: usize = args.get(2).map_or(Ok(200), |s| s.parse())?;
    let seed: u64 = args.get(3).map_or(Ok(1), |s| s.parse())?;
    let samples_per_cell: usize = args
        .get(4)
        .map_or(Ok(SolveConfig::default().samples_per_cell), |s| s.parse())?;
    let scene = scene_sampler::builtin(name)?.into_3d()?;
    let bvh = SceneBvh::new(&scene);
    let probes = scene_sampler::read_probes(format!("scenes/{name}.probes.txt"))?;
    let points = scene.snap_probes(&probes, name)?;
    let t = std::time::Instant::now();
    let reference = baselines::pointwise::radiosity_at(&scene, &bvh, &points, 20_000, 7);
    let t_ref = t.elapsed().as_secs_f64();
    println!(
        "reference: {} probes, 20000 paths each, {t_ref:.1} s",
        points.len()
    );
    let domain = Domain::ThreeD(KernelSampler::new(&scene, &bvh));
    let emitters = Emitters::new(&domain);
    for output_fit in [OutputFit::Projection, OutputFit::DeltaRule] {
        let config = SolveConfig {
            kernel_cells: cells,
            shading_cells: cells / 2,
            output_fit,
            seed,
            samples_per_cell,
            // The base gather below reads the shading network's base: keep it.
            skip_unused_base: false,
            ..SolveConfig::default()
        };
        let t = std::time::Instant::now();
        let trained = gcr::solve(&domain, &config, &mut |_| {})?;
        let seconds = t.elapsed().as_secs_f64();
        for gather in [GatherMode::Base, GatherMode::Kernel, GatherMode::Rays] {
            let config = SolveConfig { gather, ..config };
            let (mut num, mut den) = (0.0, 0.0);
            let at: Vec<_> = points.iter().map(|p| (p.point, p.normal, p.face)).collect();
            let gathered = radiosity_at_points(&domain, &trained, &emitters, &config, &at)?;
            for ((p, r), g) in points.iter().zip(&reference).zip(&gathered) {
                // Emitter probes would dominate the L2 sum with their exact E: leave them out.
                if !scene.faces[p.face as usize].emission.is_zero() {
                    continue;
                }
                for b in 0..3 {
                    num += (g.radiosity[b] - r.mean[b]).powi(2);
                    den += r.mean[b].powi(2);
                }
            }
            println!(
                "{name} cells={cells} seed={seed} samples_per_cell={samples_per_cell} output_fit={} gather={} rel_l2={:.3} solve_seconds={seconds:.1}",
                output_fit.name(),
                gather.name(),
                (num / den).sqrt(),
            );
        }
    }
    Ok(())
}
