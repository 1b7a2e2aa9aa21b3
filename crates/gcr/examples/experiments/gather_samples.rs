//! How much of the ray gather's error is its own Monte-Carlo noise: one solve, then the ray gather
//! (`--gather rays`) with more and more shadow and indirect rays per point, against the path-traced
//! reference at points spread area-uniformly over the non-emitting faces.
//!
//! `cargo run --release -p gcr --example gather_samples -- cornell-box 200 [points] [reference paths] [seed] [rays,…] [samples per cell] [min support]`
//!
//! `rays,…` lists the ray counts per point to try (default `16,64,256,1024,4096`); the last two
//! set `SolveConfig::samples_per_cell` and `SolveConfig::projection_min_support` (defaults: the
//! solver's). The reference is cached in the temporary directory.
//!
//! Prints one line per sample count: relative L2 of B (and of B − E, the part the gather
//! estimates) and the gather's seconds.

use gcr::{Domain, Emitters, GatherMode, GatherSamples, SolveConfig, radiosity_at_points};
use scene_sampler::{KernelSampler, Scene, SceneBvh, SurfacePoint, SurfaceSampler};

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let name = args.get(1).map_or("cornell-box", |s| s.as_str());
    let cells: usize = args.get(2).map_or(Ok(200), |s| s.parse())?;
    let count: usize = args.get(3).map_or(Ok(200), |s| s.parse())?;
    let paths: usize = args.get(4).map_or(Ok(100_000), |s| s.parse())?;
    let seed: u64 = args.get(5).map_or(Ok(1), |s| s.parse())?;
    let rays: Vec<usize> = args
        .get(6)
        .map_or("16,64,256,1024,4096", |s| s.as_str())
        .split(',')
        .map(|s| s.parse())
        .collect::<Result<_, _>>()?;
    let defaults = SolveConfig::default();
    let samples_per_cell: usize = args
        .get(7)
        .map_or(Ok(defaults.samples_per_cell), |s| s.parse())?;
    let min_support: f64 = args
        .get(8)
        .map_or(Ok(defaults.projection_min_support), |s| s.parse())?;
    let scene = scene_sampler::builtin(name)?.into_3d()?;
    let bvh = SceneBvh::new(&scene);
    // Non-emitting points, unless every face emits (the furnace).
    let all_emit = scene.faces.iter().all(|f| !f.emission.is_zero());
    let points = SurfaceSampler::new(&scene).spread(count, |p| {
        all_emit || scene.faces[p.face as usize].emission.is_zero()
    });
    let reference = cached_reference(&scene, &bvh, &points, name, paths)?;
    let domain = Domain::ThreeD(KernelSampler::new(&scene, &bvh));
    let emitters = Emitters::new(&domain);
    let config = SolveConfig {
        kernel_cells: cells,
        shading_cells: cells / 2,
        seed,
        samples_per_cell,
        projection_min_support: min_support,
        ..defaults
    };
    let trained = gcr::solve(&domain, &config, &mut |_| {})?;
    let at: Vec<_> = points.iter().map(|p| (p.point, p.normal, p.face)).collect();
    let noise: f64 = {
        let (mut num, mut den) = (0.0, 0.0);
        for r in &reference {
            for k in 0..3 {
                num += r.std_error[k].powi(2);
                den += r.mean[k].powi(2);
            }
        }
        (num / den).sqrt()
    };
    println!(
        "{name}, {cells} cells, {} points, reference {paths} paths (its own relative L2 noise {:.2} %)",
        points.len(),
        100.0 * noise
    );
    println!("| rays per point (direct + indirect) | rel. L2 of B | rel. L2 of B − E | gather s |");
    println!("|---:|---:|---:|---:|");
    for n in rays {
        let config = SolveConfig {
            gather: GatherMode::Rays,
            gather_samples: GatherSamples {
                direct: n,
                indirect: n,
            },
            ..config
        };
        let t = std::time::Instant::now();
        let got = radiosity_at_points(&domain, &trained, &emitters, &config, &at)?;
        let seconds = t.elapsed().as_secs_f64();
        let (mut num, mut den, mut den_r) = (0.0, 0.0, 0.0);
        for ((g, r), p) in got.iter().zip(&reference).zip(&points) {
            let e = scene.faces[p.face as usize].emission.0;
            for k in 0..3 {
                num += (g.radiosity[k] - r.mean[k]).powi(2);
                den += r.mean[k].powi(2);
                den_r += (r.mean[k] - e[k]).powi(2);
            }
        }
        println!(
            "| {n} + {n} | {:.4} | {:.4} | {seconds:.2} |",
            (num / den).sqrt(),
            (num / den_r).sqrt()
        );
    }
    Ok(())
}

/// The path-traced reference at `points`: the slow part of a sweep over seeds or budgets, so it
/// is cached in the system's temporary directory, keyed by everything it depends on.
fn cached_reference(
    scene: &Scene,
    bvh: &SceneBvh,
    points: &[SurfacePoint],
    name: &str,
    paths: usize,
) -> anyhow::Result<Vec<baselines::Estimate>> {
    let cache = std::env::temp_dir().join(format!(
        "gcr-gather-samples-{name}-{}-{paths}.txt",
        points.len()
    ));
    let reference = match std::fs::read_to_string(&cache) {
        Ok(text) => text
            .lines()
            .map(|l| {
                let v: Vec<f64> = l
                    .split(' ')
                    .map(|x| x.parse().unwrap_or(f64::NAN))
                    .collect();
                baselines::Estimate {
                    mean: [v[0], v[1], v[2]],
                    std_error: [v[3], v[4], v[5]],
                    paths,
                }
            })
            .collect(),
        Err(_) => {
            let r = baselines::pointwise::radiosity_at(scene, bvh, points, paths, 0x5EED);
            let text: String = r
                .iter()
                .map(|e| {
                    let [a, b, c] = e.mean;
                    let [d, f, g] = e.std_error;
                    format!("{a:e} {b:e} {c:e} {d:e} {f:e} {g:e}\n")
                })
                .collect();
            std::fs::write(&cache, text)?;
            r
        }
    };
    anyhow::ensure!(
        reference.len() == points.len(),
        "stale cache {}",
        cache.display()
    );
    Ok(reference)
}
