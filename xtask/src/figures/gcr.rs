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
//! * `gcr-{wall-floor,two-blockers}-{samples,network,triangulation}.png` ([`topology`]),
//!   `gcr-wall-floor-network-unbroken.png` (the network of a solve without our breaking operator, as
//!   the dissertation's), and the panels `gcr-wall-floor-fig4.12.png` (fig. 4.12a–c) and `gcr-two-blockers-fig4.15.png` (fig. 4.15d–f:
//!   network, triangulation, the kernel-gather render); their counts in `gcr-topology.md`.
//! * `gcr-two-blockers-sharp-fine-{kernel,rays}.png` and the panel `gcr-two-blockers-sharp-fig4.19.png`
//!   (fig. 4.19c): the blurry shadows of the kernel collection against the ray gather's, on the second
//!   two-blocker geometry, both gathered on one fine uniform mesh.

use super::topology;
use crate::ctx::Ctx;
use anyhow::{Context, Result};
use gcr::output::Exposure;
use gcr::output::{Image, PinholeCamera, render_image};
use gcr::stages::retriangulate;
use gcr::{
    Domain, Emitters, GatherMode, RetriangulateLimits, ShadedMesh, SolveConfig, output_mesh,
    radiosity_at_points,
};
use glam::DVec3;
use rayon::prelude::*;
use scene_sampler::{AnyScene, FlatKernelSampler, KernelSampler, Scene, SceneBvh};
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
    let trained = gcr::solve(&domain, &config, &mut |_| {})?;
    // Row-major, row 0 at the top = t close to 1.
    let near = 0.05 * domain.diagonal();
    let cells_grid: Vec<(f64, f64, bool)> = (0..n * n)
        .into_par_iter()
        .map(|i| {
            let (row, col) = (i / n, i % n);
            let s = (col as f64 + 0.5) / n as f64;
            let t = 1.0 - (row as f64 + 0.5) / n as f64;
            let ray = domain.ray(&[s, t]);
            let strength = ray.emission_x[0] + trained.reflected_kernel(ray.x, ray.nx)[0];
            let far = ray.x.distance(ray.y) > near;
            (
                ray.kernel[0] * strength,
                trained.kernel.evaluate(ray.x, ray.nx, ray.y, ray.ny)[0],
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

/// Renders of one solve, one per gather, and (when asked for) its topology overlays.
struct SceneFigures {
    /// One image per requested gather, in the order asked for.
    renders: Vec<(GatherMode, Image)>,
    /// Samples, shading network and re-triangulation (figs. 4.12a–c, 4.15d–e).
    topology: Option<([Image; 3], topology::Counts)>,
}

/// The scene's default camera as the rasterizer's.
fn camera(scene: &Scene) -> PinholeCamera {
    PinholeCamera {
        eye: scene.camera.eye,
        target: scene.camera.target,
        up: scene.camera.up,
        fov_y_degrees: scene.camera.fov_y_deg,
    }
}

/// One exposure for several renders (from the first one's non-emitting vertices).
fn exposure_of(scene: &Scene, mesh: &ShadedMesh) -> Exposure {
    Exposure::auto(
        mesh.triangles
            .iter()
            .zip(&mesh.face_of_triangle)
            .filter(|(_, f)| scene.faces[**f as usize].emission.is_zero())
            .map(|(t, _)| mesh.radiosity[t[0] as usize]),
    )
}

/// Fig. 4.13a–c: one solve of `name`, rendered with each gather into `gcr-<name>-<gather>.png`;
/// with `with_topology`, also the overlays of [`topology::write`] (figs. 4.12, 4.15d–e).
fn scene_gathers(
    ctx: &Ctx,
    name: &str,
    cells: usize,
    gathers: &[GatherMode],
    with_topology: bool,
) -> Result<SceneFigures> {
    let scene = scene_sampler::builtin(name)?.into_3d()?;
    let bvh = SceneBvh::new(&scene);
    let domain = Domain::ThreeD(KernelSampler::new(&scene, &bvh));
    let config = SolveConfig {
        kernel_cells: cells,
        shading_cells: cells / 2,
        // Fig. 4.13a/b show the base gather, figs. 4.12b / 4.15d its shading network: keep the base.
        skip_unused_base: false,
        ..SolveConfig::default()
    };
    let trained = gcr::solve(&domain, &config, &mut |_| {})?;
    let cam = camera(&scene);
    let size = if ctx.quick { 128 } else { 512 };
    // One exposure for all gathers (from the first, the ray gather), so that the images compare.
    let mut exposure: Option<Exposure> = None;
    let mut figures = SceneFigures {
        renders: Vec::new(),
        topology: None,
    };
    for &gather in gathers {
        let config = SolveConfig { gather, ..config };
        let (mesh, _) = output_mesh(&domain, &trained, &config, RetriangulateLimits::default())?;
        let exposure = exposure.get_or_insert_with(|| exposure_of(&scene, &mesh));
        let img = render_image(&mesh, None, &cam, exposure, size, size, 2);
        topology::save(
            &img,
            &ctx.out.join(format!("gcr-{name}-{}.png", gather.name())),
        )?;
        figures.renders.push((gather, img));
        if with_topology && figures.topology.is_none() {
            // The output mesh is the same for every gather: draw it once.
            figures.topology = Some(topology::write(
                &ctx.out, name, &scene, &trained, &mesh, &cam, size,
            )?);
        }
    }
    Ok(figures)
}

/// Fig. 4.12b as the dissertation has it: the same solve as [`scene_gathers`] with the breaking
/// operator off, only its shading network drawn (`gcr-<name>-network-unbroken.png`).
/// Returns the image, the shading cells and the shading triangles.
fn unbroken_network(ctx: &Ctx, name: &str, cells: usize) -> Result<(Image, usize, usize)> {
    let scene = scene_sampler::builtin(name)?.into_3d()?;
    let bvh = SceneBvh::new(&scene);
    let domain = Domain::ThreeD(KernelSampler::new(&scene, &bvh));
    let mut config = SolveConfig {
        kernel_cells: cells,
        shading_cells: cells / 2,
        skip_unused_base: false,
        ..SolveConfig::default()
    };
    config.breaking.enabled = false;
    let trained = gcr::solve(&domain, &config, &mut |_| {})?;
    let cam = camera(&scene);
    let size = if ctx.quick { 128 } else { 512 };
    let background = topology::geometry_background(&scene, &cam, size, 2);
    let img = topology::network_image(&background, &trained);
    topology::save(
        &img,
        &ctx.out.join(format!("gcr-{name}-network-unbroken.png")),
    )?;
    let geo = &trained.fem.base.geo;
    Ok((img, geo.centres.len(), geo.simplices.len()))
}

/// Fig. 4.19c: the kernel collection (the dissertation's final shading, fig. 4.13c) next to our
/// ray gather on one solve of a two-blocker scene, both gathered at the vertices of one uniform
/// mesh of edge length `edge` (finer than the shading network's), so that the two images differ
/// by the gather only: the RBF kernel blurs the shadows, the shadow rays keep them.
/// Writes `gcr-<scene>-fine-{kernel,rays}.png` and returns them (kernel first).
fn blocking_effects(
    ctx: &Ctx,
    scene: Scene,
    cells: usize,
    edge: f64,
) -> Result<Vec<(GatherMode, Image)>> {
    let name = scene.name.clone();
    let bvh = SceneBvh::new(&scene);
    let domain = Domain::ThreeD(KernelSampler::new(&scene, &bvh));
    let config = SolveConfig {
        kernel_cells: cells,
        shading_cells: cells / 2,
        ..SolveConfig::default()
    };
    let trained = gcr::solve(&domain, &config, &mut |_| {})?;
    let faces: Vec<[DVec3; 3]> = scene.faces.iter().map(|f| f.v).collect();
    let tri = retriangulate(&faces, |_| edge, RetriangulateLimits::default());
    let mut vertex_face = vec![0u32; tri.positions.len()];
    for (t, f) in tri.triangles.iter().zip(&tri.face_of_triangle) {
        for &v in t {
            vertex_face[v as usize] = *f;
        }
    }
    let points: Vec<(DVec3, DVec3, u32)> = tri
        .positions
        .iter()
        .zip(&vertex_face)
        .map(|(p, &f)| (*p, scene.faces[f as usize].normal, f))
        .collect();
    let emitters = Emitters::new(&domain);
    let cam = camera(&scene);
    let size = if ctx.quick { 128 } else { 512 };
    let mut exposure: Option<Exposure> = None;
    let mut out = Vec::new();
    // Rays first: the exposure comes from the sharper solution.
    for gather in [GatherMode::Rays, GatherMode::Kernel] {
        let config = SolveConfig { gather, ..config };
        let b = radiosity_at_points(&domain, &trained, &emitters, &config, &points)?;
        let mesh = ShadedMesh {
            positions: tri.positions.clone(),
            triangles: tri.triangles.clone(),
            face_of_triangle: tri.face_of_triangle.clone(),
            radiosity: b.iter().map(|g| [g.radiosity[0]; 3]).collect(),
        };
        let exposure = exposure.get_or_insert_with(|| exposure_of(&scene, &mesh));
        let img = render_image(&mesh, None, &cam, exposure, size, size, 2);
        topology::save(
            &img,
            &ctx.out
                .join(format!("gcr-{name}-fine-{}.png", gather.name())),
        )?;
        println!(
            "figures gcr: {name} fig. 4.19c, {} gather at {} vertices",
            gather.name(),
            points.len()
        );
        out.push((gather, img));
    }
    out.reverse();
    Ok(out)
}

/// A panel of rendered images with their labels (see [`crate::plot::panel`]).
fn panel(path: &std::path::Path, tiles: &[(&str, &Image)]) -> Result<()> {
    let tiles: Vec<(&str, u32, u32, &[u8])> = tiles
        .iter()
        .map(|(l, i)| (*l, i.width, i.height, i.pixels.as_slice()))
        .collect();
    crate::plot::panel(path, &tiles)
}

/// One row of `gcr-topology.md` (and the same on stdout).
fn topo_row(md: &mut String, name: &str, cells: usize, c: &topology::Counts) -> Result<()> {
    println!(
        "figures gcr: {name}: {} samples, {} shading cells, {} shading triangles, output {} triangles / {} vertices",
        c.samples, c.cells, c.simplices, c.triangles, c.vertices
    );
    writeln!(
        md,
        "| {name} | {cells} | {} | {} | {} | {} | {} |",
        c.samples, c.cells, c.simplices, c.triangles, c.vertices
    )?;
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
    let mut topo_md = String::from(
        "# What the overlays of figs. 4.12 and 4.15 show\n\n\
         Command: `cargo xtask figures --only gcr`. One solve per scene (default settings, the base kept); \
         the shading network is the one of the last FEM step. Images: `gcr-<scene>-{samples,network,triangulation}.png`, \
         panels `gcr-wall-floor-fig4.12.png` and `gcr-two-blockers-fig4.15.png`.\n\n\
         | scene | kernel cells | sample rays (receiver points, fig. 4.12a) | shading cells | shading triangles (after breaking) | output triangles | output vertices |\n\
         |---|---:|---:|---:|---:|---:|---:|\n",
    );
    // Figs. 4.11c, 4.12a–c, 4.13a–c.
    let wf = scene_gathers(ctx, "wall-floor", cells, &all, true)?;
    let (unbroken, unbroken_cells, unbroken_triangles) =
        unbroken_network(ctx, "wall-floor", cells)?;
    if let Some(([samples, network, tri], counts)) = &wf.topology {
        topo_row(&mut topo_md, "wall-floor", cells, counts)?;
        writeln!(
            topo_md,
            "| wall-floor, breaking operator off (network only) | {cells} | | {unbroken_cells} | {unbroken_triangles} | | |"
        )?;
        panel(
            &ctx.out.join("gcr-wall-floor-fig4.12.png"),
            &[
                ("(a) kernel training samples: receivers y", samples),
                ("(b) shading network (no breaking)", &unbroken),
                ("(b') ... with our breaking operator", network),
                ("(c) re-triangulation", tri),
            ],
        )?;
    }
    // Fig. 4.15d–f: the two-blocker scene's network, triangulation and final shading (the
    // kernel collection, as the dissertation's; the ray gather is written next to it).
    let two_cells = if ctx.quick { 40 } else { cells };
    let tb = scene_gathers(
        ctx,
        "two-blockers",
        two_cells,
        &[GatherMode::Rays, GatherMode::Kernel],
        true,
    )?;
    if let Some(([_, network, tri], counts)) = &tb.topology {
        topo_row(&mut topo_md, "two-blockers", two_cells, counts)?;
        let kernel = tb
            .renders
            .iter()
            .find(|(g, _)| *g == GatherMode::Kernel)
            .map(|(_, i)| i)
            .context("kernel render")?;
        panel(
            &ctx.out.join("gcr-two-blockers-fig4.15.png"),
            &[
                ("(d) shading network", network),
                ("(e) triangulation", tri),
                ("(f) final shading (kernel gather)", kernel),
            ],
        )?;
    }
    std::fs::write(ctx.out.join("gcr-topology.md"), topo_md)?;
    // Fig. 4.19c on the second two-blocker geometry (small light, sharp shadows).
    let edge = if ctx.quick { 0.2 } else { 0.03 };
    let fine = blocking_effects(
        ctx,
        scene_sampler::builtin::two_blockers_sharp(),
        two_cells,
        edge,
    )?;
    panel(
        &ctx.out.join("gcr-two-blockers-sharp-fig4.19.png"),
        &[
            ("(c) kernel gather (dissertation)", &fine[0].1),
            ("ray gather (ours)", &fine[1].1),
        ],
    )?;
    if !ctx.quick {
        scene_gathers(
            ctx,
            "cornell-box",
            cells,
            &[GatherMode::Rays, GatherMode::Kernel],
            false,
        )?;
    }
    Ok(())
}
