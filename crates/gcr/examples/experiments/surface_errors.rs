//! Where the networks' reflected radiosity is wrong: per object of the scene, the mean of B_refl
//! (kernel collection) against the path-traced reference's B − E, their relative L2 difference,
//! and the ray gather's error there.
//!
//! `cargo run --release -p gcr --example surface_errors -- cornell-box 400 [points] [paths] [samples per cell] [facing]`
//! (`facing`: with [`SolveConfig::kernel_facing`])
//!
//! The ray gather averages B_refl over the hemisphere it sees, so pointwise errors that cancel
//! within an object matter less than a wrong mean per object; this prints both.

use baselines::pointwise::Estimate;
use gcr::Gathered;
use gcr::{Domain, Emitters, GatherMode, SolveConfig, radiosity_at_points};
use scene_sampler::{KernelSampler, Scene, SceneBvh, SurfacePoint, SurfaceSampler};

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let name = args.get(1).map_or("cornell-box", |s| s.as_str());
    let cells: usize = args.get(2).map_or(Ok(400), |s| s.parse())?;
    let count: usize = args.get(3).map_or(Ok(1000), |s| s.parse())?;
    let paths: usize = args.get(4).map_or(Ok(4000), |s| s.parse())?;
    let per_cell: usize = args.get(5).map_or(Ok(10), |s| s.parse())?;
    let kernel_facing = args.get(6).is_some_and(|s| s == "facing");
    let scene = scene_sampler::builtin(name)?.into_3d()?;
    let bvh = SceneBvh::new(&scene);
    // Non-emitting points, unless every face emits (the furnace).
    let all_emit = scene.faces.iter().all(|f| !f.emission.is_zero());
    let points = SurfaceSampler::new(&scene).spread(count, |p| {
        all_emit || scene.faces[p.face as usize].emission.is_zero()
    });
    let reference = baselines::pointwise::radiosity_at(&scene, &bvh, &points, paths, 0x5EED);
    let domain = Domain::ThreeD(KernelSampler::new(&scene, &bvh));
    let emitters = Emitters::new(&domain);
    let config = SolveConfig {
        kernel_cells: cells,
        shading_cells: cells / 2,
        samples_per_cell: per_cell,
        kernel_facing,
        ..SolveConfig::default()
    };
    let trained = gcr::solve(&domain, &config, &mut |_| {})?;
    let at: Vec<_> = points.iter().map(|p| (p.point, p.normal, p.face)).collect();
    let kernel = radiosity_at_points(
        &domain,
        &trained,
        &emitters,
        &SolveConfig {
            gather: GatherMode::Kernel,
            ..config.clone()
        },
        &at,
    )?;
    let rays = radiosity_at_points(&domain, &trained, &emitters, &config, &at)?;
    let acc = per_object_sums(&scene, &points, &reference, &kernel, &rays);
    let tr = print_per_object(&scene, &acc, &reference, name, cells, count, paths);
    // Oracle: the kernel collection scaled per object and band to the reference's mean.
    let factor: Vec<[f64; 3]> = acc
        .0
        .iter()
        .map(|a| {
            std::array::from_fn(|b| {
                if a[b][1] != 0.0 {
                    a[b][0] / a[b][1]
                } else {
                    1.0
                }
            })
        })
        .collect();
    let oracle: Vec<_> = at
        .iter()
        .enumerate()
        .map(|(i, &(y, nrm, face))| {
            gcr::stages::gather(
                &domain,
                &emitters,
                y,
                nrm,
                face,
                config.gather_samples,
                i as u64,
                &|x, n, f| {
                    let k = trained.reflected_kernel(x, n);
                    let s = factor[scene.faces[f as usize].object as usize];
                    std::array::from_fn(|b| k[b] * s[b])
                },
            )
        })
        .collect();
    let e2: f64 = oracle
        .iter()
        .zip(&reference)
        .map(|(g, r)| {
            (0..3)
                .map(|b| (g.radiosity[b] - r.mean[b]).powi(2))
                .sum::<f64>()
        })
        .sum();
    print_worst(&scene, &points, &reference, &rays, &kernel);
    println!(
        "rays with B_refl scaled per object to the reference's means: {:.3}",
        (e2 / tr).sqrt()
    );
    Ok(())
}

/// Per object and band: Σ ref, Σ kernel, Σ (kernel − ref)², Σ ref², Σ (rays − ref)²; with the
/// point count per object.
type Sums = (Vec<[[f64; 5]; 3]>, Vec<usize>);

fn per_object_sums(
    scene: &Scene,
    points: &[SurfacePoint],
    reference: &[Estimate],
    kernel: &[Gathered],
    rays: &[Gathered],
) -> Sums {
    let objects = scene.objects.len();
    let mut acc = vec![[[0.0f64; 5]; 3]; objects];
    let mut n = vec![0usize; objects];
    for (i, p) in points.iter().enumerate() {
        let f = &scene.faces[p.face as usize];
        let o = f.object as usize;
        n[o] += 1;
        for b in 0..3 {
            let r = reference[i].mean[b] - f.emission.0[b];
            let k = kernel[i].radiosity[b] - f.emission.0[b];
            let g = rays[i].radiosity[b];
            let a = &mut acc[o][b];
            a[0] += r;
            a[1] += k;
            a[2] += (k - r).powi(2);
            a[3] += r * r;
            a[4] += (g - reference[i].mean[b]).powi(2);
        }
    }
    (acc, n)
}

/// Prints the per-object table; returns Σ ref² (the normalization of the relative errors).
fn print_per_object(
    scene: &Scene,
    (acc, n): &Sums,
    reference: &[Estimate],
    name: &str,
    cells: usize,
    count: usize,
    paths: usize,
) -> f64 {
    let objects = scene.objects.len();
    println!("{name}, {cells} cells, {count} area-uniform points, reference {paths} paths");
    println!(
        "| object | points | mean B_refl ref (r g b) | mean kernel / ref − 1 (r g b) | rel. L2 kernel | rel. L2 rays (of B) |"
    );
    println!("|---|---:|---|---|---:|---:|");
    let (mut tk, mut tr, mut tg) = (0.0, 0.0, 0.0);
    for o in 0..objects {
        if n[o] == 0 {
            continue;
        }
        let a = &acc[o];
        let m = n[o] as f64;
        let bias: Vec<String> = (0..3)
            .map(|b| format!("{:+.3}", a[b][1] / a[b][0] - 1.0))
            .collect();
        let mean: Vec<String> = (0..3).map(|b| format!("{:.3}", a[b][0] / m)).collect();
        let k2: f64 = (0..3).map(|b| a[b][2]).sum();
        let r2: f64 = (0..3).map(|b| a[b][3]).sum();
        let g2: f64 = (0..3).map(|b| a[b][4]).sum();
        tk += k2;
        tr += r2;
        tg += g2;
        println!(
            "| {} | {} | {} | {} | {:.3} | {:.3} |",
            scene.objects[o],
            n[o],
            mean.join(" "),
            bias.join(" "),
            (k2 / r2).sqrt(),
            (g2 / r2).sqrt()
        );
    }
    let noise: f64 = reference
        .iter()
        .map(|r| (0..3).map(|b| r.std_error[b].powi(2)).sum::<f64>())
        .sum();
    println!(
        "all: rel. L2 kernel B_refl {:.3}, rays (of B) {:.3}, reference noise {:.3}",
        (tk / tr).sqrt(),
        (tg / tr).sqrt(),
        (noise / tr).sqrt()
    );
    tr
}

/// The 20 points with the largest squared error of the ray gather.
fn print_worst(
    scene: &Scene,
    points: &[SurfacePoint],
    reference: &[Estimate],
    rays: &[Gathered],
    kernel: &[Gathered],
) {
    let mut worst: Vec<(f64, usize)> = rays
        .iter()
        .zip(reference)
        .enumerate()
        .map(|(i, (g, r))| {
            let d: f64 = (0..3).map(|b| (g.radiosity[b] - r.mean[b]).powi(2)).sum();
            (d, i)
        })
        .collect();
    worst.sort_by(|a, b| b.0.total_cmp(&a.0));
    let total: f64 = worst.iter().map(|w| w.0).sum();
    let mut run = 0.0;
    println!("worst points (share of the squared error, cumulative):");
    for &(d, i) in worst.iter().take(20) {
        run += d;
        let p = &points[i];
        println!(
            "  {:.3} {:.3} {} at ({:.3} {:.3} {:.3}) ref {:.3} {:.3} {:.3} rays {:.3} {:.3} {:.3} kernel {:.3}",
            d / total,
            run / total,
            scene.objects[scene.faces[p.face as usize].object as usize],
            p.point.x,
            p.point.y,
            p.point.z,
            reference[i].mean[0],
            reference[i].mean[1],
            reference[i].mean[2],
            rays[i].radiosity[0],
            rays[i].radiosity[1],
            rays[i].radiosity[2],
            kernel[i].radiosity[0],
        );
    }
}
