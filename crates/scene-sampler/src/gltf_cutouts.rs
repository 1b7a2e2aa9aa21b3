//! glTF materials' alpha as cut-outs ([`crate::cutout`]): `alphaMode` MASK with `alphaCutoff`,
//! BLEND read as MASK at 0.5 with a warning, OPAQUE ignoring alpha (glTF 2.0 §3.9.4).

use crate::Result;
use crate::cutout::AlphaMask;
use crate::gltf_resources::Images;
use crate::texture::Wrap;
use glam::DVec2;

/// How a primitive's material cuts its faces.
#[derive(Debug)]
pub(crate) enum Alpha {
    /// Solid everywhere.
    Opaque,
    /// A hole everywhere (α below the cut-off with no texture): the faces are dropped.
    Hidden,
    /// Holes where the mask's alpha is below `threshold`, on the texture coordinates `uv`.
    Cut {
        /// Index into [`Cutouts::masks`].
        mask: u32,
        /// Per-vertex texture coordinates of the base colour texture.
        uv: Vec<DVec2>,
        /// Cut-off / alpha factor.
        threshold: f64,
    },
}

/// The alpha masks of a glTF document, decoded once per (image, wrap modes).
#[derive(Debug, Default)]
pub(crate) struct Cutouts {
    /// The masks, for [`crate::Scene::masks`].
    pub masks: Vec<AlphaMask>,
    mask_of: Vec<((usize, [Wrap; 2]), u32)>,
    /// Materials already warned about (BLEND; a masked emitter).
    warned: Vec<Option<usize>>,
    /// Faces dropped as hidden.
    pub hidden: usize,
}

impl Cutouts {
    /// The cut-out of a primitive of material `mat` (emitting when `emits`), whose texture
    /// coordinate set `k` is `read_uv(k)`; warnings name the material.
    pub(crate) fn of_primitive(
        &mut self,
        mat: &gltf::Material,
        emits: bool,
        read_uv: impl Fn(u32) -> Option<Vec<DVec2>>,
        images: &mut Images,
        warnings: &mut Vec<String>,
    ) -> Result<Alpha> {
        use gltf::material::AlphaMode;
        let name = match (mat.name(), mat.index()) {
            (Some(n), _) => format!("material `{n}`"),
            (None, Some(i)) => format!("material {i}"),
            (None, None) => return Ok(Alpha::Opaque),
        };
        let cutoff = match mat.alpha_mode() {
            AlphaMode::Opaque => return Ok(Alpha::Opaque),
            AlphaMode::Mask => f64::from(mat.alpha_cutoff().unwrap_or(0.5)),
            AlphaMode::Blend => {
                self.warn_once(mat, warnings, || {
                    format!(
                        "{}: {name}: alphaMode BLEND is read as MASK at alpha 0.5 (a diffuse \
                         solver has no partial transparency)",
                        images.source
                    )
                });
                0.5
            }
        };
        if emits {
            self.warn_once(mat, warnings, || {
                format!(
                    "{}: {name}: an emitting material's alpha mask is ignored (solid)",
                    images.source
                )
            });
            return Ok(Alpha::Opaque);
        }
        let pbr = mat.pbr_metallic_roughness();
        let factor = f64::from(pbr.base_color_factor()[3]);
        let hidden = factor < cutoff;
        let Some(info) = pbr.base_color_texture() else {
            return Ok(if hidden { Alpha::Hidden } else { Alpha::Opaque });
        };
        let Some(uv) = crate::gltf_resources::info_uv(&info, read_uv) else {
            return Ok(if hidden { Alpha::Hidden } else { Alpha::Opaque });
        };
        let Some(mask) = self.mask(&info.texture(), images)? else {
            // a texture without alpha is opaque: the factor alone decides
            return Ok(if hidden { Alpha::Hidden } else { Alpha::Opaque });
        };
        if factor <= 0.0 {
            return Ok(Alpha::Hidden);
        }
        Ok(Alpha::Cut {
            mask,
            uv,
            threshold: cutoff / factor,
        })
    }

    /// The mask of a texture's image (its alpha channel), decoded once; `None` when the image has
    /// no alpha channel.
    fn mask(&mut self, tex: &gltf::Texture, images: &mut Images) -> Result<Option<u32>> {
        let wrap = crate::gltf_resources::wrap_of(tex);
        let image = tex.source();
        let key = (image.index(), wrap);
        if let Some(&(_, i)) = self.mask_of.iter().find(|(k, _)| *k == key) {
            return Ok((i != u32::MAX).then_some(i));
        }
        let name = image.name().map_or_else(
            || format!("{}: image {} (alpha)", images.source, image.index()),
            |n| format!("{}: image `{n}` (alpha)", images.source),
        );
        let img = crate::gltf_resources::read_image(&image, &name, images)?;
        let index = match AlphaMask::of_image(&name, &img, wrap, false) {
            Some(m) => {
                self.masks.push(m);
                self.masks.len() as u32 - 1
            }
            None => u32::MAX,
        };
        self.mask_of.push((key, index));
        Ok((index != u32::MAX).then_some(index))
    }

    fn warn_once(
        &mut self,
        mat: &gltf::Material,
        warnings: &mut Vec<String>,
        message: impl FnOnce() -> String,
    ) {
        if !self.warned.contains(&mat.index()) {
            self.warned.push(mat.index());
            warnings.push(message());
        }
    }
}
