//! Diagnostics of the kernel network: B_refl by kernel collection against the reference's
//! B − E at the probes, and the pointwise fit of K·s on the final samples.
//!
//! `cargo run --release -p gcr --example kernel_diagnostics -- cornell-box 200`

use gcr::{Domain, SolveConfig};
use scene_sampler::{KernelSampler, Scene, SceneBvh, SurfacePoint};

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let name = args.get(1).map_or("cornell-box", |s| s.as_str());
    let cells: usize = args.get(2).map_or(Ok(200), |s| s.parse())?;
    let scene = scene_sampler::builtin(name)?.into_3d()?;
    let bvh = SceneBvh::new(&scene);
    let probes = scene_sampler::read_probes(format!("scenes/{name}.probes.txt"))?;
    let points = scene.snap_probes(&probes, name)?;
    let reference = baselines::pointwise::radiosity_at(&scene, &bvh, &points, 20_000, 7);
    let domain = Domain::ThreeD(KernelSampler::new(&scene, &bvh));
    let config = SolveConfig {
        kernel_cells: cells,
        shading_cells: cells / 2,
        ..SolveConfig::default()
    };
    let t = std::time::Instant::now();
    let (mut kernel, mut shading) = gcr::make_networks(&domain, &config)?;
    let trained = gcr::train(&domain, &mut kernel, &mut shading, &config, &mut |_| {})?;
    let secs = t.elapsed().as_secs_f64();
    let (mut num, mut den, mut sk, mut sr) = (0.0, 0.0, 0.0, 0.0);
    for (p, r) in points.iter().zip(&reference) {
        let e = scene.faces[p.face as usize].emission;
        if !e.is_zero() {
            continue;
        }
        let k = trained.reflected_kernel(p.point, p.normal);
        print!("  ref");
        for b in 0..3 {
            print!(" {:.4}", r.mean[b]);
        }
        print!("  kernel");
        for b in 0..3 {
            print!(" {:.4}", k[b]);
            num += (k[b] - r.mean[b]).powi(2);
            den += r.mean[b].powi(2);
            sk += k[b];
            sr += r.mean[b];
        }
        println!();
    }
    // Pointwise fit on the samples.
    let (mut fnum, mut fden) = (0.0, 0.0);
    let mut input = Vec::new();
    let mut out = vec![0.0; 3];
    for smp in &trained.samples {
        domain.kernel_input(&smp.ray, &mut input);
        kernel.predict_global(&input, &mut out);
        for b in 0..domain.bands() {
            let t = smp.ray.kernel[b] * smp.s[b];
            fnum += (out[b] - t).powi(2);
            fden += t * t;
        }
    }
    print_target_quantiles(&trained);
    least_squares_fit(&scene, &trained, &points, &reference);
    println!(
        "{name} cells={cells} B_refl rel_l2={:.3} sum_ratio={:.3} fit_rel_rms={:.3} samples={} seconds={secs:.1}",
        (num / den).sqrt(),
        sk / sr,
        (fnum / fden).sqrt(),
        trained.samples.len()
    );
    Ok(())
}

/// The distribution of the kernel network's targets K·s (band 0) on the final samples.
fn print_target_quantiles(trained: &gcr::Trained) {
    let mut t: Vec<f64> = trained
        .samples
        .iter()
        .map(|s| s.ray.kernel[0] * s.s[0])
        .collect();
    t.sort_by(f64::total_cmp);
    let q = |f: f64| t[((t.len() - 1) as f64 * f) as usize];
    let total: f64 = t.iter().map(|v| v * v).sum();
    let top: f64 = t[t.len() * 99 / 100..].iter().map(|v| v * v).sum();
    println!(
        "targets: zero={:.2} p50={:.3e} p90={:.3e} p99={:.3e} max={:.3e} top1%_share_of_sumsq={:.3}",
        t.iter().filter(|v| **v == 0.0).count() as f64 / t.len() as f64,
        q(0.5),
        q(0.9),
        q(0.99),
        q(1.0),
        top / total
    );
}

/// Least-squares output weights on the same centres and widths (ridge 1e-6·trace/n): their fit
/// on the samples and B_refl at the probes.
fn least_squares_fit(
    scene: &Scene,
    trained: &gcr::Trained,
    points: &[SurfacePoint],
    reference: &[baselines::Estimate],
) {
    let n = trained.kernel.len();
    let m = trained.samples.len();
    let mut phi = nalgebra::DMatrix::<f64>::zeros(m, n);
    let mut rhs = nalgebra::DMatrix::<f64>::zeros(m, 3);
    for (i, smp) in trained.samples.iter().enumerate() {
        for o in 0..n {
            let d2 = trained.kernel.wx[o].distance_squared(smp.ray.x)
                + trained.kernel.wy[o].distance_squared(smp.ray.y);
            phi[(i, o)] = (-d2 / trained.kernel.width[o].powi(2)).exp();
        }
        for b in 0..3 {
            rhs[(i, b)] = smp.ray.kernel[b] * smp.s[b];
        }
    }
    let mut a = phi.transpose() * &phi;
    let tr = a.trace() / n as f64;
    for o in 0..n {
        a[(o, o)] += 1e-6 * tr;
    }
    let v = a.cholesky().unwrap().solve(&(phi.transpose() * &rhs));
    let fit = &phi * &v - &rhs;
    let mut ls = trained.kernel.clone();
    for o in 0..n {
        for b in 0..3 {
            ls.v[o][b] = v[(o, b)];
        }
    }
    let (mut lnum, mut lden) = (0.0, 0.0);
    for (p, r) in points.iter().zip(reference) {
        if !scene.faces[p.face as usize].emission.is_zero() {
            continue;
        }
        let k = gcr::stages::reflected_from_kernel(&ls, &trained.sender, p.point, p.normal);
        for b in 0..3 {
            lnum += (k[b] - r.mean[b]).powi(2);
            lden += r.mean[b].powi(2);
        }
    }
    println!(
        "least squares: fit_rel_rms={:.3} B_refl rel_l2={:.3}",
        fit.norm() / rhs.norm(),
        (lnum / lden).sqrt()
    );
}
