//! GCR on a generated large scene (`tessellated-cornell-<N>`: the Cornell box cut into about N
//! triangles; `random-boxes-<N>`: the Cornell box filled with small random boxes), against the
//! path-traced reference at 200 area-uniform probes, for several cluster criteria θ
//! (`gcr`'s cluster tree).
//!
//! `cargo run --release -p gcr --example large_scene -- tessellated-cornell-1000000 300 1 0.5`
//! (scene, kernel cells, then the θ values; default: the configuration's θ).

use gcr::{Domain, Emitters, GatherMode, SolveConfig, SurfaceClusters, radiosity_at_points};
use scene_sampler::{KernelSampler, SceneBvh, SurfaceSampler};
use std::time::Instant;

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let name = args
        .get(1)
        .map_or("tessellated-cornell-1000000", |s| s.as_str());
    let cells: usize = args.get(2).map_or(Ok(300), |s| s.parse())?;
    let thetas: Vec<f64> = if args.len() > 3 {
        args[3..]
            .iter()
            .map(|s| s.parse())
            .collect::<Result<_, _>>()?
    } else {
        vec![SurfaceClusters::default().theta]
    };
    let t = Instant::now();
    let scene = scene_sampler::builtin(name)?.into_3d()?;
    let t_scene = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let bvh = SceneBvh::new(&scene);
    let t_bvh = t.elapsed().as_secs_f64();
    println!(
        "{name}: {} triangles, generated in {t_scene:.1} s, BVH {t_bvh:.1} s",
        scene.faces.len()
    );
    // 200 probes, area-uniform over the non-emitting faces (as `cargo xtask bench`).
    let points = SurfaceSampler::new(&scene)
        .spread(200, |p| scene.faces[p.face as usize].emission.is_zero());
    let t = Instant::now();
    let reference = baselines::pointwise::radiosity_at(&scene, &bvh, &points, 20_000, 7);
    println!(
        "reference: 200 probes, 20000 paths each, {:.1} s",
        t.elapsed().as_secs_f64()
    );
    let domain = Domain::ThreeD(KernelSampler::new(&scene, &bvh));
    let emitters = Emitters::new(&domain);
    for theta in thetas {
        let config = SolveConfig {
            kernel_cells: cells,
            shading_cells: cells / 2,
            surface_clusters: SurfaceClusters {
                theta,
                ..SurfaceClusters::default()
            },
            ..SolveConfig::default()
        };
        let t = Instant::now();
        let trained = gcr::solve(&domain, &config, &mut |_| {})?;
        let seconds = t.elapsed().as_secs_f64();
        print!(
            "θ = {theta}: solve {seconds:.1} s (FEM {:.1} s), energy factor {:?}",
            trained.metrics.seconds.fem, trained.metrics.energy_balance
        );
        for gather in [GatherMode::Kernel, GatherMode::Rays] {
            let config = SolveConfig { gather, ..config };
            let t = Instant::now();
            let at: Vec<_> = points.iter().map(|p| (p.point, p.normal, p.face)).collect();
            let values: Vec<[f64; 3]> =
                radiosity_at_points(&domain, &trained, &emitters, &config, &at)?
                    .into_iter()
                    .map(|g| g.radiosity)
                    .collect();
            let (mut num, mut den, mut sum_v, mut sum_r) = (0.0, 0.0, 0.0, 0.0);
            for (v, r) in values.iter().zip(&reference) {
                for b in 0..3 {
                    num += (v[b] - r.mean[b]).powi(2);
                    den += r.mean[b].powi(2);
                    sum_v += v[b];
                    sum_r += r.mean[b];
                }
            }
            // bias: Σ B / Σ B_ref − 1 over probes and bands (a systematic offset, not noise).
            print!(
                " | {}: rel L2 {:.3}, bias {:+.3} ({:.1} s)",
                gather.name(),
                (num / den).sqrt(),
                sum_v / sum_r - 1.0,
                t.elapsed().as_secs_f64()
            );
        }
        println!();
    }
    if let Some(peak) = gcr::peak_memory_bytes() {
        println!("peak resident memory {:.0} MiB", peak as f64 / 1048576.0);
    }
    Ok(())
}
