//! Figures of the `gauss` group (crate `gauss-integrals`):
//! - `gauss-fig3.4.png`: the error of an orthonormalized Gaussian base approximating the constant
//!   1 inside a central triangle, against the jitter of the centres (sec. 3.7, fig. 3.4), with
//!   its numbers in `gauss-fig3.4.md`;
//! - `gauss-fig3.12.png`: the four error estimates E_FI, E_FT (against roughness tan α) and
//!   E_DI, E_DT (against depth δ) of sec. 3.9.4 (eq. 3.62–3.73, fig. 3.12).

use crate::ctx::Ctx;
use anyhow::Result;
use gauss_integrals::criteria::{e_di, e_dt, e_fi, e_ft};
use gauss_integrals::gram::{Domain, Gaussian, GramConfig, gram};
use gauss_integrals::{Orthonormal, classical_gram_schmidt};
use plotters::prelude::*;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::fmt::Write;

/// Errors of one fig.-3.4 experiment at the samples of the central triangle.
#[derive(Clone, Copy, Debug, Default)]
struct Fit {
    /// √(mean (f − 1)²).
    rms: f64,
    /// mean |f − 1|.
    mean_abs: f64,
    /// max |f − 1|.
    max_abs: f64,
    /// Gaussians rejected as nearly dependent.
    rejected: usize,
}

/// Sec. 3.7: an n×n grid of unit spacing, every centre moved by a uniform random offset in the
/// disk of radius `jitter` (fraction of the spacing; below 0.35 no triangle folds over), the
/// grid triangulated (two triangles per square), each width the mean length of the cell's edges
/// (eq. 2.10) times `width_factor`. The base is orthonormalized (Cholesky, docs/design/math.md §5) on that triangulated domain, 1
/// is projected onto it (`γ = G⁻¹ u`, `u_p = ∫_S Λ_p`), and `f = Σ γ_p Λ_p` is compared to 1 at
/// 231 barycentric grid points of the triangle at the centre of the network. Returns the errors
/// with exact element sums and Cholesky, with the flat closed forms of an unbounded plane
/// (eq. 3.52, `u_p = π d_p²`), and with exact element sums and the classical Gram–Schmidt of
/// fig. B.3.
fn fig_3_4_run(n: usize, jitter: f64, seed: u64, width_factor: f64) -> Result<(Fit, Fit, Fit)> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut v = Vec::with_capacity(n * n);
    for y in 0..n {
        for x in 0..n {
            let (r, t) = (
                jitter * rng.random::<f64>().sqrt(),
                std::f64::consts::TAU * rng.random::<f64>(),
            );
            v.push([x as f64 + r * t.cos(), y as f64 + r * t.sin(), 0.0]);
        }
    }
    let id = |x: usize, y: usize| (y * n + x) as u32;
    let mut tris = Vec::new();
    for y in 0..n - 1 {
        for x in 0..n - 1 {
            tris.push([id(x, y), id(x + 1, y), id(x + 1, y + 1)]);
            tris.push([id(x, y), id(x + 1, y + 1), id(x, y + 1)]);
        }
    }
    // Mean edge length per vertex over the triangulation's edges.
    let mut sum = vec![0.0; v.len()];
    let mut cnt = vec![0usize; v.len()];
    let mut edges: Vec<(u32, u32)> = tris
        .iter()
        .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
        .map(|(a, b)| (a.min(b), a.max(b)))
        .collect();
    edges.sort_unstable();
    edges.dedup();
    for (a, b) in edges {
        let (p, q) = (v[a as usize], v[b as usize]);
        let l = ((p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2)).sqrt();
        for k in [a, b] {
            sum[k as usize] += l;
            cnt[k as usize] += 1;
        }
    }
    let g: Vec<Gaussian> = v
        .iter()
        .enumerate()
        .map(|(k, c)| Gaussian::new(*c, width_factor * sum[k] / cnt[k] as f64))
        .collect();
    let central = [
        id(n / 2 - 1, n / 2 - 1),
        id(n / 2, n / 2 - 1),
        id(n / 2, n / 2),
    ];
    let dom = Domain::triangles(v.clone(), &tris)?;
    let cfg = GramConfig::default();
    let t = central.map(|k| v[k as usize]);
    // Exact: element sums over the network's triangles, u_p = ∫_S Λ_p.
    let gm = gram(&dom, &g, &cfg)?.matrix.to_dense();
    let o = Orthonormal::new(&gm, 1e-12);
    let u: Vec<f64> = g
        .iter()
        .map(|x| dom.integrate(x.centre, 1.0 / (x.width * x.width), cfg.tol, false, None))
        .collect();
    let exact = evaluate(&g, &o.solve(&u), t, o.rejected());
    // The same Gram matrix orthonormalized by the classical Gram–Schmidt printed in fig. B.3:
    // γ = Aᵀ(A u).
    let a = classical_gram_schmidt(&gm);
    let nn = u.len();
    let r: Vec<f64> = (0..nn)
        .map(|k| (0..nn).map(|j| a[(k, j)] * u[j]).sum())
        .collect();
    let gamma: Vec<f64> = (0..nn)
        .map(|j| (0..nn).map(|k| a[(k, j)] * r[k]).sum())
        .collect();
    let cgs = evaluate(&g, &gamma, t, 0);
    // Flat unbounded domain: eq. 3.52 everywhere, u_p = π d_p² (the whole plane).
    let gf: Vec<Gaussian> = g.iter().map(|x| Gaussian { flat: true, ..*x }).collect();
    let gm = gram(&dom, &gf, &cfg)?.matrix.to_dense();
    let o = Orthonormal::new(&gm, 1e-12);
    let u: Vec<f64> = g
        .iter()
        .map(|x| std::f64::consts::PI * x.width * x.width)
        .collect();
    let flat = evaluate(&g, &o.solve(&u), t, o.rejected());
    Ok((exact, flat, cgs))
}

/// Errors of `f = Σ γ_p Λ_p` against 1 at the 231 points of a barycentric grid on `t`.
fn evaluate(g: &[Gaussian], gamma: &[f64], t: [[f64; 3]; 3], rejected: usize) -> Fit {
    let m = 20;
    let mut fit = Fit {
        rejected,
        ..Fit::default()
    };
    let mut count = 0;
    for i in 0..=m {
        for j in 0..=m - i {
            let (l0, l1) = (i as f64 / m as f64, j as f64 / m as f64);
            let l2 = 1.0 - l0 - l1;
            let x = [0, 1].map(|k| l0 * t[0][k] + l1 * t[1][k] + l2 * t[2][k]);
            let f: f64 = g
                .iter()
                .zip(gamma)
                .map(|(gp, c)| {
                    let d2 = (x[0] - gp.centre[0]).powi(2) + (x[1] - gp.centre[1]).powi(2);
                    c * (-d2 / (gp.width * gp.width)).exp()
                })
                .sum();
            let e = (f - 1.0).abs();
            fit.rms += e * e;
            fit.mean_abs += e;
            fit.max_abs = fit.max_abs.max(e);
            count += 1;
        }
    }
    fit.rms = (fit.rms / count as f64).sqrt();
    fit.mean_abs /= count as f64;
    fit
}

fn fig_3_4(ctx: &Ctx) -> Result<()> {
    let (n, rates, seeds): (usize, Vec<f64>, u64) = if ctx.quick {
        (8, vec![0.0, 0.1, 0.3], 1)
    } else {
        (20, (0..=6).map(|k| 0.05 * k as f64).collect(), 4)
    };
    let mut rows = Vec::new();
    let mut flat_rows = Vec::new();
    for &r in &rates {
        let both = (0..seeds)
            .map(|s| fig_3_4_run(n, r, 1000 + s, 1.0))
            .collect::<Result<Vec<_>>>()?;
        let fits: Vec<Fit> = both.iter().map(|b| b.0).collect();
        let k = fits.len() as f64;
        let mean = |f: fn(&Fit) -> f64| fits.iter().map(f).sum::<f64>() / k;
        let rms = mean(|f| f.rms);
        let lo = fits.iter().map(|f| f.rms).fold(f64::INFINITY, f64::min);
        let hi = fits.iter().map(|f| f.rms).fold(0.0, f64::max);
        let mse = mean(|f| f.rms * f.rms);
        let mean_abs = mean(|f| f.mean_abs);
        let max_abs = fits.iter().map(|f| f.max_abs).fold(0.0, f64::max);
        let rejected = fits.iter().map(|f| f.rejected).sum::<usize>();
        let flat_rms = both.iter().map(|b| b.1.rms).sum::<f64>() / k;
        let flat_rej = both.iter().map(|b| b.1.rejected).sum::<usize>();
        let cgs_rms = both.iter().map(|b| b.2.rms).sum::<f64>() / k;
        flat_rows.push((flat_rms, flat_rej, cgs_rms));
        rows.push((r, rms, lo, hi, mse, mean_abs, max_abs, rejected));
    }
    let mut md = String::new();
    writeln!(
        md,
        "# Fig. 3.4: Gaussian base approximating the constant 1\n\n`cargo xtask figures --only gauss{}`: \
         {n}×{n} Gaussians, centres jittered uniformly in a disk of radius rate × spacing, width = mean \
         edge length of the triangulated grid (eq. 2.10), exact element-sum Gram matrix, Cholesky \
         (threshold 1e-12), projection of 1; errors of `f = Σ γ_p Λ_p` against 1 at 231 points of the \
         central triangle, over {seeds} seeds per rate. Last two columns: the same base with the flat \
         closed forms of an unbounded plane instead (eq. 3.52, `u_p = π d_p²`); last column: exact element \
         sums orthonormalized by the classical Gram–Schmidt of fig. B.3.\n\n\
         | jitter | RMS error (mean over seeds) | RMS min | RMS max | MSE | mean abs error | max abs error | rejected | RMS error, flat closed forms | rejected (flat) | RMS error, classical Gram–Schmidt |\n\
         |---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|",
        if ctx.quick { " --quick" } else { "" }
    )?;
    for ((r, rms, lo, hi, mse, ma, mx, rej), (frms, frej, crms)) in rows.iter().zip(&flat_rows) {
        writeln!(
            md,
            "| {:.0} % | {rms:.2e} | {lo:.2e} | {hi:.2e} | {mse:.2e} | {ma:.2e} | {mx:.2e} | {rej} | {frms:.2e} | {frej} | {crms:.2e} |",
            100.0 * r
        )?;
    }
    if !ctx.quick {
        // How narrow must the Gaussians be for the dissertation's ~10 %? Widths scaled at 10 %
        // jitter, same seeds.
        writeln!(
            md,
            "\nWidth sweep at 10 % jitter (widths = factor × mean edge length, exact element sums, \
             Cholesky, same {seeds} seeds):\n\n| width factor | RMS error | mean abs error | rejected |\n|---:|---:|---:|---:|"
        )?;
        for f in [0.4, 0.5, 0.6, 0.7, 0.85, 1.0] {
            let fits = (0..seeds)
                .map(|s| fig_3_4_run(n, 0.1, 1000 + s, f).map(|b| b.0))
                .collect::<Result<Vec<_>>>()?;
            let k = fits.len() as f64;
            writeln!(
                md,
                "| {f} | {:.2e} | {:.2e} | {} |",
                fits.iter().map(|x| x.rms).sum::<f64>() / k,
                fits.iter().map(|x| x.mean_abs).sum::<f64>() / k,
                fits.iter().map(|x| x.rejected).sum::<usize>()
            )?;
        }
    }
    std::fs::write(ctx.out.join("gauss-fig3.4.md"), &md)?;
    println!("{md}");

    let ymax = rows
        .iter()
        .map(|r| r.3)
        .chain(flat_rows.iter().map(|f| f.0.max(f.2)))
        .fold(0.0, f64::max)
        .max(1e-9)
        * 1.1
        * 100.0;
    crate::plot::png(&ctx.out.join("gauss-fig3.4.png"), 640, 420, |root| {
        let mut ch = ChartBuilder::on(root)
            .caption(
                format!("Fig. 3.4: error of {n}x{n} Gaussians approximating 1"),
                ("sans-serif", 18),
            )
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d(0.0..rates.last().copied().unwrap_or(0.3) * 100.0, 0.0..ymax)
            .map_err(|e| anyhow::anyhow!("{e}"))?;
        ch.configure_mesh()
            .x_desc("jitter of the centres (% of spacing)")
            .y_desc("error at the central triangle (%)")
            .draw()
            .map_err(|e| anyhow::anyhow!("{e}"))?;
        ch.draw_series(rows.iter().map(|r| {
            PathElement::new(
                vec![(r.0 * 100.0, r.2 * 100.0), (r.0 * 100.0, r.3 * 100.0)],
                BLUE.mix(0.4),
            )
        }))
        .map_err(|e| anyhow::anyhow!("{e}"))?;
        ch.draw_series(LineSeries::new(
            rows.iter().map(|r| (r.0 * 100.0, r.1 * 100.0)),
            &BLUE,
        ))
        .map_err(|e| anyhow::anyhow!("{e}"))?
        .label("RMS error (mean; bars: min-max over seeds)")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLUE));
        ch.draw_series(LineSeries::new(
            rows.iter().map(|r| (r.0 * 100.0, r.5 * 100.0)),
            &RED,
        ))
        .map_err(|e| anyhow::anyhow!("{e}"))?
        .label("mean absolute error")
        .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], RED));
        let green = RGBColor(0, 140, 0);
        ch.draw_series(LineSeries::new(
            rows.iter()
                .zip(&flat_rows)
                .map(|(r, f)| (r.0 * 100.0, f.0 * 100.0)),
            &green,
        ))
        .map_err(|e| anyhow::anyhow!("{e}"))?
        .label("RMS error, flat closed forms of an unbounded plane (eq. 3.52)")
        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], green));
        let purple = RGBColor(140, 0, 160);
        ch.draw_series(LineSeries::new(
            rows.iter()
                .zip(&flat_rows)
                .map(|(r, f)| (r.0 * 100.0, f.2 * 100.0)),
            &purple,
        ))
        .map_err(|e| anyhow::anyhow!("{e}"))?
        .label("RMS error, classical Gram-Schmidt (fig. B.3)")
        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], purple));
        ch.configure_series_labels()
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .position(SeriesLabelPosition::MiddleLeft)
            .draw()
            .map_err(|e| anyhow::anyhow!("{e}"))?;
        Ok(())
    })
}

fn fig_3_12(ctx: &Ctx) -> Result<()> {
    let n = if ctx.quick { 50 } else { 400 };
    let tan_max = 1.0;
    let fi: Vec<(f64, f64)> = (0..=n)
        .map(|k| {
            let t = tan_max * k as f64 / n as f64;
            (t, 300.0 * e_fi(t.atan()))
        })
        .collect();
    let ft: Vec<(f64, f64)> = (0..=n)
        .map(|k| {
            let t = tan_max * k as f64 / n as f64;
            (t, e_ft(t.atan()))
        })
        .collect();
    let dmax = 3.0;
    let di: Vec<(f64, f64)> = (0..=n)
        .map(|k| {
            let d = dmax * k as f64 / n as f64;
            (d, e_di(d))
        })
        .collect();
    let dt: Vec<(f64, f64)> = (0..=n)
        .map(|k| {
            let d = dmax * k as f64 / n as f64;
            (d, e_dt(d))
        })
        .collect();
    let top = |v: &[(f64, f64)]| v.iter().map(|p| p.1).fold(0.0, f64::max);
    let (y_left, y_right) = (top(&fi).max(top(&ft)) * 1.05, top(&di).max(top(&dt)) * 1.05);
    crate::plot::png(&ctx.out.join("gauss-fig3.12.png"), 900, 380, |root| {
        let (l, r) = root.split_horizontally(450);
        for (area, (xs, ymax, xdesc, a, b, la, lb)) in [
            (
                &l,
                (
                    tan_max,
                    y_left,
                    "roughness tan α",
                    &fi,
                    &ft,
                    "300 · E_FI",
                    "E_FT",
                ),
            ),
            (
                &r,
                (dmax, y_right, "depth δ (widths)", &di, &dt, "E_DI", "E_DT"),
            ),
        ] {
            let mut ch = ChartBuilder::on(area)
                .margin(12)
                .x_label_area_size(40)
                .y_label_area_size(60)
                .build_cartesian_2d(0.0..xs, 0.0..ymax)
                .map_err(|e| anyhow::anyhow!("{e}"))?;
            ch.configure_mesh()
                .x_desc(xdesc)
                .y_desc("error estimate")
                .draw()
                .map_err(|e| anyhow::anyhow!("{e}"))?;
            ch.draw_series(LineSeries::new(a.iter().copied(), &BLUE))
                .map_err(|e| anyhow::anyhow!("{e}"))?
                .label(la)
                .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLUE));
            ch.draw_series(LineSeries::new(b.iter().copied(), &RED))
                .map_err(|e| anyhow::anyhow!("{e}"))?
                .label(lb)
                .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], RED));
            ch.configure_series_labels()
                .background_style(WHITE.mix(0.8))
                .border_style(BLACK)
                .position(SeriesLabelPosition::UpperLeft)
                .draw()
                .map_err(|e| anyhow::anyhow!("{e}"))?;
        }
        Ok(())
    })?;
    let mut md = String::from(
        "# Fig. 3.12: error estimates of sec. 3.9.4\n\n| tan α | E_FI | E_FT | δ | E_DI | E_DT |\n|---:|---:|---:|---:|---:|---:|\n",
    );
    for k in 0..=5 {
        let (t, d) = (0.2 * k as f64, 0.5 * k as f64);
        writeln!(
            md,
            "| {t:.1} | {:.2e} | {:.2e} | {d:.1} | {:.2e} | {:.2e} |",
            e_fi(t.atan()),
            e_ft(t.atan()),
            e_di(d),
            e_dt(d)
        )?;
    }
    std::fs::write(ctx.out.join("gauss-fig3.12.md"), &md)?;
    Ok(())
}

/// Writes this group's figures into `ctx.out`.
pub fn run(ctx: &Ctx) -> Result<()> {
    fig_3_12(ctx)?;
    fig_3_4(ctx)
}
