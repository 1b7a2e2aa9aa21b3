//! HR kernel error at 16 / 100 / 500 links on the two Flatland scenes of sec. 4.1 (figs. 4.1a, 4.6a), every
//! normalization of [`baselines::hierarchical::KernelError`], for `docs/hierarchical.md`.
//!
//! `cargo run --release -p baselines --example hierarchical_kernel [grid]` (default grid 1024).

use baselines::hierarchical::*;
use scene_sampler::builtin;
use std::time::Instant;

fn main() -> Result<()> {
    let grid: usize = std::env::args()
        .nth(1)
        .map(|a| a.parse().expect("grid must be a positive integer"))
        .unwrap_or(1024);
    println!(
        "| scene | target | links | ε | HR time | weight | rel. RMS | RMS/max | MSE/max² | RMS/mean | MSE/mean² | max K |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|");
    for name in ["flatland-corner", "flatland-blocker"] {
        let scene = builtin(name)?.into_flatland()?;
        for target in [16usize, 100, 500] {
            let base = FlatHrConfig {
                min_length: budget::min_length_for(&scene, target),
                ..FlatHrConfig::default()
            };
            let t0 = Instant::now();
            let r = solve_for_links(&scene, target, base, 0.05)?;
            // time one solve at the found ε (the search made several)
            let t1 = Instant::now();
            let hr = FlatHr::solve(
                &scene,
                FlatHrConfig {
                    epsilon: r.epsilon,
                    ..base
                },
            )?;
            let solve = t1.elapsed();
            let _search = t1 - t0;
            for weight in [Weight::Emission, Weight::None] {
                let e = kernel_error(&hr, grid, weight)?;
                println!(
                    "| {name} | {target} | {} | {:.3e} | {:.1} ms | {:?} | {:.2} % | {:.3} % | {:.2e} | {:.1} % | {:.3} | {:.1} |",
                    hr.link_count(),
                    r.epsilon,
                    solve.as_secs_f64() * 1e3,
                    weight,
                    100.0 * e.relative_rms,
                    100.0 * e.rms_over_max,
                    e.mse_over_max2,
                    100.0 * e.rms_over_mean,
                    e.mse_over_mean2,
                    e.max_exact,
                );
            }
        }
    }
    Ok(())
}
