//! Binary glTF 2.0 (.glb) writer for a [`ShadedMesh`] with vertex colours.
//!
//! One mesh, one primitive: `POSITION` (f32 VEC3), `COLOR_0` (f32 VEC3, display-linear: tone
//! mapped but not sRGB-encoded, since glTF colours are linear) and u32 indices. The raw radiosity
//! values are in the PLY output and the probe files. The material is `KHR_materials_unlit`, so viewers show the
//! vertex colours as they are instead of lighting them again.

use crate::mesh::ShadedMesh;
use crate::output::tonemap::Exposure;
use std::io::Write;

/// Encodes `mesh` as a .glb byte vector.
pub fn to_glb(mesh: &ShadedMesh, exposure: &Exposure) -> Vec<u8> {
    let n = mesh.positions.len();
    let mut bin: Vec<u8> = Vec::with_capacity(n * 36 + mesh.triangles.len() * 12);
    let (mut lo, mut hi) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
    for p in &mesh.positions {
        let p = p.as_vec3().to_array();
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
            bin.extend_from_slice(&p[k].to_le_bytes());
        }
    }
    let colours_at = bin.len();
    for b in &mesh.radiosity {
        for c in exposure.linear(*b) {
            bin.extend_from_slice(&(c as f32).to_le_bytes());
        }
    }
    let indices_at = bin.len();
    for t in &mesh.triangles {
        for i in t {
            bin.extend_from_slice(&i.to_le_bytes());
        }
    }
    let indices_len = bin.len() - indices_at;
    while bin.len() % 4 != 0 {
        bin.push(0);
    }
    if n == 0 {
        lo = [0.0; 3];
        hi = [0.0; 3];
    }
    let vec3 = n * 12;
    let json = format!(
        concat!(
            r#"{{"asset":{{"version":"2.0","generator":"gcr (Growing Cells Radiosity)"}},"#,
            r#""extensionsUsed":["KHR_materials_unlit"],"scene":0,"scenes":[{{"nodes":[0]}}],"#,
            r#""nodes":[{{"mesh":0,"name":"radiosity"}}],"#,
            r#""materials":[{{"pbrMetallicRoughness":{{"baseColorFactor":[1,1,1,1],"metallicFactor":0,"roughnessFactor":1}},"#,
            r#""extensions":{{"KHR_materials_unlit":{{}}}},"doubleSided":false}}],"#,
            r#""meshes":[{{"primitives":[{{"attributes":{{"POSITION":0,"COLOR_0":1}},"indices":2,"material":0,"mode":4}}]}}],"#,
            r#""buffers":[{{"byteLength":{total}}}],"#,
            r#""bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":{vec3},"target":34962}},"#,
            r#"{{"buffer":0,"byteOffset":{c_at},"byteLength":{vec3},"target":34962}},"#,
            r#"{{"buffer":0,"byteOffset":{i_at},"byteLength":{i_len},"target":34963}}],"#,
            r#""accessors":[{{"bufferView":0,"componentType":5126,"count":{n},"type":"VEC3","min":[{lo0},{lo1},{lo2}],"max":[{hi0},{hi1},{hi2}]}},"#,
            r#"{{"bufferView":1,"componentType":5126,"count":{n},"type":"VEC3"}},"#,
            r#"{{"bufferView":2,"componentType":5125,"count":{ni},"type":"SCALAR"}}]}}"#
        ),
        total = bin.len(),
        vec3 = vec3,
        c_at = colours_at,
        i_at = indices_at,
        i_len = indices_len,
        n = n,
        ni = mesh.triangles.len() * 3,
        lo0 = lo[0],
        lo1 = lo[1],
        lo2 = lo[2],
        hi0 = hi[0],
        hi1 = hi[1],
        hi2 = hi[2],
    );
    let mut json = json.into_bytes();
    while json.len() % 4 != 0 {
        json.push(b' ');
    }
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&json);
    out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    out.extend_from_slice(b"BIN\0");
    out.extend_from_slice(&bin);
    out
}

/// Writes `mesh` as .glb to `w`.
pub fn write_glb(mesh: &ShadedMesh, exposure: &Exposure, mut w: impl Write) -> std::io::Result<()> {
    w.write_all(&to_glb(mesh, exposure))
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    #[test]
    fn the_gltf_crate_reads_back_positions_colours_and_indices() {
        let mesh = ShadedMesh {
            positions: vec![DVec3::ZERO, DVec3::X, DVec3::new(0.0, 2.0, 0.5)],
            triangles: vec![[0, 1, 2]],
            face_of_triangle: vec![0],
            radiosity: vec![[0.0; 3], [1.0, 2.0, 3.0], [3.0; 3]],
        };
        let bytes = to_glb(&mesh, &Exposure { scale: 1.0 });
        let (doc, buffers, _) = gltf::import_slice(&bytes).expect("valid glb");
        let prim = doc.meshes().next().unwrap().primitives().next().unwrap();
        let reader = prim.reader(|b| Some(&buffers[b.index()]));
        let pos: Vec<[f32; 3]> = reader.read_positions().unwrap().collect();
        assert_eq!(pos[2], [0.0, 2.0, 0.5]);
        let col: Vec<[f32; 3]> = reader.read_colors(0).unwrap().into_rgb_f32().collect();
        assert!((col[1][1] as f64 - 2.0 / std::f64::consts::PI).abs() < 1e-6);
        let idx: Vec<u32> = reader.read_indices().unwrap().into_u32().collect();
        assert_eq!(idx, vec![0, 1, 2]);
    }
}
