//! Shared plotting helpers: plotters with a bundled font, PNG writers.

use anyhow::Result;
use std::path::Path;

/// DejaVu Sans (Bitstream Vera licence), bundled so that plots render the same on every machine.
static FONT: &[u8] = include_bytes!("../assets/DejaVuSans.ttf");

/// Registers the bundled font as plotters' `sans-serif`. Call before drawing text.
pub fn register_font() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        // Registration only fails for an unparsable font; ours is bundled and valid.
        let _ =
            plotters::style::register_font("sans-serif", plotters::style::FontStyle::Normal, FONT);
    });
}

/// Draws with plotters into an RGB buffer of `width`×`height` and writes it as PNG.
///
/// `draw` receives the root drawing area (already filled white).
pub fn png<F>(path: &Path, width: u32, height: u32, draw: F) -> Result<()>
where
    F: FnOnce(
        &plotters::drawing::DrawingArea<
            plotters::prelude::BitMapBackend<'_>,
            plotters::coord::Shift,
        >,
    ) -> Result<()>,
{
    use plotters::prelude::*;
    register_font();
    let mut buf = vec![0u8; (width * height * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buf, (width, height)).into_drawing_area();
        root.fill(&WHITE)
            .map_err(|e| anyhow::anyhow!("plotting: {e}"))?;
        draw(&root)?;
        root.present()
            .map_err(|e| anyhow::anyhow!("plotting: {e}"))?;
    }
    image::RgbImage::from_raw(width, height, buf)
        .ok_or_else(|| anyhow::anyhow!("bad image buffer"))?
        .save(path)?;
    Ok(())
}

/// Writes a row-major grey image (values mapped linearly from `[lo, hi]` to black..white) as PNG.
pub fn write_grey_png(
    path: &Path,
    width: usize,
    height: usize,
    values: &[f64],
    lo: f64,
    hi: f64,
) -> Result<()> {
    anyhow::ensure!(values.len() == width * height, "image size mismatch");
    let span = if hi > lo { hi - lo } else { 1.0 };
    let pixels: Vec<u8> = values
        .iter()
        .map(|v| (((v - lo) / span).clamp(0.0, 1.0) * 255.0).round() as u8)
        .collect();
    image::GrayImage::from_raw(width as u32, height as u32, pixels)
        .ok_or_else(|| anyhow::anyhow!("bad image buffer"))?
        .save(path)?;
    Ok(())
}
