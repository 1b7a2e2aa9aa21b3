//! Figures of the `scenes` group: the built-in scenes as seen from their default cameras (ray cast through
//! `SceneBvh::closest_hit`), the Flatland scenes' geometry (`scene-flatland-*.png`, figs. 4.1a and 4.6a),
//! and the Flatland kernel goal functions over `(s, t)` (figs. 4.1b and 4.6b).

use crate::ctx::Ctx;
use anyhow::Result;
use scene_sampler::{
    AnyScene, BUILTIN_NAMES, FlatKernelSampler, FlatlandScene, Scene, SceneBvh, builtin,
};

/// Writes this group's figures into `ctx.out`.
pub fn run(ctx: &Ctx) -> Result<()> {
    for name in BUILTIN_NAMES {
        match builtin(name)? {
            AnyScene::ThreeD(s) => {
                let (w, h) = if ctx.quick { (160, 120) } else { (480, 360) };
                render_geometry(&s, w, h, &ctx.out.join(format!("scene-{name}.png")))?;
            }
            AnyScene::Flatland(s) => {
                let n = if ctx.quick { 96 } else { 400 };
                kernel_image(&s, n, &ctx.out.join(format!("kernel-{name}.png")))?;
                let side = if ctx.quick { 200 } else { 480 };
                flatland_geometry(&s, side, &ctx.out.join(format!("scene-{name}.png")))?;
            }
        }
    }
    Ok(())
}

/// A Flatland scene's geometry (figs. 4.1a, 4.6a): every segment as a line, emitters orange and thick,
/// reflectors grey with their shade darker for lower ρ, and a short tick at each segment's midpoint
/// along its normal (the side that reflects and emits).
fn flatland_geometry(scene: &FlatlandScene, side: u32, path: &std::path::Path) -> Result<()> {
    use plotters::prelude::*;
    let (mut lo, mut hi) = (
        glam::DVec2::splat(f64::INFINITY),
        glam::DVec2::splat(f64::NEG_INFINITY),
    );
    for seg in &scene.segments {
        lo = lo.min(seg.a).min(seg.b);
        hi = hi.max(seg.a).max(seg.b);
    }
    let pad = 0.08 * (hi - lo).max_element().max(1e-9);
    let (lo, hi) = (lo - glam::DVec2::splat(pad), hi + glam::DVec2::splat(pad));
    let tick = 0.04 * (hi - lo).max_element();
    let e = |m: String| anyhow::anyhow!("plotting: {m}");
    crate::plot::png(path, side, side, |root| {
        let mut chart = ChartBuilder::on(root)
            .caption(scene.name.as_str(), ("sans-serif", 16))
            .margin(8)
            .x_label_area_size(24)
            .y_label_area_size(32)
            .build_cartesian_2d(lo.x..hi.x, lo.y..hi.y)
            .map_err(|x| e(x.to_string()))?;
        chart
            .configure_mesh()
            .disable_mesh()
            .draw()
            .map_err(|x| e(x.to_string()))?;
        for seg in &scene.segments {
            let emits = seg.emission.max() > 0.0;
            let style = if emits {
                RGBColor(230, 120, 0).stroke_width(4)
            } else {
                let g = (200.0 * (1.0 - seg.rho.max())).round() as u8;
                RGBColor(g, g, g).stroke_width(2)
            };
            chart
                .draw_series(LineSeries::new(
                    [(seg.a.x, seg.a.y), (seg.b.x, seg.b.y)],
                    style,
                ))
                .map_err(|x| e(x.to_string()))?;
            let m = 0.5 * (seg.a + seg.b);
            let t = m + seg.normal * tick;
            chart
                .draw_series(LineSeries::new(
                    [(m.x, m.y), (t.x, t.y)],
                    BLUE.stroke_width(1),
                ))
                .map_err(|x| e(x.to_string()))?;
        }
        Ok(())
    })
}

/// A flat-shaded view from the scene's camera: colour = ρ·(0.25 + 0.75·|cos|), emitters white, back faces
/// magenta (so wrong windings show at once), background dark blue.
fn render_geometry(scene: &Scene, w: usize, h: usize, path: &std::path::Path) -> Result<()> {
    use rayon::prelude::*;
    let bvh = SceneBvh::new(scene);
    let cam = scene.camera;
    let fwd = (cam.target - cam.eye).normalize();
    let right = fwd.cross(cam.up).normalize();
    let up = right.cross(fwd);
    let tan = (0.5 * cam.fov_y_deg.to_radians()).tan();
    let aspect = w as f64 / h as f64;
    let px: Vec<[u8; 3]> = (0..w * h)
        .into_par_iter()
        .map(|k| {
            let (i, j) = (k % w, k / w);
            let sx = (2.0 * (i as f64 + 0.5) / w as f64 - 1.0) * tan * aspect;
            let sy = (1.0 - 2.0 * (j as f64 + 0.5) / h as f64) * tan;
            let d = (fwd + right * sx + up * sy).normalize();
            match bvh.closest_hit(cam.eye, d, f64::INFINITY, u32::MAX) {
                None => [20, 24, 60],
                Some(hit) => {
                    let f = &scene.faces[hit.face as usize];
                    let c = -f.normal.dot(d);
                    let rgb = if c <= 0.0 {
                        [1.0, 0.0, 1.0]
                    } else if f.emission.max() > 0.0 {
                        [1.0, 1.0, 1.0]
                    } else {
                        (f.rho * (0.25 + 0.75 * c)).0
                    };
                    rgb.map(|v| (v.clamp(0.0, 1.0).powf(1.0 / 2.2) * 255.0).round() as u8)
                }
            }
        })
        .collect();
    let img = image::RgbImage::from_raw(w as u32, h as u32, px.concat())
        .ok_or_else(|| anyhow::anyhow!("bad image buffer"))?;
    img.save(path)?;
    Ok(())
}

/// The kernel goal function `K(x(s), y(t))·E(x(s))` over the arc-length parameters (x: sender along the
/// horizontal axis, y: receiver along the vertical axis, t = 0 at the bottom), grey = sqrt of the value
/// normalized to its 99th percentile (the corner singularity would otherwise wash everything out).
fn kernel_image(scene: &FlatlandScene, n: usize, path: &std::path::Path) -> Result<()> {
    let k = FlatKernelSampler::new(scene);
    let mut v = vec![0.0; n * n];
    for row in 0..n {
        let t = 1.0 - (row as f64 + 0.5) / n as f64;
        for col in 0..n {
            let s = (col as f64 + 0.5) / n as f64;
            let smp = k.sample(s, t);
            let e = scene.segments[smp.x.segment as usize].emission;
            v[row * n + col] = smp.k_times_s(e).0[0].sqrt();
        }
    }
    let mut sorted = v.clone();
    sorted.sort_by(f64::total_cmp);
    let hi = sorted[(0.99 * (sorted.len() - 1) as f64) as usize].max(1e-12);
    crate::plot::write_grey_png(path, n, n, &v, 0.0, hi)
}
