//! Image encoders: tone-mapped PNG and JPEG, and linear HDR OpenEXR (RGB, 32-bit float,
//! radiance L = B/π per pixel).

use super::raster::RadianceImage;
use std::io::Write;
use std::path::Path;

/// Encodes `img` as an OpenEXR file (channels R, G, B as f32, lossless), in memory.
pub fn encode_exr(img: &RadianceImage) -> std::io::Result<Vec<u8>> {
    use exr::prelude::{Image, SpecificChannels, Vec2, WritableImage};
    let w = img.width as usize;
    let channels = SpecificChannels::rgb(|Vec2(x, y): Vec2<usize>| {
        let p = img.radiance[y * w + x];
        (p[0], p[1], p[2])
    });
    let image = Image::from_channels((w, img.height as usize), channels);
    let mut buf = std::io::Cursor::new(Vec::new());
    image
        .write()
        .to_buffered(&mut buf)
        .map_err(std::io::Error::other)?;
    Ok(buf.into_inner())
}

/// Encodes `img` as JPEG (quality 92) into `w`.
pub fn write_jpeg(img: &image::RgbImage, w: &mut dyn Write) -> std::io::Result<()> {
    encode(
        image::codecs::jpeg::JpegEncoder::new_with_quality(w, 92),
        img,
    )
}

/// Encodes `img` as PNG into `w` (the encoder `image::save` uses for .png, same bytes).
pub fn write_png(img: &image::RgbImage, w: &mut dyn Write) -> std::io::Result<()> {
    encode(image::codecs::png::PngEncoder::new(w), img)
}

/// `img` through `encoder`, its errors as I/O errors.
fn encode(encoder: impl image::ImageEncoder, img: &image::RgbImage) -> std::io::Result<()> {
    encoder
        .write_image(
            img.as_raw(),
            img.width(),
            img.height(),
            image::ExtendedColorType::Rgb8,
        )
        .map_err(|e| match e {
            image::ImageError::IoError(e) => e,
            other => std::io::Error::other(other),
        })
}

/// An image's file format, from its extension (checked by [`super::OutputPlan::with_images`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Format {
    Png,
    Jpeg,
    Exr,
}

/// The format an image output gets from its extension (PNG unless .jpg, .jpeg or .exr).
pub(super) fn format_of(path: &Path) -> Format {
    match path.extension().map(|e| e.to_string_lossy().to_lowercase()) {
        Some(e) if e == "exr" => Format::Exr,
        Some(e) if e == "jpg" || e == "jpeg" => Format::Jpeg,
        _ => Format::Png,
    }
}
