//! Cut-outs: faces with holes where an alpha mask says so — foliage cards, grilles, perforated
//! panels, fences (glTF `alphaMode` MASK, OBJ `map_d`).
//!
//! A face with a [`FaceCutout`] is a hole at every point x whose alpha
//! α(x) = factor × mask(uv(x)) is below the cut-off, and opaque elsewhere: every ray passes the
//! holes ([`crate::SceneBvh`] tests the mask at each candidate hit), so a cut-out casts a patterned
//! shadow, is seen through, and reflects light only where it is solid. The comparison is folded into
//! one threshold, α(x) < cut-off ⇔ mask(uv(x)) < cut-off / factor.
//!
//! Where the masks come from (the loaders):
//! * **glTF**: `alphaMode` MASK with `alphaCutoff` (default 0.5) — α is `baseColorFactor`'s alpha
//!   times the alpha channel of `baseColorTexture` (linear, glTF 2.0 §3.9.4), on its texture
//!   coordinates. `alphaMode` BLEND (partial transparency, which a diffuse solver has no model
//!   for) is read as MASK at 0.5, with a warning naming the material. OPAQUE ignores alpha, as the
//!   specification says.
//! * **OBJ/MTL**: `map_d` (the image's alpha channel, or its grey level when it has none) and `d`
//!   (`Tr` = 1 − d) as the factor, cut off at 0.5.
//!
//! A face whose α is below the cut-off everywhere (a constant factor below it, no mask) is dropped
//! at load with a warning. A mask on an emitting face is ignored with a warning (its light would
//! have to be sampled through the mask too). Masks are kept as 8-bit alpha, looked up bilinearly
//! like the albedo textures ([`crate::Texture::sample`]).

use crate::texture::{Wrap, bilinear};
use crate::{Result, SceneError};
use glam::DVec2;

/// An 8-bit alpha image with its wrap modes (module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct AlphaMask {
    /// Name for messages (the file or the glTF image).
    pub name: String,
    width: u32,
    height: u32,
    /// Row-major from the top row.
    alpha: Vec<u8>,
    /// Wrap along u and v.
    pub wrap: [Wrap; 2],
}

impl AlphaMask {
    /// A mask of `width × height` alpha values (0 transparent, 255 opaque), row-major from the top.
    ///
    /// # Errors
    /// [`SceneError::Texture`] when the size is zero or does not match `alpha`'s length.
    pub fn new(
        name: &str,
        width: u32,
        height: u32,
        alpha: Vec<u8>,
        wrap: [Wrap; 2],
    ) -> Result<Self> {
        if width == 0 || height == 0 || alpha.len() != width as usize * height as usize {
            return Err(SceneError::Texture {
                name: name.into(),
                message: format!("an alpha mask of {width}×{height} needs that many values"),
            });
        }
        Ok(Self {
            name: name.into(),
            width,
            height,
            alpha,
            wrap,
        })
    }

    /// The alpha channel of a decoded image (16-bit channels by their high byte); with
    /// `grey_if_opaque`, an image without one gives its grey level instead (OBJ `map_d`), else
    /// `None` (glTF: a texture without alpha is opaque).
    pub(crate) fn of_image(
        name: &str,
        img: &image::DynamicImage,
        wrap: [Wrap; 2],
        grey_if_opaque: bool,
    ) -> Option<Self> {
        let alpha: Vec<u8> = if img.color().has_alpha() {
            img.to_rgba8().pixels().map(|p| p.0[3]).collect()
        } else if grey_if_opaque {
            img.to_luma8().into_raw()
        } else {
            return None;
        };
        Self::new(name, img.width(), img.height(), alpha, wrap).ok()
    }

    /// Alpha in [0, 1] at texture coordinates `uv`, bilinear between texel centres.
    pub fn alpha(&self, uv: DVec2) -> f64 {
        let [a] = bilinear((self.width, self.height), self.wrap, uv, |k| {
            [f32::from(self.alpha[k]) / 255.0]
        });
        a
    }

    /// Size in texels (width, height).
    pub fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }
}

/// A face's cut-out: which mask, the texture coordinates of its three vertices, and the threshold
/// below which the mask's alpha is a hole (module docs: cut-off / factor).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FaceCutout {
    /// Index into [`crate::Scene::masks`].
    pub mask: u32,
    /// Texture coordinates of `v[0]`, `v[1]`, `v[2]`.
    pub uv: [DVec2; 3],
    /// A hole where the mask's alpha is below this.
    pub threshold: f64,
}

impl FaceCutout {
    /// Whether the point with barycentric weights `(1 − b1 − b2, b1, b2)` is a hole.
    pub fn is_hole(&self, masks: &[AlphaMask], b1: f64, b2: f64) -> bool {
        let uv = self.uv[0] * (1.0 - b1 - b2) + self.uv[1] * b1 + self.uv[2] * b2;
        masks
            .get(self.mask as usize)
            .is_some_and(|m| m.alpha(uv) < self.threshold)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 2 × 1 mask (left transparent, right opaque) cuts the left half of a face mapped across it,
    /// with the threshold deciding where between the texel centres the edge falls.
    #[test]
    fn a_mask_cuts_where_alpha_is_low() {
        let mask = AlphaMask::new("m", 2, 1, vec![0, 255], [Wrap::ClampToEdge; 2]).unwrap();
        let cut = FaceCutout {
            mask: 0,
            uv: [
                DVec2::new(0.0, 0.5),
                DVec2::new(1.0, 0.5),
                DVec2::new(0.0, 0.6),
            ],
            threshold: 0.5,
        };
        let masks = [mask];
        assert!(cut.is_hole(&masks, 0.1, 0.0), "left");
        assert!(!cut.is_hole(&masks, 0.9, 0.0), "right");
        // halfway between the centres (u = 0.25, 0.75) alpha is 0.5: the edge is at u = 0.5
        assert!(cut.is_hole(&masks, 0.49, 0.0) && !cut.is_hole(&masks, 0.51, 0.0));
        let strict = FaceCutout {
            threshold: 0.9,
            ..cut
        };
        assert!(
            strict.is_hole(&masks, 0.6, 0.0),
            "a higher threshold cuts more"
        );
        assert!(AlphaMask::new("bad", 2, 2, vec![0; 3], [Wrap::Repeat; 2]).is_err());
        let grey =
            image::DynamicImage::ImageLuma8(image::GrayImage::from_raw(1, 1, vec![7]).unwrap());
        assert!(AlphaMask::of_image("g", &grey, [Wrap::Repeat; 2], false).is_none());
        let m = AlphaMask::of_image("g", &grey, [Wrap::Repeat; 2], true).unwrap();
        assert!((m.alpha(DVec2::splat(0.3)) - 7.0 / 255.0).abs() < 1e-6);
    }
}
