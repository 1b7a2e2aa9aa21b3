//! Scene files: OBJ + MTL (tobj), glTF 2.0 / .glb (gltf), Flatland JSON; and the writers for OBJ/MTL,
//! glTF and Flatland ([`crate::write`]'s), re-exported here.
//!
//! Units (FORMATS.md): OBJ `Ke` and glTF `emissiveFactor × emissive_strength` are emitted **radiance** L_e, as a
//! path tracer reads them; the scene stores emitted radiosity (exitance) `E = π·L_e`, and every solver reports
//! radiosity B (exitance; `B = π·L` on a Lambertian surface). Flatland JSON gives E directly.

use crate::confine::{Folder, Refusal, read_regular_text};
use crate::provenance::{GltfSource, Part};
use crate::scene::check_file_material;
use crate::texture::TextureBudget;
use crate::{
    AnyScene, Camera, Face, FaceTexture, FlatlandScene, LoadOptions, Result, Scene, SceneError,
    Spectrum, Texture, Wrap,
};
use glam::{DMat4, DVec3};
use std::f64::consts::PI;
use std::path::Path;

pub use crate::write::{to_gltf, to_obj, write_flatland, write_gltf, write_obj};

fn stem(path: &Path) -> String {
    path.file_stem()
        .map_or_else(|| "scene".into(), |s| s.to_string_lossy().into_owned())
}

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
        "obj" => obj_with(path, options).map(AnyScene::ThreeD),
        "gltf" | "glb" => gltf_with(path, options).map(AnyScene::ThreeD),
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

/// The 1-based line of byte offset `at` in `bytes`.
fn line_of(bytes: &[u8], at: usize) -> usize {
    1 + bytes[..at.min(bytes.len())]
        .iter()
        .filter(|&&b| b == b'\n')
        .count()
}

/// Reads a text file (a regular file of at most `limit` bytes) as UTF-8, or an error naming the
/// first line that is not.
fn read_text(path: &Path, limit: u64) -> Result<String> {
    let bytes = crate::confine::read_regular_file(path, limit)?;
    String::from_utf8(bytes).map_err(|e| SceneError::Parse {
        source_name: path.display().to_string(),
        message: format!(
            "line {}: not UTF-8 text",
            line_of(e.as_bytes(), e.utf8_error().valid_up_to())
        ),
    })
}

/// The MTL keywords the loader uses (`Kd` → ρ, `Ke` → emitted radiance) and the colour keywords that share
/// their syntax.
const MTL_COLOURS: [&str; 5] = ["Ka", "Kd", "Ks", "Ke", "Tf"];

/// Rewrites MTL text into the subset tobj parses without trouble: only `newmtl`, `Kd`, `Ke`, `map_Kd`, `d`
/// and `map_d` lines are kept (maps with their file name alone: texture options are an error naming the
/// line; `d` one number in [0, 1]; `Tr` is dropped: exporters disagree on its sense),
/// and a colour with one number (`Kd 0.5`, grey in the MTL format) is written out as three. A colour
/// keyword with no number, two numbers, or a word that is not a number is an error naming file and line
/// (tobj 4 panics on the one-number form and names no line for the others).
fn sanitize_mtl(source: &str, text: &str) -> Result<String> {
    let mut out = String::with_capacity(text.len());
    for (k, raw) in text.lines().enumerate() {
        let line = k + 1;
        let err = |message: String| SceneError::Parse {
            source_name: source.into(),
            message: format!("line {line}: {message}"),
        };
        let l = raw.trim();
        let mut words = l.split_whitespace();
        let Some(key) = words.next() else { continue };
        if key == "newmtl" {
            let name = l[6..].trim();
            if name.is_empty() {
                return Err(err("`newmtl` without a material name".into()));
            }
            out.push_str("newmtl ");
            out.push_str(name);
            out.push('\n');
        } else if MTL_COLOURS.contains(&key) {
            let vals: Vec<f64> = words
                .map(|w| {
                    w.parse::<f64>().map_err(|_| {
                        err(format!(
                            "`{key}`: `{w}` is not a number (spectral and xyz colours are not supported)"
                        ))
                    })
                })
                .collect::<Result<_>>()?;
            let rgb = match vals[..] {
                [] => {
                    return Err(err(format!(
                        "`{key}` without a value: give one number (grey) or three (r g b)"
                    )));
                }
                [v] => [v; 3],
                [_, _] => {
                    return Err(err(format!(
                        "`{key}` with two numbers: give one (grey) or three (r g b)"
                    )));
                }
                [r, g, b, ..] => [r, g, b],
            };
            if key == "Kd" || key == "Ke" {
                out.push_str(&format!("{key} {:?} {:?} {:?}\n", rgb[0], rgb[1], rgb[2]));
            }
        } else if key == "map_Kd" || key == "map_d" {
            // `map_Kd [options] file`: the options (scale, offset, …) are not supported; the file
            // is the last word.
            let args: Vec<&str> = words.collect();
            let Some(file) = args.last() else {
                return Err(err(format!("`{key}` without a file name")));
            };
            if args.len() > 1 {
                return Err(err(format!(
                    "`{key}` options ({}) are not supported: give the file name alone",
                    args[..args.len() - 1].join(" ")
                )));
            }
            out.push_str(&format!("{key} {file}\n"));
        } else if key == "d" {
            // dissolve (opacity): one number in [0, 1]; `-halo` is not supported
            let d = match words.collect::<Vec<_>>()[..] {
                [v] => v.parse::<f64>().ok().filter(|d| (0.0..=1.0).contains(d)),
                _ => None,
            };
            let d = d.ok_or_else(|| err("`d` needs one number in [0, 1] (opacity)".into()))?;
            out.push_str(&format!("d {d:?}\n"));
        }
    }
    Ok(out)
}

/// A statement of an OBJ file found by the loader's own scan: keyword, argument (as tobj reads it) and line.
struct Statement {
    line: usize,
    key: &'static str,
    arg: String,
}

/// The `mtllib` and `usemtl` statements of OBJ text, with their lines, read as tobj reads them (the argument
/// is everything after the first space, trimmed).
fn scan_obj(text: &str) -> Vec<Statement> {
    let mut out = Vec::new();
    for (k, raw) in text.lines().enumerate() {
        let key = match raw.split_whitespace().next() {
            Some("mtllib") => "mtllib",
            Some("usemtl") => "usemtl",
            _ => continue,
        };
        out.push(Statement {
            line: k + 1,
            key,
            arg: raw.split_once(' ').unwrap_or_default().1.trim().to_owned(),
        });
    }
    out
}

/// Loads an OBJ file and its MTL library.
///
/// Polygons are triangulated as fans (tobj). Coordinates are read in f64, so a scene far from the origin
/// keeps its shape. `Kd` → ρ, `Ke` → emitted radiance (E = π·Ke); a colour with one number is grey (MTL
/// format); ρ ≥ 1 is clamped to [`RHO_MAX`] with a warning naming the material. Faces without a material get
/// ρ = 0.5 grey, E = 0 (reported in `warnings`); a `usemtl` naming a material that is not defined, or an
/// `mtllib` that cannot be read, is an error naming the line. Each OBJ object/group becomes an object; each
/// input polygon one surface. Windings are kept as written (front side = counter-clockwise); faces whose `vn`
/// normals point against their winding are counted in a warning naming the object.
///
/// Material libraries and textures are read from the OBJ file's folder only, within the default
/// [`LoadOptions`] ([`load_with`] takes others).
pub fn load_obj(path: impl AsRef<Path>) -> Result<Scene> {
    obj_with(path.as_ref(), &LoadOptions::default())
}

fn obj_with(path: &Path, options: &LoadOptions) -> Result<Scene> {
    let source = path.display().to_string();
    let text = read_text(path, options.max_file_bytes)?;
    let folder = Folder::of(path, options)?;
    let statements = scan_obj(&text);
    let opts = tobj::LoadOptions {
        triangulate: true,
        single_index: false,
        ..Default::default()
    };
    let problem: std::cell::RefCell<Option<SceneError>> = std::cell::RefCell::new(None);
    let material_loader = |mtl: &Path| -> tobj::MTLLoadResult {
        let full = folder.shown(mtl);
        let line = (statements.iter())
            .find(|s| s.key == "mtllib" && Path::new(&s.arg) == mtl)
            .map_or(0, |s| s.line);
        let read = (folder.read(mtl))
            .map_err(|r| match r {
                Refusal::Outside => SceneError::OutsideFolder {
                    source_name: format!("{source}:{line}"),
                    what: "`mtllib`".into(),
                    uri: mtl.display().to_string(),
                },
                Refusal::Refused(e) => e,
                Refusal::Io(e) => SceneError::MaterialLibrary {
                    source_name: source.clone(),
                    line,
                    path: full.clone(),
                    source: e,
                },
            })
            .and_then(|bytes| {
                let mtl_source = full.display().to_string();
                let text = String::from_utf8(bytes).map_err(|e| SceneError::Parse {
                    source_name: mtl_source.clone(),
                    message: format!(
                        "line {}: not UTF-8 text",
                        line_of(e.as_bytes(), e.utf8_error().valid_up_to())
                    ),
                })?;
                sanitize_mtl(&mtl_source, &text)
            });
        match read {
            Ok(clean) => tobj::load_mtl_buf(&mut clean.as_bytes()),
            Err(e) => {
                problem.borrow_mut().get_or_insert(e);
                Err(tobj::LoadError::OpenFileFailed)
            }
        }
    };
    // tobj is third-party parsing of user input: a panic inside it becomes a parse error, never an abort.
    let loaded = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        tobj::load_obj_buf(&mut text.as_bytes(), &opts, material_loader)
    }))
    .map_err(|_| SceneError::Parse {
        source_name: source.clone(),
        message: "the OBJ parser (tobj) failed on this file".into(),
    })?;
    if let Some(e) = problem.into_inner() {
        return Err(e);
    }
    let (models, materials) = loaded.map_err(|e| SceneError::Parse {
        source_name: source.clone(),
        message: e.to_string(),
    })?;
    let materials = materials.map_err(|e| SceneError::Parse {
        source_name: source.clone(),
        message: format!("material library: {e}"),
    })?;
    // tobj silently gives no material for an undefined name: the faces would turn grey and, if the name
    // was the light's, the scene would fail later with "no face emits light".
    for s in statements.iter().filter(|s| s.key == "usemtl") {
        if !materials.iter().any(|m| m.name == s.arg) {
            let known = if materials.is_empty() {
                if statements.iter().any(|s| s.key == "mtllib") {
                    "the material libraries define none".to_string()
                } else {
                    "the file has no `mtllib` line".to_string()
                }
            } else {
                let names: Vec<&str> = materials.iter().map(|m| m.name.as_str()).collect();
                format!("defined: {}", names.join(", "))
            };
            return Err(SceneError::UndefinedMaterial {
                source_name: source,
                line: s.line,
                name: s.arg.clone(),
                known,
            });
        }
    }
    let mut warnings = Vec::new();
    let mut textures: Vec<Texture> = Vec::new();
    // per material: its texture's index once loaded
    let mut texture_of: Vec<Option<u32>> = vec![None; materials.len()];
    let mut budget = TextureBudget::new(options.max_texture_bytes);
    for (i, mat) in materials.iter().enumerate() {
        if let Some(file) = &mat.diffuse_texture {
            let tex = obj_texture(&folder, file, &mat.name, &source, &mut budget)?;
            texture_of[i] = Some(textures.len() as u32);
            textures.push(tex);
        }
    }
    let (masks, alpha_of) = obj_alphas(&materials, &folder, &source, &mut budget, &mut warnings)?;
    let mut hidden = 0usize;
    let mut untextured: Vec<String> = Vec::new();
    let mut checked: Vec<Option<(Spectrum, Spectrum)>> = vec![None; materials.len()];
    let mut faces = Vec::new();
    let mut objects: Vec<String> = Vec::new();
    let mut missing_material = 0usize;
    let mut against_normals: Vec<(String, usize)> = Vec::new();
    let mut surface = 0u32;
    for m in &models {
        // tobj splits an object at every `usemtl`: parts of one name stay one object
        let oi = match objects.iter().position(|o| *o == m.name) {
            Some(k) => k,
            None => {
                objects.push(m.name.clone());
                objects.len() - 1
            }
        };
        let mesh = &m.mesh;
        let (rho, e) = match mesh.material_id.filter(|&i| i < materials.len()) {
            Some(i) => match checked[i] {
                Some(v) => v,
                None => {
                    let mat = &materials[i];
                    let kd = Spectrum(mat.diffuse.unwrap_or([0.0; 3]));
                    let e = Spectrum(mat.emissive.unwrap_or([0.0; 3]).map(|v| v * PI));
                    let rho = check_file_material(&source, &mat.name, kd, e, &mut warnings)?;
                    checked[i] = Some((rho, e));
                    (rho, e)
                }
            },
            None => {
                missing_material += mesh.indices.len() / 3;
                (Spectrum::grey(0.5), Spectrum::ZERO)
            }
        };
        let pos = |i: u32| -> Result<DVec3> {
            let i = i as usize * 3;
            match mesh.positions.get(i..i + 3) {
                Some(p) => Ok(DVec3::new(p[0], p[1], p[2])),
                None => Err(SceneError::Parse {
                    source_name: source.clone(),
                    message: format!("object `{}`: vertex index {} out of range", m.name, i / 3),
                }),
            }
        };
        let normal = |i: u32| -> Option<DVec3> {
            let i = i as usize * 3;
            mesh.normals
                .get(i..i + 3)
                .map(|n| DVec3::new(n[0], n[1], n[2]))
        };
        let with_normals = mesh.normal_indices.len() == mesh.indices.len();
        // ⟨The texture mapping of a textured material: vt per corner, v flipped (OBJ's v = 0 is the
        // image's bottom row)⟩
        let texture = mesh
            .material_id
            .and_then(|i| texture_of.get(i).copied().flatten());
        let with_uv = mesh.texcoord_indices.len() == mesh.indices.len();
        // a `vt nan` would read texel 0 (ρ = 0) in silence
        if with_uv && mesh.texcoords.iter().any(|t| !t.is_finite()) {
            return Err(SceneError::Parse {
                source_name: source.clone(),
                message: format!(
                    "object `{}`: a `vt` coordinate is not a finite number",
                    m.name
                ),
            });
        }
        if texture.is_some() && !with_uv && !untextured.contains(&m.name) {
            untextured.push(m.name.clone());
        }
        let uv = |i: u32| -> Option<glam::DVec2> {
            let i = i as usize * 2;
            (mesh.texcoords.get(i..i + 2)).map(|t| glam::DVec2::new(t[0], 1.0 - t[1]))
        };
        let alpha = (mesh.material_id)
            .and_then(|i| alpha_of.get(i).copied())
            .unwrap_or(ObjAlpha::Opaque);
        let mut against = 0usize;
        // tobj gives face_arities only when not triangulating; with triangulation each polygon's fan shares a
        // surface id only if we track it, which tobj does not expose: one surface per triangle then.
        for (k, t) in mesh.indices.chunks_exact(3).enumerate() {
            let v = [pos(t[0])?, pos(t[1])?, pos(t[2])?];
            if with_normals {
                let n = &mesh.normal_indices[3 * k..3 * k + 3];
                if let (Some(a), Some(b), Some(c)) = (normal(n[0]), normal(n[1]), normal(n[2])) {
                    let winding = (v[1] - v[0]).cross(v[2] - v[0]);
                    if (a + b + c).dot(winding) < 0.0 {
                        against += 1;
                    }
                }
            }
            let mut face = Face::new(v, rho, e, oi as u32, surface);
            match (alpha, with_uv) {
                (ObjAlpha::Hidden, _) => {
                    hidden += 1;
                    continue;
                }
                (ObjAlpha::Cut(mask, threshold), true) => {
                    let c = &mesh.texcoord_indices[3 * k..3 * k + 3];
                    if let (Some(a), Some(b), Some(d)) = (uv(c[0]), uv(c[1]), uv(c[2])) {
                        face.cutout = Some(crate::FaceCutout {
                            mask,
                            uv: [a, b, d],
                            threshold,
                        });
                    }
                }
                _ => {}
            }
            if let (Some(tex), true) = (texture, with_uv) {
                let c = &mesh.texcoord_indices[3 * k..3 * k + 3];
                if let (Some(a), Some(b), Some(d)) = (uv(c[0]), uv(c[1]), uv(c[2])) {
                    let ft = FaceTexture {
                        texture: tex,
                        uv: [a, b, d],
                        factor: rho,
                    };
                    face.texture = Some(ft);
                }
            }
            faces.push(face);
            surface += 1;
        }
        if against > 0 {
            match against_normals.iter_mut().find(|(o, _)| *o == m.name) {
                Some((_, n)) => *n += against,
                None => against_normals.push((m.name.clone(), against)),
            }
        }
    }
    average_albedo(&mut faces, &textures);
    if hidden > 0 {
        warnings.push(format!(
            "{source}: dropped {hidden} face(s) whose material's opacity `d` is below 0.5 (fully \
             cut out)"
        ));
    }
    let mut scene = Scene::new(&stem(path), &source, faces, objects, None)?
        .with_textures(textures)?
        .with_masks(masks)?;
    warnings.extend(untextured.into_iter().map(|o| {
        format!("{source}: object `{o}`: a textured material (map_Kd) but no `vt`: its Kd is used")
    }));
    warnings.extend(against_normals.into_iter().map(|(o, n)| {
        format!(
            "{source}: object `{o}`: {n} face(s) whose `vn` normals point against their winding; the front \
             side comes from the winding (counter-clockwise), so these faces are lit from behind and \
             look black: fix the winding or the normals"
        )
    }));
    if missing_material > 0 {
        warnings.push(format!(
            "{source}: {missing_material} face(s) without material: ρ = 0.5, E = 0"
        ));
    }
    scene.warnings.extend(warnings);
    Ok(scene)
}

/// How an OBJ material's opacity cuts its faces ([`crate::cutout`]).
#[derive(Clone, Copy, Debug)]
enum ObjAlpha {
    Opaque,
    /// `d` below 0.5 and no `map_d`: the faces are dropped.
    Hidden,
    /// A `map_d` mask (index) and its threshold 0.5/d.
    Cut(u32, f64),
}

/// The OBJ materials' alpha masks and, per material, how its opacity (`d`, `map_d`, cut off at
/// 0.5) cuts it; an emitting material's opacity is ignored with a warning.
fn obj_alphas(
    materials: &[tobj::Material],
    folder: &Folder,
    source: &str,
    budget: &mut TextureBudget,
    warnings: &mut Vec<String>,
) -> Result<(Vec<crate::AlphaMask>, Vec<ObjAlpha>)> {
    let mut masks = Vec::new();
    let mut alpha_of = vec![ObjAlpha::Opaque; materials.len()];
    for (i, mat) in materials.iter().enumerate() {
        let d = mat.dissolve.unwrap_or(1.0);
        if d >= 1.0 && mat.dissolve_texture.is_none() {
            continue;
        }
        if mat.emissive.is_some_and(|e| e.iter().any(|v| *v > 0.0)) {
            warnings.push(format!(
                "{source}: material `{}`: an emitting material's opacity (`d`, `map_d`) is \
                 ignored (solid)",
                mat.name
            ));
            continue;
        }
        alpha_of[i] = match &mat.dissolve_texture {
            Some(_) if d <= 0.0 => ObjAlpha::Hidden,
            Some(file) => {
                masks.push(obj_mask(folder, file, &mat.name, source, budget)?);
                ObjAlpha::Cut(masks.len() as u32 - 1, 0.5 / d)
            }
            None if d < 0.5 => ObjAlpha::Hidden,
            None => ObjAlpha::Opaque,
        };
    }
    Ok((masks, alpha_of))
}

/// An OBJ material's `map_Kd` texture `file`, read within the scene's folder and decoded within
/// `budget`; a file that cannot be read or decoded is an error naming the material.
fn obj_texture(
    folder: &Folder,
    file: &str,
    material: &str,
    source: &str,
    budget: &mut TextureBudget,
) -> Result<Texture> {
    let (full, bytes) = obj_map(folder, file, material, source, "map_Kd")?;
    let name = full.display().to_string();
    Texture::from_file_bytes(&name, &full, &bytes, [Wrap::Repeat; 2], budget)
        .map_err(|e| obj_map_error(e, source, material, "map_Kd"))
}

/// An OBJ material's `map_d` alpha mask `file` ([`crate::cutout`]: its alpha channel, or its grey
/// level when it has none), read and decoded as [`obj_texture`].
fn obj_mask(
    folder: &Folder,
    file: &str,
    material: &str,
    source: &str,
    budget: &mut TextureBudget,
) -> Result<crate::AlphaMask> {
    let (full, bytes) = obj_map(folder, file, material, source, "map_d")?;
    let name = full.display().to_string();
    let decoded = image::ImageFormat::from_path(&full)
        .map_err(|e| SceneError::Texture {
            name: name.clone(),
            message: e.to_string(),
        })
        .and_then(|format| budget.decode(&name, &bytes, format));
    let img = decoded.map_err(|e| obj_map_error(e, source, material, "map_d"))?;
    crate::AlphaMask::of_image(&name, &img, [Wrap::Repeat; 2], true).ok_or_else(|| {
        SceneError::Texture {
            name,
            message: "an empty image".into(),
        }
    })
}

/// The path (as messages show it) and bytes of the image `file` that statement `key` of an OBJ
/// material names, read within the scene's folder.
fn obj_map(
    folder: &Folder,
    file: &str,
    material: &str,
    source: &str,
    key: &str,
) -> Result<(std::path::PathBuf, Vec<u8>)> {
    let full = folder.shown(Path::new(file));
    let bytes = folder.read(Path::new(file)).map_err(|r| match r {
        Refusal::Outside => SceneError::OutsideFolder {
            source_name: source.into(),
            what: format!("material `{material}`: `{key}`"),
            uri: file.into(),
        },
        Refusal::Refused(e) => e,
        Refusal::Io(e) => obj_map_error(
            SceneError::Texture {
                name: full.display().to_string(),
                message: e.to_string(),
            },
            source,
            material,
            key,
        ),
    })?;
    Ok((full, bytes))
}

/// An image error of an OBJ material's statement `key`, naming the material (over the texture
/// memory bound: as it is).
fn obj_map_error(e: SceneError, source: &str, material: &str, key: &str) -> SceneError {
    match e {
        SceneError::TextureMemory { .. } => e,
        e => SceneError::Parse {
            source_name: source.into(),
            message: format!("material `{material}`: {key}: {e}"),
        },
    }
}

/// The glTF document of `path`, its buffers and its folder: the file and every buffer it names
/// read through the folder's confined reader (`gltf::import` would read any path it names).
fn gltf_document(
    path: &Path,
    source: &str,
    options: &LoadOptions,
) -> Result<(gltf::Document, Vec<Vec<u8>>, Folder)> {
    let bytes = crate::confine::read_regular_file(path, options.max_file_bytes)?;
    let folder = Folder::of(path, options)?;
    let parse = |message: String| SceneError::Parse {
        source_name: source.into(),
        message,
    };
    // gltf is third-party parsing of user input: a panic inside it becomes a parse error, never an abort.
    let gltf::Gltf { document, blob } = std::panic::catch_unwind(|| gltf::Gltf::from_slice(&bytes))
        .map_err(|_| parse("the glTF parser failed on this file".into()))?
        .map_err(|e| parse(e.to_string()))?;
    let buffers = crate::gltf_resources::read_buffers(&document, blob, source, &folder)?;
    Ok((document, buffers, folder))
}

/// Loads a glTF 2.0 file (`.gltf` with its buffers, or `.glb`).
///
/// Every triangle primitive of every mesh instance in the default scene (or the first) is loaded with its
/// node's world transform applied (windings flipped under mirroring transforms). `baseColorFactor.rgb` → ρ,
/// `emissiveFactor × KHR_materials_emissive_strength` → emitted radiance, E = π·that (ρ ≥ 1, such as the
/// default material's white, is clamped to [`RHO_MAX`] with a warning naming the material);
/// `baseColorTexture` (on its TEXCOORD set, with its sampler's wrap modes; sRGB) multiplies it per point
/// ([`Scene::rho_at`]). Triangle strips and fans are loaded as triangles; points and lines are skipped with a warning
/// naming their mesh, and a file with nothing else is an error saying so. The first node with a
/// perspective camera (in traversal order) becomes [`Scene::camera`] (with
/// [`Scene::camera_given`]); without one the image output places its automatic camera.
///
/// Provenance ([`crate::provenance`]): each node with a mesh is an object, each of its triangle
/// primitives a [`Part`] (node, mesh, primitive) that its faces name in [`Face::part`]; the
/// document's node tree, meshes and materials are kept in [`Scene::gltf`], with the world
/// transform applied to each node of the loaded scene.
///
/// Buffers and images are read from the file's folder only, and only the images a material's
/// baseColorTexture uses are decoded, within the default [`LoadOptions`] ([`load_with`] takes
/// others).
pub fn load_gltf(path: impl AsRef<Path>) -> Result<Scene> {
    gltf_with(path.as_ref(), &LoadOptions::default())
}

fn gltf_with(path: &Path, options: &LoadOptions) -> Result<Scene> {
    let source = path.display().to_string();
    let (doc, buffers, folder) = gltf_document(path, &source, options)?;
    let mut budget = TextureBudget::new(options.max_texture_bytes);
    let scene = doc
        .default_scene()
        .or_else(|| doc.scenes().next())
        .ok_or_else(|| SceneError::Parse {
            source_name: source.clone(),
            message: "no scene in file".into(),
        })?;
    let mut faces = Vec::new();
    let mut objects = Vec::new();
    let mut warnings = Vec::new();
    let mut skipped: Vec<String> = Vec::new();
    let mut checked: Vec<(Option<usize>, Spectrum)> = Vec::new();
    let mut textures: Vec<Texture> = Vec::new();
    // (image, wrap modes) → index into `textures`
    let mut texture_of: Vec<((usize, [Wrap; 2]), u32)> = Vec::new();
    let mut cutouts = crate::gltf_cutouts::Cutouts::default();
    let mut emissive = crate::gltf_emission::EmissiveTextures::default();
    // per part: whether its material is doubleSided
    let mut two_sided: Vec<bool> = Vec::new();
    let mut surface = 0u32;
    let mut camera: Option<Camera> = None;
    let mut lights = Vec::new();
    let mut provenance = GltfSource::of_document(&doc, &scene);
    let mut parts: Vec<Part> = Vec::new();
    let mut stack: Vec<(gltf::Node, DMat4, usize)> =
        scene.nodes().map(|n| (n, DMat4::IDENTITY, 0)).collect();
    while let Some((node, parent, depth)) = stack.pop() {
        // a node graph with a cycle (invalid glTF, but parseable) would never end
        if depth > 256 {
            return Err(SceneError::Parse {
                source_name: source.clone(),
                message: format!(
                    "node {} is nested more than 256 deep (a cycle?)",
                    node.index()
                ),
            });
        }
        // node transforms are composed in f64: only the mesh-local positions are f32 (glTF spec)
        let local = DMat4::from_cols_array_2d(&node.transform().matrix().map(|c| c.map(f64::from)));
        let world = parent * local;
        if let Some(n) = provenance.nodes.get_mut(node.index()) {
            n.world = Some(world);
        }
        for child in node.children() {
            stack.push((child, world, depth + 1));
        }
        if camera.is_none() {
            camera = gltf_camera(&node, world, &source, &mut warnings);
        }
        lights.extend(crate::gltf_lights::node_light(&node, world, &source)?);
        let Some(mesh) = node.mesh() else { continue };
        let obj = objects.len() as u32;
        let obj_name = node
            .name()
            .or(mesh.name())
            .map_or_else(|| format!("node{}", node.index()), String::from);
        objects.push(obj_name.clone());
        let flip = world.determinant() < 0.0;
        for prim in mesh.primitives() {
            use gltf::mesh::Mode;
            let mode = prim.mode();
            if !matches!(
                mode,
                Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
            ) {
                skipped.push(format!("`{obj_name}` ({mode:?})"));
                continue;
            }
            let part = parts.len() as u32;
            two_sided.push(prim.material().double_sided());
            parts.push(Part {
                object: obj,
                node: Some(node.index() as u32),
                mesh: Some(mesh.index() as u32),
                primitive: prim.index() as u32,
            });
            let mat = prim.material();
            let pbr = mat.pbr_metallic_roughness();
            let bc = pbr.base_color_factor();
            let strength = f64::from(mat.emissive_strength().unwrap_or(1.0));
            let ef = mat.emissive_factor();
            let e = Spectrum(ef.map(|v| f64::from(v) * strength * PI));
            let rho = match checked.iter().find(|(i, _)| *i == mat.index()) {
                Some(&(_, rho)) => rho,
                None => {
                    let name = match (mat.name(), mat.index()) {
                        (Some(n), _) => n.to_string(),
                        (None, Some(i)) => format!("material {i}"),
                        (None, None) => "the default material".to_string(),
                    };
                    let rho = Spectrum([bc[0], bc[1], bc[2]].map(f64::from));
                    let rho = check_file_material(&source, &name, rho, e, &mut warnings)?;
                    checked.push((mat.index(), rho));
                    rho
                }
            };
            let reader = prim.reader(|b| buffers.get(b.index()).map(Vec::as_slice));
            let read_uv = |k: u32| {
                (reader.read_tex_coords(k)).map(|c| {
                    (c.into_f32())
                        .map(|[u, v]| glam::DVec2::new(f64::from(u), f64::from(v)))
                        .collect::<Vec<_>>()
                })
            };
            let mut images = crate::gltf_resources::Images {
                source: &source,
                folder: &folder,
                buffers: &buffers,
                budget: &mut budget,
            };
            // ⟨baseColorTexture × baseColorFactor, on its TEXCOORD set⟩
            let texture = match pbr.base_color_texture() {
                Some(info) => {
                    let tex = info.texture();
                    let wrap = crate::gltf_resources::wrap_of(&tex);
                    let image = tex.source().index();
                    let index = match texture_of.iter().find(|(k, _)| *k == (image, wrap)) {
                        Some(&(_, i)) => i,
                        None => {
                            let name = tex.source().name().map_or_else(
                                || format!("{source}: image {image}"),
                                |n| format!("{source}: image `{n}`"),
                            );
                            textures.push(crate::gltf_resources::decode_image(
                                &tex.source(),
                                &name,
                                wrap,
                                &mut images,
                            )?);
                            texture_of.push(((image, wrap), textures.len() as u32 - 1));
                            textures.len() as u32 - 1
                        }
                    };
                    let uv = crate::gltf_resources::info_uv(&info, read_uv);
                    match uv {
                        Some(uv) => Some((index, uv)),
                        None => {
                            warnings.push(format!(
                                "{source}: mesh `{obj_name}`: a baseColorTexture but no TEXCOORD_{}: \
                                 its baseColorFactor is used",
                                info.tex_coord()
                            ));
                            None
                        }
                    }
                }
                None => None,
            };
            // ⟨alphaMode: cut-outs; emissiveTexture⟩
            let alpha =
                cutouts.of_primitive(&mat, e.max() > 0.0, read_uv, &mut images, &mut warnings)?;
            let emissive_map = match e.max() > 0.0 {
                true => emissive.of_primitive(&mat, read_uv, &mut images)?,
                false => None,
            };
            let Some(pos) = reader.read_positions() else {
                return Err(SceneError::Parse {
                    source_name: source.clone(),
                    message: format!("mesh `{obj_name}`: primitive without POSITION"),
                });
            };
            let pos: Vec<DVec3> = pos
                .map(|p| world.transform_point3(DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64)))
                .collect();
            let idx: Vec<u32> = match reader.read_indices() {
                Some(i) => i.into_u32().collect(),
                None => (0..pos.len() as u32).collect(),
            };
            // strips and fans as triangle lists (glTF 2.0 §3.7.2.1: strip triangle i is (i, i+1, i+2) for even
            // i and (i+1, i, i+2) for odd i, so that every triangle winds like the first; fan i is (i+1, i+2, 0))
            let tris: Vec<[u32; 3]> = match mode {
                Mode::TriangleStrip => (0..idx.len().saturating_sub(2))
                    .map(|i| {
                        if i % 2 == 0 {
                            [idx[i], idx[i + 1], idx[i + 2]]
                        } else {
                            [idx[i + 1], idx[i], idx[i + 2]]
                        }
                    })
                    .collect(),
                Mode::TriangleFan => (1..idx.len().saturating_sub(1))
                    .map(|i| [idx[i], idx[i + 1], idx[0]])
                    .collect(),
                _ => idx.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect(),
            };
            for t in tris {
                let get = |i: u32| {
                    pos.get(i as usize)
                        .copied()
                        .ok_or_else(|| SceneError::Parse {
                            source_name: source.clone(),
                            message: format!(
                                "mesh `{obj_name}`: index {i} out of range ({} vertices)",
                                pos.len()
                            ),
                        })
                };
                let (a, b, c) = (get(t[0])?, get(t[1])?, get(t[2])?);
                let (v, corners) = if flip {
                    ([a, c, b], [t[0], t[2], t[1]])
                } else {
                    ([a, b, c], t)
                };
                let mut face = Face {
                    part,
                    ..Face::new(v, rho, e, obj, surface)
                };
                if let Some((tex, uv)) = &emissive_map {
                    let at = |i: u32| uv.get(i as usize).copied();
                    if let [Some(a), Some(b), Some(c)] = corners.map(at) {
                        emissive.add(faces.len(), *tex, [a, b, c], e);
                    }
                }
                match &alpha {
                    crate::gltf_cutouts::Alpha::Opaque => {}
                    crate::gltf_cutouts::Alpha::Hidden => {
                        cutouts.hidden += 1;
                        continue;
                    }
                    crate::gltf_cutouts::Alpha::Cut {
                        mask,
                        uv,
                        threshold,
                    } => {
                        let at = |i: u32| uv.get(i as usize).copied();
                        if let [Some(a), Some(b), Some(c)] = corners.map(at) {
                            face.cutout = Some(crate::FaceCutout {
                                mask: *mask,
                                uv: [a, b, c],
                                threshold: *threshold,
                            });
                        }
                    }
                }
                if let Some((index, uv)) = &texture {
                    let at = |i: u32| uv.get(i as usize).copied();
                    if let [Some(a), Some(b), Some(c)] = corners.map(at) {
                        let ft = FaceTexture {
                            texture: *index,
                            uv: [a, b, c],
                            factor: rho,
                        };
                        face.texture = Some(ft);
                    }
                }
                faces.push(face);
                surface += 1;
            }
        }
    }
    if faces.is_empty() && !skipped.is_empty() {
        return Err(SceneError::Parse {
            source_name: source,
            message: format!(
                "no triangles: every primitive is points or lines ({}), which have no area to light",
                skipped.join(", ")
            ),
        });
    }
    average_albedo(&mut faces, &textures);
    let emitting = emissive.apply(&mut faces);
    if emitting > 0 {
        warnings.push(format!(
            "{source}: {emitting} face(s) with an emissiveTexture emit its mean over each face \
             (constant per face: a pattern finer than the faces is averaged)"
        ));
    }
    if cutouts.hidden > 0 {
        warnings.push(format!(
            "{source}: dropped {} face(s) whose material's alpha is below its alphaCutoff              everywhere (fully cut out)",
            cutouts.hidden
        ));
    }
    let mut scene = Scene::new(&stem(path), &source, faces, objects, camera)?
        .with_textures(textures)?
        .with_masks(cutouts.masks)?;
    scene.parts = parts;
    scene.gltf = Some(Box::new(provenance));
    if !options.single_sided {
        let backs = scene.add_back_faces(|f| two_sided.get(f.part as usize) == Some(&true));
        if backs > 0 {
            warnings.push(format!(
                "{source}: {backs} face(s) of doubleSided materials got a back face (both sides \
                 reflect and are solved); for closed solids --single-sided halves the work"
            ));
        }
    }
    scene.add_lights(lights);
    if !skipped.is_empty() {
        warnings.push(format!(
            "{source}: skipped {} point/line primitive(s): {}",
            skipped.len(),
            skipped.join(", ")
        ));
    }
    scene.warnings.extend(warnings);
    Ok(scene)
}

/// The camera of a glTF node, if it has a perspective one (glTF 2.0 §3.10: the lens looks along the
/// node's local −Z, local +Y is up, `yfov` is the vertical field of view in radians); the node's
/// world transform places it. An orthographic camera, or one whose transform collapses its axes,
/// is skipped with a warning (the image then uses the automatic camera).
fn gltf_camera(
    node: &gltf::Node,
    world: DMat4,
    source: &str,
    warnings: &mut Vec<String>,
) -> Option<Camera> {
    let cam = node.camera()?;
    let name = cam
        .name()
        .map_or_else(|| format!("camera {}", cam.index()), |n| format!("`{n}`"));
    let gltf::camera::Projection::Perspective(p) = cam.projection() else {
        warnings.push(format!(
            "{source}: {name} is orthographic: not supported, the image uses the automatic camera"
        ));
        return None;
    };
    let eye = world.transform_point3(DVec3::ZERO);
    let forward = world.transform_vector3(DVec3::NEG_Z).normalize_or_zero();
    let up = world.transform_vector3(DVec3::Y).normalize_or_zero();
    let fov_y_deg = f64::from(p.yfov()).to_degrees();
    let usable = eye.is_finite()
        && forward != DVec3::ZERO
        && forward.cross(up).length() > 1e-6
        && fov_y_deg > 0.0
        && fov_y_deg < 180.0;
    if !usable {
        warnings.push(format!(
            "{source}: {name}: degenerate transform or field of view ({fov_y_deg}°): ignored, the \
             image uses the automatic camera"
        ));
        return None;
    }
    Some(Camera {
        eye,
        target: eye + forward,
        up,
        fov_y_deg,
    })
}

/// Sets every textured face's [`crate::Face::rho`] to its texture's mean over the face
/// ([`crate::FaceTexture::mean_rho`]), in parallel over the faces.
fn average_albedo(faces: &mut [Face], textures: &[crate::Texture]) {
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
