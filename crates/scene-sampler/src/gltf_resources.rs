//! The data a glTF document names — its buffers and images — read by the loader itself rather than
//! by `gltf::import`, so that every file goes through the confined reader ([`crate::confine`]) and
//! only the images a material uses are decoded, each charged to the texture memory bound first.
//!
//! URIs, as the gltf crate's importer reads them: `data:[<media type>];base64,<data>`; `file:` and
//! `file://` followed by a path; anything else with a `:` is an unsupported scheme; the rest is a
//! path relative to the scene's folder. Paths are percent-decoded (`%20` is a space), and one that
//! decodes to bytes that are not UTF-8 is an error. A GLB's binary chunk is the buffer without a URI.

use crate::confine::{Folder, Refusal};
use crate::texture::TextureBudget;
use crate::{Result, SceneError, Texture, Wrap};
use glam::DVec2;
use std::path::Path;

/// What a URI names.
enum Uri<'a> {
    /// Embedded data: the media type (if given) and the base64 text.
    Data(Option<&'a str>, &'a str),
    /// A file, relative to the scene's folder or absolute, percent-decoded.
    File(String),
}

/// Parses `uri`; the error is the message.
fn parse_uri(uri: &str) -> std::result::Result<Uri<'_>, String> {
    let path = if let Some(rest) = uri.strip_prefix("data:") {
        return match rest.split_once(";base64,") {
            Some((media, data)) => Ok(Uri::Data(Some(media).filter(|m| !m.is_empty()), data)),
            None => Err("a data URI without `;base64,`: only base64 data is supported".into()),
        };
    } else if let Some(rest) = uri.strip_prefix("file://") {
        rest
    } else if let Some(rest) = uri.strip_prefix("file:") {
        rest
    } else if uri.contains(':') {
        return Err("unsupported URI scheme (data:, file: or a relative path)".into());
    } else {
        uri
    };
    String::from_utf8(percent_decode(path))
        .map(Uri::File)
        .map_err(|_| "percent-decodes to bytes that are not UTF-8".into())
}

/// `%XX` (two hex digits) as the byte; a `%` not followed by two hex digits stays as written.
fn percent_decode(s: &str) -> Vec<u8> {
    let b = s.as_bytes();
    let hex = |c: u8| (c as char).to_digit(16);
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        let pair = b
            .get(i + 1..i + 3)
            .and_then(|p| Some((hex(p[0])?, hex(p[1])?)));
        match (b[i], pair) {
            (b'%', Some((hi, lo))) => {
                out.push((hi * 16 + lo) as u8);
                i += 3;
            }
            (c, _) => {
                out.push(c);
                i += 1;
            }
        }
    }
    out
}

/// Standard base64 (RFC 4648 §4), with or without its `=` padding; `None` if malformed.
fn base64_decode(text: &str) -> Option<Vec<u8>> {
    let value = |c: u8| -> Option<u32> {
        Some(u32::from(match c {
            b'A'..=b'Z' => c - b'A',
            b'a'..=b'z' => c - b'a' + 26,
            b'0'..=b'9' => c - b'0' + 52,
            b'+' => 62,
            b'/' => 63,
            _ => return None,
        }))
    };
    let body = text.as_bytes();
    let pad = body.iter().rev().take_while(|&&c| c == b'=').count();
    let body = &body[..body.len() - pad];
    if pad > 2 || body.len() % 4 == 1 || (pad > 0 && (body.len() + pad) % 4 != 0) {
        return None;
    }
    let mut out = Vec::with_capacity(body.len() / 4 * 3 + 2);
    for chunk in body.chunks(4) {
        let mut n = 0u32;
        for (k, &c) in chunk.iter().enumerate() {
            n |= value(c)? << (18 - 6 * k);
        }
        let bytes = n.to_be_bytes();
        let keep = chunk.len() - 1;
        // the bits below the last whole byte must be zero (canonical encoding)
        if keep < 3 && n & (0xFF_FFFF >> (8 * keep)) != 0 {
            return None;
        }
        out.extend_from_slice(&bytes[1..=keep]);
    }
    Some(out)
}

/// The bytes `uri` names: decoded data, or the file read within the folder's bounds. `what` names
/// the buffer or image in errors, `source` the scene file.
fn read_uri(uri: &str, what: &str, source: &str, folder: &Folder) -> Result<Vec<u8>> {
    let parse = |message: String| SceneError::Parse {
        source_name: source.into(),
        message: format!("{what} `{uri}`: {message}"),
    };
    match parse_uri(uri).map_err(parse)? {
        Uri::Data(_, data) => {
            base64_decode(data).ok_or_else(|| parse("invalid base64 data".into()))
        }
        Uri::File(path) => folder.read(Path::new(&path)).map_err(|r| match r {
            Refusal::Outside => SceneError::OutsideFolder {
                source_name: source.into(),
                what: what.into(),
                uri: uri.into(),
            },
            Refusal::Refused(e) => e,
            Refusal::Io(e) => SceneError::Io {
                path: folder.shown(Path::new(&path)),
                source: e,
            },
        }),
    }
}

/// The document's buffers, each padded with zeros to a multiple of 4 bytes (as the gltf crate's
/// importer does); a buffer shorter than its `byteLength` is an error.
pub(crate) fn read_buffers(
    doc: &gltf::Document,
    mut blob: Option<Vec<u8>>,
    source: &str,
    folder: &Folder,
) -> Result<Vec<Vec<u8>>> {
    let mut out = Vec::new();
    for buffer in doc.buffers() {
        let what = format!("buffer {}", buffer.index());
        let mut data = match buffer.source() {
            gltf::buffer::Source::Uri(uri) => read_uri(uri, &what, source, folder)?,
            gltf::buffer::Source::Bin => blob.take().ok_or_else(|| SceneError::Parse {
                source_name: source.into(),
                message: format!("{what}: the binary chunk of the .glb is missing"),
            })?,
        };
        while data.len() % 4 != 0 {
            data.push(0);
        }
        if data.len() < buffer.length() {
            return Err(SceneError::Parse {
                source_name: source.into(),
                message: format!(
                    "{what}: expected {} bytes but received {} bytes",
                    buffer.length(),
                    data.len()
                ),
            });
        }
        out.push(data);
    }
    Ok(out)
}

/// Where a document's images come from: the file (for messages), its folder, its buffers, and the
/// texture memory still allowed.
pub(crate) struct Images<'a> {
    pub source: &'a str,
    pub folder: &'a Folder,
    pub buffers: &'a [Vec<u8>],
    pub budget: &'a mut TextureBudget,
}

/// Reads, checks against the budget and decodes an image a material uses (base colour or
/// emissive), as a colour texture named `name`. Its format is the data URI's or the image's media
/// type (PNG or JPEG), else the URI's extension, else (this build) unsupported — as the gltf
/// crate's importer.
pub(crate) fn decode_image(
    image: &gltf::Image,
    name: &str,
    wrap: [Wrap; 2],
    images: &mut Images,
) -> Result<Texture> {
    let img = read_image(image, name, images)?;
    gltf_texture(name, img, wrap)
}

/// Reads, checks against the budget and decodes a glTF image ([`decode_image`]'s first steps): the
/// image as decoded, for a colour texture or an alpha mask ([`crate::cutout`]).
pub(crate) fn read_image(
    image: &gltf::Image,
    name: &str,
    images: &mut Images,
) -> Result<image::DynamicImage> {
    let Images {
        source,
        folder,
        buffers,
        ..
    } = *images;
    let from_media = |m: Option<&str>| match m {
        Some("image/png") => Some(image::ImageFormat::Png),
        Some("image/jpeg") => Some(image::ImageFormat::Jpeg),
        _ => None,
    };
    let what = format!("image {}", image.index());
    // (an image without a source, on which `source()` panics, was refused before:
    // `gltf_accessors::parser_prechecks`)
    let (bytes, format) = match image.source() {
        gltf::image::Source::View { view, mime_type } => {
            let data = buffers.get(view.buffer().index());
            let end = view.offset().checked_add(view.length());
            let bytes = data.zip(end).and_then(|(d, end)| d.get(view.offset()..end));
            let bytes = bytes.ok_or_else(|| SceneError::Parse {
                source_name: source.into(),
                message: format!("{what}: buffer view {} is outside its buffer", view.index()),
            })?;
            (bytes.to_vec(), from_media(Some(mime_type)))
        }
        gltf::image::Source::Uri { uri, mime_type } => {
            let bytes = read_uri(uri, &what, source, folder)?;
            let format = match parse_uri(uri) {
                Ok(Uri::Data(media, _)) => from_media(media).or(from_media(mime_type)),
                _ => from_media(mime_type).or(match uri.rsplit('.').next() {
                    Some("png") => Some(image::ImageFormat::Png),
                    Some("jpg" | "jpeg") => Some(image::ImageFormat::Jpeg),
                    _ => None,
                }),
            };
            (bytes, format)
        }
    };
    let format = format.ok_or_else(|| SceneError::Texture {
        name: name.into(),
        message: "unsupported image encoding (PNG or JPEG, by its mimeType or extension)".into(),
    })?;
    images.budget.decode(name, &bytes, format)
}

/// A glTF texture's sampler wrap modes (u, v).
pub(crate) fn wrap_of(tex: &gltf::Texture) -> [Wrap; 2] {
    use gltf::texture::WrappingMode as W;
    [tex.sampler().wrap_s(), tex.sampler().wrap_t()].map(|w| match w {
        W::ClampToEdge => Wrap::ClampToEdge,
        W::MirroredRepeat => Wrap::MirroredRepeat,
        W::Repeat => Wrap::Repeat,
    })
}

/// The texture coordinates a texture reference `info` reads: its `TEXCOORD_n` set (`read_uv(n)`;
/// `KHR_texture_transform`'s `texCoord` overrides n), through `KHR_texture_transform` when given:
/// uv' = T(offset) · R(rotation) · S(scale) · uv, R = [[cos r, sin r], [−sin r, cos r]] (the
/// extension's matrices). `None` when the set is missing.
pub(crate) fn info_uv(
    info: &gltf::texture::Info,
    read_uv: impl Fn(u32) -> Option<Vec<DVec2>>,
) -> Option<Vec<DVec2>> {
    let Some(t) = info.texture_transform() else {
        return read_uv(info.tex_coord());
    };
    let uv = read_uv(t.tex_coord().unwrap_or(info.tex_coord()))?;
    let ([ox, oy], r, [sx, sy]) = (t.offset(), f64::from(t.rotation()), t.scale());
    let (c, s) = (r.cos(), r.sin());
    let (ox, oy, sx, sy) = (f64::from(ox), f64::from(oy), f64::from(sx), f64::from(sy));
    Some(
        uv.into_iter()
            .map(|p| {
                let (u, v) = (sx * p.x, sy * p.y);
                DVec2::new(c * u + s * v + ox, -s * u + c * v + oy)
            })
            .collect(),
    )
}

/// A decoded glTF image as an albedo texture, as the gltf crate's importer gave it to the loader:
/// 8-bit channels are sRGB (glTF 2.0 §3.9.2: baseColorTexture is sRGB-encoded), 16-bit ones rounded
/// to 8 (as OBJ textures are); alpha is dropped, grey (and grey + alpha) expanded to RGB.
fn gltf_texture(name: &str, img: image::DynamicImage, wrap: [Wrap; 2]) -> Result<Texture> {
    use image::DynamicImage as D;
    let (w, h) = (img.width(), img.height());
    let rgb: Vec<u8> = match &img {
        D::ImageRgb8(b) => b.as_raw().clone(),
        D::ImageRgba8(b) => b.chunks_exact(4).flat_map(|p| [p[0], p[1], p[2]]).collect(),
        D::ImageLuma8(b) => b.iter().flat_map(|&g| [g, g, g]).collect(),
        D::ImageLumaA8(b) => b.chunks_exact(2).flat_map(|p| [p[0]; 3]).collect(),
        // 16-bit channels rounded to 8 by the image crate, as the OBJ loader's textures are
        D::ImageRgb16(_) | D::ImageRgba16(_) | D::ImageLuma16(_) | D::ImageLumaA16(_) => {
            img.to_rgb8().into_raw()
        }
        other => {
            return Err(SceneError::Texture {
                name: name.into(),
                message: format!(
                    "pixel format {:?} is not supported (8- or 16-bit colour)",
                    other.color()
                ),
            });
        }
    };
    Texture::from_srgb8(name, w, h, &rgb, wrap)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 16-bit PNG gives the glTF loader the texels it gives the OBJ loader (both round to 8
    /// bits; glTF truncated before: 0xFF00 read as 255 there, 254 through OBJ).
    #[test]
    fn sixteen_bit_textures_read_alike_through_gltf_and_obj() {
        let img = image::ImageBuffer::<image::Rgb<u16>, _>::from_raw(
            2,
            1,
            vec![0xFF00, 0x1280, 0xFFFF, 0, 0x7F7F, 0x0101],
        )
        .unwrap();
        let mut png = Vec::new();
        image::DynamicImage::ImageRgb16(img)
            .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
            .unwrap();
        let obj = Texture::from_encoded("t", &png, [Wrap::Repeat; 2]).unwrap();
        let decoded = image::load_from_memory(&png).unwrap();
        let gltf = gltf_texture("t", decoded, [Wrap::Repeat; 2]).unwrap();
        assert_eq!(obj.texels(), gltf.texels());
        let want = crate::srgb_to_linear(254.0 / 255.0) as f32;
        assert!(
            (gltf.texels()[0][0] - want).abs() < 1e-6,
            "{:?}",
            gltf.texels()[0]
        );
    }

    #[test]
    fn base64_decodes_standard_text_with_or_without_padding() {
        assert_eq!(base64_decode("").unwrap(), b"");
        assert_eq!(base64_decode("Zg==").unwrap(), b"f");
        assert_eq!(base64_decode("Zg").unwrap(), b"f");
        assert_eq!(base64_decode("Zm8=").unwrap(), b"fo");
        assert_eq!(base64_decode("Zm9vYmFy").unwrap(), b"foobar");
        assert_eq!(base64_decode("+/8=").unwrap(), [0xfb, 0xff]);
        for bad in ["Z", "Zh==", "Zg=", "Zg===", "Z!==", "Zg==Zg==", "Zm9v="] {
            assert!(base64_decode(bad).is_none(), "{bad}");
        }
    }

    #[test]
    fn uris_decode_percent_escapes_and_refuse_invalid_utf8() {
        let file = |u: &str| match parse_uri(u) {
            Ok(Uri::File(p)) => p,
            _ => panic!("{u}"),
        };
        assert_eq!(file("a%20b.bin"), "a b.bin");
        assert_eq!(file("%2e%2E/x"), "../x");
        assert_eq!(file("100%.bin"), "100%.bin");
        assert_eq!(file("file:///x/y"), "/x/y");
        assert!(parse_uri("%ff.bin").is_err());
        assert!(parse_uri("http://example.invalid/x.bin").is_err());
        assert!(matches!(
            parse_uri("data:image/png;base64,AAAA"),
            Ok(Uri::Data(Some("image/png"), "AAAA"))
        ));
    }
}
