//! Scene files: OBJ + MTL (tobj), glTF 2.0 / .glb (gltf), Flatland JSON; and writers for OBJ/MTL.
//!
//! Units (FORMATS.md): OBJ `Ke` and glTF `emissiveFactor × emissive_strength` are emitted **radiance** L_e, as a
//! path tracer reads them; the scene stores emitted radiosity (exitance) `E = π·L_e`, and every solver reports
//! radiosity B (exitance; `B = π·L` on a Lambertian surface). Flatland JSON gives E directly.

use crate::{AnyScene, Camera, Face, FlatlandScene, Result, Scene, SceneError, Spectrum};
use glam::{DMat4, DVec3};
use std::f64::consts::PI;
use std::path::Path;

fn stem(path: &Path) -> String {
    path.file_stem()
        .map_or_else(|| "scene".into(), |s| s.to_string_lossy().into_owned())
}

fn io(path: &Path) -> impl FnOnce(std::io::Error) -> SceneError + '_ {
    move |source| SceneError::Io {
        path: path.into(),
        source,
    }
}

/// Loads a scene file, choosing the loader by extension: `.obj` (with its MTL), `.gltf`/`.glb`, `.json`
/// (Flatland).
pub fn load(path: impl AsRef<Path>) -> Result<AnyScene> {
    let path = path.as_ref();
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    match ext.as_str() {
        "obj" => load_obj(path).map(AnyScene::ThreeD),
        "gltf" | "glb" => load_gltf(path).map(AnyScene::ThreeD),
        "json" => load_flatland(path).map(AnyScene::Flatland),
        _ => Err(SceneError::UnsupportedFormat { path: path.into() }),
    }
}

/// Loads `name` as a built-in if [`crate::builtin::is_builtin`] says so (one of [`crate::BUILTIN_NAMES`] or
/// `random-boxes-<N>`), else as a file.
pub fn load_or_builtin(name: &str) -> Result<AnyScene> {
    if crate::builtin::is_builtin(name) {
        crate::builtin(name)
    } else {
        load(name)
    }
}

/// Loads a Flatland JSON scene (format in FORMATS.md and [`FlatlandScene::from_json`]).
pub fn load_flatland(path: impl AsRef<Path>) -> Result<FlatlandScene> {
    let path = path.as_ref();
    let text = std::fs::read_to_string(path).map_err(io(path))?;
    FlatlandScene::from_json(&stem(path), &path.display().to_string(), &text)
}

/// Loads an OBJ file and its MTL library.
///
/// Polygons are triangulated as fans (tobj). `Kd` → ρ, `Ke` → emitted radiance (E = π·Ke). Faces without a
/// material get ρ = 0.5 grey, E = 0 (reported in `warnings`). Each OBJ object/group becomes an object; each
/// input polygon one surface. Windings are kept as written (front side = counter-clockwise).
pub fn load_obj(path: impl AsRef<Path>) -> Result<Scene> {
    let path = path.as_ref();
    let source = path.display().to_string();
    // Read first: a missing file is an I/O error, not a parse error.
    std::fs::metadata(path).map_err(io(path))?;
    let opts = tobj::LoadOptions {
        triangulate: true,
        single_index: false,
        ..Default::default()
    };
    let (models, materials) = tobj::load_obj(path, &opts).map_err(|e| SceneError::Parse {
        source_name: source.clone(),
        message: e.to_string(),
    })?;
    let materials = materials.map_err(|e| SceneError::Parse {
        source_name: source.clone(),
        message: format!("material library: {e}"),
    })?;
    let mut faces = Vec::new();
    let mut objects = Vec::new();
    let mut missing_material = 0usize;
    let mut surface = 0u32;
    for (oi, m) in models.iter().enumerate() {
        objects.push(m.name.clone());
        let mesh = &m.mesh;
        let (rho, e) = match mesh.material_id.and_then(|i| materials.get(i)) {
            Some(mat) => {
                let kd = mat.diffuse.unwrap_or([0.0; 3]);
                let ke = mat.emissive.unwrap_or([0.0; 3]);
                (
                    Spectrum(kd.map(f64::from)),
                    Spectrum(ke.map(|v| f64::from(v) * PI)),
                )
            }
            None => {
                missing_material += mesh.indices.len() / 3;
                (Spectrum::grey(0.5), Spectrum::ZERO)
            }
        };
        let pos = |i: u32| -> Result<DVec3> {
            let i = i as usize * 3;
            match mesh.positions.get(i..i + 3) {
                Some(p) => Ok(DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64)),
                None => Err(SceneError::Parse {
                    source_name: source.clone(),
                    message: format!("object `{}`: vertex index {} out of range", m.name, i / 3),
                }),
            }
        };
        // tobj gives face_arities only when not triangulating; with triangulation each polygon's fan shares a
        // surface id only if we track it, which tobj does not expose: one surface per triangle then.
        for t in mesh.indices.chunks_exact(3) {
            faces.push(Face::new(
                [pos(t[0])?, pos(t[1])?, pos(t[2])?],
                rho,
                e,
                oi as u32,
                surface,
            ));
            surface += 1;
        }
    }
    let mut scene = Scene::new(&stem(path), &source, faces, objects, None)?;
    if missing_material > 0 {
        scene.warnings.push(format!(
            "{source}: {missing_material} face(s) without material: ρ = 0.5, E = 0"
        ));
    }
    Ok(scene)
}

/// Loads a glTF 2.0 file (`.gltf` with its buffers, or `.glb`).
///
/// Every triangle primitive of every mesh instance in the default scene (or the first) is loaded with its
/// node's world transform applied (windings flipped under mirroring transforms). `baseColorFactor.rgb` → ρ,
/// `emissiveFactor × KHR_materials_emissive_strength` → emitted radiance, E = π·that. Textures are ignored.
/// Non-triangle primitives (points, lines, strips) are skipped with a warning.
pub fn load_gltf(path: impl AsRef<Path>) -> Result<Scene> {
    let path = path.as_ref();
    let source = path.display().to_string();
    std::fs::metadata(path).map_err(io(path))?;
    let (doc, buffers, _images) = gltf::import(path).map_err(|e| SceneError::Parse {
        source_name: source.clone(),
        message: e.to_string(),
    })?;
    let scene = doc
        .default_scene()
        .or_else(|| doc.scenes().next())
        .ok_or_else(|| SceneError::Parse {
            source_name: source.clone(),
            message: "no scene in file".into(),
        })?;
    let mut faces = Vec::new();
    let mut objects = Vec::new();
    let mut skipped = 0usize;
    let mut surface = 0u32;
    let mut stack: Vec<(gltf::Node, DMat4)> = scene.nodes().map(|n| (n, DMat4::IDENTITY)).collect();
    while let Some((node, parent)) = stack.pop() {
        let local = DMat4::from_cols_array_2d(&node.transform().matrix().map(|c| c.map(f64::from)));
        let world = parent * local;
        for child in node.children() {
            stack.push((child, world));
        }
        let Some(mesh) = node.mesh() else { continue };
        let obj = objects.len() as u32;
        objects.push(
            node.name()
                .or(mesh.name())
                .map_or_else(|| format!("node{}", node.index()), String::from),
        );
        let flip = world.determinant() < 0.0;
        for prim in mesh.primitives() {
            if prim.mode() != gltf::mesh::Mode::Triangles {
                skipped += 1;
                continue;
            }
            let mat = prim.material();
            let pbr = mat.pbr_metallic_roughness();
            let bc = pbr.base_color_factor();
            let strength = f64::from(mat.emissive_strength().unwrap_or(1.0));
            let ef = mat.emissive_factor();
            let rho = Spectrum([bc[0], bc[1], bc[2]].map(f64::from));
            let e = Spectrum(ef.map(|v| f64::from(v) * strength * PI));
            let reader = prim.reader(|b| buffers.get(b.index()).map(|d| &d.0[..]));
            let Some(pos) = reader.read_positions() else {
                return Err(SceneError::Parse {
                    source_name: source.clone(),
                    message: format!(
                        "mesh `{}`: primitive without POSITION",
                        mesh.name().unwrap_or("?")
                    ),
                });
            };
            let pos: Vec<DVec3> = pos
                .map(|p| world.transform_point3(DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64)))
                .collect();
            let idx: Vec<u32> = match reader.read_indices() {
                Some(i) => i.into_u32().collect(),
                None => (0..pos.len() as u32).collect(),
            };
            for t in idx.chunks_exact(3) {
                let get = |i: u32| {
                    pos.get(i as usize)
                        .copied()
                        .ok_or_else(|| SceneError::Parse {
                            source_name: source.clone(),
                            message: format!("index {i} out of range ({} vertices)", pos.len()),
                        })
                };
                let (a, b, c) = (get(t[0])?, get(t[1])?, get(t[2])?);
                let v = if flip { [a, c, b] } else { [a, b, c] };
                faces.push(Face::new(v, rho, e, obj, surface));
                surface += 1;
            }
        }
    }
    let camera: Option<Camera> = None;
    let mut scene = Scene::new(&stem(path), &source, faces, objects, camera)?;
    if skipped > 0 {
        scene.warnings.push(format!(
            "{source}: skipped {skipped} non-triangle primitive(s)"
        ));
    }
    Ok(scene)
}

/// Writes a scene as OBJ text plus MTL text (one material per distinct (ρ, E) pair, `Ke = E/π`), with
/// `mtllib <mtl_name>`. Numbers are written with full f64 precision; tobj parses them as f32, so a round trip
/// through [`load_obj`] reproduces the faces to f32 rounding.
pub fn to_obj(scene: &Scene, mtl_name: &str) -> (String, String) {
    use std::fmt::Write;
    let mut obj = format!(
        "# {} — written by scene-sampler; Ke is emitted radiance (E = pi*Ke)\nmtllib {mtl_name}\n",
        scene.name
    );
    let mut mtl = String::from("# Kd = reflectance, Ke = emitted radiance (E = pi*Ke)\n");
    let mut mats: Vec<(Spectrum, Spectrum)> = Vec::new();
    let mut vcount = 0usize;
    let mut cur_obj = u32::MAX;
    let mut cur_mat = usize::MAX;
    for f in &scene.faces {
        if f.object != cur_obj {
            cur_obj = f.object;
            let name = scene.objects[f.object as usize].replace(char::is_whitespace, "_");
            let _ = writeln!(obj, "o {name}");
            cur_mat = usize::MAX;
        }
        let m = match mats
            .iter()
            .position(|&(r, e)| r == f.rho && e == f.emission)
        {
            Some(m) => m,
            None => {
                mats.push((f.rho, f.emission));
                let k = mats.len() - 1;
                let ke = f.emission / PI;
                let _ = writeln!(
                    mtl,
                    "newmtl m{k}\nKd {} {} {}\nKe {} {} {}\n",
                    f.rho.0[0], f.rho.0[1], f.rho.0[2], ke.0[0], ke.0[1], ke.0[2]
                );
                k
            }
        };
        if m != cur_mat {
            cur_mat = m;
            let _ = writeln!(obj, "usemtl m{m}");
        }
        for v in f.v {
            let _ = writeln!(obj, "v {} {} {}", v.x, v.y, v.z);
        }
        let _ = writeln!(obj, "f {} {} {}", vcount + 1, vcount + 2, vcount + 3);
        vcount += 3;
    }
    (obj, mtl)
}

/// Writes `scene` to `dir/<name>.obj` and `dir/<name>.mtl`; returns the OBJ path.
pub fn write_obj(scene: &Scene, dir: impl AsRef<Path>) -> Result<std::path::PathBuf> {
    let dir = dir.as_ref();
    let mtl_name = format!("{}.mtl", scene.name);
    let (obj, mtl) = to_obj(scene, &mtl_name);
    let p = dir.join(format!("{}.obj", scene.name));
    std::fs::write(&p, obj).map_err(io(&p))?;
    let m = dir.join(&mtl_name);
    std::fs::write(&m, mtl).map_err(io(&m))?;
    Ok(p)
}

/// Writes a Flatland scene to `dir/<name>.json`; returns the path.
pub fn write_flatland(scene: &FlatlandScene, dir: impl AsRef<Path>) -> Result<std::path::PathBuf> {
    let p = dir.as_ref().join(format!("{}.json", scene.name));
    std::fs::write(&p, scene.to_json()).map_err(io(&p))?;
    Ok(p)
}

fn base64(bytes: &[u8]) -> String {
    const T: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::with_capacity(bytes.len().div_ceil(3) * 4);
    for c in bytes.chunks(3) {
        let n = (u32::from(c[0]) << 16)
            | (u32::from(*c.get(1).unwrap_or(&0)) << 8)
            | u32::from(*c.get(2).unwrap_or(&0));
        for k in 0..4 {
            if k <= c.len() {
                out.push(T[(n >> (18 - 6 * k) & 63) as usize] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}

/// Writes a scene as a self-contained glTF 2.0 JSON document (buffer embedded as a base64 data URI).
///
/// One node per object, one triangle primitive per distinct material, non-indexed f32 positions.
/// `baseColorFactor = (ρ, 1)`; emitted radiance `Ke = E/π` is stored as `emissiveFactor = Ke / max(Ke)` times
/// `KHR_materials_emissive_strength = max(Ke)` (glTF requires factors ≤ 1).
pub fn to_gltf(scene: &Scene) -> String {
    use serde_json::json;
    let mut mats: Vec<(Spectrum, Spectrum)> = Vec::new();
    let mut bytes: Vec<u8> = Vec::new();
    let (mut views, mut accessors, mut meshes, mut nodes) = (vec![], vec![], vec![], vec![]);
    for (oi, oname) in scene.objects.iter().enumerate() {
        let faces: Vec<&Face> = scene
            .faces
            .iter()
            .filter(|f| f.object as usize == oi)
            .collect();
        if faces.is_empty() {
            continue;
        }
        let mut prims = vec![];
        let mut keys: Vec<(Spectrum, Spectrum)> = Vec::new();
        for f in &faces {
            if !keys.contains(&(f.rho, f.emission)) {
                keys.push((f.rho, f.emission));
            }
        }
        for key in keys {
            let m = match mats.iter().position(|&k| k == key) {
                Some(m) => m,
                None => {
                    mats.push(key);
                    mats.len() - 1
                }
            };
            let offset = bytes.len();
            let mut lo = [f32::INFINITY; 3];
            let mut hi = [f32::NEG_INFINITY; 3];
            let mut count = 0;
            for f in faces.iter().filter(|f| (f.rho, f.emission) == key) {
                for v in f.v {
                    let p = [v.x as f32, v.y as f32, v.z as f32];
                    for k in 0..3 {
                        lo[k] = lo[k].min(p[k]);
                        hi[k] = hi[k].max(p[k]);
                        bytes.extend_from_slice(&p[k].to_le_bytes());
                    }
                    count += 1;
                }
            }
            views.push(
                json!({"buffer": 0, "byteOffset": offset, "byteLength": bytes.len() - offset}),
            );
            accessors.push(
                json!({"bufferView": views.len() - 1, "componentType": 5126, "count": count,
                                  "type": "VEC3", "min": lo, "max": hi}),
            );
            prims.push(
                json!({"attributes": {"POSITION": accessors.len() - 1}, "material": m, "mode": 4}),
            );
        }
        meshes.push(json!({"name": oname, "primitives": prims}));
        nodes.push(json!({"name": oname, "mesh": meshes.len() - 1}));
    }
    let materials: Vec<serde_json::Value> = mats
        .iter()
        .map(|(rho, e)| {
            let ke = *e / PI;
            let s = ke.max();
            let factor = if s > 0.0 { (ke / s).0 } else { [0.0; 3] };
            let mut m = json!({
                "pbrMetallicRoughness": {"baseColorFactor": [rho.0[0], rho.0[1], rho.0[2], 1.0],
                                         "metallicFactor": 0.0, "roughnessFactor": 1.0},
                "emissiveFactor": factor,
            });
            if s > 0.0 {
                m["extensions"] =
                    json!({"KHR_materials_emissive_strength": {"emissiveStrength": s}});
            }
            m
        })
        .collect();
    let doc = json!({
        "asset": {"version": "2.0", "generator": "scene-sampler"},
        "extensionsUsed": ["KHR_materials_emissive_strength"],
        "scene": 0,
        "scenes": [{"name": scene.name, "nodes": (0..nodes.len()).collect::<Vec<_>>()}],
        "nodes": nodes, "meshes": meshes, "materials": materials,
        "accessors": accessors, "bufferViews": views,
        "buffers": [{"byteLength": bytes.len(),
                     "uri": format!("data:application/octet-stream;base64,{}", base64(&bytes))}],
    });
    serde_json::to_string_pretty(&doc).unwrap_or_default()
}

/// Writes `scene` to `dir/<name>.gltf` (self-contained); returns the path.
pub fn write_gltf(scene: &Scene, dir: impl AsRef<Path>) -> Result<std::path::PathBuf> {
    let p = dir.as_ref().join(format!("{}.gltf", scene.name));
    std::fs::write(&p, to_gltf(scene)).map_err(io(&p))?;
    Ok(p)
}

#[cfg(test)]
mod tests {
    #[test]
    fn base64_known_vectors() {
        assert_eq!(super::base64(b""), "");
        assert_eq!(super::base64(b"f"), "Zg==");
        assert_eq!(super::base64(b"fo"), "Zm8=");
        assert_eq!(super::base64(b"foo"), "Zm9v");
        assert_eq!(super::base64(b"foobar"), "Zm9vYmFy");
    }
}
