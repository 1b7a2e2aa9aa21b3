//! Figures of the `isgcs` group: the dissertation's figs. 2.4–2.8 (networks adapting to data
//! distributions by unsupervised training and growth, sec. 2.2–2.3), redrawn from our crate.
//!
//! Every figure shows three snapshots of one training run (a third, two thirds and all of the
//! cell budget): grey dots are a subsample of the training data, black lines the edges of the
//! network's simplicial complex; 3-D data are drawn in an oblique parallel projection.

use crate::ctx::Ctx;
use anyhow::Result;
use isgcs::{Isgcs, Params};
use plotters::prelude::*;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// One network state: projected edges.
struct Snapshot {
    cells: usize,
    components: usize,
    edges: Vec<[(f64, f64); 2]>,
}

/// ε of the deletion runs (figs. 2.7, 2.8). With α = 0.03 the resource forgets within ~33 steps
/// while a cell of z wins once per ~z steps, so the lowest resource is tiny even among useful
/// cells (ε = 1e-5 deleted cells inside the clusters and broke them into up to 7 components);
/// τ^USL ≈ 3e-3 · 0.97^s after s steps without a win, so 1e-40 means "no win for ~3000 steps".
const DELETION_EPSILON: f64 = 1e-40;

/// Snapshots of one run and a subsample of its data, projected.
type Run = (Vec<Snapshot>, Vec<(f64, f64)>);

/// Parallel projection of a 1-, 2- or 3-D point onto the drawing plane (3-D: azimuth 30°,
/// elevation 35°).
fn project(p: &[f64]) -> (f64, f64) {
    match p.len() {
        1 => (p[0], 0.0),
        2 => (p[0], p[1]),
        _ => {
            let (sa, ca) = 30f64.to_radians().sin_cos();
            let (se, ce) = 35f64.to_radians().sin_cos();
            (
                ca * p[0] - sa * p[1],
                ce * p[2] + se * (sa * p[0] + ca * p[1]),
            )
        }
    }
}

/// Trains an n-D, k-topology network on samples from `draw` with unsupervised resources
/// (quantization error, sec. 2.4 pure USL) and records snapshots at a third, two thirds and all
/// of `cells`.
fn grow(
    n: usize,
    k: usize,
    cells: usize,
    seed: u64,
    deletion: bool,
    draw: &dyn Fn(&mut ChaCha8Rng) -> Vec<f64>,
) -> Result<Run> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    // The initial simplex on k + 1 data points.
    let init: Vec<Vec<f64>> = (0..=k).map(|_| draw(&mut rng)).collect();
    let params = Params {
        usl_weight: 1.0,
        lambda: 300,
        // Deletion (sec. 2.4.2) for the separated data sets: a cell that stops winning samples
        // sees its resource decay by (1 − α)^κ per test period and goes.
        kappa: if deletion { 400 } else { 0 },
        epsilon: if deletion { DELETION_EPSILON } else { 0.0 },
        ..Params::default()
    };
    let mut net = Isgcs::new(params, n, 1, k, init)?;
    let marks = [cells / 3, 2 * cells / 3, cells];
    let mut shots = Vec::new();
    for &mark in &marks {
        // Cap the steps: with deletion on, growth could in principle stall.
        let cap = net.steps() + 3 * params.lambda as u64 * cells as u64;
        while net.len() < mark.max(k + 1) && net.steps() < cap {
            let x = draw(&mut rng);
            net.train(&x, &[0.0], None);
        }
        // Let the last insertion settle before the picture.
        for _ in 0..params.lambda / 2 {
            let x = draw(&mut rng);
            net.set_growing(false);
            net.train(&x, &[0.0], None);
        }
        net.set_growing(true);
        let mut edges = Vec::new();
        for i in 0..net.len() {
            for &j in net.neighbours(i) {
                if (j as usize) > i {
                    edges.push([project(net.centre(i)), project(net.centre(j as usize))]);
                }
            }
        }
        shots.push(Snapshot {
            cells: net.len(),
            components: net.component_count(),
            edges,
        });
    }
    let dots = (0..500).map(|_| project(&draw(&mut rng))).collect();
    Ok((shots, dots))
}

/// Draws the snapshots side by side into `path`.
fn draw_figure(
    ctx: &Ctx,
    name: &str,
    title: &str,
    shots: &[Snapshot],
    dots: &[(f64, f64)],
) -> Result<()> {
    let dir = &ctx.out;
    std::fs::create_dir_all(dir)?;
    let (w, h) = if ctx.quick { (450, 170) } else { (840, 300) };
    let all = dots
        .iter()
        .chain(shots.iter().flat_map(|s| s.edges.iter().flatten()));
    let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for &(x, y) in all {
        (x0, x1, y0, y1) = (x0.min(x), x1.max(x), y0.min(y), y1.max(y));
    }
    let pad = 0.05 * (x1 - x0).max(y1 - y0).max(1e-9);
    let e = |m: String| anyhow::anyhow!("plotting: {m}");
    let path = dir.join(format!("isgcs-{name}.png"));
    crate::plot::png(&path, w, h, |root| {
        let root = root
            .titled(title, ("sans-serif", if ctx.quick { 11 } else { 18 }))
            .map_err(|x| e(x.to_string()))?;
        let panels = root.split_evenly((1, shots.len()));
        for (panel, shot) in panels.iter().zip(shots) {
            let mut chart = ChartBuilder::on(panel)
                .caption(
                    if shot.components > 1 {
                        format!("{} cells, {} components", shot.cells, shot.components)
                    } else {
                        format!("{} cells", shot.cells)
                    },
                    ("sans-serif", if ctx.quick { 10 } else { 15 }),
                )
                .margin(4)
                .build_cartesian_2d(x0 - pad..x1 + pad, y0 - pad..y1 + pad)
                .map_err(|x| e(x.to_string()))?;
            chart
                .draw_series(
                    dots.iter()
                        .map(|&p| Circle::new(p, 1, RGBColor(170, 170, 170).filled())),
                )
                .map_err(|x| e(x.to_string()))?;
            chart
                .draw_series(
                    shot.edges
                        .iter()
                        .map(|s| PathElement::new(vec![s[0], s[1]], BLACK.stroke_width(1))),
                )
                .map_err(|x| e(x.to_string()))?;
        }
        Ok(())
    })?;
    // The drawing is black on white: store it as 8-bit grey (a third of the RGB file).
    image::open(&path)?.to_luma8().save(&path)?;
    Ok(())
}

/// Writes figs. 2.4–2.8 into `ctx.out/figures/isgcs-*.png`.
pub fn run(ctx: &Ctx) -> Result<()> {
    let budget = |full: usize| if ctx.quick { 24 } else { full };
    // A bent 2-D sheet in 3-D: (u, v) ∈ [0, 1]² ↦ (u, v, 0.3 sin(π u)).
    let sheet = |u: f64, v: f64| vec![u, v, 0.3 * (std::f64::consts::PI * u).sin()];
    // Fig. 2.4: k = 2 on a 2-D area in 3-D, uniform.
    let (s, d) = grow(3, 2, budget(200), 1, false, &|r| {
        sheet(r.random(), r.random())
    })?;
    draw_figure(
        ctx,
        "2.4-sheet",
        "fig. 2.4: k = 2 network, n = 3 data on a 2-D sheet (uniform)",
        &s,
        &d,
    )?;
    // Fig. 2.5: the same with doubled density in the lower right quarter (u > ½, v < ½):
    // draw from the square with weight 1, the quarter with weight 2 (density ratio 2).
    let (s, d) = grow(3, 2, budget(200), 2, false, &|r| {
        if r.random::<f64>() < 2.0 / 5.0 {
            sheet(0.5 + 0.5 * r.random::<f64>(), 0.5 * r.random::<f64>())
        } else {
            loop {
                let (u, v): (f64, f64) = (r.random(), r.random());
                if !(u > 0.5 && v < 0.5) {
                    break sheet(u, v);
                }
            }
        }
    })?;
    draw_figure(
        ctx,
        "2.5-density",
        "fig. 2.5: as fig. 2.4, doubled density in the lower right quarter",
        &s,
        &d,
    )?;
    // Fig. 2.6 (right picture): k = 1 on 2-D data.
    let (s, d) = grow(2, 1, budget(120), 3, false, &|r| {
        vec![r.random(), r.random()]
    })?;
    draw_figure(
        ctx,
        "2.6-curve",
        "fig. 2.6: k = 1 network on 2-D data (uniform square)",
        &s,
        &d,
    )?;
    // Fig. 2.7: two separate 2-D clusters in 3-D (two tilted discs).
    let (s, d) = grow(3, 2, budget(160), 4, true, &|r| {
        let (a, rr): (f64, f64) = (r.random::<f64>() * std::f64::consts::TAU, r.random());
        let (x, y) = (0.35 * rr.sqrt() * a.cos(), 0.35 * rr.sqrt() * a.sin());
        if r.random::<bool>() {
            vec![x, y, 0.3 * x]
        } else {
            vec![1.2 + x, 0.1 * y, 0.5 + y]
        }
    })?;
    draw_figure(
        ctx,
        "2.7-clusters",
        "fig. 2.7: k = 2 network on two separate 2-D clusters in 3-D, with deletion",
        &s,
        &d,
    )?;
    // Fig. 2.8: k = 3 network on 3-D data (two separate boxes).
    let (s, d) = grow(3, 3, budget(150), 5, true, &|r| {
        let p: Vec<f64> = (0..3).map(|_| r.random::<f64>() * 0.5).collect();
        if r.random::<bool>() {
            p
        } else {
            vec![p[0] + 0.9, p[1], p[2] + 0.2]
        }
    })?;
    draw_figure(
        ctx,
        "2.8-volume",
        "fig. 2.8: k = 3 network on 3-D data (two separate boxes), with deletion",
        &s,
        &d,
    )?;
    Ok(())
}
