//! Figures of the `gcr` group.
//!
//! * `gcr-kernel-<scene>-<cells>.png` (figs. 4.1b, 4.3, 4.6b–c): the Flatland light flow
//!   K(x,y)·s(x) over the arc-length parameters (s of the sender x horizontally, t of the receiver y
//!   vertically, origin bottom left) — the sampled kernel on the left, the kernel network's Ψ in
//!   the middle, |Ψ − K·s| on the right, all on one grey scale (white = the 99th percentile of K·s).
//!   s(x) = E(x) + B_refl(x) is GCR's own final strength, so the error isolates the kernel
//!   network's approximation of the light flow it was trained on.
//! * `gcr-kernel-error.md`: relative RMS of Ψ against K·s over the grid, per scene and budget.
//! * `gcr-wall-floor-{base,kernel,rays}.png` (fig. 4.13a–c, 4.11c): the three gathers of one solve.
//! * `gcr-two-blockers-{rays,kernel}.png` (fig. 4.15f) and `gcr-cornell-box-{rays,kernel}.png`.

use crate::Ctx;
use anyhow::{Context, Result};
use gcr::config::{GatherMode, SolveConfig};
use gcr::domain::Domain;
use gcr::output::tonemap::Exposure;
use gcr::pipeline::output_mesh;
use gcr::retriangulate::RetriangulateLimits;
use rayon::prelude::*;
use scene_sampler::{AnyScene, FlatKernelSampler, KernelSampler, SceneBvh};
use std::fmt::Write;

/// Errors of Ψ against K·s over the grid.
struct KernelError {
    /// Relative RMS over the whole grid.
    rms: f64,
    /// Relative mean absolute error (the 1/r singularity of G where surfaces meet is
    /// integrable in L1 but not in L2, so the RMS is dominated by the grid points nearest to it).
    l1: f64,
    /// Relative RMS over the pairs farther apart than 5 % of the scene's diagonal.
    rms_far: f64,
}

/// One Flatland kernel figure and its errors.
fn flatland_kernel(ctx: &Ctx, name: &str, cells: usize, n: usize) -> Result<KernelError> {
    let AnyScene::Flatland(scene) = scene_sampler::builtin(name)? else {
        anyhow::bail!("{name} is not a Flatland scene");
    };
    let domain = Domain::Flat(FlatKernelSampler::new(&scene));
    let config = SolveConfig {
        kernel_cells: cells,
        shading_cells: (cells / 2).max(3),
        ..SolveConfig::default()
    };
    let trained = gcr::solve::solve(&domain, &config, &mut |_| {})?;
    // Row-major, row 0 at the top = t close to 1.
    let near = 0.05 * domain.diagonal();
    let cells_grid: Vec<(f64, f64, bool)> = (0..n * n)
        .into_par_iter()
        .map(|i| {
            let (row, col) = (i / n, i % n);
            let s = (col as f64 + 0.5) / n as f64;
            let t = 1.0 - (row as f64 + 0.5) / n as f64;
            let ray = domain.ray(&[s, t]);
            let strength = ray.emission_x[0] + trained.reflected_kernel(ray.x)[0];
            let far = ray.x.distance(ray.y) > near;
            (
                ray.kernel[0] * strength,
                trained.kernel.evaluate(ray.x, ray.y)[0],
                far,
            )
        })
        .collect();
    let exact: Vec<f64> = cells_grid.iter().map(|c| c.0).collect();
    let net: Vec<f64> = cells_grid.iter().map(|c| c.1).collect();
    let diff: Vec<f64> = cells_grid.iter().map(|c| (c.1 - c.0).abs()).collect();
    let mut sorted = exact.clone();
    sorted.sort_by(f64::total_cmp);
    let hi = sorted[(sorted.len() * 99 / 100).min(sorted.len() - 1)].max(1e-300);
    // Three panels side by side, separated by 4 white columns.
    let w = 3 * n + 8;
    let mut panel = vec![hi; w * n];
    for row in 0..n {
        for col in 0..n {
            panel[row * w + col] = exact[row * n + col];
            panel[row * w + n + 4 + col] = net[row * n + col];
            panel[row * w + 2 * n + 8 + col] = diff[row * n + col];
        }
    }
    let path = ctx.out.join(format!("gcr-kernel-{name}-{cells}.png"));
    crate::plot::write_grey_png(&path, w, n, &panel, 0.0, hi)?;
    let ratio = |num: f64, den: f64| num / den.max(1e-300);
    let sq = |far_only: bool| {
        let pick = cells_grid.iter().filter(|c| c.2 || !far_only);
        let num: f64 = pick.clone().map(|c| (c.1 - c.0).powi(2)).sum();
        let den: f64 = pick.map(|c| c.0 * c.0).sum();
        ratio(num, den).sqrt()
    };
    let l1 = ratio(
        cells_grid.iter().map(|c| (c.1 - c.0).abs()).sum(),
        exact.iter().map(|v| v.abs()).sum(),
    );
    Ok(KernelError {
        rms: sq(false),
        l1,
        rms_far: sq(true),
    })
}

/// Fig. 4.13a–c: one solve of `wall-floor`, rendered with each gather.
fn scene_gathers(ctx: &Ctx, name: &str, cells: usize, gathers: &[GatherMode]) -> Result<()> {
    let scene = scene_sampler::builtin(name)?.into_3d()?;
    let bvh = SceneBvh::new(&scene);
    let domain = Domain::ThreeD(KernelSampler::new(&scene, &bvh));
    let config = SolveConfig {
        kernel_cells: cells,
        shading_cells: cells / 2,
        // Fig. 4.13a/b show the base gather: keep the base.
        skip_unused_base: false,
        ..SolveConfig::default()
    };
    let trained = gcr::solve::solve(&domain, &config, &mut |_| {})?;
    let cam = gcr::output::raster::PinholeCamera {
        eye: scene.camera.eye,
        target: scene.camera.target,
        up: scene.camera.up,
        fov_y_degrees: scene.camera.fov_y_deg,
    };
    // One exposure for all three (from the ray gather), so that the images compare.
    let mut exposure: Option<Exposure> = None;
    for &gather in gathers {
        let config = SolveConfig { gather, ..config };
        let (mesh, _) = output_mesh(&domain, &trained, &config, RetriangulateLimits::default());
        let exposure = exposure.get_or_insert_with(|| {
            Exposure::auto(
                mesh.triangles
                    .iter()
                    .zip(&mesh.face_of_triangle)
                    .filter(|(_, f)| scene.faces[**f as usize].emission.is_zero())
                    .map(|(t, _)| mesh.radiosity[t[0] as usize]),
            )
        });
        let size = if ctx.quick { 128 } else { 512 };
        let px = gcr::output::raster::render(&mesh, &cam, exposure, size, size, 2);
        let path = ctx.out.join(format!("gcr-{name}-{}.png", gather.name()));
        image::RgbImage::from_raw(size, size, px)
            .context("image buffer")?
            .save(&path)
            .with_context(|| format!("writing {}", path.display()))?;
    }
    Ok(())
}

/// Writes this group's figures into `ctx.out`.
pub fn run(ctx: &Ctx) -> Result<()> {
    let (budgets, n): (&[usize], usize) = if ctx.quick {
        (&[16, 40], 48)
    } else {
        (&[16, 100, 500], 256)
    };
    let mut md = String::from(
        "# Flatland light flow: the kernel network against the sampled kernel\n\n\
         Relative RMS of Ψ(x,y) against K(x,y)·s(x) over an n×n grid of the arc-length parameters \
         (s(x) = GCR's final strength). Command: `cargo xtask figures --only gcr`.\n\n\
         | scene | kernel cells | grid | relative RMS | relative L1 | relative RMS, pairs > 5 % apart |\n\
         |---|---:|---:|---:|---:|---:|\n",
    );
    for name in ["flatland-corner", "flatland-blocker"] {
        for &cells in budgets {
            let e = flatland_kernel(ctx, name, cells, n)?;
            println!(
                "figures gcr: {name} {cells} cells: kernel relative RMS {:.4}, L1 {:.4}, far RMS {:.4}",
                e.rms, e.l1, e.rms_far
            );
            writeln!(
                md,
                "| {name} | {cells} | {n}² | {:.4} | {:.4} | {:.4} |",
                e.rms, e.l1, e.rms_far
            )?;
        }
    }
    std::fs::write(ctx.out.join("gcr-kernel-error.md"), md)?;
    let all = [GatherMode::Rays, GatherMode::Base, GatherMode::Kernel];
    let cells = if ctx.quick { 40 } else { 300 };
    scene_gathers(ctx, "wall-floor", cells, &all)?;
    if !ctx.quick {
        // Fig. 4.15f (the final solution of the two-blocker scene) and the Cornell box.
        scene_gathers(
            ctx,
            "two-blockers",
            cells,
            &[GatherMode::Rays, GatherMode::Kernel],
        )?;
        scene_gathers(
            ctx,
            "cornell-box",
            cells,
            &[GatherMode::Rays, GatherMode::Kernel],
        )?;
    }
    Ok(())
}
