//! Flatland pictures: the scene drawn with its radiosity (segments as thick strokes coloured by B),
//! and a function over the kernel domain (s,t) ∈ [0,1]² as a grey image (figs. 4.1b, 4.6b: bright
//! = small, dark = large, like the dissertation).

use super::OutputError;
use super::encode::write_png;
use super::plan::OutputPlan;
use super::stage::Stage;
use crate::config::SolveConfig;
use crate::domain::Domain;
use crate::emitters::Emitters;
use crate::estimator::{GatherError, radiosity_at_points};
use crate::output::tonemap::Exposure;
use crate::solve::Trained;
use glam::{DVec2, DVec3};
use scene_sampler::FlatlandScene;
use std::time::Instant;

/// Side of the square [`scene_image`] in pixels.
pub const SCENE_IMAGE_SIZE: u32 = 512;
/// Side of each of the two square panels of [`light_flow_image`] in pixels.
pub const LIGHT_FLOW_PANEL: u32 = 256;
/// Pixels between the two panels of [`light_flow_image`].
const LIGHT_FLOW_GAP: u32 = 8;

/// The Flatland step of the output stage: the scene image ([`scene_image`]) and the light-flow
/// image ([`light_flow_image`], when the solution has a kernel network), staged.
pub(super) fn write_images(
    domain: &Domain,
    (trained, emitters): (&Trained, &Emitters),
    config: &SolveConfig,
    plan: &OutputPlan,
    stage: &mut Stage,
) -> Result<(), OutputError> {
    let Some(flat) = domain.scene_flat() else {
        return Ok(());
    };
    let to = Instant::now();
    let paths = plan.paths();
    if let Some(path) = &paths.image {
        let img = scene_image(domain, trained, emitters, config, flat)?;
        stage.files.write(path, |w| write_png(&img, w))?;
    }
    if let Some(path) = &paths.kernel_image {
        if let Some(img) = light_flow_image(domain, trained) {
            stage.files.write(path, |w| write_png(&img, w))?;
        }
    }
    stage.metrics.seconds.output += to.elapsed().as_secs_f64();
    Ok(())
}

/// A polyline piece with its radiosity, for [`draw_segments`].
#[derive(Clone, Copy, Debug)]
pub struct Stroke {
    /// Start.
    pub a: DVec2,
    /// End.
    pub b: DVec2,
    /// Radiosity B (RGB) at the start.
    pub ba: [f64; 3],
    /// Radiosity B (RGB) at the end.
    pub bb: [f64; 3],
    /// Unit front normal: the stroke is drawn on the front side (a thin dark line marks the back).
    pub normal: DVec2,
}

/// Draws strokes into an 8-bit RGB image of `size × size` covering the square view `(lo, hi)`
/// (grey background). Stroke width is `width_px`.
pub fn draw_segments(
    strokes: &[Stroke],
    lo: DVec2,
    hi: DVec2,
    size: u32,
    width_px: f64,
    exposure: &Exposure,
) -> Vec<u8> {
    let n = size as usize;
    let mut img = vec![48u8; n * n * 3];
    let span = (hi - lo).max_element().max(1e-300);
    let to_px = |p: DVec2| {
        DVec2::new(
            (p.x - lo.x) / span * (n as f64 - 1.0),
            (hi.y - p.y) / span * (n as f64 - 1.0),
        )
    };
    for s in strokes {
        let (pa, pb) = (to_px(s.a), to_px(s.b));
        // Screen-space normal (y flips).
        let nrm = DVec2::new(s.normal.x, -s.normal.y);
        let steps = ((pb - pa).length() * 2.0).ceil().max(1.0) as usize;
        for i in 0..=steps {
            let t = i as f64 / steps as f64;
            let c: [f64; 3] = [0, 1, 2].map(|k| s.ba[k] + t * (s.bb[k] - s.ba[k]));
            let rgb = exposure.srgb8(c);
            let centre = pa + t * (pb - pa);
            let w = width_px.max(1.0);
            let mut j = 0.0;
            while j <= w {
                let p = centre + nrm * j;
                let (x, y) = (p.x.round() as i64, p.y.round() as i64);
                if x >= 0 && y >= 0 && (x as usize) < n && (y as usize) < n {
                    let o = (y as usize * n + x as usize) * 3;
                    img[o..o + 3].copy_from_slice(&rgb);
                }
                j += 0.5;
            }
        }
    }
    img
}

/// Samples `f(s, t)` on a `size × size` grid over [0,1]² (s to the right, t upwards) and maps it to
/// grey: white for the minimum (0), black for `max` (or the largest value when `max` is `None`).
#[cfg(test)]
fn kernel_image(size: u32, max: Option<f64>, f: impl Fn(f64, f64) -> f64 + Sync) -> Vec<u8> {
    use rayon::prelude::*;
    let n = size as usize;
    let values: Vec<f64> = (0..n * n)
        .into_par_iter()
        .map(|i| {
            let (px, py) = (i % n, i / n);
            let s = (px as f64 + 0.5) / n as f64;
            let t = 1.0 - (py as f64 + 0.5) / n as f64;
            f(s, t)
        })
        .collect();
    let top = max.unwrap_or_else(|| {
        values
            .iter()
            .copied()
            .filter(|v| v.is_finite())
            .fold(0.0, f64::max)
    });
    let top = if top > 0.0 { top } else { 1.0 };
    values
        .iter()
        .map(|v| 255 - ((v / top).clamp(0.0, 1.0) * 255.0).round() as u8)
        .collect()
}

/// The Flatland scene drawn with its radiosity: every segment cut into 64 strokes, B gathered
/// at their ends by the configured gather ([`radiosity_at_points`]), auto-exposed, drawn into a
/// [`SCENE_IMAGE_SIZE`]² RGB image of the scene's view.
pub fn scene_image(
    domain: &Domain,
    trained: &Trained,
    emitters: &Emitters,
    config: &SolveConfig,
    flat: &FlatlandScene,
) -> Result<image::RgbImage, GatherError> {
    const PIECES: usize = 64;
    let mut points = Vec::with_capacity(flat.segments.len() * (PIECES + 1));
    for (si, s) in flat.segments.iter().enumerate() {
        let n = DVec3::new(s.normal.x, s.normal.y, 0.0);
        for j in 0..=PIECES {
            let p = s.point(j as f64 / PIECES as f64);
            points.push((DVec3::new(p.x, p.y, 0.0), n, si as u32));
        }
    }
    let b = radiosity_at_points(domain, trained, emitters, config, &points)?;
    let mut strokes = Vec::with_capacity(flat.segments.len() * PIECES);
    for (si, s) in flat.segments.iter().enumerate() {
        for j in 0..PIECES {
            let at = si * (PIECES + 1) + j;
            strokes.push(Stroke {
                a: s.point(j as f64 / PIECES as f64),
                b: s.point((j + 1) as f64 / PIECES as f64),
                ba: b[at].radiosity,
                bb: b[at + 1].radiosity,
                normal: s.normal,
            });
        }
    }
    let exposure = Exposure::auto(strokes.iter().map(|s| s.ba));
    let size = SCENE_IMAGE_SIZE;
    let px = draw_segments(&strokes, flat.view.min, flat.view.max, size, 4.0, &exposure);
    Ok(image::RgbImage::from_raw(size, size, px).expect("draw_segments fills size² RGB pixels"))
}

/// The light flow over (s, t) ∈ [0,1]² (fig. 4.1b): two [`LIGHT_FLOW_PANEL`]² panels, the sampled
/// kernel K·s with GCR's own final strength s = E + B_refl on the left and the network's Ψ on the
/// right, on one grey scale (white = 0, black = the 99th percentile of K·s; band 0), the training
/// rays as red dots on the right. `None` for a 3-D domain (its kernel has four parameters).
pub fn light_flow_image(domain: &Domain, trained: &Trained) -> Option<image::RgbImage> {
    use rayon::prelude::*;
    let Domain::Flat(sampler) = domain else {
        return None;
    };
    let n = LIGHT_FLOW_PANEL as usize;
    let pairs: Vec<(f64, f64)> = (0..n * n)
        .into_par_iter()
        .map(|i| {
            let s = (i % n) as f64 / n as f64 + 0.5 / n as f64;
            let t = 1.0 - ((i / n) as f64 + 0.5) / n as f64;
            let ray = domain.ray(&[s, t]);
            let strength = ray.emission_x[0] + trained.reflected_kernel(ray.x, ray.nx)[0];
            (
                ray.kernel[0] * strength,
                trained.kernel.evaluate(ray.x, ray.nx, ray.y, ray.ny)[0],
            )
        })
        .collect();
    let mut sorted: Vec<f64> = pairs
        .iter()
        .map(|p| p.0)
        .filter(|v| v.is_finite())
        .collect();
    sorted.sort_by(f64::total_cmp);
    let top = sorted
        .get(sorted.len() * 99 / 100)
        .copied()
        .filter(|v| *v > 0.0)
        .unwrap_or(1.0);
    let grey = |v: f64| 255 - ((v / top).clamp(0.0, 1.0) * 255.0).round() as u8;
    let (w, gap) = (2 * n + LIGHT_FLOW_GAP as usize, LIGHT_FLOW_GAP as usize);
    let mut img = image::RgbImage::from_pixel(w as u32, n as u32, image::Rgb([255, 255, 255]));
    for (i, (exact, psi)) in pairs.iter().enumerate() {
        let (x, y) = ((i % n) as u32, (i / n) as u32);
        img.put_pixel(x, y, image::Rgb([grey(*exact); 3]));
        img.put_pixel((n + gap) as u32 + x, y, image::Rgb([grey(*psi); 3]));
    }
    for smp in &trained.samples {
        let s = sampler
            .sampler
            .inverse(smp.ray.face_x, smp.ray.x.truncate());
        let t = sampler
            .sampler
            .inverse(smp.ray.face_y, smp.ray.y.truncate());
        let x = (n + gap) as f64 + (s * n as f64).min(n as f64 - 1.0);
        let y = ((1.0 - t) * n as f64).min(n as f64 - 1.0);
        img.put_pixel(x as u32, y as u32, image::Rgb([220, 30, 30]));
    }
    Some(img)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_horizontal_stroke_is_drawn_above_its_line_and_the_kernel_image_is_oriented() {
        let s = Stroke {
            a: DVec2::new(0.0, 0.5),
            b: DVec2::new(1.0, 0.5),
            ba: [1e9; 3],
            bb: [1e9; 3],
            normal: DVec2::Y,
        };
        let img = draw_segments(
            &[s],
            DVec2::ZERO,
            DVec2::ONE,
            64,
            4.0,
            &Exposure { scale: 1.0 },
        );
        let px = |x: usize, y: usize| img[(y * 64 + x) * 3];
        assert_eq!(px(32, 30), 255, "front side (above) is lit");
        assert_eq!(px(32, 40), 48, "below stays background");
        let k = kernel_image(8, None, |s, t| s * t);
        assert_eq!(k[7], 0, "top-right (s = t = 1) is the maximum: black");
        assert!(k[7 * 8] > 240, "bottom-left is ~0: white");
    }
}
