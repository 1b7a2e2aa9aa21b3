//! Scene files: the loader chosen by extension — OBJ + MTL (tobj, `obj.rs`), glTF
//! 2.0 / .glb (gltf, `gltf.rs`), Flatland JSON (here) — and the writers for OBJ/MTL, glTF
//! and Flatland (`write.rs`), re-exported here.
//!
//! Units (FORMATS.md): OBJ `Ke` and glTF `emissiveFactor × emissive_strength` are emitted **radiance** L_e, as a
//! path tracer reads them; the scene stores emitted radiosity (exitance) `E = π·L_e`, and every solver reports
//! radiosity B (exitance; `B = π·L` on a Lambertian surface). Flatland JSON gives E directly.

use crate::confine::read_regular_text;
use crate::read::stem;
use crate::{AnyScene, FlatlandScene, LoadOptions, Result, SceneError};
use std::path::Path;

pub use crate::gltf::load_gltf;
pub use crate::obj::load_obj;
pub use crate::write::{to_gltf, to_obj, write_flatland, write_gltf, write_obj};

/// Loads a scene file, choosing the loader by extension: `.obj` (with its MTL), `.gltf`/`.glb`, `.json`
/// (Flatland); within the default [`LoadOptions`] (nothing outside the file's folder, bounded sizes).
pub fn load(path: impl AsRef<Path>) -> Result<AnyScene> {
    load_with(path, &LoadOptions::default())
}

/// [`load`] within `options`: whether the files the scene names may lie outside its folder, and
/// the bounds on file size and decoded texture memory ([`crate::confine`]).
pub fn load_with(path: impl AsRef<Path>, options: &LoadOptions) -> Result<AnyScene> {
    let path = path.as_ref();
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    match ext.as_str() {
        "obj" => crate::obj::obj_with(path, options).map(AnyScene::ThreeD),
        "gltf" | "glb" => crate::gltf::gltf_with(path, options).map(AnyScene::ThreeD),
        "json" => flatland_with(path, options).map(AnyScene::Flatland),
        _ => Err(SceneError::UnsupportedFormat { path: path.into() }),
    }
}

/// Loads `name` as a built-in if [`crate::builtin::is_builtin`] says so (one of [`crate::BUILTIN_NAMES`] or
/// `random-boxes-<N>`), else as a file.
///
/// A name that is neither a built-in nor an existing file, and has no scene extension (`cornel-box`), is an
/// unknown built-in ([`SceneError::UnknownBuiltin`], with the nearest known name), not an "unsupported
/// format".
pub fn load_or_builtin(name: &str) -> Result<AnyScene> {
    load_or_builtin_with(name, &LoadOptions::default())
}

/// [`load_or_builtin`], a file loaded within `options` ([`load_with`]).
pub fn load_or_builtin_with(name: &str, options: &LoadOptions) -> Result<AnyScene> {
    if crate::builtin::is_builtin(name) {
        return crate::builtin(name);
    }
    let path = Path::new(name);
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase());
    let scene_ext = matches!(ext.as_deref(), Some("obj" | "gltf" | "glb" | "json"));
    if !scene_ext && !path.exists() {
        return Err(SceneError::UnknownBuiltin {
            name: name.into(),
            hint: crate::builtin::hint(name),
            known: format!(
                "{}, random-boxes-<N>, tessellated-cornell-<N>; or a .obj, .gltf, .glb or .json file",
                crate::BUILTIN_NAMES.join(", ")
            ),
        });
    }
    load_with(path, options)
}

/// Loads a Flatland JSON scene (format in FORMATS.md and [`FlatlandScene::from_json`]).
pub fn load_flatland(path: impl AsRef<Path>) -> Result<FlatlandScene> {
    flatland_with(path.as_ref(), &LoadOptions::default())
}

fn flatland_with(path: &Path, options: &LoadOptions) -> Result<FlatlandScene> {
    let text = read_regular_text(path, options.max_file_bytes)?;
    FlatlandScene::from_json(&stem(path), &path.display().to_string(), &text)
}
