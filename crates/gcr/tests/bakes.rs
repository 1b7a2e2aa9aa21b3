//! The bake (`gcr solve --mesh out.glb`, [`gcr::output::glb`]) in the shape of its input: a glTF
//! scene with a node hierarchy (a TRS node with rotation, non-uniform scale and translation, a
//! mirroring one, a matrix node, a mesh used by two nodes, a mesh with two materials, a root
//! without a mesh) is solved and baked, and the bake is read back with the `gltf` crate and
//! checked against the input document read the same way: node names, hierarchy, roots and local
//! transforms; mesh, primitive and material names; every vertex on its input primitive's
//! surface; normals; `_RADIOSITY` = the gathered B and `COLOR_0` its tone map. The Khronos
//! validator runs on the bakes when it is installed (skipped with a note otherwise).

use gcr::output::Exposure;
use gcr::output::to_glb;
use gcr::{
    Domain, Emitters, GatherMode, RetriangulateLimits, SolveConfig, output_mesh,
    radiosity_at_points,
};
use glam::{DMat4, DVec3, Quat, Vec3};
use scene_sampler::{KernelSampler, Scene, SceneBvh};
use serde_json::json;
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// A fresh directory for this test's files.
fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("gcr-bakes-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// The binary buffer of a hand-made glTF, with one bufferView per accessor.
#[derive(Default)]
struct Buffer {
    bin: Vec<u8>,
    views: Vec<serde_json::Value>,
    accessors: Vec<serde_json::Value>,
}

impl Buffer {
    fn positions(&mut self, p: &[[f32; 3]]) -> usize {
        let at = self.bin.len();
        let (mut lo, mut hi) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
        for v in p {
            for k in 0..3 {
                lo[k] = lo[k].min(v[k]);
                hi[k] = hi[k].max(v[k]);
                self.bin.extend_from_slice(&v[k].to_le_bytes());
            }
        }
        self.views.push(json!({"buffer": 0, "byteOffset": at,
            "byteLength": self.bin.len() - at, "target": 34962}));
        self.accessors.push(
            json!({"bufferView": self.views.len() - 1, "componentType": 5126,
            "count": p.len(), "type": "VEC3", "min": lo, "max": hi}),
        );
        self.accessors.len() - 1
    }

    fn indices(&mut self, idx: &[u32]) -> usize {
        let at = self.bin.len();
        for i in idx {
            self.bin.extend_from_slice(&i.to_le_bytes());
        }
        self.views.push(json!({"buffer": 0, "byteOffset": at,
            "byteLength": self.bin.len() - at, "target": 34963}));
        self.accessors.push(
            json!({"bufferView": self.views.len() - 1, "componentType": 5125,
            "count": idx.len(), "type": "SCALAR"}),
        );
        self.accessors.len() - 1
    }
}

/// Writes the hierarchy scene as `dir/hierarchy.gltf` + `hierarchy.bin`; returns the path.
fn write_hierarchy_scene(dir: &Path) -> PathBuf {
    let mut buf = Buffer::default();
    // floor: 2 × 2 at y = 0 facing +y; lamp: 0.5 × 0.5 facing −y
    let floor = [
        [-1.0, 0.0, -1.0],
        [1.0, 0.0, -1.0],
        [1.0, 0.0, 1.0],
        [-1.0, 0.0, 1.0],
    ];
    let lamp = floor.map(|p| p.map(|c| c * 0.25));
    // unit cube, outward windings; the top face (+y) is its own primitive
    let mut cube = Vec::new();
    let (mut top, mut sides) = (Vec::new(), Vec::new());
    for a in 0..3 {
        for s in [1.0f32, -1.0] {
            let e = |k: usize| {
                let mut v = [0.0f32; 3];
                v[k % 3] = 1.0;
                Vec3::from(v)
            };
            let (mut u, mut v) = (e(a + 1), e(a + 2));
            if s < 0.0 {
                std::mem::swap(&mut u, &mut v);
            }
            let c = e(a) * 0.5 * s;
            let base = cube.len() as u32;
            for (x, y) in [(-0.5, -0.5), (0.5, -0.5), (0.5, 0.5), (-0.5, 0.5)] {
                cube.push((c + u * x + v * y).to_array());
            }
            let idx = [base, base + 1, base + 2, base, base + 2, base + 3];
            if a == 1 && s > 0.0 {
                &mut top
            } else {
                &mut sides
            }
            .extend(idx);
        }
    }
    let floor_pos = buf.positions(&floor);
    let floor_idx = buf.indices(&[0, 3, 2, 0, 2, 1]);
    let lamp_pos = buf.positions(&lamp);
    let lamp_idx = buf.indices(&[0, 2, 3, 0, 1, 2]);
    let cube_pos = buf.positions(&cube);
    let top_idx = buf.indices(&top);
    let sides_idx = buf.indices(&sides);
    let q =
        |axis: Vec3, deg: f32| Quat::from_axis_angle(axis.normalize(), deg.to_radians()).to_array();
    let doc = json!({
        "asset": {"version": "2.0"},
        "extensionsUsed": ["KHR_materials_emissive_strength"],
        "scene": 0,
        "scenes": [{"name": "hierarchy", "nodes": [0, 6]}],
        "nodes": [
            {"name": "room", "translation": [0.0, -0.1, 0.0], "children": [1, 2, 3]},
            {"name": "floor", "mesh": 0},
            {"name": "lamp", "mesh": 1, "translation": [0.0, 1.5, 0.0]},
            {"name": "group", "children": [4, 5],
             "matrix": [0.8, 0.0, 0.0, 0.0, 0.0, 0.8, 0.0, 0.0, 0.0, 0.0, 0.8, 0.0, 0.1, 0.3, 0.0, 1.0]},
            {"name": "box A", "mesh": 2, "translation": [-0.4, 0.1, 0.1],
             "rotation": q(Vec3::new(1.0, 2.0, 0.5), 40.0), "scale": [0.3, 0.5, 0.4]},
            {"name": "box B", "mesh": 2, "translation": [0.45, 0.1, -0.2],
             "rotation": q(Vec3::Y, 20.0), "scale": [-0.3, 0.35, 0.3]},
            {"name": "spare", "translation": [5.0, 0.0, 0.0]}
        ],
        "meshes": [
            {"name": "floor", "primitives": [{"attributes": {"POSITION": floor_pos}, "indices": floor_idx, "material": 0}]},
            {"name": "lamp", "primitives": [{"attributes": {"POSITION": lamp_pos}, "indices": lamp_idx, "material": 2}]},
            {"name": "box", "primitives": [
                {"attributes": {"POSITION": cube_pos}, "indices": top_idx, "material": 1},
                {"attributes": {"POSITION": cube_pos}, "indices": sides_idx, "material": 0}]}
        ],
        "materials": [
            {"name": "white", "pbrMetallicRoughness": {"baseColorFactor": [0.7, 0.7, 0.7, 1.0]}},
            {"name": "red", "pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.2, 0.2, 1.0]}},
            {"name": "lamp", "pbrMetallicRoughness": {"baseColorFactor": [0.0, 0.0, 0.0, 1.0]},
             "emissiveFactor": [1.0, 1.0, 1.0],
             "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 2.0}}}
        ],
        "buffers": [{"uri": "hierarchy.bin", "byteLength": buf.bin.len()}],
        "bufferViews": buf.views,
        "accessors": buf.accessors,
    });
    std::fs::write(dir.join("hierarchy.bin"), &buf.bin).unwrap();
    let path = dir.join("hierarchy.gltf");
    std::fs::write(&path, serde_json::to_string_pretty(&doc).unwrap()).unwrap();
    path
}

/// An output mesh vertex (world) and its B.
type Vertex = (DVec3, [f64; 3]);

/// Solves `scene` (small networks, the rays gather: B at a point depends only on the point) and
/// bakes it; returns the .glb bytes, the output mesh's vertices with B, and the exposure.
fn bake(scene: &Scene) -> (Vec<u8>, Vec<Vertex>, Exposure) {
    let bvh = SceneBvh::new(scene);
    let domain = Domain::ThreeD(KernelSampler::new(scene, &bvh));
    let config = SolveConfig {
        kernel_cells: 60,
        shading_cells: 30,
        gather: GatherMode::Rays,
        ..SolveConfig::default()
    };
    let trained = gcr::solve(&domain, &config, &mut |_| {}).unwrap();
    let (mesh, _) =
        output_mesh(&domain, &trained, &config, RetriangulateLimits::default()).unwrap();
    assert!(
        mesh.triangle_count() > scene.faces.len(),
        "not re-triangulated"
    );
    // the vertices' B is the gather at those points (just inside their faces)
    let points: Vec<(DVec3, DVec3, u32)> = (0..mesh.vertex_count())
        .map(|v| {
            let t = mesh
                .triangles
                .iter()
                .position(|t| t.contains(&(v as u32)))
                .unwrap();
            let f = mesh.face_of_triangle[t];
            let at = gcr::vertex_gather_point(scene, &bvh, f, mesh.positions[v]);
            (at, scene.faces[f as usize].normal, f)
        })
        .collect();
    let again =
        radiosity_at_points(&domain, &trained, &Emitters::new(&domain), &config, &points).unwrap();
    // a vertex that coplanar faces of one material share is gathered once, on one of its faces
    let colour = |g: &gcr::Gathered| {
        if scene.bands == 1 {
            [g.radiosity[0]; 3]
        } else {
            g.radiosity
        }
    };
    let mut at: std::collections::HashMap<[u64; 3], Vec<usize>> = Default::default();
    for (v, p) in mesh.positions.iter().enumerate() {
        at.entry(p.to_array().map(f64::to_bits))
            .or_default()
            .push(v);
    }
    for (v, b) in mesh.radiosity.iter().enumerate() {
        let same_place = &at[&mesh.positions[v].to_array().map(f64::to_bits)];
        assert!(
            same_place.iter().any(|&u| colour(&again[u]) == *b),
            "output_mesh's B is not a gather at its vertex {v}"
        );
    }
    let exposure = Exposure::auto(mesh.radiosity.iter().copied());
    let bytes = to_glb(&mesh, scene, &exposure);
    let verts = mesh
        .positions
        .iter()
        .copied()
        .zip(mesh.radiosity.iter().copied())
        .collect();
    (bytes, verts, exposure)
}

fn to_d(m: [[f32; 4]; 4]) -> DMat4 {
    DMat4::from_cols_array_2d(&m.map(|c| c.map(f64::from)))
}

/// World transform of every node reachable from the default scene's roots.
fn world_transforms(doc: &gltf::Document) -> HashMap<usize, DMat4> {
    let mut out = HashMap::new();
    let mut stack: Vec<(gltf::Node, DMat4)> = doc
        .default_scene()
        .unwrap()
        .nodes()
        .map(|n| (n, DMat4::IDENTITY))
        .collect();
    while let Some((n, parent)) = stack.pop() {
        let w = parent * to_d(n.transform().matrix());
        out.insert(n.index(), w);
        stack.extend(n.children().map(|c| (c, w)));
    }
    out
}

fn dvec(p: [f32; 3]) -> DVec3 {
    DVec3::new(p[0].into(), p[1].into(), p[2].into())
}

/// Distance from `p` to triangle `[a, b, c]`.
fn distance_to_triangle(p: DVec3, t: [DVec3; 3]) -> f64 {
    let f = scene_sampler::Face::new(t, Default::default(), Default::default(), 0, 0);
    f.closest_point(p).distance(p)
}

/// The world triangles of primitive `prim` under `world`.
fn world_triangles(
    prim: &gltf::Primitive,
    buffers: &[gltf::buffer::Data],
    world: DMat4,
) -> Vec<[DVec3; 3]> {
    let r = prim.reader(|b| Some(&buffers[b.index()]));
    let pos: Vec<DVec3> = r
        .read_positions()
        .unwrap()
        .map(|p| world.transform_point3(dvec(p)))
        .collect();
    let idx: Vec<u32> = match r.read_indices() {
        Some(i) => i.into_u32().collect(),
        None => (0..pos.len() as u32).collect(),
    };
    idx.chunks(3)
        .map(|t| [pos[t[0] as usize], pos[t[1] as usize], pos[t[2] as usize]])
        .collect()
}

fn same_transform(a: &gltf::scene::Transform, b: &gltf::scene::Transform) -> bool {
    use gltf::scene::Transform::*;
    match (a, b) {
        (Matrix { matrix: x }, Matrix { matrix: y }) => x == y,
        (
            Decomposed {
                translation: t1,
                rotation: r1,
                scale: s1,
            },
            Decomposed {
                translation: t2,
                rotation: r2,
                scale: s2,
            },
        ) => t1 == t2 && r1 == r2 && s1 == s2,
        _ => false,
    }
}

/// Checks the bake against its input document (module docs); returns the number of vertices
/// checked.
fn check_bake_against_input(
    input: &Path,
    bake: &[u8],
    verts: &[Vertex],
    exposure: &Exposure,
) -> usize {
    let (src, src_buffers, _) = gltf::import(input).unwrap();
    let (out, out_buffers, _) = gltf::import_slice(bake).expect("the bake is valid glTF");
    // ⟨Node tree: names, transforms, children, roots⟩
    assert_eq!(out.nodes().count(), src.nodes().count());
    for (a, b) in src.nodes().zip(out.nodes()) {
        assert_eq!(b.name(), a.name(), "node {}", a.index());
        assert!(
            same_transform(&a.transform(), &b.transform()),
            "node {:?}: transform",
            a.name()
        );
        let ca: Vec<usize> = a.children().map(|c| c.index()).collect();
        let cb: Vec<usize> = b.children().map(|c| c.index()).collect();
        assert_eq!(ca, cb, "node {:?}: children", a.name());
        assert_eq!(
            a.mesh().is_some(),
            b.mesh().is_some(),
            "node {:?}: mesh",
            a.name()
        );
    }
    let roots = |d: &gltf::Document| -> Vec<usize> {
        d.default_scene()
            .unwrap()
            .nodes()
            .map(|n| n.index())
            .collect()
    };
    assert_eq!(roots(&out), roots(&src));
    // ⟨Meshes per node instance, primitives and materials⟩
    let src_world = world_transforms(&src);
    let out_world = world_transforms(&out);
    let diag = {
        let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
        for n in src.nodes().filter(|n| n.mesh().is_some()) {
            for p in n.mesh().unwrap().primitives() {
                for t in world_triangles(&p, &src_buffers, src_world[&n.index()]) {
                    for v in t {
                        lo = lo.min(v);
                        hi = hi.max(v);
                    }
                }
            }
        }
        (hi - lo).length()
    };
    let instances = |m: usize| {
        src.nodes()
            .filter(|n| n.mesh().map(|x| x.index()) == Some(m))
            .count()
    };
    let mut out_meshes = std::collections::HashSet::new();
    let mut checked = 0;
    let scale = exposure.scale as f32;
    for (a, b) in src.nodes().zip(out.nodes()) {
        let (Some(ma), Some(mb)) = (a.mesh(), b.mesh()) else {
            continue;
        };
        assert!(
            out_meshes.insert(mb.index()),
            "a mesh shared by two output nodes"
        );
        let expect = if instances(ma.index()) > 1 {
            format!("{}@{}", ma.name().unwrap(), a.name().unwrap())
        } else {
            ma.name().unwrap_or_default().to_string()
        };
        assert_eq!(mb.name().unwrap_or_default(), expect);
        let pa: Vec<gltf::Primitive> = ma.primitives().collect();
        let pb: Vec<gltf::Primitive> = mb.primitives().collect();
        assert_eq!(pa.len(), pb.len(), "mesh {expect}: primitives");
        let (wa, wb) = (src_world[&a.index()], out_world[&b.index()]);
        let mirrored = wb.determinant() < 0.0;
        for (k, (p, q)) in pa.iter().zip(&pb).enumerate() {
            assert_eq!(
                q.material().name(),
                p.material().name(),
                "mesh {expect} primitive {k}: material"
            );
            let surface = world_triangles(p, &src_buffers, wa);
            let r = q.reader(|buf| Some(&out_buffers[buf.index()]));
            let pos: Vec<DVec3> = r
                .read_positions()
                .unwrap()
                .map(|v| wb.transform_point3(dvec(v)))
                .collect();
            let nrm: Vec<DVec3> = r.read_normals().unwrap().map(dvec).collect();
            let col: Vec<[f32; 3]> = r.read_colors(0).unwrap().into_rgb_f32().collect();
            let rad_acc = q
                .attributes()
                .find(|(s, _)| matches!(s, gltf::Semantic::Extras(n) if n == "RADIOSITY"))
                .expect("_RADIOSITY")
                .1;
            assert_eq!(rad_acc.count(), pos.len());
            let view = rad_acc.view().unwrap();
            let data = &out_buffers[view.buffer().index()][view.offset() + rad_acc.offset()..];
            let rad: Vec<[f32; 3]> = (0..pos.len())
                .map(|i| {
                    std::array::from_fn(|c| {
                        let at = 12 * i + 4 * c;
                        f32::from_le_bytes(data[at..at + 4].try_into().unwrap())
                    })
                })
                .collect();
            let normal_to_world = wb.inverse().transpose();
            let idx: Vec<u32> = r.read_indices().unwrap().into_u32().collect();
            for t in idx.chunks(3) {
                let [x, y, z] = [0, 1, 2].map(|i| pos[t[i] as usize]);
                // the triangle's front side (glTF: reversed under a mirroring transform) is NORMAL's side
                let front = (y - x).cross(z - x) * if mirrored { -1.0 } else { 1.0 };
                for &v in t {
                    let n_local = nrm[v as usize];
                    assert!((n_local.length() - 1.0).abs() < 1e-6, "NORMAL not unit");
                    let n = normal_to_world.transform_vector3(n_local).normalize();
                    assert!(
                        n.dot(front.normalize()) > 1.0 - 1e-6,
                        "mesh {expect}: winding against NORMAL"
                    );
                    // on the input surface
                    let p = pos[v as usize];
                    let d = surface
                        .iter()
                        .map(|s| distance_to_triangle(p, *s))
                        .fold(f64::INFINITY, f64::min);
                    assert!(
                        d <= 1e-5 * diag,
                        "mesh {expect}: a vertex {d} off its input primitive"
                    );
                }
                // NORMAL is the front normal of the input triangle under the output triangle's
                // centroid (inside it, unlike a vertex on an edge of two)
                let c = (x + y + z) / 3.0;
                let (_, tri) = surface
                    .iter()
                    .map(|s| (distance_to_triangle(c, *s), *s))
                    .min_by(|a, b| a.0.total_cmp(&b.0))
                    .unwrap();
                let input_front = (tri[1] - tri[0]).cross(tri[2] - tri[0]).normalize()
                    * wa.determinant().signum();
                let n = normal_to_world
                    .transform_vector3(nrm[t[0] as usize])
                    .normalize();
                assert!(
                    n.dot(input_front) > 1.0 - 1e-5,
                    "mesh {expect}: NORMAL against the input's"
                );
            }
            for i in 0..pos.len() {
                // _RADIOSITY is B gathered at that point, COLOR_0 its tone map
                // (a point on an edge of two input triangles is a vertex of each, gathered for
                // each face: B may differ in the last bits)
                let matches = verts
                    .iter()
                    .filter(|(x, _)| x.distance(pos[i]) <= 1e-6 * diag)
                    .any(|(_, b)| rad[i] == b.map(|c| c as f32));
                assert!(
                    matches,
                    "mesh {expect}: _RADIOSITY {:?} is no vertex's B",
                    rad[i]
                );
                for c in 0..3 {
                    let expect_c = (rad[i][c] / std::f32::consts::PI * scale).clamp(0.0, 1.0);
                    assert!(
                        (col[i][c] - expect_c).abs() < 1e-5,
                        "COLOR_0 {} vs {}",
                        col[i][c],
                        expect_c
                    );
                }
                checked += 1;
            }
        }
    }
    checked
}

#[test]
fn the_bake_keeps_the_input_node_tree_meshes_and_materials() {
    let dir = temp_dir("hierarchy");
    let path = write_hierarchy_scene(&dir);
    let scene = scene_sampler::load_gltf(&path).unwrap();
    // provenance on load: the parts (node, mesh, primitive) and the document's tree
    let src = scene.gltf.as_deref().expect("a glTF source");
    assert_eq!(src.roots, vec![0, 6]);
    assert_eq!(src.nodes[3].children, vec![4, 5]);
    assert_eq!(src.nodes[4].mesh, Some(2));
    assert_eq!(src.instances(2), 2);
    assert!(src.nodes[6].world.is_some() && src.nodes[6].mesh.is_none());
    let parts: Vec<(Option<u32>, u32)> =
        scene.parts.iter().map(|p| (p.node, p.primitive)).collect();
    for want in [
        (Some(1), 0),
        (Some(2), 0),
        (Some(4), 0),
        (Some(4), 1),
        (Some(5), 0),
        (Some(5), 1),
    ] {
        assert!(parts.contains(&want), "no part {want:?} in {parts:?}");
    }
    for f in &scene.faces {
        let p = scene.parts[f.part as usize];
        assert_eq!(p.object, f.object);
        // box faces: the top (+y in the box's frame) is primitive 0
        if p.mesh == Some(2) {
            let w = src.nodes[p.node.unwrap() as usize].world.unwrap();
            let up = w
                .inverse()
                .transpose()
                .transform_vector3(DVec3::Y)
                .normalize();
            assert_eq!(
                p.primitive == 0,
                f.normal.dot(up) > 0.999,
                "face of primitive {}",
                p.primitive
            );
        }
    }
    let (bytes, verts, exposure) = bake(&scene);
    std::fs::write(dir.join("hierarchy.glb"), &bytes).unwrap();
    let checked = check_bake_against_input(&path, &bytes, &verts, &exposure);
    assert_eq!(
        checked,
        verts.len(),
        "every output vertex is in the bake once"
    );
    validate(&[dir.join("hierarchy.glb")]);
}

#[test]
fn the_bake_of_the_cornell_box_gltf_overlays_it() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/cornell-box.gltf");
    let scene = scene_sampler::load_gltf(&path).unwrap();
    let (bytes, verts, exposure) = bake(&scene);
    let checked = check_bake_against_input(&path, &bytes, &verts, &exposure);
    assert_eq!(checked, verts.len());
    let dir = temp_dir("cornell-gltf");
    std::fs::write(dir.join("cornell-box.glb"), &bytes).unwrap();
    validate(&[dir.join("cornell-box.glb")]);
}

/// Built-ins (and OBJ) have no node tree: one root node per object, named after it, identity
/// transform, its triangles in world coordinates.
#[test]
fn the_bake_of_a_builtin_has_a_node_per_object() {
    let scene = scene_sampler::builtin("cornell-box")
        .unwrap()
        .into_3d()
        .unwrap();
    let (bytes, verts, _) = bake(&scene);
    let (doc, buffers, _) = gltf::import_slice(&bytes).unwrap();
    let names: Vec<&str> = doc.nodes().map(|n| n.name().unwrap()).collect();
    let objects: Vec<&str> = scene.objects.iter().map(String::as_str).collect();
    assert_eq!(names, objects);
    assert_eq!(doc.default_scene().unwrap().nodes().count(), objects.len());
    let mut count = 0;
    for n in doc.nodes() {
        assert_eq!(to_d(n.transform().matrix()), DMat4::IDENTITY);
        let m = n.mesh().unwrap();
        assert_eq!(m.name(), n.name());
        for p in m.primitives() {
            let r = p.reader(|b| Some(&buffers[b.index()]));
            let o = scene
                .objects
                .iter()
                .position(|o| Some(o.as_str()) == n.name())
                .unwrap();
            for v in r.read_positions().unwrap().map(dvec) {
                let d = scene
                    .faces
                    .iter()
                    .filter(|f| f.object as usize == o)
                    .map(|f| f.closest_point(v).distance(v))
                    .fold(f64::INFINITY, f64::min);
                assert!(d < 1e-6 * scene.diagonal(), "vertex off its object");
                count += 1;
            }
        }
    }
    assert_eq!(count, verts.len());
    let dir = temp_dir("builtin");
    std::fs::write(dir.join("cornell-builtin.glb"), &bytes).unwrap();
    validate(&[dir.join("cornell-builtin.glb")]);
}

/// Runs the Khronos glTF-Validator (tests/scripts/gltf-validate.js, through node and the npm
/// package `gltf-validator`) on `files`: no errors allowed. Skipped, with a note, when node or
/// the package is missing.
fn validate(files: &[PathBuf]) {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/scripts/gltf-validate.js");
    let npm_root = std::process::Command::new("npm")
        .args(["root", "-g"])
        .output()
        .ok()
        .filter(|o| o.status.success())
        .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string());
    let mut cmd = std::process::Command::new("node");
    cmd.arg(&script).args(files);
    if let Some(root) = npm_root {
        cmd.env("NODE_PATH", root);
    }
    match cmd.output() {
        Err(_) => eprintln!("gltf-validator: skipped (node not found)"),
        Ok(o) if o.status.code() == Some(2) => {
            eprintln!(
                "gltf-validator: skipped (npm package not installed: npm install -g gltf-validator)"
            )
        }
        Ok(o) => {
            let text = String::from_utf8_lossy(&o.stdout);
            eprintln!("{text}");
            assert!(
                o.status.success(),
                "gltf-validator found errors:\n{text}{}",
                String::from_utf8_lossy(&o.stderr)
            );
        }
    }
}

/// A floor whose corner lies under a closed box standing on it: the corner vertex would gather
/// the box's dark inside (a dark wedge across the floor in the image); it gathers just past the
/// box's wall on the way to its face's centre instead, on the floor, and a free corner stays put.
#[test]
fn a_vertex_under_a_solid_gathers_where_its_face_comes_out() {
    let dir = temp_dir("buried-corner");
    // floor [0, 2]² at y = 0 facing up; a box [-0.1, 0.4] × [0, 0.5] × [-0.1, 0.4] over its
    // corner at the origin (faces outward); a lamp above
    let obj = "\
mtllib m.mtl
v 0 0 0\nv 2 0 0\nv 2 0 2\nv 0 0 2
v -0.1 0 -0.1\nv 0.4 0 -0.1\nv 0.4 0 0.4\nv -0.1 0 0.4
v -0.1 0.5 -0.1\nv 0.4 0.5 -0.1\nv 0.4 0.5 0.4\nv -0.1 0.5 0.4
v 0.8 1.5 0.8\nv 1.2 1.5 0.8\nv 1.2 1.5 1.2\nv 0.8 1.5 1.2
o floor\nusemtl white\nf 1 4 3\nf 1 3 2
o box\nusemtl white
f 5 6 7\nf 5 7 8
f 9 12 11\nf 9 11 10
f 5 9 10\nf 5 10 6
f 6 10 11\nf 6 11 7
f 7 11 12\nf 7 12 8
f 8 12 9\nf 8 9 5
o lamp\nusemtl lamp\nf 13 14 15\nf 13 15 16
";
    std::fs::write(dir.join("s.obj"), obj).unwrap();
    std::fs::write(
        dir.join("m.mtl"),
        "newmtl white\nKd 0.7 0.7 0.7\nnewmtl lamp\nKd 0 0 0\nKe 5 5 5\n",
    )
    .unwrap();
    let scene = scene_sampler::load_obj(dir.join("s.obj")).unwrap();
    let bvh = SceneBvh::new(&scene);
    let floor = (0..scene.faces.len() as u32)
        .find(|&f| {
            let face = &scene.faces[f as usize];
            face.normal.y > 0.9 && face.v.iter().all(|v| v.y == 0.0) && face.area > 1.0
        })
        .expect("a floor triangle");
    let face = &scene.faces[floor as usize];
    let corner = face.v.iter().copied().find(|v| *v == DVec3::ZERO).unwrap();
    let moved = gcr::vertex_gather_point(&scene, &bvh, floor, corner);
    assert!(moved.y.abs() < 1e-9, "off the floor: {moved}");
    assert!(
        moved.x > 0.4 || moved.z > 0.4,
        "still under the box: {moved}"
    );
    assert!(moved.length() < 0.7, "moved farther than the box: {moved}");
    let free = face.v.iter().copied().find(|v| v.x == 2.0).unwrap();
    let stays = gcr::vertex_gather_point(&scene, &bvh, floor, free);
    assert!(stays.distance(free) < 1e-3, "a free corner moved: {stays}");
}

/// A ground triangle (0, 0)–(10, 0)–(0, 10) in x, z whose three corners and centroid lie under
/// two closed boxes standing on it (x, z in [−1, 11] × [−1, 4] and [−1, 2] × [4, 11]) while the
/// strip x > 2, z > 4 shows: the way from a corner to the centroid never comes out, so each
/// corner gathers at the nearest point of the triangle that is under no box (a temple's ground
/// triangle of three buried corners showed a dark wedge); a point that is not buried stays.
#[test]
fn a_triangle_buried_but_for_a_strip_gathers_on_the_strip() {
    let dir = temp_dir("buried-triangle");
    let boxed = |(x0, x1): (f64, f64), (z0, z1): (f64, f64), at: usize| {
        let mut s = String::new();
        for y in [0.0, 1.0] {
            for (x, z) in [(x0, z0), (x1, z0), (x1, z1), (x0, z1)] {
                s += &format!("v {x} {y} {z}\n");
            }
        }
        let i = |k: usize| at + k;
        // faces outward: bottom, top, four sides
        for f in [
            [1, 2, 3, 4],
            [5, 8, 7, 6],
            [1, 5, 6, 2],
            [2, 6, 7, 3],
            [3, 7, 8, 4],
            [4, 8, 5, 1],
        ] {
            s += &format!(
                "f {} {} {}\nf {} {} {}\n",
                i(f[0]),
                i(f[1]),
                i(f[2]),
                i(f[0]),
                i(f[2]),
                i(f[3])
            );
        }
        s
    };
    let obj = format!(
        "mtllib m.mtl\nusemtl white\nv 0 0 0\nv 10 0 0\nv 0 0 10\no ground\nf 1 3 2\n\
         o a\n{}o b\n{}",
        boxed((-1.0, 11.0), (-1.0, 4.0), 3),
        boxed((-1.0, 2.0), (4.0, 11.0), 11)
    );
    std::fs::write(dir.join("s.obj"), obj).unwrap();
    std::fs::write(dir.join("m.mtl"), "newmtl white\nKd 0.7 0.7 0.7\n").unwrap();
    let scene = scene_sampler::load_obj(dir.join("s.obj")).unwrap();
    let bvh = SceneBvh::new(&scene);
    let ground = (0..scene.faces.len() as u32)
        .find(|&f| scene.faces[f as usize].area > 40.0)
        .expect("the ground triangle");
    let face = &scene.faces[ground as usize];
    assert!(face.normal.y > 0.99, "the ground faces up");
    for corner in face.v {
        let at = gcr::vertex_gather_point(&scene, &bvh, ground, corner);
        assert!(at.y.abs() < 1e-9, "off the ground: {at}");
        assert!(
            at.x > 2.0 && at.z > 4.0 && at.x + at.z < 10.0,
            "{corner} gathers at {at}"
        );
        // (0, 10) comes out of box b on the way to the centroid (at x = 2); the others, whose way
        // stays under box a, at the strip's nearest point, within a grid cell (10/16 a side)
        let nearest = match (corner.x, corner.z) {
            (0.0, 0.0) => DVec3::new(2.0, 0.0, 4.0),
            (10.0, 0.0) => DVec3::new(6.0, 0.0, 4.0),
            _ => continue,
        };
        assert!(
            at.distance(nearest) < 1.0,
            "{corner} gathers at {at}, far from {nearest}"
        );
    }
    let open = DVec3::new(3.0, 0.0, 5.0);
    assert!(gcr::vertex_gather_point(&scene, &bvh, ground, open).distance(open) < 1e-2);
}
