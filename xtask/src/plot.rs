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

/// Writes RGB tiles (each `(label, width, height, pixels)`, row-major, top row first) side by side
/// as one PNG: a white gap of 8 pixels between them and a white strip with each tile's label above it.
pub fn panel(path: &Path, tiles: &[(&str, u32, u32, &[u8])]) -> Result<()> {
    use plotters::prelude::*;
    anyhow::ensure!(!tiles.is_empty(), "empty panel");
    let gap = 8u32;
    let strip = 28u32;
    let width = tiles.iter().map(|t| t.1).sum::<u32>() + gap * (tiles.len() as u32 - 1);
    let height = strip + tiles.iter().map(|t| t.2).max().unwrap_or(0);
    let mut buf = vec![255u8; (width * height * 3) as usize];
    let mut x0 = 0u32;
    let mut label_x = Vec::with_capacity(tiles.len());
    for &(_, w, h, px) in tiles {
        anyhow::ensure!(px.len() == (w * h * 3) as usize, "tile size mismatch");
        for y in 0..h {
            let src = &px[(y * w * 3) as usize..((y + 1) * w * 3) as usize];
            let dst = (((strip + y) * width + x0) * 3) as usize;
            buf[dst..dst + src.len()].copy_from_slice(src);
        }
        label_x.push(x0);
        x0 += w + gap;
    }
    register_font();
    {
        // Draws on the composed buffer without clearing it.
        let root = BitMapBackend::with_buffer(&mut buf, (width, height)).into_drawing_area();
        for (&(label, ..), &x) in tiles.iter().zip(&label_x) {
            root.draw(&Text::new(
                label.to_string(),
                (x as i32 + 4, 6),
                ("sans-serif", 16).into_font().color(&BLACK),
            ))
            .map_err(|e| anyhow::anyhow!("plotting: {e}"))?;
        }
        root.present()
            .map_err(|e| anyhow::anyhow!("plotting: {e}"))?;
    }
    image::RgbImage::from_raw(width, height, buf)
        .ok_or_else(|| anyhow::anyhow!("bad image buffer"))?
        .save(path)?;
    Ok(())
}

/// A log–log line plot of named series of `(x, y)` points (900 × 600), each drawn as a line with dots.
pub fn loglog(
    path: &Path,
    title: &str,
    x_desc: &str,
    y_desc: &str,
    series: &[(String, Vec<(f64, f64)>)],
) -> Result<()> {
    use plotters::prelude::*;
    let pts = series.iter().flat_map(|s| s.1.iter().copied());
    let (mut xmin, mut xmax, mut ymin, mut ymax) = (f64::INFINITY, 0.0f64, f64::INFINITY, 0.0f64);
    for (x, y) in pts.filter(|(x, y)| *x > 0.0 && *y > 0.0) {
        (xmin, xmax, ymin, ymax) = (xmin.min(x), xmax.max(x), ymin.min(y), ymax.max(y));
    }
    anyhow::ensure!(xmax > 0.0 && ymax > 0.0, "nothing to plot");
    let colours = [RED, BLUE, GREEN, BLACK, MAGENTA, CYAN];
    png(path, 900, 600, |root| {
        let err = |e: &dyn std::fmt::Display| anyhow::anyhow!("plotting: {e}");
        let mut chart = ChartBuilder::on(root)
            .caption(title, ("sans-serif", 22))
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(60)
            .build_cartesian_2d(
                (xmin * 0.7..xmax * 1.4).log_scale(),
                (ymin * 0.7..ymax * 1.4).log_scale(),
            )
            .map_err(|e| err(&e))?;
        chart
            .configure_mesh()
            .x_desc(x_desc)
            .y_desc(y_desc)
            .x_label_formatter(&|v| format!("{v:.0e}"))
            .y_label_formatter(&|v| format!("{v:.3}"))
            .draw()
            .map_err(|e| err(&e))?;
        for ((name, points), colour) in series.iter().zip(colours.iter().cycle()) {
            let points: Vec<(f64, f64)> = points
                .iter()
                .copied()
                .filter(|(x, y)| *x > 0.0 && *y > 0.0)
                .collect();
            chart
                .draw_series(LineSeries::new(points.clone(), colour.stroke_width(2)))
                .map_err(|e| err(&e))?
                .label(name.clone())
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 18, y)], colour.stroke_width(2))
                });
            chart
                .draw_series(
                    points
                        .into_iter()
                        .map(|p| Circle::new(p, 4, colour.filled())),
                )
                .map_err(|e| err(&e))?;
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .draw()
            .map_err(|e| err(&e))?;
        Ok(())
    })
}
