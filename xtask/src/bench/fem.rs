//! How one FEM step's cost grows with the kernel network (issue: "the FEM step scales linearly in
//! kernel cells at fixed base size"). On `cornell-box`, networks trained to each budget are frozen
//! and the parts of a step timed separately: the sender integrals c_o (one surface integral per
//! cell: linear), and the projection's Gram matrix with its Cholesky factor (pairs of cells within
//! the support cut-off: quadratic while the supports overlap most of the network, as they do in
//! 6-D with eq. 2.10's widths). Writes `benchmarks-fem.md`.

use crate::ctx::Ctx;
use anyhow::Result;
use gcr::stages::{KernelProjection, SceneSurface, sender_integrals};
use gcr::{Domain, SolveConfig};
use scene_sampler::{KernelSampler, SceneBvh};
use std::fmt::Write;
use std::time::Instant;

/// Runs this group's benchmarks and writes its report into `ctx.out`.
pub fn run(ctx: &Ctx) -> Result<()> {
    let budgets: &[usize] = if ctx.quick {
        &[40, 80]
    } else {
        &[100, 200, 400, 800, 1400]
    };
    let scene = scene_sampler::builtin("cornell-box")?.into_3d()?;
    let bvh = SceneBvh::new(&scene);
    let domain = Domain::ThreeD(KernelSampler::new(&scene, &bvh));
    let surface = SceneSurface::of(&domain);
    let defaults = SolveConfig::default();
    let mut md = format!(
        "# FEM step against kernel cells\n\n\
         Command: `cargo xtask bench --only fem`{}. `cornell-box`, default settings, the network trained to \
         each budget, then frozen; best of 3 timings of each part on {} threads. Gram = \
         `KernelProjection::new` (every cell pair within the support cut-off {:.0e}: two sums of exact \
         triangle integrals each, then the Cholesky factor).\n\n\
         | kernel cells | sender integrals (ms) | per cell (µs) | Gram + Cholesky (ms) | non-zero Gram entries | entries / cells² | per entry (µs) |\n\
         |---:|---:|---:|---:|---:|---:|---:|\n",
        if ctx.quick { " --quick" } else { "" },
        rayon::current_num_threads(),
        defaults.projection_tolerance,
    );
    let mut rows: Vec<(f64, f64, f64)> = Vec::new();
    for &cells in budgets {
        let config = SolveConfig {
            kernel_cells: cells,
            shading_cells: cells / 2,
            ..SolveConfig::default()
        };
        let trained = gcr::solve(&domain, &config, &mut |_| {})?;
        let kernel = &trained.kernel;
        let best = |f: &mut dyn FnMut()| {
            (0..3)
                .map(|_| {
                    let t = Instant::now();
                    f();
                    t.elapsed().as_secs_f64()
                })
                .fold(f64::INFINITY, f64::min)
        };
        let sender = best(&mut || {
            std::hint::black_box(sender_integrals(
                kernel,
                &surface,
                config.projection_tolerance,
            ));
        });
        let mut entries = 0;
        let gram = best(&mut || {
            let p = KernelProjection::new(
                kernel,
                &surface,
                config.projection_tolerance,
                config.projection_rejection,
            );
            entries = p.report().gram_entries;
        });
        let z = kernel.len() as f64;
        let line = format!(
            "| {} | {:.2} | {:.1} | {:.1} | {entries} | {:.2} | {:.2} |",
            kernel.len(),
            1e3 * sender,
            1e6 * sender / z,
            1e3 * gram,
            entries as f64 / (z * z),
            1e6 * gram / entries.max(1) as f64,
        );
        println!("fem: {line}");
        writeln!(md, "{line}")?;
        rows.push((z, 1e3 * sender, 1e3 * gram));
    }
    let dir = ctx.out.join("figures");
    std::fs::create_dir_all(&dir)?;
    plot(&dir.join("fem-scaling.png"), &rows)?;
    md += "\n![FEM parts against kernel cells, log-log, with slopes 1 and 2 for reference](figures/fem-scaling.png)\n";
    md += &base_scaling(ctx, &surface, &domain)?;
    std::fs::write(ctx.out.join("benchmarks-fem.md"), md)?;
    Ok(())
}

/// The base side of a FEM step (the dissertation's: base Gram matrix, orthonormalization and the
/// receiver projections u_q = Σ_o v_o c_o β_qo) against the base size at a fixed kernel budget: the
/// shading network (the base) is kept (`skip_unused_base: false`) and trained to each budget.
fn base_scaling(ctx: &Ctx, surface: &gcr::stages::SceneSurface, domain: &Domain) -> Result<String> {
    let (kernel_cells, budgets): (usize, &[usize]) = if ctx.quick {
        (60, &[20, 40])
    } else {
        (400, &[50, 100, 200, 400, 800])
    };
    let mut md = format!(
        "\n## FEM step against base size\n\n\
         The base side of one step (`gcr::stages::fem_step`: the base's Gram matrix under the fig. 3.6 rules, its \
         orthonormalization, sender integrals and u_q = Σ_o v_o c_o β_qo) at {kernel_cells} kernel cells, with the \
         shading network kept and trained to each budget; best of 3. The default solver skips this part \
         (`skip_unused_base`) because the projected kernel does not read the base.\n\n\
         | base Gaussians | kernel cells | FEM step (ms) | per base Gaussian (µs) | per kernel × base pair (ns) |\n\
         |---:|---:|---:|---:|---:|\n"
    );
    for &shading in budgets {
        let config = SolveConfig {
            kernel_cells,
            shading_cells: shading,
            skip_unused_base: false,
            ..SolveConfig::default()
        };
        let trained = gcr::solve(domain, &config, &mut |_| {})?;
        let base = trained.fem.base.clone();
        let n = base.len();
        let secs = (0..3)
            .map(|_| {
                let b = base.clone();
                let t = Instant::now();
                let tol = gcr::stages::FemSettings::default().support_tolerance;
                let mut c = sender_integrals(&trained.kernel, surface, tol);
                std::hint::black_box(gcr::stages::fem_step(b, &trained.kernel, &mut c));
                t.elapsed().as_secs_f64()
            })
            .fold(f64::INFINITY, f64::min);
        let z = trained.kernel.len();
        let line = format!(
            "| {n} | {z} | {:.1} | {:.1} | {:.1} |",
            1e3 * secs,
            1e6 * secs / n.max(1) as f64,
            1e9 * secs / (n.max(1) * z.max(1)) as f64
        );
        println!("fem: base {line}");
        writeln!(md, "{line}")?;
    }
    md += "\nThe shading network grows with the kernel's insertions, so at a fixed kernel budget it stops near the \
           kernel's size: larger budgets repeat the last row. The base side grows faster than linearly: its Gram \
           matrix has O(n²) overlapping pairs and its orthonormalization is a dense O(n³) factorization.\n";
    Ok(md)
}

/// Log-log plot of the two parts' milliseconds against kernel cells, with lines of slope 1 and 2
/// through the first point of each for reference.
fn plot(path: &std::path::Path, rows: &[(f64, f64, f64)]) -> Result<()> {
    use plotters::prelude::*;
    let Some(&(z0, s0, g0)) = rows.first() else {
        return Ok(());
    };
    let z1 = rows.last().map_or(z0, |r| r.0).max(z0 * 1.5);
    let lo = rows
        .iter()
        .map(|r| r.1.min(r.2))
        .fold(f64::INFINITY, f64::min);
    let hi = rows.iter().map(|r| r.1.max(r.2)).fold(0.0, f64::max);
    crate::plot::png(path, 720, 480, |root| {
        let mut chart = ChartBuilder::on(root)
            .caption(
                "one FEM step's parts against kernel cells (cornell-box)",
                ("sans-serif", 20),
            )
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d(
                (z0 * 0.8..z1 * 1.25).log_scale(),
                (lo * 0.5..hi * 2.0).log_scale(),
            )
            .map_err(|e| anyhow::anyhow!("{e}"))?;
        chart
            .configure_mesh()
            .x_desc("kernel cells")
            .y_desc("milliseconds")
            .draw()
            .map_err(|e| anyhow::anyhow!("{e}"))?;
        type Series = (&'static str, RGBColor, Vec<(f64, f64)>);
        let series: [Series; 4] = [
            (
                "Gram + Cholesky",
                RED,
                rows.iter().map(|r| (r.0, r.2)).collect(),
            ),
            (
                "sender integrals",
                BLUE,
                rows.iter().map(|r| (r.0, r.1)).collect(),
            ),
            (
                "slope 2",
                RGBColor(200, 150, 150),
                vec![(z0, g0), (z1, g0 * (z1 / z0).powi(2))],
            ),
            (
                "slope 1",
                RGBColor(150, 150, 200),
                vec![(z0, s0), (z1, s0 * z1 / z0)],
            ),
        ];
        for (label, colour, pts) in series {
            chart
                .draw_series(LineSeries::new(pts, colour.stroke_width(2)))
                .map_err(|e| anyhow::anyhow!("{e}"))?
                .label(label)
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 18, y)], colour.stroke_width(2))
                });
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .position(SeriesLabelPosition::UpperLeft)
            .draw()
            .map_err(|e| anyhow::anyhow!("{e}"))?;
        Ok(())
    })
}
