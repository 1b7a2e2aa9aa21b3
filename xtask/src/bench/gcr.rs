//! Benchmarks of the `gcr` group: time against error of `gcr solve` (every gather, several kernel
//! budgets) beside the pointwise path tracer at several path counts, on the same probes of the
//! same scenes against one high-accuracy reference, in one run. Writes `benchmarks-gcr.md` and one
//! log-log plot per scene (`benchmarks-gcr-<scene>.png`).

use crate::ctx::Ctx;
use anyhow::Result;
use gcr::{Domain, Emitters, GatherMode, SolveConfig, radiosity_at_points};
use scene_sampler::{KernelSampler, Scene, SceneBvh, SurfacePoint};
use std::fmt::Write;
use std::time::Instant;

/// One measured run: wall-clock seconds and relative L2 error at the probes.
#[derive(Clone, Copy, Debug)]
pub struct Point {
    /// Budget label (cells or paths).
    pub budget: usize,
    /// Seconds, solve plus gather at the probes.
    pub seconds: f64,
    /// Relative L2 error of B at the non-emitting probes.
    pub error: f64,
}

/// A solver's curve on one scene.
#[derive(Clone, Debug)]
pub struct Curve {
    /// Solver label.
    pub name: String,
    /// Runs, by increasing budget.
    pub points: Vec<Point>,
}

impl Curve {
    /// A curve without runs yet.
    pub fn new(name: &str) -> Self {
        Curve {
            name: name.into(),
            points: Vec::new(),
        }
    }

    /// Adds a run and prints it as `{label} {name} budget=… s error …`.
    pub fn record(&mut self, label: &str, budget: usize, seconds: f64, error: f64) {
        println!(
            "{label} {} budget={budget} {seconds:.3} s error {error:.4}",
            self.name
        );
        self.points.push(Point {
            budget,
            seconds,
            error,
        });
    }

    /// Seconds to reach `target` error, interpolated log-log between the first run at or below
    /// it and the run before; `None` when no run reaches it.
    pub fn time_to(&self, target: f64) -> Option<f64> {
        let i = self.points.iter().position(|p| p.error <= target)?;
        if i == 0 {
            return Some(self.points[0].seconds);
        }
        let (a, b) = (self.points[i - 1], self.points[i]);
        if a.error <= b.error {
            return Some(b.seconds);
        }
        let t = (a.error.ln() - target.ln()) / (a.error.ln() - b.error.ln());
        Some((a.seconds.ln() + t * (b.seconds.ln() - a.seconds.ln())).exp())
    }
}

/// Relative L2 error of `values` against `reference` over the probes that do not emit.
pub fn relative_l2(
    scene: &Scene,
    points: &[SurfacePoint],
    values: &[[f64; 3]],
    reference: &[[f64; 3]],
) -> f64 {
    let (mut num, mut den) = (0.0, 0.0);
    for ((p, v), r) in points.iter().zip(values).zip(reference) {
        if !scene.faces[p.face as usize].emission.is_zero() {
            continue;
        }
        for b in 0..3 {
            num += (v[b] - r[b]).powi(2);
            den += r[b].powi(2);
        }
    }
    (num / den.max(1e-300)).sqrt()
}

/// Loads a built-in 3-D scene and `count` probe points spread area-uniformly over its
/// non-emitting faces (a Kronecker sequence through the surface parameterization, so the same
/// points every run): B over the whole scene, not at a few hand-picked spots.
pub fn scene_and_probes(name: &str, count: usize) -> Result<(Scene, Vec<SurfacePoint>)> {
    let scene = scene_sampler::builtin(name)?.into_3d()?;
    let points = scene_sampler::SurfaceSampler::new(&scene)
        .spread(count, |p| scene.faces[p.face as usize].emission.is_zero());
    Ok((scene, points))
}

/// The reference B at the probes: the path tracer with many paths (its own seed).
pub fn reference(
    scene: &Scene,
    bvh: &SceneBvh,
    points: &[SurfacePoint],
    paths: usize,
) -> Vec<[f64; 3]> {
    baselines::pointwise::radiosity_at(scene, bvh, points, paths, 0x5EED)
        .into_iter()
        .map(|e| e.mean)
        .collect()
}

/// GCR curves (one per gather) on one scene at the given kernel budgets, and the skip timings.
pub fn gcr_curves(
    scene: &Scene,
    points: &[SurfacePoint],
    reference: &[[f64; 3]],
    budgets: &[usize],
) -> Result<(Vec<Curve>, Vec<Skip>)> {
    let bvh = SceneBvh::new(scene);
    let domain = Domain::ThreeD(KernelSampler::new(scene, &bvh));
    let emitters = Emitters::new(&domain);
    let gathers = [GatherMode::Base, GatherMode::Kernel, GatherMode::Rays];
    let mut curves: Vec<Curve> = gathers
        .iter()
        .map(|g| Curve {
            name: format!("gcr {}", g.name()),
            points: Vec::new(),
        })
        .collect();
    let mut skips = Vec::new();
    for &cells in budgets {
        // Solved twice: with the shading network and base (the base gather reads them), and
        // without (the default for the kernel and ray gathers: `skip_unused_base`).
        let mut solved = Vec::new();
        for skip in [false, true] {
            let config = SolveConfig {
                kernel_cells: cells,
                shading_cells: cells / 2,
                skip_unused_base: skip,
                ..SolveConfig::default()
            };
            let t = Instant::now();
            let trained = gcr::solve(&domain, &config, &mut |_| {})?;
            solved.push((config, trained, t.elapsed().as_secs_f64()));
        }
        let same = solved[0].1.kernel.v == solved[1].1.kernel.v
            && solved[0].1.sender == solved[1].1.sender;
        skips.push(Skip {
            cells,
            kept: solved[0].2,
            skipped: solved[1].2,
            identical: same,
        });
        for (curve, &gather) in curves.iter_mut().zip(&gathers) {
            let (config, trained, solve_seconds) = &solved[usize::from(gather != GatherMode::Base)];
            let (trained, solve_seconds) = (trained, *solve_seconds);
            let config = SolveConfig { gather, ..*config };
            let t = Instant::now();
            let at: Vec<_> = points.iter().map(|p| (p.point, p.normal, p.face)).collect();
            let values: Vec<[f64; 3]> =
                radiosity_at_points(&domain, trained, &emitters, &config, &at)?
                    .into_iter()
                    .map(|g| g.radiosity)
                    .collect();
            let seconds = solve_seconds + t.elapsed().as_secs_f64();
            let error = relative_l2(scene, points, &values, reference);
            println!(
                "gcr: {} cells={cells} {:.2} s error {:.4}",
                curve.name, seconds, error
            );
            curve.points.push(Point {
                budget: cells,
                seconds,
                error,
            });
        }
    }
    Ok((curves, skips))
}

/// Solve time with and without the shading network and base at one budget
/// (`SolveConfig::skip_unused_base`), and whether the kernel solution came out identical.
#[derive(Clone, Copy, Debug)]
pub struct Skip {
    /// Kernel cells.
    pub cells: usize,
    /// Seconds with the base kept.
    pub kept: f64,
    /// Seconds with it skipped.
    pub skipped: f64,
    /// Kernel output weights and sender integrals bit-identical.
    pub identical: bool,
}

/// The path tracer's curve at the given path counts (a different seed from the reference's).
pub fn path_tracer_curve(
    scene: &Scene,
    points: &[SurfacePoint],
    reference: &[[f64; 3]],
    paths: &[usize],
) -> Curve {
    let bvh = SceneBvh::new(scene);
    let points_out = paths
        .iter()
        .map(|&n| {
            let t = Instant::now();
            let values: Vec<[f64; 3]> =
                baselines::pointwise::radiosity_at(scene, &bvh, points, n, 11)
                    .into_iter()
                    .map(|e| e.mean)
                    .collect();
            let seconds = t.elapsed().as_secs_f64();
            let error = relative_l2(scene, points, &values, reference);
            println!("gcr: path tracer paths={n} {seconds:.3} s error {error:.4}");
            Point {
                budget: n,
                seconds,
                error,
            }
        })
        .collect();
    Curve {
        name: "path tracer".into(),
        points: points_out,
    }
}

/// Writes one log-log plot of error (`y_desc` says which) against seconds; the error axis spans
/// the data (no floor: per-pixel relative MSEs reach 10⁻⁶).
pub fn plot_curves(
    path: &std::path::Path,
    title: &str,
    y_desc: &str,
    curves: &[Curve],
) -> Result<()> {
    use plotters::prelude::*;
    let all: Vec<Point> = curves
        .iter()
        .flat_map(|c| c.points.iter().copied())
        .collect();
    let (tmin, tmax) = all.iter().fold((f64::INFINITY, 0.0f64), |(a, b), p| {
        (a.min(p.seconds), b.max(p.seconds))
    });
    let (emin, emax) = (all.iter())
        .filter(|p| p.error > 0.0)
        .fold((f64::INFINITY, 0.0f64), |(a, b), p| {
            (a.min(p.error), b.max(p.error))
        });
    let floor = if emin.is_finite() { 0.7 * emin } else { 1e-4 };
    // One colour per curve position (8 distinct), so that a solver keeps its colour in every plot.
    let colours = [
        RED,
        BLUE,
        GREEN,
        BLACK,
        MAGENTA,
        CYAN,
        RGBColor(230, 120, 0),
        RGBColor(120, 80, 40),
    ];
    crate::plot::png(path, 900, 600, |root| {
        let mut chart = ChartBuilder::on(root)
            .caption(title, ("sans-serif", 22))
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d(
                (tmin.max(1e-4) * 0.7..tmax * 1.4).log_scale(),
                (floor..emax.clamp(floor, 100.0) * 1.4).log_scale(),
            )
            .map_err(|e| anyhow::anyhow!("{e}"))?;
        chart
            .configure_mesh()
            .x_desc("seconds (2 threads)")
            .x_label_formatter(&|v| format!("{v:.0e}"))
            .y_label_formatter(&|v| {
                if *v >= 10.0 {
                    format!("{v:.0}")
                } else if *v >= 1.0 {
                    format!("{v:.1}")
                } else if *v >= 0.01 {
                    format!("{v:.3}")
                } else {
                    format!("{v:.0e}")
                }
            })
            .y_desc(y_desc)
            .draw()
            .map_err(|e| anyhow::anyhow!("{e}"))?;
        for (curve, colour) in curves.iter().zip(colours.iter().cycle()) {
            if curve.points.is_empty() {
                continue; // not run on this scene: no legend entry either
            }
            let pts: Vec<(f64, f64)> = curve
                .points
                .iter()
                .map(|p| (p.seconds.max(1e-4), p.error.clamp(floor, 100.0)))
                .collect();
            chart
                .draw_series(LineSeries::new(pts.clone(), colour.stroke_width(2)))
                .map_err(|e| anyhow::anyhow!("{e}"))?
                .label(curve.name.clone())
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 18, y)], colour.stroke_width(2))
                });
            chart
                .draw_series(pts.into_iter().map(|p| Circle::new(p, 4, colour.filled())))
                .map_err(|e| anyhow::anyhow!("{e}"))?;
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .draw()
            .map_err(|e| anyhow::anyhow!("{e}"))?;
        Ok(())
    })
}

/// Markdown: every run, then the time to reach 10 %, 5 % and 2 %.
pub fn markdown(scene: &str, curves: &[Curve]) -> String {
    let mut md = String::new();
    let _ = writeln!(
        md,
        "### {scene}\n\n| solver | budget | seconds | rel. L2 error |\n|---|---:|---:|---:|"
    );
    for c in curves {
        for p in &c.points {
            let _ = writeln!(
                md,
                "| {} | {} | {:.3} | {:.4} |",
                c.name, p.budget, p.seconds, p.error
            );
        }
    }
    let _ = writeln!(
        md,
        "\n| solver | to 10 % (s) | to 5 % (s) | to 2 % (s) |\n|---|---:|---:|---:|"
    );
    for c in curves {
        let cell = |t: f64| c.time_to(t).map_or("—".to_string(), |s| format!("{s:.3}"));
        let _ = writeln!(
            md,
            "| {} | {} | {} | {} |",
            c.name,
            cell(0.10),
            cell(0.05),
            cell(0.02)
        );
    }
    md
}

/// Runs this group's benchmarks and writes its report into `ctx.out`.
pub fn run(ctx: &Ctx) -> Result<()> {
    // (scenes, kernel budgets, path counts, reference paths, probe points)
    type Plan<'a> = (&'a [&'a str], &'a [usize], &'a [usize], usize, usize);
    let (scenes, budgets, paths, reference_paths, probes): Plan = if ctx.quick {
        (&["wall-floor"], &[40], &[100, 1000], 20_000, 50)
    } else {
        (
            &["cornell-box", "wall-floor", "two-blockers"],
            &[50, 100, 200, 300, 400],
            &[30, 100, 300, 1000, 3000, 10_000],
            50_000,
            500,
        )
    };
    let mut md = format!(
        "# `gcr` against the path tracer: time and error\n\n\
         Command: `cargo xtask bench --only gcr{}` (release, {} threads). Error: relative L2 of B at \
         {probes} points spread area-uniformly over the non-emitting faces against the path tracer with {reference_paths} \
         paths per probe (a different seed from the path tracer's own runs). GCR seconds are solve plus \
         gather at the probes; GCR budgets are kernel cells (shading cells = half), the path tracer's are \
         paths per probe. The path tracer computes only the probes, GCR the whole solution: \
         with more points the path tracer's time grows in proportion, GCR's hardly.\n\n",
        if ctx.quick { " --quick" } else { "" },
        rayon::current_num_threads()
    );
    let mut skip_table = Vec::new();
    for &name in scenes {
        let (scene, points) = scene_and_probes(name, probes)?;
        let bvh = SceneBvh::new(&scene);
        let t = Instant::now();
        let reference = reference(&scene, &bvh, &points, reference_paths);
        println!("gcr: {name} reference {:.1} s", t.elapsed().as_secs_f64());
        let (mut curves, skips) = gcr_curves(&scene, &points, &reference, budgets)?;
        curves.push(path_tracer_curve(&scene, &points, &reference, paths));
        skip_table.push((name, skips));
        let png = format!("benchmarks-gcr-{name}.png");
        plot_curves(
            &ctx.out.join(&png),
            &format!("{name}: error against time"),
            "relative L2 error of B at the probes",
            &curves,
        )?;
        md.push_str(&markdown(name, &curves));
        let _ = writeln!(md, "\n![{name}]({png})\n");
    }
    md.push_str(
        "## Skipping the unused shading network and base\n\n\
         The kernel and ray gathers read neither the shading network nor its base, so by default \
         `gcr` does not train or build them (`SolveConfig::skip_unused_base`; `gcr solve --keep-base` \
         turns the skip off). Solve seconds at each budget with the base kept and skipped, and \
         whether the kernel solution (output weights and sender integrals) came out bit-identical:\n\n\
         | scene | kernel cells | kept (s) | skipped (s) | speed-up | identical |\n|---|---:|---:|---:|---:|---|\n",
    );
    for (name, skips) in &skip_table {
        for s in skips {
            let _ = writeln!(
                md,
                "| {name} | {} | {:.2} | {:.2} | {:.2}× | {} |",
                s.cells,
                s.kept,
                s.skipped,
                s.kept / s.skipped.max(1e-9),
                if s.identical { "yes" } else { "NO" }
            );
        }
    }
    std::fs::write(ctx.out.join("benchmarks-gcr.md"), md)?;
    Ok(())
}
