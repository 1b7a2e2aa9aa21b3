//! Figures of the `kernel3d` group: the growing-cells kernel network (GCR) against hierarchical
//! radiosity (HR) at equal numbers of links in 3-D (sec. 4.3, figs. 4.14 and 4.16: "two geometries
//! without blockers" and "with blockers"; the dissertation reports GCR's error at about half HR's).
//!
//! The light flow `L(x,y) = K(x,y)·B(x)` (docs/design/math.md §4, K = ρ(y)·G(x,y)·V(x,y)) is compared at N random
//! pairs (x, y) drawn area-uniformly over the scene's faces ((s,t,u,v) ∈ \[0,1\]⁴, fig. B.2):
//! * **exact**: the traced kernel times B(x) from the pointwise path tracer (`paths` per point; its own
//!   noise is part of the reference, reported);
//! * **GCR**: the kernel network Ψ(x,y) ([`gcr::stages::KernelCells::evaluate`]) after a default solve with
//!   `kernel_cells` = the budget;
//! * **HR**: `K̂·B_HR(x)`, with `K̂ = ρ(y)·F_rs/A_s` of the link (r, s) whose receiver contains y and
//!   whose sender contains x (the 3-D analogue of fig. 4.2b), and B_HR(x) HR's leaf value; the budget is
//!   met within 25 % by `solve_tri_for_links` (ε searched). Pairs no link covers (faces that do not see each other)
//!   get 0.
//!
//! Errors over the pairs and the three bands: relative RMS, relative L1, RMS/max (as in the Flatland
//! comparison). Outputs `comparison-kernel-3d.md` and `comparison-kernel-3d-<scene>.png`.

use super::comparisons::{Run, error_plot, flow_error};
use crate::ctx::Ctx;
use anyhow::Result;
use baselines::hierarchical::{TriHr, TriHrConfig, solve_tri_for_links};
use gcr::{Domain, Ray, SolveConfig};
use glam::DVec3;
use rayon::prelude::*;
use scene_sampler::{KernelSampler, Scene, SceneBvh, SurfacePoint};
use std::collections::HashMap;
use std::time::Instant;

/// Barycentric (b1, b2) of `p` projected onto triangle `v`.
fn barycentric(v: [DVec3; 3], p: DVec3) -> (f64, f64) {
    let (e1, e2, d) = (v[1] - v[0], v[2] - v[0], p - v[0]);
    let (a, b, c) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
    let (d1, d2) = (d.dot(e1), d.dot(e2));
    let det = a * c - b * b;
    if det <= 0.0 {
        return (1.0 / 3.0, 1.0 / 3.0);
    }
    ((c * d1 - b * d2) / det, (a * d2 - b * d1) / det)
}

/// Patch indices from the root (the face) down to the leaf containing `p`, as `TriHr::leaf_at` descends.
fn chain(hr: &TriHr, face: u32, p: DVec3) -> Vec<u32> {
    let patches = hr.patches();
    let mut out = vec![face];
    let mut i = face as usize;
    while let Some(c) = patches[i].children {
        let (b1, b2) = barycentric(patches[i].v, p);
        let b0 = 1.0 - b1 - b2;
        let k = if b0 >= 0.5 {
            0
        } else if b1 >= 0.5 {
            1
        } else if b2 >= 0.5 {
            2
        } else {
            3
        };
        i = c[k] as usize;
        out.push(i as u32);
    }
    out
}

/// HR's light flow at the pairs (all three bands, flattened).
fn hr_flow(scene: &Scene, hr: &TriHr, rays: &[Ray]) -> Result<Vec<f64>> {
    let links: HashMap<(u32, u32), f64> = hr
        .links()
        .iter()
        .map(|l| ((l.receiver, l.sender), l.form_factor()))
        .collect();
    let patches = hr.patches();
    let mut out = Vec::with_capacity(3 * rays.len());
    for r in rays {
        let (cy, cx) = (chain(hr, r.face_y, r.y), chain(hr, r.face_x, r.x));
        let k = cy
            .iter()
            .flat_map(|&a| cx.iter().map(move |&b| (a, b)))
            .find_map(|key| links.get(&key).map(|f| (key.1, *f)))
            .map(|(s, f)| f / patches[s as usize].area);
        let bx = hr.radiosity_at(&SurfacePoint {
            point: r.x,
            normal: r.nx,
            face: r.face_x,
        })?;
        let rho = scene.faces[r.face_y as usize].rho.0;
        for band in 0..3 {
            out.push(k.map_or(0.0, |k| rho[band] * k * bx.0[band]));
        }
    }
    Ok(out)
}

/// One scene: exact flow, then GCR and HR at each budget. Returns the markdown rows.
fn scene_rows(
    ctx: &Ctx,
    name: &str,
    budgets: &[usize],
    pairs: usize,
    paths: usize,
) -> Result<String> {
    let scene = scene_sampler::builtin(name)?.into_3d()?;
    let bvh = SceneBvh::new(&scene);
    let domain = Domain::ThreeD(KernelSampler::new(&scene, &bvh));
    // A 4-D Kronecker sequence: the same pairs every run.
    let alpha = [0.819_172_513, 0.671_043_606, 0.549_700_478, 0.450_299_522];
    let rays: Vec<Ray> = (1..=pairs)
        .into_par_iter()
        .map(|i| domain.ray(&alpha.map(|a| (i as f64 * a).fract())))
        .collect();
    let senders: Vec<SurfacePoint> = rays
        .iter()
        .map(|r| SurfacePoint {
            point: r.x,
            normal: r.nx,
            face: r.face_x,
        })
        .collect();
    let t = Instant::now();
    let b = baselines::pointwise::radiosity_at(&scene, &bvh, &senders, paths, 0x3D);
    let ref_s = t.elapsed().as_secs_f64();
    let exact: Vec<f64> = rays
        .iter()
        .zip(&b)
        .flat_map(|(r, e)| (0..3).map(move |k| r.kernel[k] * e.mean[k]))
        .collect();
    let noisy: Vec<f64> = rays
        .iter()
        .zip(&b)
        .flat_map(|(r, e)| (0..3).map(move |k| r.kernel[k] * (e.mean[k] + e.std_error[k])))
        .collect();
    let noise = flow_error(&noisy, &exact);
    let mut md = format!(
        "\n### {name}\n\n{pairs} pairs, reference B(x) by the path tracer with {paths} paths per point \
         ({ref_s:.1} s; one standard error moves the flow by {:.2} % relative RMS, {:.2} % relative L1).\n\n\
         | budget | method | links / cells | rel. RMS | rel. L1 | RMS/max | ΣL̃/ΣL | seconds |\n\
         |---:|---|---:|---:|---:|---:|---:|---:|\n",
        100.0 * noise.rel_rms,
        100.0 * noise.rel_l1
    );
    let (mut gcr_runs, mut hr_runs) = (Vec::new(), Vec::new());
    for &links in budgets {
        let config = SolveConfig {
            kernel_cells: links,
            shading_cells: links / 2,
            ..SolveConfig::default()
        };
        let t = Instant::now();
        let trained = gcr::solve(&domain, &config, &mut |_| {})?;
        let seconds = t.elapsed().as_secs_f64();
        let flow: Vec<f64> = rays
            .par_iter()
            .flat_map_iter(|r| trained.kernel.evaluate(r.x, r.nx, r.y, r.ny))
            .collect();
        let error = flow_error(&flow, &exact);
        let row = |m: &str, n: usize, e: &super::comparisons::FlowError, s: f64| {
            format!(
                "| {links} | {m} | {n} | {:.1} % | {:.1} % | {:.3} % | {:.3} | {s:.2} |\n",
                100.0 * e.rel_rms,
                100.0 * e.rel_l1,
                100.0 * e.rms_over_max,
                e.total
            )
        };
        md += &row("GCR", trained.kernel.len(), &error, seconds);
        println!("figures kernel3d: {name} GCR {links}: {error:?}");
        gcr_runs.push(Run {
            links: trained.kernel.len(),
            seconds,
            one_solve: None,
            flow: Vec::new(),
            error,
        });
        let t = Instant::now();
        match solve_tri_for_links(&scene, links, TriHrConfig::default(), 0.25) {
            Ok(found) => {
                let seconds = t.elapsed().as_secs_f64();
                let flow = hr_flow(&scene, &found.hr, &rays)?;
                let error = flow_error(&flow, &exact);
                println!("figures kernel3d: {name} HR {links}: {error:?}");
                md += &row("HR", found.hr.link_count(), &error, seconds);
                hr_runs.push(Run {
                    links: found.hr.link_count(),
                    seconds,
                    one_solve: None,
                    flow: Vec::new(),
                    error,
                });
            }
            Err(why) => {
                println!("figures kernel3d: {name} HR {links}: not reached: {why}");
                md += &format!("| {links} | HR | not reached: {why} | | | | | |\n");
            }
        }
    }
    error_plot(
        &ctx.out.join(format!("comparison-kernel-3d-{name}.png")),
        &format!("{name}: light flow K·B at random pairs, GCR vs HR"),
        &gcr_runs,
        &hr_runs,
    )?;
    Ok(md)
}

/// Writes this group's figures into `ctx.out`.
pub fn run(ctx: &Ctx) -> Result<()> {
    let (scenes, budgets, pairs, paths): (&[&str], &[usize], usize, usize) = if ctx.quick {
        (&["wall-floor"], &[30], 400, 64)
    } else {
        (
            &["wall-floor", "two-blockers"],
            &[50, 100, 200, 400, 1000],
            20_000,
            1000,
        )
    };
    let mut md = format!(
        "# 3-D light flow: GCR against HR at equal links (figs. 4.14, 4.16)\n\n\
         Command: `cargo xtask figures --only kernel3d{}`. Method: `xtask/src/figures/kernel3d.rs` (module \
         docs). Errors over random pairs (x, y) and the three bands against the traced kernel times the \
         path-traced B(x).\n",
        if ctx.quick { " --quick" } else { "" }
    );
    for name in scenes {
        md += &scene_rows(ctx, name, budgets, pairs, paths)?;
    }
    std::fs::write(ctx.out.join("comparison-kernel-3d.md"), md)?;
    Ok(())
}
