//! 3-D HR in the furnace (closed unit cube, E = 0.7, ρ = 0.6, exact B = E/(1 − ρ) = 1.75): the error of the
//! leaves' B as the BF threshold ε falls, for `docs/design/hierarchical.md`.
//!
//! `cargo run --release -p baselines --example hierarchical_furnace`

use baselines::hierarchical::*;
use scene_sampler::Spectrum;
use scene_sampler::builtin::furnace;
use std::time::Instant;

fn main() -> Result<()> {
    let (e, rho) = (0.7, 0.6);
    let want = e / (1.0 - rho);
    let scene = furnace(Spectrum::grey(e), Spectrum::grey(rho));
    println!(
        "| ε | links | leaves | solve | max leaf error | area-weighted mean abs. error | area with error > 5 % |"
    );
    println!("|---|---|---|---|---|---|---|");
    for eps in [100.0, 0.05, 0.02, 0.01, 0.005, 0.002] {
        let t = Instant::now();
        let hr = TriHr::solve(
            &scene,
            TriHrConfig {
                epsilon: eps,
                min_area: 0.5 / 256.0,
                tolerance: 1e-13,
                ..TriHrConfig::default()
            },
        )?;
        let dt = t.elapsed().as_secs_f64();
        let (mut area, mut l1, mut bad, mut worst) = (0.0, 0.0, 0.0, 0.0f64);
        for l in hr.leaves() {
            let err = (l.radiosity.0[0] / want - 1.0).abs();
            worst = worst.max(err);
            area += l.area;
            l1 += l.area * err;
            if err > 0.05 {
                bad += l.area;
            }
        }
        println!(
            "| {eps} | {} | {} | {dt:.2} s | {:.2e} | {:.2e} | {:.1} % |",
            hr.link_count(),
            hr.leaves().count(),
            worst,
            l1 / area,
            100.0 * bad / area
        );
    }
    Ok(())
}
