//! Figures of the `floor` group: figs. 4.9 and 4.10, the floor edge of the Flatland scenes with,
//! from top to bottom, the shading network's cell centres, the end points of the kernel's training
//! rays on the floor, and the subdivision hierarchical radiosity derives at an equal number of links
//! (the boundaries of its leaves). With a blocker (fig. 4.10) the blocker's extent over the floor is
//! marked by two vertical bars. Writes `floor-<scene>.png` and `floor.md` (counts per strip, and
//! how many of each fall under the blocker's extent, against its share of the floor's length).

use crate::ctx::Ctx;
use anyhow::{Context, Result};
use baselines::hierarchical::{FlatHrConfig, budget, solve_for_links};
use gcr::{Domain, SolveConfig};
use plotters::prelude::*;
use scene_sampler::{AnyScene, FlatKernelSampler, FlatlandScene};

/// The floor: the lowest segment facing up. Returns its index and x range.
fn floor(scene: &FlatlandScene) -> Option<(usize, f64, f64)> {
    scene
        .segments
        .iter()
        .enumerate()
        .filter(|(_, s)| s.normal.y > 0.9)
        .min_by(|a, b| (a.1.a.y + a.1.b.y).total_cmp(&(b.1.a.y + b.1.b.y)))
        .map(|(i, s)| (i, s.a.x.min(s.b.x), s.a.x.max(s.b.x)))
}

/// The x extent of the segments between the floor and the emitters that are not the floor's
/// walls: the blocker, if any (segments facing up or down above the floor, below the highest).
fn blocker(scene: &FlatlandScene, floor_y: f64) -> Option<(f64, f64)> {
    let top = scene
        .segments
        .iter()
        .map(|s| s.a.y.max(s.b.y))
        .fold(f64::MIN, f64::max);
    let xs: Vec<f64> = scene
        .segments
        .iter()
        .filter(|s| s.normal.y.abs() > 0.9 && s.emission.is_zero())
        .filter(|s| s.a.y > floor_y + 1e-9 && s.a.y < top - 1e-9)
        .flat_map(|s| [s.a.x, s.b.x])
        .collect();
    (!xs.is_empty()).then(|| {
        (
            xs.iter().copied().fold(f64::MAX, f64::min),
            xs.iter().copied().fold(f64::MIN, f64::max),
        )
    })
}

/// One figure: returns the markdown row.
fn figure(ctx: &Ctx, name: &str, cells: usize) -> Result<String> {
    let AnyScene::Flatland(scene) = scene_sampler::builtin(name)? else {
        anyhow::bail!("{name} is not a Flatland scene");
    };
    let (fi, x0, x1) = floor(&scene).context("no floor segment")?;
    let fy = scene.segments[fi].a.y;
    let domain = Domain::Flat(FlatKernelSampler::new(&scene));
    let config = SolveConfig {
        kernel_cells: cells,
        shading_cells: (cells / 2).max(3),
        skip_unused_base: false,
        ..SolveConfig::default()
    };
    let trained = gcr::solve(&domain, &config, &mut |_| {})?;
    let tol = 1e-3 * domain.diagonal();
    let centres: Vec<f64> = trained
        .fem
        .base
        .geo
        .centres
        .iter()
        .filter(|c| {
            (c.y - fy).abs() < 0.05 * domain.diagonal() && c.x >= x0 - tol && c.x <= x1 + tol
        })
        .map(|c| c.x)
        .collect();
    let ends: Vec<f64> = trained
        .samples
        .iter()
        .filter(|s| s.ray.face_y as usize == fi)
        .map(|s| s.ray.y.x)
        .collect();
    // HR at the same budget (within 25 %); a budget it cannot reach leaves its strip empty.
    let hr = solve_for_links(
        &scene,
        cells,
        FlatHrConfig {
            min_length: budget::min_length_for(&scene, cells),
            ..FlatHrConfig::default()
        },
        0.25,
    );
    let seg = &scene.segments[fi];
    let cuts: Vec<f64> = match &hr {
        Ok(found) => found
            .hr
            .leaves()
            .filter(|p| p.segment as usize == fi)
            .map(|p| seg.a.x + p.t0 * (seg.b.x - seg.a.x))
            .collect(),
        Err(why) => {
            println!("figures floor: {name}: HR at {cells} links not reached: {why}");
            Vec::new()
        }
    };
    let shadow = blocker(&scene, fy);
    let path = ctx.out.join(format!("floor-{name}.png"));
    crate::plot::png(&path, 900, 300, |root| {
        let mut chart = ChartBuilder::on(root)
            .caption(
                format!("{name}: floor edge ({cells} cells / links)"),
                ("sans-serif", 20),
            )
            .margin(10)
            .x_label_area_size(30)
            .y_label_area_size(150)
            .build_cartesian_2d(x0..x1, 0.0..3.0)
            .map_err(|e| anyhow::anyhow!("{e}"))?;
        chart
            .configure_mesh()
            .disable_mesh()
            .y_labels(7)
            .y_label_formatter(&|y: &f64| {
                // Rows are [k, k + 1]; label their middles.
                match (*y * 2.0_f64).round() as i32 {
                    5 => "shading centres",
                    3 => "ray end points",
                    1 => "HR subdivision",
                    _ => "",
                }
                .to_string()
            })
            .x_desc("x on the floor")
            .draw()
            .map_err(|e| anyhow::anyhow!("{e}"))?;
        let ticks = |xs: &[f64], row: f64, colour: RGBColor| {
            xs.iter()
                .map(|&x| PathElement::new(vec![(x, row + 0.15), (x, row + 0.85)], colour))
                .collect::<Vec<_>>()
        };
        for (xs, row, colour) in [
            (&centres, 2.0, RED),
            (&ends, 1.0, RGBColor(60, 60, 60)),
            (&cuts, 0.0, BLUE),
        ] {
            chart
                .draw_series(ticks(xs, row, colour))
                .map_err(|e| anyhow::anyhow!("{e}"))?;
        }
        if let Some((b0, b1)) = shadow {
            for b in [b0, b1] {
                chart
                    .draw_series(std::iter::once(PathElement::new(
                        vec![(b, 0.0), (b, 3.0)],
                        GREEN.stroke_width(3),
                    )))
                    .map_err(|e| anyhow::anyhow!("{e}"))?;
            }
        }
        Ok(())
    })?;
    let under = |xs: &[f64]| match shadow {
        Some((b0, b1)) => format!(
            "{} ({:.0} %)",
            xs.iter().filter(|&&x| x >= b0 && x <= b1).count(),
            100.0 * xs.iter().filter(|&&x| x >= b0 && x <= b1).count() as f64
                / xs.len().max(1) as f64
        ),
        None => "—".into(),
    };
    let share = shadow.map_or("—".into(), |(b0, b1)| {
        format!("{:.0} %", 100.0 * (b1 - b0) / (x1 - x0))
    });
    Ok(format!(
        "| {name} | {cells} | {} | {} | {} | {share} | {} | {} | {} |\n",
        centres.len(),
        ends.len(),
        cuts.len(),
        under(&centres),
        under(&ends),
        under(&cuts)
    ))
}

/// Writes this group's figures into `ctx.out`.
pub fn run(ctx: &Ctx) -> Result<()> {
    let cells = if ctx.quick { 20 } else { 100 };
    let mut md = format!(
        "# Floor edge distributions (figs. 4.9, 4.10)\n\n\
         Command: `cargo xtask figures --only floor{}`. On the floor segment: shading-network cell centres \
         within 5 % of the diagonal of it, kernel training-ray end points on it, HR leaves on it at the same (within 25 %) \
         number of links; \"under the blocker\" counts those within the blocker's x extent.\n\n\
         | scene | cells / links | shading centres | ray end points | HR leaves | blocker's share of the floor | centres under it | ray ends under it | HR leaves under it |\n\
         |---|---:|---:|---:|---:|---:|---:|---:|---:|\n",
        if ctx.quick { " --quick" } else { "" }
    );
    for name in ["flatland-corner", "flatland-blocker"] {
        md += &figure(ctx, name, cells)?;
    }
    std::fs::write(ctx.out.join("floor.md"), md)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn floors_and_blockers_of_the_builtins() {
        let AnyScene::Flatland(corner) = scene_sampler::builtin("flatland-corner").unwrap() else {
            panic!()
        };
        let AnyScene::Flatland(blocked) = scene_sampler::builtin("flatland-blocker").unwrap()
        else {
            panic!()
        };
        let (_, x0, x1) = floor(&corner).unwrap();
        assert!(x1 > x0);
        assert!(blocker(&corner, corner.segments[floor(&corner).unwrap().0].a.y).is_none());
        let (fi, x0, x1) = floor(&blocked).unwrap();
        let (b0, b1) = blocker(&blocked, blocked.segments[fi].a.y).unwrap();
        assert!(x0 <= b0 && b0 < b1 && b1 <= x1, "{x0} {b0} {b1} {x1}");
    }
}
