//! glTF `emissiveTexture` (× `emissiveFactor` × `KHR_materials_emissive_strength`): each face
//! emits the texture's mean over its texture-coordinate triangle, constant over the face — the
//! mean read from the mip chain as an albedo texture's ([`crate::FaceTexture::mean_rho`]). A
//! pattern finer than the faces is averaged (a warning says so once per file); the total power
//! is right.

use crate::gltf_resources::Images;
use crate::{Face, FaceTexture, Result, Spectrum, Texture, Wrap};
use glam::DVec2;

/// The emissive textures of a glTF document and the faces that use them.
#[derive(Debug, Default)]
pub(crate) struct EmissiveTextures {
    textures: Vec<Texture>,
    /// (image, wrap modes) → index into `textures`.
    texture_of: Vec<((usize, [Wrap; 2]), u32)>,
    /// Faces (index into the loader's faces) and their emissive mapping (factor: the emission).
    faces: Vec<(usize, FaceTexture)>,
}

impl EmissiveTextures {
    /// A primitive's emissive texture (index) and the per-vertex texture coordinates of its set,
    /// decoded once per (image, wrap modes); `None` without one (or without its coordinates).
    pub(crate) fn of_primitive(
        &mut self,
        mat: &gltf::Material,
        read_uv: impl Fn(u32) -> Option<Vec<DVec2>>,
        images: &mut Images,
    ) -> Result<Option<(u32, Vec<DVec2>)>> {
        let Some(info) = mat.emissive_texture() else {
            return Ok(None);
        };
        let Some(uv) = crate::gltf_resources::info_uv(&info, read_uv) else {
            return Ok(None);
        };
        let tex = info.texture();
        let wrap = crate::gltf_resources::wrap_of(&tex);
        let image = tex.source();
        let key = (image.index(), wrap);
        if let Some(&(_, i)) = self.texture_of.iter().find(|(k, _)| *k == key) {
            return Ok(Some((i, uv)));
        }
        let name = image.name().map_or_else(
            || format!("{}: image {} (emissive)", images.source, image.index()),
            |n| format!("{}: image `{n}` (emissive)", images.source),
        );
        (self.textures).push(crate::gltf_resources::decode_image(
            &image, &name, wrap, images,
        )?);
        let i = self.textures.len() as u32 - 1;
        self.texture_of.push((key, i));
        Ok(Some((i, uv)))
    }

    /// Records that face `face` (an index into the loader's faces) emits `emission` × texture
    /// `texture` on the coordinates `uv`.
    pub(crate) fn add(&mut self, face: usize, texture: u32, uv: [DVec2; 3], emission: Spectrum) {
        self.faces.push((
            face,
            FaceTexture {
                texture,
                uv,
                factor: emission,
            },
        ));
    }

    /// Sets each recorded face's emission to its mean (module docs); the faces' count, for the
    /// warning.
    pub(crate) fn apply(self, faces: &mut [Face]) -> usize {
        if self.faces.is_empty() {
            return 0;
        }
        let mipmaps = crate::Mipmaps::new(&self.textures);
        for (i, t) in &self.faces {
            faces[*i].emission = t.mean_rho(&mipmaps);
        }
        self.faces.len()
    }
}
