//! What the scene loaders share: a scene's name from its file, UTF-8 text read with the line of
//! its first error, and the mean albedo of textured faces.

use crate::{Face, Result, SceneError};
use std::path::Path;

/// The scene name of a file: its stem (`scene` when it has none).
pub(crate) fn stem(path: &Path) -> String {
    path.file_stem()
        .map_or_else(|| "scene".into(), |s| s.to_string_lossy().into_owned())
}

/// The 1-based line of byte offset `at` in `bytes`.
pub(crate) fn line_of(bytes: &[u8], at: usize) -> usize {
    1 + bytes[..at.min(bytes.len())]
        .iter()
        .filter(|&&b| b == b'\n')
        .count()
}

/// Reads a text file (a regular file of at most `limit` bytes) as UTF-8, or an error naming the
/// first line that is not.
pub(crate) fn read_text(path: &Path, limit: u64) -> Result<String> {
    let bytes = crate::confine::read_regular_file(path, limit)?;
    String::from_utf8(bytes).map_err(|e| SceneError::Parse {
        source_name: path.display().to_string(),
        message: format!(
            "line {}: not UTF-8 text",
            line_of(e.as_bytes(), e.utf8_error().valid_up_to())
        ),
    })
}

/// Sets every textured face's [`crate::Face::rho`] to its texture's mean over the face
/// ([`crate::FaceTexture::mean_rho`]), in parallel over the faces.
pub(crate) fn average_albedo(faces: &mut [Face], textures: &[crate::Texture]) {
    use rayon::prelude::*;
    if !faces.iter().any(|f| f.texture.is_some()) {
        return;
    }
    let mipmaps = crate::Mipmaps::new(textures);
    faces.par_iter_mut().for_each(|f| {
        if let Some(t) = &f.texture {
            f.rho = t.mean_rho(&mipmaps);
        }
    });
}
