//! Binary glTF 2.0 (.glb) writer for the bake: a [`ShadedMesh`] in the shape of its input scene.
//!
//! The output mesh's triangles are grouped by the input part they were cut from
//! ([`scene_sampler::Face::part`]), so the file overlays the original asset:
//!
//! * **From glTF** ([`Scene::gltf`]): every node of the input document, in the same order, with
//!   the same name, local transform (matrix or TRS, as given) and children; the same scene roots.
//!   Each node of the loaded scene that has a mesh gets a mesh of its own (a mesh used by two
//!   nodes is lit differently at each, so the output has one per instance), named after the input
//!   mesh (`<mesh>`, or `<mesh>@<node>` when the input mesh is used by more than one node), with
//!   one primitive per input triangle primitive that kept triangles (extras `input_primitive`
//!   give its index in the input mesh). Positions and normals are in the node's **local** frame:
//!   the world positions mapped back by the inverse of the node's world transform (in f64), the
//!   normal by the transpose of its linear part, and under a mirroring transform (determinant < 0)
//!   the winding is reversed back, as glTF viewers reverse it again. Materials keep the input's
//!   order and names (an extra `default` one stands for glTF's default material). Names the
//!   input does not give are not given. Cameras,
//!   textures, skins and animations are not written.
//! * **Otherwise** (OBJ, built-ins): one root node per object, named after it, identity
//!   transform, one mesh per object; one material.
//!
//! Attributes per primitive: `POSITION` (f32 VEC3, with min/max), `NORMAL` (f32 VEC3, unit, the
//! face's geometric normal), `COLOR_0` (f32 VEC3, display-linear: `clamp(B/π · exposure)`, not
//! sRGB-encoded since glTF colours are linear), `_RADIOSITY` (f32 VEC3, linear radiosity B, the
//! exitance in scene units, emission included) and u32 indices. Materials are
//! `KHR_materials_unlit` with a white base colour, so viewers show the vertex colours as they are
//! instead of lighting them again. `asset.extras` records the exposure scale.

use super::gltf_bin::Bin;
use crate::mesh::ShadedMesh;
use crate::output::tonemap::Exposure;
use glam::{DMat4, DVec3};
use scene_sampler::{GltfSource, NodeTransform, Scene};
use serde_json::{Value, json};
use std::collections::HashMap;
use std::io::Write;

/// The accessors of one written primitive.
struct Primitive {
    /// Input primitive index (glTF), or the part's index within its object.
    input: u32,
    /// Output material.
    material: usize,
    attributes: Value,
    indices: usize,
}

impl Bin {
    /// Writes the triangles `tris` of `mesh` as one primitive in the frame whose world transform
    /// is `world`; `None` when there are none.
    fn primitive(
        &mut self,
        mesh: &ShadedMesh,
        scene: &Scene,
        tris: &[usize],
        world: DMat4,
        exposure: &Exposure,
    ) -> Option<(Value, usize)> {
        if tris.is_empty() {
            return None;
        }
        let to_local = world.inverse();
        let normal_to_local = world.transpose();
        let mirrored = world.determinant() < 0.0;
        let mut local_index: HashMap<u32, u32> = HashMap::new();
        let (mut pos, mut nrm, mut col, mut rad) = (vec![], vec![], vec![], vec![]);
        let mut out_tris = Vec::with_capacity(tris.len());
        let f32x3 = |v: DVec3| [v.x as f32, v.y as f32, v.z as f32];
        for &t in tris {
            let face = &scene.faces[mesh.face_of_triangle[t] as usize];
            let n = normal_to_local
                .transform_vector3(face.normal)
                .normalize_or_zero();
            let ids = mesh.triangles[t].map(|v| {
                *local_index.entry(v).or_insert_with(|| {
                    let b = mesh.radiosity[v as usize];
                    pos.push(f32x3(to_local.transform_point3(mesh.positions[v as usize])));
                    nrm.push(f32x3(n));
                    col.push(exposure.linear(b).map(|c| c as f32));
                    rad.push(b.map(|c| c as f32));
                    (pos.len() - 1) as u32
                })
            });
            out_tris.push(if mirrored {
                [ids[0], ids[2], ids[1]]
            } else {
                ids
            });
        }
        let attributes = json!({
            "POSITION": self.floats(&pos, "VEC3", true),
            "NORMAL": self.floats(&nrm, "VEC3", false),
            "COLOR_0": self.floats(&col, "VEC3", false),
            "_RADIOSITY": self.floats(&rad, "VEC3", false),
        });
        Some((attributes, self.indices(&out_tris)))
    }
}

/// An unlit material (white base colour: the vertex colours are what is shown).
fn unlit(name: Option<&str>) -> Value {
    let mut m = json!({"pbrMetallicRoughness": {"baseColorFactor": [1.0, 1.0, 1.0, 1.0],
            "metallicFactor": 0.0, "roughnessFactor": 1.0},
        "extensions": {"KHR_materials_unlit": {}}});
    if let Some(name) = name {
        m["name"] = json!(name);
    }
    m
}

/// A glTF mesh from written primitives; `None` when there are none (glTF meshes need one).
fn mesh_json(name: Option<&str>, input_mesh: Option<u32>, prims: Vec<Primitive>) -> Option<Value> {
    if prims.is_empty() {
        return None;
    }
    let primitives: Vec<Value> = prims
        .into_iter()
        .map(|p| {
            json!({"attributes": p.attributes, "indices": p.indices, "material": p.material,
                "mode": 4, "extras": {"input_primitive": p.input}})
        })
        .collect();
    let mut m = json!({"primitives": primitives});
    if let Some(name) = name {
        m["name"] = json!(name);
    }
    if let Some(i) = input_mesh {
        m["extras"] = json!({"input_mesh": i});
    }
    Some(m)
}

/// The node's local transform as JSON members (nothing for the identity).
fn transform_json(node: &mut Value, t: &NodeTransform) {
    if t.is_identity() {
        return;
    }
    match t {
        NodeTransform::Matrix(m) => {
            let flat: Vec<f32> = m.iter().flatten().copied().collect();
            node["matrix"] = json!(flat);
        }
        NodeTransform::Trs {
            translation,
            rotation,
            scale,
        } => {
            if *translation != [0.0; 3] {
                node["translation"] = json!(translation);
            }
            if *rotation != [0.0, 0.0, 0.0, 1.0] {
                node["rotation"] = json!(rotation);
            }
            if *scale != [1.0; 3] {
                node["scale"] = json!(scale);
            }
        }
    }
}

/// The output's node tree, meshes and materials, and its scene's roots and name.
struct Tree {
    nodes: Vec<Value>,
    meshes: Vec<Value>,
    materials: Vec<Value>,
    roots: Vec<u32>,
    scene_name: String,
}

/// Encodes the bake of `scene` (`mesh` is its output mesh) as a .glb byte vector (module docs).
pub fn to_glb(mesh: &ShadedMesh, scene: &Scene, exposure: &Exposure) -> Vec<u8> {
    // ⟨Triangles by input part⟩
    let mut by_part: Vec<Vec<usize>> = vec![Vec::new(); scene.parts.len()];
    for (t, &f) in mesh.face_of_triangle.iter().enumerate() {
        let part = scene.faces[f as usize].part as usize;
        if part >= by_part.len() {
            by_part.resize(part + 1, Vec::new());
        }
        by_part[part].push(t);
    }
    let mut bin = Bin::default();
    let Tree {
        nodes,
        meshes,
        materials,
        roots,
        scene_name,
    } = match scene.gltf.as_deref() {
        // ⟨The input's node tree; a mesh per node instance, a primitive per input primitive⟩
        Some(src) => gltf_tree(mesh, scene, src, &by_part, exposure, &mut bin),
        // ⟨One node per object, identity transform⟩
        None => object_tree(mesh, scene, &by_part, exposure, &mut bin),
    };
    let mut doc = json!({
        "asset": {"version": "2.0", "generator": "gcr (Growing Cells Radiosity)",
            "extras": {"exposure_scale": exposure.scale,
                "radiosity": "_RADIOSITY: linear radiosity B per vertex (RGB); COLOR_0 = clamp(B / pi * exposure_scale)"}},
        "extensionsUsed": ["KHR_materials_unlit"],
        "scene": 0,
        "scenes": [{"name": scene_name, "nodes": roots}],
        "nodes": nodes,
        "materials": materials,
    });
    if !meshes.is_empty() {
        doc["meshes"] = json!(meshes);
    }
    bin.into_glb(doc)
}

/// [`to_glb`]'s tree for a scene loaded from glTF.
fn gltf_tree(
    mesh: &ShadedMesh,
    scene: &Scene,
    src: &GltfSource,
    by_part: &[Vec<usize>],
    exposure: &Exposure,
    bin: &mut Bin,
) -> Tree {
    let part_of: HashMap<(u32, u32), usize> = scene
        .parts
        .iter()
        .enumerate()
        .filter_map(|(k, p)| Some(((p.node?, p.primitive), k)))
        .collect();
    let mut materials = src
        .materials
        .iter()
        .map(|m| unlit(m.name.as_deref()))
        .collect::<Vec<_>>();
    let default_material = materials.len();
    let mut uses_default = false;
    let mut meshes = Vec::new();
    let mut nodes = Vec::new();
    for (i, node) in src.nodes.iter().enumerate() {
        let mut out = json!({});
        if let Some(name) = &node.name {
            out["name"] = json!(name);
        }
        transform_json(&mut out, &node.transform);
        if !node.children.is_empty() {
            out["children"] = json!(node.children);
        }
        if let (Some(m), Some(world)) = (node.mesh, node.world) {
            let input = &src.meshes[m as usize];
            let mut prims = Vec::new();
            for (k, material) in input.primitives.iter().enumerate() {
                let Some(&part) = part_of.get(&(i as u32, k as u32)) else {
                    continue;
                };
                let Some((attributes, indices)) =
                    bin.primitive(mesh, scene, &by_part[part], world, exposure)
                else {
                    continue;
                };
                let material = match material {
                    Some(j) => *j as usize,
                    None => {
                        uses_default = true;
                        default_material
                    }
                };
                prims.push(Primitive {
                    input: k as u32,
                    material,
                    attributes,
                    indices,
                });
            }
            let name = if src.instances(m) > 1 {
                Some(format!(
                    "{}@{}",
                    input.name.clone().unwrap_or_else(|| format!("mesh{m}")),
                    node.name.clone().unwrap_or_else(|| format!("node{i}"))
                ))
            } else {
                input.name.clone()
            };
            if let Some(json) = mesh_json(name.as_deref(), Some(m), prims) {
                meshes.push(json);
                out["mesh"] = json!(meshes.len() - 1);
            }
        }
        nodes.push(out);
    }
    if uses_default {
        materials.push(unlit(Some("default")));
    }
    let roots = src.roots.clone();
    let scene_name = src.scene_name.clone().unwrap_or_else(|| scene.name.clone());
    Tree {
        nodes,
        meshes,
        materials,
        roots,
        scene_name,
    }
}

/// [`to_glb`]'s tree for a scene without a node tree (OBJ, built-ins).
fn object_tree(
    mesh: &ShadedMesh,
    scene: &Scene,
    by_part: &[Vec<usize>],
    exposure: &Exposure,
    bin: &mut Bin,
) -> Tree {
    let materials = vec![unlit(Some("radiosity"))];
    let mut meshes = Vec::new();
    let mut nodes = Vec::new();
    for (o, name) in scene.objects.iter().enumerate() {
        let mut prims = Vec::new();
        for (k, _) in scene
            .parts
            .iter()
            .enumerate()
            .filter(|(_, p)| p.object as usize == o)
        {
            let Some((attributes, indices)) =
                bin.primitive(mesh, scene, &by_part[k], DMat4::IDENTITY, exposure)
            else {
                continue;
            };
            prims.push(Primitive {
                input: prims.len() as u32,
                material: 0,
                attributes,
                indices,
            });
        }
        let mut out = json!({"name": name});
        if let Some(json) = mesh_json(Some(name), None, prims) {
            meshes.push(json);
            out["mesh"] = json!(meshes.len() - 1);
        }
        nodes.push(out);
    }
    let roots = (0..nodes.len() as u32).collect();
    let scene_name = scene.name.clone();
    Tree {
        nodes,
        meshes,
        materials,
        roots,
        scene_name,
    }
}

/// Writes the bake of `scene` (`mesh` is its output mesh) as .glb to `w` ([`to_glb`]).
pub fn write_glb(
    mesh: &ShadedMesh,
    scene: &Scene,
    exposure: &Exposure,
    mut w: impl Write,
) -> std::io::Result<()> {
    w.write_all(&to_glb(mesh, scene, exposure))
}

#[cfg(test)]
mod tests {
    use super::*;
    use scene_sampler::{Face, Spectrum};

    /// One object with one triangle, lit: the gltf crate reads back positions, normals, colours,
    /// radiosity and indices, and the node is named after the object.
    #[test]
    fn the_gltf_crate_reads_back_positions_normals_colours_radiosity_and_indices() {
        let v = [DVec3::ZERO, DVec3::X, DVec3::new(0.0, 2.0, 0.5)];
        let face = Face::new(v, Spectrum::grey(0.5), Spectrum::grey(1.0), 0, 0);
        let scene = Scene::new("t", "test", vec![face], vec!["thing".into()], None).unwrap();
        let mesh = ShadedMesh {
            positions: v.to_vec(),
            triangles: vec![[0, 1, 2]],
            face_of_triangle: vec![0],
            radiosity: vec![[0.0; 3], [1.0, 2.0, 3.0], [3.0; 3]],
        };
        let bytes = to_glb(&mesh, &scene, &Exposure { scale: 1.0 });
        let (doc, buffers, _) = gltf::import_slice(&bytes).expect("valid glb");
        let node = doc.nodes().next().unwrap();
        assert_eq!(node.name(), Some("thing"));
        let prim = node.mesh().unwrap().primitives().next().unwrap();
        let reader = prim.reader(|b| Some(&buffers[b.index()]));
        let pos: Vec<[f32; 3]> = reader.read_positions().unwrap().collect();
        assert_eq!(pos[2], [0.0, 2.0, 0.5]);
        let n: Vec<[f32; 3]> = reader.read_normals().unwrap().collect();
        let expect = face.normal;
        assert!(
            (DVec3::new(n[0][0] as f64, n[0][1] as f64, n[0][2] as f64) - expect).length() < 1e-6
        );
        let col: Vec<[f32; 3]> = reader.read_colors(0).unwrap().into_rgb_f32().collect();
        assert!((col[1][1] as f64 - 2.0 / std::f64::consts::PI).abs() < 1e-6);
        let idx: Vec<u32> = reader.read_indices().unwrap().into_u32().collect();
        assert_eq!(idx, vec![0, 1, 2]);
        let rad = prim
            .attributes()
            .find(|(s, _)| matches!(s, gltf::Semantic::Extras(n) if n == "RADIOSITY"))
            .expect("_RADIOSITY");
        assert_eq!(rad.1.count(), 3);
    }
}
