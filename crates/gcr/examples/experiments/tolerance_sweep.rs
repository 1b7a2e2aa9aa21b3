//! Solve time and error against the projection's support cut-off
//! (`SolveConfig::projection_tolerance`): how much exactness the Gram matrix needs.
//!
//! `cargo run --release -p gcr --example tolerance_sweep -- cornell-box 400 [tolerances…]`
//! (default tolerances 1e-12 1e-9 1e-6; the solver accepts at most 1e-6)
//!
//! Prints, per tolerance, the solve seconds (wall and the FEM share) and the relative L2 error of
//! the kernel and ray gathers at the scene's probes against the path-traced reference; a
//! tolerance whose solve goes unstable prints the solver's error instead.

use gcr::{Domain, Emitters, GatherMode, SolveConfig, radiosity_at_points};
use scene_sampler::{KernelSampler, SceneBvh};

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let name = args.get(1).map_or("cornell-box", |s| s.as_str());
    let cells: usize = args.get(2).map_or(Ok(400), |s| s.parse())?;
    let scene = scene_sampler::builtin(name)?.into_3d()?;
    let bvh = SceneBvh::new(&scene);
    let probes = scene_sampler::read_probes(format!("scenes/{name}.probes.txt"))?;
    let points = scene.snap_probes(&probes, name)?;
    let reference = baselines::pointwise::radiosity_at(&scene, &bvh, &points, 20_000, 7);
    let domain = Domain::ThreeD(KernelSampler::new(&scene, &bvh));
    let emitters = Emitters::new(&domain);
    println!("| tolerance | seconds | FEM s | kernel error | rays error |");
    println!("|---:|---:|---:|---:|---:|");
    let mut tolerances: Vec<f64> = args[3.min(args.len())..]
        .iter()
        .map(|s| s.parse())
        .collect::<Result<_, _>>()?;
    if tolerances.is_empty() {
        tolerances = vec![1e-12, 1e-9, 1e-6];
    }
    for tol in tolerances {
        let config = SolveConfig {
            kernel_cells: cells,
            shading_cells: cells / 2,
            projection_tolerance: tol,
            ..SolveConfig::default()
        };
        let t = std::time::Instant::now();
        let trained = match gcr::solve(&domain, &config, &mut |_| {}) {
            Ok(t) => t,
            Err(e) => {
                println!("| {tol:.0e} | {e} | | | |");
                continue;
            }
        };
        let seconds = t.elapsed().as_secs_f64();
        let mut errors = Vec::new();
        for gather in [GatherMode::Kernel, GatherMode::Rays] {
            let config = SolveConfig { gather, ..config };
            let (mut num, mut den) = (0.0, 0.0);
            let at: Vec<_> = points.iter().map(|p| (p.point, p.normal, p.face)).collect();
            let gathered = radiosity_at_points(&domain, &trained, &emitters, &config, &at)?;
            for ((p, r), g) in points.iter().zip(&reference).zip(&gathered) {
                if !scene.faces[p.face as usize].emission.is_zero() {
                    continue;
                }
                for b in 0..3 {
                    num += (g.radiosity[b] - r.mean[b]).powi(2);
                    den += r.mean[b].powi(2);
                }
            }
            errors.push((num / den).sqrt());
        }
        println!(
            "| {tol:.0e} | {seconds:.2} | {:.2} | {:.4} | {:.4} |",
            trained.metrics.seconds.fem, errors[0], errors[1]
        );
    }
    Ok(())
}
