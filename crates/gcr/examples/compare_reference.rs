//! Relative L2 error of `gcr solve` at a scene's non-emitting probes against the path-traced
//! reference.
//!
//! `cargo run --release -p gcr --example compare_reference -- cornell-box 200`

use gcr::config::{GatherMode, SolveConfig};
use gcr::domain::Domain;
use gcr::gather::Emitters;
use gcr::pipeline::radiosity_at;
use scene_sampler::{KernelSampler, SceneBvh};

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let name = args.get(1).map_or("cornell-box", |s| s.as_str());
    let cells: usize = args.get(2).map_or(Ok(200), |s| s.parse())?;
    let scene = scene_sampler::builtin(name)?.into_3d()?;
    let bvh = SceneBvh::new(&scene);
    let probes = scene_sampler::read_probes(format!("scenes/{name}.probes.txt"))?;
    let points = scene.snap_probes(&probes, name)?;
    let t = std::time::Instant::now();
    let reference = baselines::pointwise::radiosity_at(&scene, &bvh, &points, 20_000, 7);
    let t_ref = t.elapsed().as_secs_f64();
    let domain = Domain::ThreeD(KernelSampler::new(&scene, &bvh));
    for gather in [GatherMode::Base, GatherMode::Kernel, GatherMode::Rays] {
        let config = SolveConfig {
            kernel_cells: cells,
            shading_cells: cells / 2,
            gather,
            ..SolveConfig::default()
        };
        let t = std::time::Instant::now();
        let trained = gcr::solve::solve(&domain, &config, &mut |_| {})?;
        let emitters = Emitters::new(&domain);
        let mut scratch = Vec::new();
        let (mut num, mut den) = (0.0, 0.0);
        for (i, (p, r)) in points.iter().zip(&reference).enumerate() {
            // Emitter probes would dominate the L2 sum with their exact E: leave them out.
            if !scene.faces[p.face as usize].emission.is_zero() {
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
                num += (g.radiosity[b] - r.mean[b]).powi(2);
                den += r.mean[b].powi(2);
            }
        }
        println!(
            "{name} cells={cells} gather={} rel_l2={:.3} seconds={:.1} (reference: {} probes, 20000 paths, {t_ref:.1} s)",
            gather.name(),
            (num / den).sqrt(),
            t.elapsed().as_secs_f64(),
            points.len()
        );
    }
    Ok(())
}
