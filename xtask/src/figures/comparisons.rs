//! Figures of the `comparisons` group: the growing-cells kernel network (GCR) against hierarchical
//! radiosity (HR) at equal numbers of links in Flatland (sec. 4.1, figs. 4.4, 4.5, 4.7, 4.8a/b).
//!
//! **What is compared.** The light flow `L(x,y) = K(x,y)·B(x)` over the kernel domain
//! `(s,t) ∈ [0,1]²` (arc length of the sender x and receiver y, fig. B.2), with
//! `K = ρ(y) cos θx cos θy / (2 max(r, r_min)) · V` (eq. 1.4 in Flatland, docs/design/math.md §7; the clamp
//! `r_min = 10⁻³·diagonal` is the one GCR is trained with):
//! * **exact**: the sampled kernel times the converged fine-mesh radiosity of
//!   [`baselines::flatland::ExactSolver`] at x (final gather);
//! * **GCR**: the kernel network's output Ψ(x,y) = Σ_o v_o exp(−|(x,y) − w_o|²/d_o²) (eq. 2.10), which
//!   is trained on `K·s` with the sender strength `s = E + B_refl` (docs/design/math.md §4), i.e. on `K·B`;
//! * **HR**: the piecewise-constant kernel `K̂ = ρ_r F_rs / L_s` of the link covering (s,t)
//!   (fig. 4.2b, [`baselines::hierarchical::HrKernel`]) times HR's own leaf radiosity at x.
//!
//! Errors over the midpoints of an n×n grid: relative RMS `‖L̃ − L‖₂/‖L‖₂`, relative L1
//! `Σ|L̃ − L|/Σ|L|`, and RMS/max `RMS(L̃ − L)/max L` (the dissertation's apparent normalization, see
//! docs/design/hierarchical.md). Outputs `comparison-error-<scene>.png` (error against links, log-log),
//! `comparison-kernels-<scene>.png` (exact | GCR | HR | |GCR − exact| | |HR − exact| per budget) and
//! `comparison-kernel-error.md` (the table).

use crate::ctx::Ctx;
use anyhow::Result;
use baselines::flatland::{ExactOptions, ExactSolver};
use baselines::hierarchical::{FlatHr, FlatHrConfig, HrKernel, budget, solve_for_links};
use gcr::{Domain, SolveConfig};
use rayon::prelude::*;
use scene_sampler::{AnyScene, FlatKernelSampler, FlatlandScene};
use std::fmt::Write;
use std::time::Instant;

/// Error of an approximation of the light flow against the exact one over the grid.
#[derive(Clone, Copy, Debug)]
pub struct FlowError {
    /// `‖L̃ − L‖₂ / ‖L‖₂`.
    pub rel_rms: f64,
    /// `Σ|L̃ − L| / Σ|L|`.
    pub rel_l1: f64,
    /// `RMS(L̃ − L) / max L`.
    pub rms_over_max: f64,
    /// `ΣL̃ / ΣL`: the total transfer relative to the exact one (1 = no bias).
    pub total: f64,
}

/// The three errors of `approx` against `exact` (same grid, same order).
pub fn flow_error(approx: &[f64], exact: &[f64]) -> FlowError {
    let n = exact.len().max(1) as f64;
    let (mut d2, mut e2, mut d1, mut e1, mut max) = (0.0, 0.0, 0.0, 0.0, 0.0f64);
    let (mut sa, mut se) = (0.0, 0.0);
    for (a, e) in approx.iter().zip(exact) {
        sa += a;
        se += e;
        d2 += (a - e) * (a - e);
        e2 += e * e;
        d1 += (a - e).abs();
        e1 += e.abs();
        max = max.max(e.abs());
    }
    FlowError {
        rel_rms: (d2 / e2.max(1e-300)).sqrt(),
        rel_l1: d1 / e1.max(1e-300),
        rms_over_max: (d2 / n).sqrt() / max.max(1e-300),
        total: sa / se.max(1e-300),
    }
}

/// Relative L1 over the grid points where `keep` is true.
fn masked_l1(approx: &[f64], exact: &[f64], keep: &[bool]) -> f64 {
    let (mut d, mut e) = (0.0, 0.0);
    for ((a, x), k) in approx.iter().zip(exact).zip(keep) {
        if *k {
            d += (a - x).abs();
            e += x.abs();
        }
    }
    d / e.max(1e-300)
}

/// Grid points (same order as the flows) whose sender and receiver are both off the object named
/// `blocker`; `None` when the scene has no such object.
fn off_blocker(scene: &FlatlandScene, n: usize) -> Option<Vec<bool>> {
    let id = scene.objects.iter().position(|o| o == "blocker")? as u32;
    let ks = FlatKernelSampler::new(scene);
    let off: Vec<bool> = (0..n)
        .map(|i| {
            let p = ks.sampler.sample((i as f64 + 0.5) / n as f64);
            scene.segments[p.segment as usize].object != id
        })
        .collect();
    // row r holds t = 1 − (r + ½)/n, i.e. the parameter index n − 1 − r
    Some(
        (0..n * n)
            .map(|i| off[i % n] && off[n - 1 - i / n])
            .collect(),
    )
}

/// One method at one budget.
pub(super) struct Run {
    /// Links (HR) or kernel cells (GCR) actually used.
    pub(super) links: usize,
    /// Seconds: GCR's whole solve; HR's budget search (all its solves).
    pub(super) seconds: f64,
    /// HR only: seconds of one solve at the found ε.
    pub(super) one_solve: Option<f64>,
    /// The light flow on the grid (row-major, row 0 = t close to 1).
    pub(super) flow: Vec<f64>,
    /// Its error against the exact flow.
    pub(super) error: FlowError,
}

/// The exact light flow on the n×n grid: `K(s,t)·B_exact(x(s))`.
fn exact_flow(scene: &FlatlandScene, n: usize) -> Result<(Vec<f64>, f64)> {
    let t = Instant::now();
    let exact = ExactSolver::new(scene, &ExactOptions::default())?;
    let ks = FlatKernelSampler::new(scene);
    let b: Vec<f64> = (0..n)
        .into_par_iter()
        .map(|i| {
            let x = ks.sampler.sample((i as f64 + 0.5) / n as f64);
            exact.gather(&x).map(|v| v[0])
        })
        .collect::<Result<_, _>>()?;
    let flow = (0..n * n)
        .into_par_iter()
        .map(|i| {
            let (row, col) = (i / n, i % n);
            let s = (col as f64 + 0.5) / n as f64;
            let t = 1.0 - (row as f64 + 0.5) / n as f64;
            ks.sample(s, t).kernel().0[0] * b[col]
        })
        .collect();
    Ok((flow, t.elapsed().as_secs_f64()))
}

/// GCR at `cells` kernel cells: Ψ on the grid.
fn gcr_run(scene: &FlatlandScene, cells: usize, n: usize, exact: &[f64]) -> Result<Run> {
    let domain = Domain::Flat(FlatKernelSampler::new(scene));
    let config = SolveConfig {
        kernel_cells: cells,
        shading_cells: (cells / 2).max(3),
        ..SolveConfig::default()
    };
    let t = Instant::now();
    let trained = gcr::solve(&domain, &config, &mut |_| {})?;
    let seconds = t.elapsed().as_secs_f64();
    let flow: Vec<f64> = (0..n * n)
        .into_par_iter()
        .map(|i| {
            let (row, col) = (i / n, i % n);
            let ray = domain.ray(&[
                (col as f64 + 0.5) / n as f64,
                1.0 - (row as f64 + 0.5) / n as f64,
            ]);
            trained.kernel.evaluate(ray.x, ray.nx, ray.y, ray.ny)[0]
        })
        .collect();
    let error = flow_error(&flow, exact);
    Ok(Run {
        links: trained.kernel.len(),
        seconds,
        one_solve: None,
        flow,
        error,
    })
}

/// HR at a budget of `links` links (ε found by [`solve_for_links`]): `K̂·B_HR` on the grid, or
/// `Ok(None)` with the reason when the budget cannot be reached.
fn hr_run(
    scene: &FlatlandScene,
    links: usize,
    n: usize,
    exact: &[f64],
) -> Result<std::result::Result<Run, String>> {
    let base = FlatHrConfig {
        min_length: budget::min_length_for(scene, links),
        ..FlatHrConfig::default()
    };
    let t = Instant::now();
    let found = match solve_for_links(scene, links, base, 0.05) {
        Ok(r) => r,
        Err(e) => return Ok(Err(e.to_string())),
    };
    let seconds = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let _again = FlatHr::solve(
        scene,
        FlatHrConfig {
            epsilon: found.epsilon,
            ..base
        },
    )?;
    let one_solve = t.elapsed().as_secs_f64();
    let hr = &found.hr;
    let hk = HrKernel::new(hr);
    let ks = FlatKernelSampler::new(scene);
    let b: Vec<f64> = (0..n)
        .map(|i| {
            let x = ks.sampler.sample((i as f64 + 0.5) / n as f64);
            hr.radiosity_at(&x).map(|v| v.0[0])
        })
        .collect::<Result<_, _>>()?;
    let flow: Vec<f64> = (0..n * n)
        .into_par_iter()
        .map(|i| {
            let (row, col) = (i / n, i % n);
            let s = (col as f64 + 0.5) / n as f64;
            let t = 1.0 - (row as f64 + 0.5) / n as f64;
            hk.hr_kernel_at(s, t).map(|k| k.0[0] * b[col])
        })
        .collect::<Result<_, _>>()?;
    let error = flow_error(&flow, exact);
    Ok(Ok(Run {
        links: hr.link_count(),
        seconds,
        one_solve: Some(one_solve),
        flow,
        error,
    }))
}

/// Box-averages an n×n image down by `f` per axis.
fn downsample(v: &[f64], n: usize, f: usize) -> Vec<f64> {
    let m = n / f;
    let mut out = vec![0.0; m * m];
    for r in 0..m * f {
        for c in 0..m * f {
            out[(r / f) * m + c / f] += v[r * n + c] / (f * f) as f64;
        }
    }
    out
}

/// Side-by-side grey images: per budget a row of exact | GCR | HR | |GCR − exact| | |HR − exact|,
/// one grey scale (white = the 99th percentile of the exact flow), 4-pixel white gaps.
fn kernel_image(
    path: &std::path::Path,
    n: usize,
    exact: &[f64],
    rows: &[(&Run, Option<&Run>)],
) -> Result<()> {
    let f = (n / 128).max(1);
    let m = n / f;
    let ex = downsample(exact, n, f);
    let mut sorted = ex.clone();
    sorted.sort_by(f64::total_cmp);
    let hi = sorted[(sorted.len() * 99 / 100).min(sorted.len() - 1)].max(1e-300);
    let gap = 4;
    let (w, h) = (5 * m + 4 * gap, rows.len() * m + (rows.len() - 1) * gap);
    let mut img = vec![hi; w * h];
    for (k, (g, hr)) in rows.iter().enumerate() {
        let gd = downsample(&g.flow, n, f);
        let hd = hr.map(|h| downsample(&h.flow, n, f));
        let panels: [Option<Vec<f64>>; 5] = [
            Some(ex.clone()),
            Some(gd.clone()),
            hd.clone(),
            Some(gd.iter().zip(&ex).map(|(a, b)| (a - b).abs()).collect()),
            hd.map(|hd| hd.iter().zip(&ex).map(|(a, b)| (a - b).abs()).collect()),
        ];
        for (p, panel) in panels.iter().enumerate() {
            for r in 0..m {
                for c in 0..m {
                    let v = panel.as_ref().map_or(hi, |pv| pv[r * m + c]);
                    img[(k * (m + gap) + r) * w + p * (m + gap) + c] = v;
                }
            }
        }
    }
    crate::plot::write_grey_png(path, w, h, &img, 0.0, hi)
}

/// Log-log plot of the relative RMS and relative L1 against links for both methods.
pub(super) fn error_plot(
    path: &std::path::Path,
    title: &str,
    gcr: &[Run],
    hr: &[Run],
) -> Result<()> {
    use plotters::prelude::*;
    let all = gcr.iter().chain(hr);
    let (mut lo, mut hi, mut emin, mut emax) = (f64::INFINITY, 0.0f64, f64::INFINITY, 0.0f64);
    for r in all {
        lo = lo.min(r.links as f64);
        hi = hi.max(r.links as f64);
        for e in [r.error.rel_rms, r.error.rel_l1] {
            emin = emin.min(e);
            emax = emax.max(e);
        }
    }
    crate::plot::png(path, 800, 520, |root| {
        let mut chart = ChartBuilder::on(root)
            .caption(title, ("sans-serif", 22))
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d(
                (lo * 0.8..hi * 1.25).log_scale(),
                (emin.max(1e-4) * 0.8..emax * 1.25).log_scale(),
            )
            .map_err(|e| anyhow::anyhow!("{e}"))?;
        chart
            .configure_mesh()
            .x_desc("links (HR) / kernel cells (GCR)")
            .y_desc("error of the light flow K·B")
            .draw()
            .map_err(|e| anyhow::anyhow!("{e}"))?;
        type Pick = fn(&Run) -> f64;
        let series: [(&str, &[Run], RGBColor, Pick); 4] = [
            ("GCR rel. RMS", gcr, RED, |r| r.error.rel_rms),
            ("GCR rel. L1", gcr, MAGENTA, |r| r.error.rel_l1),
            ("HR rel. RMS", hr, BLUE, |r| r.error.rel_rms),
            ("HR rel. L1", hr, CYAN, |r| r.error.rel_l1),
        ];
        for (label, runs, colour, pick) in series {
            let pts: Vec<(f64, f64)> = runs.iter().map(|r| (r.links as f64, pick(r))).collect();
            chart
                .draw_series(LineSeries::new(pts.clone(), colour.stroke_width(2)))
                .map_err(|e| anyhow::anyhow!("{e}"))?
                .label(label)
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

/// Writes this group's figures into `ctx.out`.
pub fn run(ctx: &Ctx) -> Result<()> {
    // (scene, budgets of the curve, budgets shown as images)
    type Plan = (&'static str, &'static [usize], &'static [usize]);
    let (plans, n): (&[Plan], usize) = if ctx.quick {
        (
            &[
                ("flatland-corner", &[16, 40], &[16]),
                ("flatland-blocker", &[11, 40], &[11]),
            ],
            64,
        )
    } else {
        (
            &[
                ("flatland-corner", &[16, 40, 100, 250, 500], &[16, 100, 500]),
                (
                    "flatland-blocker",
                    &[11, 40, 100, 250, 500],
                    &[11, 100, 500],
                ),
            ],
            512,
        )
    };
    let mut md = String::from(
        "| scene | budget | method | links | rel. RMS | rel. L1 | RMS/max | ΣL̃/ΣL | rel. L1 off the blocker | seconds |\n\
         |---|---:|---|---:|---:|---:|---:|---:|---:|---:|\n",
    );
    for &(name, budgets, shown) in plans {
        let AnyScene::Flatland(scene) = scene_sampler::builtin(name)? else {
            anyhow::bail!("{name} is not a Flatland scene");
        };
        let (exact, exact_s) = exact_flow(&scene, n)?;
        let keep = off_blocker(&scene, n);
        let off = |flow: &[f64]| {
            keep.as_ref().map_or("—".to_string(), |k| {
                format!("{:.1} %", 100.0 * masked_l1(flow, &exact, k))
            })
        };
        println!("figures comparisons: {name} exact flow {exact_s:.1} s");
        let (mut gcr_runs, mut hr_runs) = (Vec::new(), Vec::new());
        let mut image_rows = Vec::new();
        for &links in budgets {
            let g = gcr_run(&scene, links, n, &exact)?;
            let h = hr_run(&scene, links, n, &exact)?;
            println!(
                "figures comparisons: {name} {links}: GCR {} cells {:.2} s rel RMS {:.4} L1 {:.4} RMS/max {:.5} total {:.3}",
                g.links,
                g.seconds,
                g.error.rel_rms,
                g.error.rel_l1,
                g.error.rms_over_max,
                g.error.total
            );
            writeln!(
                md,
                "| {name} | {links} | GCR | {} | {:.1} % | {:.1} % | {:.3} % | {:.3} | {} | {:.3} |",
                g.links,
                100.0 * g.error.rel_rms,
                100.0 * g.error.rel_l1,
                100.0 * g.error.rms_over_max,
                g.error.total,
                off(&g.flow),
                g.seconds
            )?;
            match &h {
                Ok(h) => {
                    println!(
                        "figures comparisons: {name} {links}: HR {} links {:.3} s (one solve {:.4} s) rel RMS {:.4} L1 {:.4} RMS/max {:.5}",
                        h.links,
                        h.seconds,
                        h.one_solve.unwrap_or(0.0),
                        h.error.rel_rms,
                        h.error.rel_l1,
                        h.error.rms_over_max
                    );
                    writeln!(
                        md,
                        "| {name} | {links} | HR | {} | {:.1} % | {:.1} % | {:.3} % | {:.3} | {} | {:.3} (one solve {:.4}) |",
                        h.links,
                        100.0 * h.error.rel_rms,
                        100.0 * h.error.rel_l1,
                        100.0 * h.error.rms_over_max,
                        h.error.total,
                        off(&h.flow),
                        h.seconds,
                        h.one_solve.unwrap_or(0.0)
                    )?;
                }
                Err(why) => {
                    println!("figures comparisons: {name} {links}: HR not reached: {why}");
                    writeln!(
                        md,
                        "| {name} | {links} | HR | not reached: {why} | | | | | | |"
                    )?;
                }
            }
            let show = shown.contains(&links);
            gcr_runs.push(g);
            if let Ok(h) = h {
                hr_runs.push((links, h));
            }
            if show {
                image_rows.push(links);
            }
        }
        let rows: Vec<(&Run, Option<&Run>)> = image_rows
            .iter()
            .map(|&l| {
                let i = budgets.iter().position(|&b| b == l).unwrap_or(0);
                (
                    &gcr_runs[i],
                    hr_runs.iter().find(|(b, _)| *b == l).map(|(_, r)| r),
                )
            })
            .collect();
        kernel_image(
            &ctx.out.join(format!("comparison-kernels-{name}.png")),
            n,
            &exact,
            &rows,
        )?;
        let hr_only: Vec<Run> = hr_runs.into_iter().map(|(_, r)| r).collect();
        error_plot(
            &ctx.out.join(format!("comparison-error-{name}.png")),
            &format!("{name}: light-flow error against links ({n}² grid)"),
            &gcr_runs,
            &hr_only,
        )?;
    }
    std::fs::write(ctx.out.join("comparison-kernel-error.md"), md)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn flow_error_matches_hand_computed_norms() {
        let exact = [1.0, 2.0, 3.0, 4.0];
        let approx = [1.0, 2.0, 3.0, 5.0];
        let e = flow_error(&approx, &exact);
        assert!((e.rel_rms - 1.0 / 30f64.sqrt()).abs() < 1e-15);
        assert!((e.rel_l1 - 0.1).abs() < 1e-15);
        // RMS of the difference = sqrt(1/4) = 0.5, max = 4
        assert!((e.rms_over_max - 0.125).abs() < 1e-15);
        assert!((e.total - 1.1).abs() < 1e-15);
    }

    #[test]
    fn the_off_blocker_mask_follows_the_grid_orientation() {
        let scene = scene_sampler::builtin("flatland-blocker")
            .unwrap()
            .into_flatland()
            .unwrap();
        let n = 40;
        let keep = off_blocker(&scene, n).unwrap();
        let ks = FlatKernelSampler::new(&scene);
        let blocker = scene.objects.iter().position(|o| o == "blocker").unwrap() as u32;
        for (i, &k) in keep.iter().enumerate() {
            let (row, col) = (i / n, i % n);
            let s = (col as f64 + 0.5) / n as f64;
            let t = 1.0 - (row as f64 + 0.5) / n as f64;
            let smp = ks.sample(s, t);
            let on = |seg: u32| scene.segments[seg as usize].object == blocker;
            assert_eq!(
                k,
                !on(smp.x.segment) && !on(smp.y.segment),
                "grid point {i}"
            );
        }
        assert!(keep.iter().any(|k| !k) && keep.iter().any(|k| *k));
        let corner = scene_sampler::builtin("flatland-corner")
            .unwrap()
            .into_flatland()
            .unwrap();
        assert!(off_blocker(&corner, n).is_none());
    }
}
