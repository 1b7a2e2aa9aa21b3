//! Benchmarks of the `isgcs` group: growth time of the dissertation-default network (Franke's
//! function, n = 2, k = 2, λ = 300, to 500 cells; a smooth 6-D function, n = 6, k = 4, to 1400
//! cells) on one core, and the cost per training step against the number of cells (sec. 2.6
//! claims it is constant). Writes `benchmarks-isgcs.md` and `figures/isgcs-step-cost.png`.

use crate::ctx::Ctx;
use anyhow::Result;
use isgcs::test_functions::{franke, smooth6};
use isgcs::{Isgcs, Params};
use plotters::prelude::*;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::fmt::Write as _;
use std::time::Instant;

/// One growth run: total seconds and (cells, nanoseconds per step) per block of λ steps.
struct Growth {
    label: String,
    cells: usize,
    steps: u64,
    seconds: f64,
    cost: Vec<(usize, f64)>,
    /// (cells, mean number of cells in a Gaussian support) at the end of each block.
    support: Vec<(usize, f64)>,
}

/// Grows a thesis-default network on uniform samples of [0, 1]ⁿ labelled by `f` to `cells`
/// cells, timing every block of λ steps (one insertion each).
fn grow(
    label: &str,
    n: usize,
    k: usize,
    cells: usize,
    f: &dyn Fn(&[f64]) -> f64,
) -> Result<Growth> {
    let params = Params::thesis();
    let init: Vec<Vec<f64>> = (0..=k)
        .map(|i| (0..n).map(|a| if a + 1 == i { 0.7 } else { 0.3 }).collect())
        .collect();
    let mut net = Isgcs::new(params, n, 1, k, init)?;
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    let mut x = vec![0.0; n];
    let mut cost = Vec::new();
    let mut support = Vec::new();
    let mut cells_in: Vec<(usize, f64)> = Vec::new();
    let mut probe = ChaCha8Rng::seed_from_u64(2);
    let mut measured = std::time::Duration::ZERO;
    let start = Instant::now();
    while net.len() < cells {
        let t = Instant::now();
        for _ in 0..params.lambda {
            x.iter_mut().for_each(|v| *v = rng.random());
            let y = f(&x);
            net.train(&x, &[y], None);
        }
        cost.push((
            net.len(),
            t.elapsed().as_secs_f64() * 1e9 / params.lambda as f64,
        ));
        // Support size at 16 random points (outside the timed blocks; its time is subtracted).
        let t = Instant::now();
        let mut total = 0;
        for _ in 0..16 {
            x.iter_mut().for_each(|v| *v = probe.random());
            net.support(&x, &mut cells_in);
            total += cells_in.len();
        }
        support.push((net.len(), total as f64 / 16.0));
        measured += t.elapsed();
    }
    Ok(Growth {
        label: label.to_string(),
        cells: net.len(),
        steps: net.steps(),
        seconds: (start.elapsed() - measured).as_secs_f64(),
        cost,
        support,
    })
}

fn plot(path: &std::path::Path, runs: &[Growth]) -> Result<()> {
    let e = |m: String| anyhow::anyhow!("plotting: {m}");
    let xmax = runs.iter().map(|r| r.cells).max().unwrap_or(1) as f64;
    let ymax = runs
        .iter()
        .flat_map(|r| r.cost.iter().map(|c| c.1))
        .fold(1.0f64, f64::max);
    crate::plot::png(path, 720, 420, |root| {
        let mut chart = ChartBuilder::on(root)
            .caption("isgcs: cost per training step", ("sans-serif", 18))
            .margin(10)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d(0.0..xmax * 1.02, 0.0..ymax * 1.1)
            .map_err(|x| e(x.to_string()))?;
        chart
            .configure_mesh()
            .x_desc("cells z")
            .y_desc("ns per step")
            .draw()
            .map_err(|x| e(x.to_string()))?;
        for (r, colour) in runs.iter().zip([BLUE, RED]) {
            chart
                .draw_series(LineSeries::new(
                    r.cost.iter().map(|&(z, c)| (z as f64, c)),
                    colour.stroke_width(1),
                ))
                .map_err(|x| e(x.to_string()))?
                .label(r.label.clone())
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], colour));
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .position(SeriesLabelPosition::UpperLeft)
            .draw()
            .map_err(|x| e(x.to_string()))?;
        Ok(())
    })?;
    image::open(path)?.to_rgb8().save(path)?;
    Ok(())
}

/// Mean of `series` over the blocks whose cell count lies in [lo, hi).
fn mean_in(series: &[(usize, f64)], lo: usize, hi: usize) -> Option<f64> {
    let v: Vec<f64> = series
        .iter()
        .filter(|c| c.0 >= lo && c.0 < hi)
        .map(|c| c.1)
        .collect();
    (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64)
}

/// Runs this group's benchmarks and writes its report into `ctx.out`.
pub fn run(ctx: &Ctx) -> Result<()> {
    // One core, as the issue asks (the crate's training is sequential; the pool makes sure).
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build()?;
    pool.install(|| body(ctx))
}

fn body(ctx: &Ctx) -> Result<()> {
    let (c2, c6) = if ctx.quick { (60, 60) } else { (500, 1400) };
    let runs = [
        grow("Franke, n = 2, k = 2", 2, 2, c2, &|x| franke(x[0], x[1]))?,
        grow("smooth6, n = 6, k = 4", 6, 4, c6, &|x| smooth6(x))?,
    ];
    let dir = ctx.out.join("figures");
    std::fs::create_dir_all(&dir)?;
    plot(&dir.join("isgcs-step-cost.png"), &runs)?;
    let mut md = format!(
        "# `isgcs` benchmarks\n\n\
         Command: `cargo xtask bench --only isgcs{}` (release, one rayon thread; the machine is shared \
         with other jobs, so absolute times are noisy: compare the ratios within one run). \
         Networks with the dissertation's defaults (`Params::thesis()`, λ = 300) trained on uniform \
         random samples, growing from one k-simplex until the cell budget; times include drawing the \
         samples and evaluating the goal function.\n\n\
         | run | cells | steps | seconds | issue target |\n|---|---:|---:|---:|---|\n",
        if ctx.quick { " --quick" } else { "" }
    );
    for (r, target) in runs
        .iter()
        .zip(["< 0.5 s at 500 cells", "< 5 s at 1400 cells"])
    {
        let _ = writeln!(
            md,
            "| {} | {} | {} | {:.2} | {target} |",
            r.label, r.cells, r.steps, r.seconds
        );
    }
    md.push_str(
        "\n## Cost per training step against the number of cells\n\n\
         Nanoseconds per step, averaged over the blocks of λ steps that ended in the given range of \
         cell counts (sec. 2.6 claims a constant cost per step), and the mean number of cells in the \
         Gaussian support (|x − w_i| < 4 d_i) at 16 random points after each block. A step scans all \
         cells once (BMU and support, exact) and decays every resource, then evaluates the support's \
         Gaussians: its cost grows with z and with the support size.\n\n\
         | cells | ",
    );
    md.push_str(
        &runs
            .iter()
            .map(|r| format!("{} (ns/step) | support", r.label))
            .collect::<Vec<_>>()
            .join(" | "),
    );
    md.push_str(" |\n|---:|");
    md.push_str(&"---:|".repeat(2 * runs.len()));
    md.push('\n');
    let edges: Vec<usize> = [10, 50, 100, 200, 400, 700, 1000, 1401]
        .into_iter()
        .filter(|&c| c <= c6.max(c2) + 1)
        .collect();
    for w in edges.windows(2) {
        let cols: Vec<String> = runs
            .iter()
            .map(|r| {
                let f = |v: Option<f64>| v.map_or("–".into(), |c| format!("{c:.0}"));
                format!(
                    "{} | {}",
                    f(mean_in(&r.cost, w[0], w[1])),
                    f(mean_in(&r.support, w[0], w[1]))
                )
            })
            .collect();
        let _ = writeln!(md, "| {}–{} | {} |", w[0], w[1] - 1, cols.join(" | "));
    }
    md.push_str("\n![cost per step](figures/isgcs-step-cost.png)\n");
    std::fs::write(ctx.out.join("benchmarks-isgcs.md"), md)?;
    for r in &runs {
        println!(
            "isgcs bench: {}: {} cells, {} steps, {:.2} s",
            r.label, r.cells, r.steps, r.seconds
        );
    }
    Ok(())
}
