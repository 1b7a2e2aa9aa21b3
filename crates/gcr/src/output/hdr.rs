//! Linear HDR images as OpenEXR (RGB, 32-bit float, radiance L = B/π per pixel).

use super::raster::RadianceImage;

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
