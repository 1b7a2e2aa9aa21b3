//! The OBJ + MTL loader (tobj): materials (`Kd`, `Ke`, one-number greys), `map_Kd` textures,
//! `map_Ke` emissive textures, `d`/`map_d` cut-outs, each line of trouble named.
//!
//! Units (FORMATS.md): OBJ `Ke` is emitted **radiance** L_e, as a path tracer reads it; the scene
//! stores emitted radiosity (exitance) `E = π·L_e`.

use crate::confine::{Folder, Refusal};
use crate::read::{average_albedo, line_of, read_text, stem};
use crate::scene::check_file_material;
use crate::texture::TextureBudget;
use crate::{Face, FaceTexture, LoadOptions, Result, Scene, SceneError, Spectrum, Texture, Wrap};
use glam::{DVec2, DVec3};
use std::f64::consts::PI;
use std::path::Path;

/// The MTL keywords the loader uses (`Kd` → ρ, `Ke` → emitted radiance) and the colour keywords that share
/// their syntax.
const MTL_COLOURS: [&str; 5] = ["Ka", "Kd", "Ks", "Ke", "Tf"];

/// Rewrites MTL text into the subset tobj parses without trouble: only `newmtl`, `Kd`, `Ke`, `map_Kd`,
/// `map_Ke`, `d` and `map_d` lines are kept (maps with their file name alone: texture options are an error naming the
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
        } else if key == "map_Kd" || key == "map_Ke" || key == "map_d" {
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
/// is everything after the first space, trimmed); and, when the file has `vt` lines, every face
/// (`f`) with a corner that has none (key `f-no-vt`): tobj gives those corners another corner's
/// coordinates ([`check_missing_vt`]).
fn scan_obj(text: &str) -> Vec<Statement> {
    let mut out = Vec::new();
    let has_vt = text.lines().any(|l| l.trim_start().starts_with("vt "));
    for (k, raw) in text.lines().enumerate() {
        let mut words = raw.split_whitespace();
        let key = match words.next() {
            Some("mtllib") => "mtllib",
            Some("usemtl") => "usemtl",
            // `v` and `v//vn` corners have no texture coordinates
            Some("f") if has_vt && words.any(|c| c.split('/').nth(1).is_none_or(str::is_empty)) => {
                "f-no-vt"
            }
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
/// format); ρ ≥ 1 is clamped to [`RHO_MAX`](crate::RHO_MAX) with a warning naming the material. Faces without a material get
/// ρ = 0.5 grey, E = 0 (reported in `warnings`); a `usemtl` naming a material that is not defined, or an
/// `mtllib` that cannot be read, is an error naming the line. Each OBJ object/group becomes an object; each
/// input polygon one surface. Windings are kept as written (front side = counter-clockwise); faces whose `vn`
/// normals point against their winding are counted in a warning naming the object.
///
/// Material libraries and textures are read from the OBJ file's folder only, within the default
/// [`LoadOptions`] ([`load_with`](crate::load_with) takes others).
pub fn load_obj(path: impl AsRef<Path>) -> Result<Scene> {
    obj_with(path.as_ref(), &LoadOptions::default())
}

/// [`load_obj`] within `options` ([`crate::load_with`]).
pub(crate) fn obj_with(path: &Path, options: &LoadOptions) -> Result<Scene> {
    let source = path.display().to_string();
    let text = read_text(path, options.max_file_bytes)?;
    let folder = Folder::of(path, options)?;
    // ⟨The models and materials; every `usemtl` names a defined material⟩
    let statements = scan_obj(&text);
    let (models, materials) = parse_obj(&text, &statements, &folder, &source)?;
    check_usemtl(&statements, &materials, &source)?;
    let mut warnings = check_missing_vt(&statements, &materials, &source);
    // ⟨The materials' textures and cut-outs⟩
    let mut budget = TextureBudget::new(options.max_texture_bytes);
    let (textures, texture_of) = obj_textures(&materials, &folder, &source, &mut budget)?;
    let emissive = obj_emissive(&materials, &folder, &source, &mut budget)?;
    let (masks, alpha_of) = obj_alphas(&materials, &folder, &source, &mut budget, &mut warnings)?;
    // ⟨The faces of every model, then the scene⟩
    let looks = ObjMaterials {
        source: &source,
        materials: &materials,
        texture_of,
        alpha_of,
        emissive_of: emissive.1,
    };
    let mut faces = ObjFaces::new(materials.len());
    for m in &models {
        faces.add_model(m, &looks, &mut warnings)?;
    }
    // (the parser's models and the text are no longer needed: not held through the scene's
    // checks, a large model's peak)
    drop((models, looks, statements, text));
    faces.into_scene(path, &source, (textures, emissive.0), masks, warnings)
}

/// The models and materials tobj reads from the OBJ `text` (polygons triangulated), its
/// material libraries read through the scene's `folder` ([`read_mtl`]; the first error there is
/// the error); a panic inside tobj is a parse error naming `source`.
fn parse_obj(
    text: &str,
    statements: &[Statement],
    folder: &Folder,
    source: &str,
) -> Result<(Vec<tobj::Model>, Vec<tobj::Material>)> {
    let opts = tobj::LoadOptions {
        triangulate: true,
        single_index: false,
        ..Default::default()
    };
    let problem: std::cell::RefCell<Option<SceneError>> = std::cell::RefCell::new(None);
    let material_loader = |mtl: &Path| -> tobj::MTLLoadResult {
        match read_mtl(mtl, statements, folder, source) {
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
        source_name: source.into(),
        message: "the OBJ parser (tobj) failed on this file".into(),
    })?;
    if let Some(e) = problem.into_inner() {
        return Err(e);
    }
    let (models, materials) = loaded.map_err(|e| SceneError::Parse {
        source_name: source.into(),
        message: e.to_string(),
    })?;
    let materials = materials.map_err(|e| SceneError::Parse {
        source_name: source.into(),
        message: format!("material library: {e}"),
    })?;
    Ok((models, materials))
}

/// The text of the material library `mtl` that an `mtllib` statement of the OBJ file `source`
/// names, read within the scene's `folder` as UTF-8 and rewritten by [`sanitize_mtl`]; errors
/// name the statement's line (0 when the scan did not find it).
fn read_mtl(mtl: &Path, statements: &[Statement], folder: &Folder, source: &str) -> Result<String> {
    let full = folder.shown(mtl);
    let line = (statements.iter())
        .find(|s| s.key == "mtllib" && Path::new(&s.arg) == mtl)
        .map_or(0, |s| s.line);
    (folder.read(mtl))
        .map_err(|r| match r {
            Refusal::Outside => SceneError::OutsideFolder {
                source_name: format!("{source}:{line}"),
                what: "`mtllib`".into(),
                uri: mtl.display().to_string(),
            },
            Refusal::Refused(e) => e,
            Refusal::Io(e) => SceneError::MaterialLibrary {
                source_name: source.into(),
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
        })
}

/// A warning per textured material (`map_Kd`, `map_Ke`, `map_d`) with faces that have corners
/// without `vt` in a file that has `vt`: tobj gives such a corner the previous corner's texture
/// coordinates (or the first `vt`), so the face reads its texture at a point nobody chose. Named
/// by the first such line; the count of faces.
fn check_missing_vt(
    statements: &[Statement],
    materials: &[tobj::Material],
    source: &str,
) -> Vec<String> {
    let textured = |name: &str| {
        (materials.iter()).any(|m| {
            m.name == name
                && (m.diffuse_texture.is_some()
                    || m.dissolve_texture.is_some()
                    || m.unknown_param.contains_key("map_Ke"))
        })
    };
    // per material: the first line and the faces
    let mut found: Vec<(&str, usize, usize)> = Vec::new();
    let mut current = "";
    for s in statements {
        match s.key {
            "usemtl" => current = &s.arg,
            "f-no-vt" if textured(current) => match found.iter_mut().find(|f| f.0 == current) {
                Some(f) => f.2 += 1,
                None => found.push((current, s.line, 1)),
            },
            _ => {}
        }
    }
    (found.into_iter())
        .map(|(m, line, n)| {
            format!(
                "{source}:{line}: {n} face(s) of textured material `{m}` have corners without \
                 `vt`: the OBJ parser gives them another corner's texture coordinates, so their \
                 texture is read where no one chose; give every face of a textured material its \
                 `vt`"
            )
        })
        .collect()
}

/// An error for the first `usemtl` statement that names no material of `materials`, naming its
/// line and the materials defined. tobj silently gives no material for an undefined name: the
/// faces would turn grey and, if the name was the light's, the scene would fail later with "no
/// face emits light".
fn check_usemtl(
    statements: &[Statement],
    materials: &[tobj::Material],
    source: &str,
) -> Result<()> {
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
                source_name: source.into(),
                line: s.line,
                name: s.arg.clone(),
                known,
            });
        }
    }
    Ok(())
}

/// The materials' `map_Kd` textures ([`obj_texture`], decoded within `budget`) and, per
/// material, its texture's index.
fn obj_textures(
    materials: &[tobj::Material],
    folder: &Folder,
    source: &str,
    budget: &mut TextureBudget,
) -> Result<(Vec<Texture>, Vec<Option<u32>>)> {
    let map = |m: &tobj::Material| m.diffuse_texture.clone();
    material_maps(materials, (map, "map_Kd"), folder, source, budget)
}

/// The materials' `map_Ke` emissive textures (decoded as [`obj_texture`], within `budget`) and,
/// per material, its emissive texture's index. Each face of such a material emits its `Ke` (1 1 1
/// when the material gives only the map) times the texture's mean over the face's texture
/// coordinates, constant over the face, as glTF emissive textures (`crate::gltf_emission`).
fn obj_emissive(
    materials: &[tobj::Material],
    folder: &Folder,
    source: &str,
    budget: &mut TextureBudget,
) -> Result<(Vec<Texture>, Vec<Option<u32>>)> {
    let map = |m: &tobj::Material| m.unknown_param.get("map_Ke").cloned();
    material_maps(materials, (map, "map_Ke"), folder, source, budget)
}

/// The colour textures `map` names (the MTL keyword `key`), one per material that has one, and
/// per material its texture's index.
fn material_maps(
    materials: &[tobj::Material],
    (map, key): (impl Fn(&tobj::Material) -> Option<String>, &str),
    folder: &Folder,
    source: &str,
    budget: &mut TextureBudget,
) -> Result<(Vec<Texture>, Vec<Option<u32>>)> {
    let mut textures: Vec<Texture> = Vec::new();
    let mut index_of: Vec<Option<u32>> = vec![None; materials.len()];
    for (i, mat) in materials.iter().enumerate() {
        if let Some(file) = map(mat) {
            let tex = obj_texture(folder, &file, &mat.name, source, budget, key)?;
            index_of[i] = Some(textures.len() as u32);
            textures.push(tex);
        }
    }
    Ok((textures, index_of))
}

/// An OBJ file's materials as its faces take them: per material its texture (index into the
/// scene's textures) and how its opacity cuts it.
struct ObjMaterials<'a> {
    /// The OBJ file, for messages.
    source: &'a str,
    materials: &'a [tobj::Material],
    texture_of: Vec<Option<u32>>,
    alpha_of: Vec<ObjAlpha>,
    /// Per material: its `map_Ke` emissive texture (index into the emissive textures).
    emissive_of: Vec<Option<u32>>,
}

/// A model's mesh as its faces read it, with the model's name and the file for messages.
struct ObjMesh<'a> {
    mesh: &'a tobj::Mesh,
    name: &'a str,
    source: &'a str,
}

impl ObjMesh<'_> {
    /// The position of vertex `i`; an error naming the object when it is out of range.
    fn position(&self, i: u32) -> Result<DVec3> {
        let i = i as usize * 3;
        match self.mesh.positions.get(i..i + 3) {
            Some(p) => Ok(DVec3::new(p[0], p[1], p[2])),
            None => Err(SceneError::Parse {
                source_name: self.source.into(),
                message: format!(
                    "object `{}`: vertex index {} out of range",
                    self.name,
                    i / 3
                ),
            }),
        }
    }

    /// The normal `i`, if there is one.
    fn normal(&self, i: u32) -> Option<DVec3> {
        let i = i as usize * 3;
        (self.mesh.normals)
            .get(i..i + 3)
            .map(|n| DVec3::new(n[0], n[1], n[2]))
    }

    /// The texture coordinates `i`, v flipped (OBJ's v = 0 is the image's bottom row).
    fn uv(&self, i: u32) -> Option<DVec2> {
        let i = i as usize * 2;
        (self.mesh.texcoords.get(i..i + 2)).map(|t| DVec2::new(t[0], 1.0 - t[1]))
    }

    /// Whether every corner has a `vt` (texture coordinates).
    fn with_uv(&self) -> bool {
        self.mesh.texcoord_indices.len() == self.mesh.indices.len()
    }

    /// The texture coordinates of triangle `k`'s corners, if all three exist; only for a mesh
    /// [`Self::with_uv`].
    fn corner_uvs(&self, k: usize) -> Option<[DVec2; 3]> {
        let c = &self.mesh.texcoord_indices[3 * k..3 * k + 3];
        match (self.uv(c[0]), self.uv(c[1]), self.uv(c[2])) {
            (Some(a), Some(b), Some(d)) => Some([a, b, d]),
            _ => None,
        }
    }

    /// Whether the `vn` normals of triangle `k` (corners `v`) point against its winding
    /// (false without normals on every corner).
    fn against_winding(&self, k: usize, v: &[DVec3; 3]) -> bool {
        let mesh = self.mesh;
        if mesh.normal_indices.len() != mesh.indices.len() {
            return false;
        }
        let n = &mesh.normal_indices[3 * k..3 * k + 3];
        if let (Some(a), Some(b), Some(c)) =
            (self.normal(n[0]), self.normal(n[1]), self.normal(n[2]))
        {
            let winding = (v[1] - v[0]).cross(v[2] - v[0]);
            return (a + b + c).dot(winding) < 0.0;
        }
        false
    }
}

/// How the faces of one model look: their object, ρ and E, their material's texture (index)
/// and cut-out.
struct ModelLook {
    object: u32,
    rho: Spectrum,
    e: Spectrum,
    texture: Option<u32>,
    alpha: ObjAlpha,
    /// The material's emissive texture (index), when it has one.
    emissive: Option<u32>,
}

/// The faces of an OBJ file as its models are read, and what the warnings report.
struct ObjFaces {
    faces: Vec<Face>,
    /// The objects' names (tobj splits an object at every `usemtl`: parts of one name stay one
    /// object).
    objects: Vec<String>,
    /// Per material: its ρ and E once checked.
    checked: Vec<Option<(Spectrum, Spectrum)>>,
    /// The next face's surface (one per triangle).
    surface: u32,
    /// Faces dropped as cut out everywhere.
    hidden: usize,
    /// Faces without a material.
    missing_material: usize,
    /// Objects with a textured material but no `vt`.
    untextured: Vec<String>,
    /// Faces (index into `faces`) with an emissive texture, and their mapping (factor: E).
    emissive_faces: Vec<(usize, FaceTexture)>,
    /// Per object: its faces whose `vn` normals point against their winding.
    against_normals: Vec<(String, usize)>,
}

impl ObjFaces {
    /// No faces yet, of a file with `materials` materials.
    fn new(materials: usize) -> Self {
        Self {
            faces: Vec::new(),
            objects: Vec::new(),
            checked: vec![None; materials],
            surface: 0,
            hidden: 0,
            missing_material: 0,
            untextured: Vec::new(),
            emissive_faces: Vec::new(),
            against_normals: Vec::new(),
        }
    }

    /// Adds the faces of model `m` (its object by name): its material's ρ and E
    /// ([`Self::material_of`]), its texture mapping on its `vt` (a non-finite `vt` is an
    /// error naming the object), its cut-out; one surface per triangle (tobj gives
    /// face_arities only when not triangulating, and does not say which triangles share a
    /// polygon).
    fn add_model(
        &mut self,
        m: &tobj::Model,
        looks: &ObjMaterials,
        warnings: &mut Vec<String>,
    ) -> Result<()> {
        // tobj splits an object at every `usemtl`: parts of one name stay one object
        let oi = match self.objects.iter().position(|o| *o == m.name) {
            Some(k) => k,
            None => {
                self.objects.push(m.name.clone());
                self.objects.len() - 1
            }
        };
        let (rho, e) = self.material_of(&m.mesh, looks, warnings)?;
        let mesh = ObjMesh {
            mesh: &m.mesh,
            name: &m.name,
            source: looks.source,
        };
        // ⟨The texture mapping of a textured material: vt per corner⟩
        let texture = (m.mesh.material_id).and_then(|i| looks.texture_of.get(i).copied().flatten());
        let emissive =
            (m.mesh.material_id).and_then(|i| looks.emissive_of.get(i).copied().flatten());
        // a `vt nan` would read texel 0 (ρ = 0) in silence
        if mesh.with_uv() && m.mesh.texcoords.iter().any(|t| !t.is_finite()) {
            return Err(SceneError::Parse {
                source_name: looks.source.into(),
                message: format!(
                    "object `{}`: a `vt` coordinate is not a finite number",
                    m.name
                ),
            });
        }
        if (texture.is_some() || emissive.is_some())
            && !mesh.with_uv()
            && !self.untextured.contains(&m.name)
        {
            self.untextured.push(m.name.clone());
        }
        let look = ModelLook {
            object: oi as u32,
            rho,
            e,
            texture,
            alpha: (m.mesh.material_id)
                .and_then(|i| looks.alpha_of.get(i).copied())
                .unwrap_or(ObjAlpha::Opaque),
            emissive,
        };
        let mut against = 0usize;
        for k in 0..m.mesh.indices.len() / 3 {
            if self.add_triangle(&mesh, k, &look)? {
                against += 1;
            }
        }
        if against > 0 {
            match self.against_normals.iter_mut().find(|(o, _)| *o == m.name) {
                Some((_, n)) => *n += against,
                None => self.against_normals.push((m.name.clone(), against)),
            }
        }
        Ok(())
    }

    /// ρ and E = π·Ke of `mesh`'s material, checked once per material
    /// ([`check_file_material`]: ρ ≥ 1 clamped with a warning); ρ = 0.5 grey and E = 0 for a
    /// mesh without a material (its faces counted for the warning).
    fn material_of(
        &mut self,
        mesh: &tobj::Mesh,
        looks: &ObjMaterials,
        warnings: &mut Vec<String>,
    ) -> Result<(Spectrum, Spectrum)> {
        let materials = looks.materials;
        Ok(match mesh.material_id.filter(|&i| i < materials.len()) {
            Some(i) => match self.checked[i] {
                Some(v) => v,
                None => {
                    let mat = &materials[i];
                    let kd = Spectrum(mat.diffuse.unwrap_or([0.0; 3]));
                    // a `map_Ke` without `Ke` is the texture alone (Ke 1 1 1)
                    let ke = match mat.unknown_param.contains_key("map_Ke") {
                        true => mat.emissive.unwrap_or([1.0; 3]),
                        false => mat.emissive.unwrap_or([0.0; 3]),
                    };
                    let e = Spectrum(ke.map(|v| v * PI));
                    let rho = check_file_material(looks.source, &mat.name, kd, e, warnings)?;
                    self.checked[i] = Some((rho, e));
                    (rho, e)
                }
            },
            None => {
                self.missing_material += mesh.indices.len() / 3;
                (Spectrum::grey(0.5), Spectrum::ZERO)
            }
        })
    }

    /// Adds triangle `k` of `mesh` as a face that looks as `look` says, with its cut-out and
    /// texture mapping when the mesh has `vt`, unless it is cut out everywhere (then only
    /// counted); returns whether its `vn` normals point against its winding.
    fn add_triangle(&mut self, mesh: &ObjMesh, k: usize, look: &ModelLook) -> Result<bool> {
        let t = &mesh.mesh.indices[3 * k..3 * k + 3];
        let v = [
            mesh.position(t[0])?,
            mesh.position(t[1])?,
            mesh.position(t[2])?,
        ];
        let against = mesh.against_winding(k, &v);
        let mut face = Face::new(v, look.rho, look.e, look.object, self.surface);
        let with_uv = mesh.with_uv();
        match (look.alpha, with_uv) {
            (ObjAlpha::Hidden, _) => {
                self.hidden += 1;
                return Ok(against);
            }
            (ObjAlpha::Cut(mask, threshold), true) => {
                if let Some(uv) = mesh.corner_uvs(k) {
                    face.cutout = Some(crate::FaceCutout {
                        mask,
                        uv,
                        threshold,
                    });
                }
            }
            _ => {}
        }
        if let (Some(tex), true) = (look.texture, with_uv) {
            if let Some(uv) = mesh.corner_uvs(k) {
                let ft = FaceTexture {
                    texture: tex,
                    uv,
                    factor: look.rho,
                };
                face.texture = Some(ft);
            }
        }
        if let (Some(texture), true) = (look.emissive, with_uv) {
            if let Some(uv) = mesh.corner_uvs(k) {
                let ft = FaceTexture {
                    texture,
                    uv,
                    factor: look.e,
                };
                self.emissive_faces.push((self.faces.len(), ft));
            }
        }
        self.faces.push(face);
        self.surface += 1;
        Ok(against)
    }

    /// The scene of the faces (named after `path`), textured faces' ρ their texture's mean,
    /// with its `textures` and cut-out `masks`; the load's `warnings` and this file's
    /// (faces cut out, textures without `vt`, normals against windings, faces without a
    /// material) after the scene's own.
    fn into_scene(
        self,
        path: &Path,
        source: &str,
        (textures, emissive): (Vec<Texture>, Vec<Texture>),
        masks: Vec<crate::AlphaMask>,
        mut warnings: Vec<String>,
    ) -> Result<Scene> {
        let mut faces = self.faces;
        average_albedo(&mut faces, &textures);
        // ⟨map_Ke: each face emits its texture's mean, constant over the face⟩
        if !self.emissive_faces.is_empty() {
            let mipmaps = crate::Mipmaps::new(&emissive);
            for (i, t) in &self.emissive_faces {
                faces[*i].emission = t.mean_rho(&mipmaps);
            }
        }
        if self.hidden > 0 {
            warnings.push(format!(
                "{source}: dropped {} face(s) whose material's opacity `d` is below 0.5 (fully \
                 cut out)",
                self.hidden
            ));
        }
        let mut scene = Scene::new(&stem(path), source, faces, self.objects, None)?
            .with_textures(textures)?
            .with_masks(masks)?;
        warnings.extend(self.untextured.into_iter().map(|o| {
            format!(
                "{source}: object `{o}`: a textured material (map_Kd or map_Ke) but no `vt`: its \
                 Kd and Ke are used"
            )
        }));
        warnings.extend(self.against_normals.into_iter().map(|(o, n)| {
            format!(
                "{source}: object `{o}`: {n} face(s) whose `vn` normals point against their winding; the front \
                 side comes from the winding (counter-clockwise), so these faces are lit from behind and \
                 look black: fix the winding or the normals"
            )
        }));
        if self.missing_material > 0 {
            warnings.push(format!(
                "{source}: {} face(s) without material: ρ = 0.5, E = 0",
                self.missing_material
            ));
        }
        scene.warnings.extend(warnings);
        Ok(scene)
    }
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

/// An OBJ material's colour texture `file` (its `key`: `map_Kd` or `map_Ke`), read within the
/// scene's folder and decoded within `budget`; a file that cannot be read or decoded is an error
/// naming the material.
fn obj_texture(
    folder: &Folder,
    file: &str,
    material: &str,
    source: &str,
    budget: &mut TextureBudget,
    key: &str,
) -> Result<Texture> {
    let (full, bytes) = obj_map(folder, file, material, source, key)?;
    let name = full.display().to_string();
    Texture::from_file_bytes(&name, &full, &bytes, [Wrap::Repeat; 2], budget)
        .map_err(|e| obj_map_error(e, source, material, key))
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
