//! HR kernel error at 16 / 100 / 500 links on the two Flatland scenes of sec. 4.1 (figs. 4.1a, 4.6a), with every
//! normalization of [`baselines::hierarchical::KernelError`], both partial-visibility rules, and the grid
//! dependence of the corner's numbers — the tables of `docs/design/hierarchical.md`.
//!
//! `cargo run --release -p baselines --example hierarchical_kernel`

use baselines::hierarchical::*;
use scene_sampler::builtin;
use std::time::Instant;

fn main() -> Result<()> {
    let grid = 1024;
    println!("## Kernel error, goal function K·E, {grid}² midpoint grid\n");
    println!(
        "| scene | budget | partial rule | links | ε | one solve | rel. RMS | rel. RMS (clamped) | RMS/max | MSE/max² | RMS/mean |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|");
    let mut corner_runs = Vec::new();
    for name in ["flatland-corner", "flatland-blocker"] {
        let scene = builtin(name)?.into_flatland()?;
        let r_min = 1e-3 * scene.diagonal();
        for target in [16usize, 100, 500] {
            for partial in [
                PartialVisibility::UnoccludedBound,
                PartialVisibility::Refine,
            ] {
                let base = FlatHrConfig {
                    min_length: budget::min_length_for(&scene, target),
                    partial,
                    ..FlatHrConfig::default()
                };
                let r = match solve_for_links(&scene, target, base, 0.05) {
                    Ok(r) => r,
                    Err(e) => {
                        println!("| {name} | {target} | {partial:?} | — | {e} | | | | | | |");
                        continue;
                    }
                };
                let t1 = Instant::now();
                let hr = FlatHr::solve(
                    &scene,
                    FlatHrConfig {
                        epsilon: r.epsilon,
                        ..base
                    },
                )?;
                let solve = t1.elapsed();
                let e = kernel_error(&hr, grid, Weight::Emission)?;
                let c = kernel_error_clamped(&hr, grid, Weight::Emission, r_min)?;
                println!(
                    "| {name} | {target} | {partial:?} | {} | {:.3e} | {:.1} ms | {:.1} % | {:.1} % | {:.3} % | {:.2e} | {:.0} % |",
                    hr.link_count(),
                    r.epsilon,
                    solve.as_secs_f64() * 1e3,
                    100.0 * e.relative_rms,
                    100.0 * c.relative_rms,
                    100.0 * e.rms_over_max,
                    e.mse_over_max2,
                    100.0 * e.rms_over_mean,
                );
                if name == "flatland-corner" && partial == PartialVisibility::UnoccludedBound {
                    corner_runs.push((target, hr));
                }
            }
        }
    }
    println!("\n## flatland-corner: dependence on the grid (K·E, unclamped)\n");
    println!("| budget | grid | rel. RMS | RMS/max | max K·E |");
    println!("|---|---|---|---|---|");
    for (target, hr) in &corner_runs {
        for n in [128usize, 256, 512, 1024, 2048] {
            let e = kernel_error(hr, n, Weight::Emission)?;
            println!(
                "| {target} | {n} | {:.1} % | {:.3} % | {:.1} |",
                100.0 * e.relative_rms,
                100.0 * e.rms_over_max,
                e.max_exact
            );
        }
    }
    println!("\n## flatland-corner: radiosity against a uniform mesh (256 elements per segment)\n");
    println!("| budget | links | leaves | relative L2 error of B |");
    println!("|---|---|---|---|");
    let scene = builtin("flatland-corner")?.into_flatland()?;
    let fine = uniform_mesh(&scene, 256);
    for (target, hr) in &corner_runs {
        let (mut d2, mut r2) = (0.0, 0.0);
        for &(seg, t0, t1, b) in &fine {
            let bh = hr.leaf_at(seg, 0.5 * (t0 + t1))?.radiosity.0[0];
            d2 += (bh - b) * (bh - b);
            r2 += b * b;
        }
        println!(
            "| {target} | {} | {} | {:.2} % |",
            hr.link_count(),
            hr.leaves().count(),
            100.0 * (d2 / r2).sqrt()
        );
    }
    Ok(())
}

/// Classical radiosity on a uniform mesh of `n` elements per segment (crossed-strings form factors, no
/// occlusion: for scenes without blockers), Jacobi to 1e-13: `(segment, t0, t1, B)` per element.
fn uniform_mesh(scene: &scene_sampler::FlatlandScene, n: usize) -> Vec<(u32, f64, f64, f64)> {
    use baselines::hierarchical::strings::{Piece, form_factor};
    let mut el = Vec::new();
    for (k, s) in scene.segments.iter().enumerate() {
        for m in 0..n {
            let (t0, t1) = (m as f64 / n as f64, (m + 1) as f64 / n as f64);
            el.push((
                k as u32,
                t0,
                t1,
                Piece::new(s.point(t0), s.point(t1), k as u32),
            ));
        }
    }
    let m = el.len();
    let mut f = vec![0.0; m * m];
    for a in 0..m {
        for b in 0..m {
            if el[a].0 != el[b].0 {
                f[a * m + b] = form_factor(&el[a].3, &el[b].3);
            }
        }
    }
    let rho: Vec<f64> = el
        .iter()
        .map(|e| scene.segments[e.0 as usize].rho.0[0])
        .collect();
    let em: Vec<f64> = el
        .iter()
        .map(|e| scene.segments[e.0 as usize].emission.0[0])
        .collect();
    let mut b = em.clone();
    for _ in 0..1000 {
        let nb: Vec<f64> = (0..m)
            .map(|a| em[a] + rho[a] * (0..m).map(|c| f[a * m + c] * b[c]).sum::<f64>())
            .collect();
        let d = nb
            .iter()
            .zip(&b)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f64::max);
        b = nb;
        if d < 1e-13 {
            break;
        }
    }
    el.iter().zip(b).map(|(e, b)| (e.0, e.1, e.2, b)).collect()
}
