//! Scene writers: OBJ + MTL, self-contained glTF 2.0, Flatland JSON.

use crate::{Face, FlatlandScene, Result, Scene, SceneError, Spectrum};
use std::f64::consts::PI;
use std::path::Path;

/// The error of an I/O operation on `path`, naming it.
fn io(path: &Path) -> impl FnOnce(std::io::Error) -> SceneError + '_ {
    move |source| SceneError::Io {
        path: path.into(),
        source,
    }
}

/// Writes a scene as OBJ text plus MTL text (one material per distinct (ρ, E) pair, `Ke = E/π`), with
/// `mtllib <mtl_name>`. Numbers are written with full f64 precision and
/// [`load_obj`](crate::load_obj) reads them in f64, so a round trip reproduces the faces exactly.
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
