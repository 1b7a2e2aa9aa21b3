//! Issue 17 (reliability), loader and scene-model side: every case here failed before its fix.

use glam::DVec3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use scene_sampler::*;
use std::path::PathBuf;

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("scene-sampler-rel-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn write(d: &std::path::Path, name: &str, text: &str) -> PathBuf {
    let p = d.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

fn shifted(scene: &Scene, by: DVec3) -> Scene {
    let faces = scene
        .faces
        .iter()
        .map(|f| Face::new(f.v.map(|v| v + by), f.rho, f.emission, f.object, f.surface))
        .collect();
    Scene::new("shifted", "test", faces, scene.objects.clone(), None).unwrap()
}

/// The Cornell box moved by 10⁶ along x keeps its kernel: same G (f64), same visibility (the f32 BVH works
/// relative to its centre). Before, the f32 BVH at 10⁶ (spacing 0.06) collapsed the box.
#[test]
fn a_scene_far_from_the_origin_keeps_its_kernel() {
    let base = builtin("cornell-box").unwrap().into_3d().unwrap();
    let far = shifted(&base, DVec3::new(1e6, 0.0, 0.0));
    let (b0, b1) = (SceneBvh::new(&base), SceneBvh::new(&far));
    let (k0, k1) = (
        KernelSampler::new(&base, &b0),
        KernelSampler::new(&far, &b1),
    );
    let mut rng = ChaCha8Rng::seed_from_u64(17);
    let (mut n, mut differ, mut visible) = (0, 0, 0);
    for _ in 0..20_000 {
        let u: [f64; 4] = std::array::from_fn(|_| rng.random());
        let (s0, s1) = (k0.sample(u), k1.sample(u));
        assert_eq!(s0.x.face, s1.x.face);
        assert!(
            (s0.g - s1.g).abs() <= 1e-6 * s0.g.abs().max(1.0),
            "{} vs {}",
            s0.g,
            s1.g
        );
        if s0.cos_x > 0.0 && s0.cos_y > 0.0 {
            n += 1;
            visible += usize::from(s0.visible);
            differ += usize::from(s0.visible != s1.visible);
        }
    }
    assert!(n > 5000 && visible > n / 2, "{n} {visible}");
    // grazing pairs may flip within f32 rounding of the box's size; the collapsed box flipped thousands
    assert!(
        differ * 1000 <= n,
        "{differ} of {n} visibility results differ"
    );
    // closest hits, in the scene's own coordinates
    for _ in 0..2000 {
        let o = DVec3::new(rng.random(), rng.random(), rng.random()) * 0.5 + DVec3::splat(0.03);
        let d = cosine_hemisphere(DVec3::Y, [rng.random(), rng.random()]);
        let h0 = b0.closest_hit(o, d, f64::INFINITY, u32::MAX);
        let h1 = b1.closest_hit(o + DVec3::new(1e6, 0.0, 0.0), d, f64::INFINITY, u32::MAX);
        match (h0, h1) {
            (Some(a), Some(b)) => {
                assert!((a.t - b.t).abs() < 1e-4, "{a:?} {b:?}");
                assert!((a.point + DVec3::new(1e6, 0.0, 0.0) - b.point).length() < 1e-4);
            }
            (a, b) => assert_eq!(a.is_some(), b.is_some(), "{a:?} {b:?}"),
        }
    }
}

/// OBJ coordinates are read in f64: the shifted box written with full precision reads back exactly.
#[test]
fn obj_reads_coordinates_in_double_precision() {
    let base = builtin("cornell-box").unwrap().into_3d().unwrap();
    let far = shifted(&base, DVec3::new(1e6, -3e5, 0.0));
    let d = dir("f64");
    let p = write_obj(&far, &d).unwrap();
    let back = load_obj(&p).unwrap();
    assert_eq!(back.faces.len(), far.faces.len());
    for (a, b) in back.faces.iter().zip(&far.faces) {
        assert_eq!(a.v, b.v);
    }
}

/// The same light quad written twice: merged, with a warning naming object and faces (before, `solve`
/// doubled B). A triangle written from another vertex is the same triangle. Opposite windings (two-sided
/// thin geometry) are kept; different materials are refused. (A quad written twice from different starting
/// vertices triangulates into different triangles and is not caught: detection is per triangle.)
#[test]
fn coincident_duplicate_faces_are_merged_or_refused() {
    let d = dir("dup");
    write(
        &d,
        "m.mtl",
        "newmtl white\nKd 0.5 0.5 0.5\nnewmtl light\nKd 0 0 0\nKe 1 1 1\n",
    );
    let quad = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n";
    let once = load_obj(write(
        &d,
        "once.obj",
        &format!("mtllib m.mtl\n{quad}o light\nusemtl light\nf 1 2 3 4\n"),
    ))
    .unwrap();
    let twice = load_obj(write(
        &d,
        "twice.obj",
        &format!("mtllib m.mtl\n{quad}o light\nusemtl light\nf 1 2 3 4\nf 1 2 3 4\n"),
    ))
    .unwrap();
    assert_eq!(twice.faces.len(), once.faces.len());
    let w: Vec<_> = twice
        .warnings
        .iter()
        .filter(|w| w.contains("duplicate"))
        .collect();
    assert_eq!(w.len(), 1, "{:?}", twice.warnings);
    assert!(
        w[0].contains("merged 2") && w[0].contains("object `light`"),
        "{w:?}"
    );
    assert!(w[0].contains("face 2") && w[0].contains("face 3"), "{w:?}");
    let rotated = load_obj(write(
        &d,
        "rot.obj",
        &format!("mtllib m.mtl\n{quad}o light\nusemtl light\nf 1 2 3\nf 2 3 1\nf 3 1 2\n"),
    ))
    .unwrap();
    assert_eq!(rotated.faces.len(), 1, "{:?}", rotated.warnings);
    // two-sided: the back face is a different surface, kept without a word about duplicates
    let two_sided = load_obj(write(
        &d,
        "two.obj",
        &format!("mtllib m.mtl\n{quad}o light\nusemtl light\nf 1 2 3 4\nf 4 3 2 1\n"),
    ))
    .unwrap();
    assert_eq!(two_sided.faces.len(), 2 * once.faces.len());
    assert!(
        !two_sided.warnings.iter().any(|w| w.contains("duplicate")),
        "{:?}",
        two_sided.warnings
    );
    // a white quad on the light: which one a ray sees would be arbitrary
    let e = load_obj(write(
        &d,
        "clash.obj",
        &format!(
            "mtllib m.mtl\n{quad}o light\nusemtl light\nf 1 2 3 4\no cover\nusemtl white\nf 1 2 3 4\n"
        ),
    ))
    .unwrap_err();
    assert!(
        matches!(
            e,
            SceneError::ConflictingDuplicate {
                face: 2,
                other: 0,
                ..
            }
        ),
        "{e}"
    );
    assert!(
        e.to_string().contains("`cover`") && e.to_string().contains("`light`"),
        "{e}"
    );
}

/// `Kd 0.5` / `Ke 17` are grey in the MTL format (tobj 4 panicked on them); a bare `Kd` is an error naming
/// file and line.
#[test]
fn one_number_mtl_colours_are_grey() {
    let d = dir("grey");
    write(
        &d,
        "g.mtl",
        "# grey\nnewmtl wall\nKd 0.5\nnewmtl lamp\nKd 0\nKe 17\n",
    );
    let tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n";
    let s = load_obj(write(
        &d,
        "g.obj",
        &format!("mtllib g.mtl\n{tri}usemtl lamp\nf 1 2 3\nusemtl wall\nf 1 3 4\n"),
    ))
    .unwrap();
    assert_eq!(
        s.faces[0].emission,
        Spectrum::grey(17.0 * std::f64::consts::PI)
    );
    assert_eq!(s.faces[1].rho, Spectrum::grey(0.5));
    assert_eq!(s.bands, 1);
    write(&d, "b.mtl", "newmtl wall\nKd\n");
    let e = load_obj(write(
        &d,
        "b.obj",
        &format!("mtllib b.mtl\n{tri}usemtl wall\nf 1 2 3\n"),
    ))
    .unwrap_err();
    let m = e.to_string();
    assert!(
        m.contains("b.mtl") && m.contains("line 2") && m.contains("`Kd`"),
        "{m}"
    );
    write(&d, "c.mtl", "newmtl wall\nKd 0.5 0.5\n");
    let e = load_obj(write(
        &d,
        "c.obj",
        &format!("mtllib c.mtl\n{tri}usemtl wall\nf 1 2 3\n"),
    ))
    .unwrap_err();
    assert!(
        e.to_string().contains("c.mtl") && e.to_string().contains("two numbers"),
        "{e}"
    );
}

#[test]
fn loader_messages_name_what_is_wrong() {
    let d = dir("msg");
    let tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
    // a typo of a built-in is an unknown built-in with a suggestion, not an unsupported format
    let e = load_or_builtin("cornel-box").unwrap_err();
    assert!(matches!(e, SceneError::UnknownBuiltin { .. }), "{e}");
    assert!(e.to_string().contains("did you mean `cornell-box`"), "{e}");
    let e = load_or_builtin("random-box-1000").unwrap_err();
    assert!(e.to_string().contains("random-boxes-<N>"), "{e}");
    assert_eq!(nearest_builtin("zzzzzzzzzzzzzzzz"), None);
    // a missing MTL names the path tried and the line
    let e = load_obj(write(
        &d,
        "nomtl.obj",
        &format!("# x\nmtllib gone.mtl\n{tri}f 1 2 3\n"),
    ))
    .unwrap_err();
    assert!(
        matches!(e, SceneError::MaterialLibrary { line: 2, .. }),
        "{e}"
    );
    assert!(
        e.to_string()
            .contains(&d.join("gone.mtl").display().to_string()),
        "{e}"
    );
    // an undefined usemtl is named (before: "no face emits light")
    write(&d, "m.mtl", "newmtl light\nKd 0 0 0\nKe 1 1 1\n");
    let e = load_obj(write(
        &d,
        "typo.obj",
        &format!("mtllib m.mtl\n{tri}usemtl lihgt\nf 1 2 3\n"),
    ))
    .unwrap_err();
    assert!(
        matches!(&e, SceneError::UndefinedMaterial { line: 5, name, .. } if name == "lihgt"),
        "{e}"
    );
    assert!(e.to_string().contains("light"), "{e}");
    // negative or NaN values are refused naming the material
    write(&d, "neg.mtl", "newmtl glow\nKd 0.5 0.5 0.5\nKe 1 -1 1\n");
    let e = load_obj(write(
        &d,
        "neg.obj",
        &format!("mtllib neg.mtl\n{tri}usemtl glow\nf 1 2 3\n"),
    ))
    .unwrap_err();
    assert!(
        matches!(&e, SceneError::BadMaterial { material, .. } if material == "glow"),
        "{e}"
    );
    write(&d, "nan.mtl", "newmtl murk\nKd nan 0.5 0.5\nKe 1 1 1\n");
    let e = load_obj(write(
        &d,
        "nan.obj",
        &format!("mtllib nan.mtl\n{tri}usemtl murk\nf 1 2 3\n"),
    ))
    .unwrap_err();
    assert!(
        matches!(&e, SceneError::BadMaterial { material, .. } if material == "murk"),
        "{e}"
    );
    // vn normals against the winding: warned, naming the object (the floor renders black otherwise)
    let s = load_obj(write(
        &d,
        "vn.obj",
        &format!("mtllib m.mtl\n{tri}v 0 0 1\nvn 0 0 -1\nvn 0 -1 0\no lamp\nusemtl light\nf 1//2 3//2 4//2\no floor\nusemtl light\nf 1//1 2//1 3//1\n"),
    ))
    .unwrap();
    let w: Vec<_> = s.warnings.iter().filter(|w| w.contains("`vn`")).collect();
    assert!(
        w.len() == 1 && w[0].contains("object `floor`: 1 face"),
        "{:?}",
        s.warnings
    );
    // inconsistent windings name the object
    let s = load_obj(write(
        &d,
        "wind.obj",
        "mtllib m.mtl\nusemtl light\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\no panel\nf 1 2 3\nf 1 2 4\n",
    ))
    .unwrap();
    assert!(
        s.warnings
            .iter()
            .any(|w| w.contains("object `panel`") && w.contains("windings")),
        "{:?}",
        s.warnings
    );
}

/// glTF: a file with only line primitives says so; triangle strips and fans load as triangles; the default
/// material (white) is clamped with a warning naming it.
#[test]
fn gltf_primitive_modes_and_default_material() {
    let d = dir("gltf");
    // two triangles of a unit quad as 4 f32 positions, in the order a strip needs: 0 1 2, (2 1 3)
    let pos: [f32; 12] = [0., 0., 0., 1., 0., 0., 0., 1., 0., 1., 1., 0.];
    let bytes: Vec<u8> = pos.iter().flat_map(|v| v.to_le_bytes()).collect();
    let b64 = {
        const T: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
        let mut out = String::new();
        for c in bytes.chunks(3) {
            let n = (u32::from(c[0]) << 16)
                | (u32::from(*c.get(1).unwrap_or(&0)) << 8)
                | u32::from(*c.get(2).unwrap_or(&0));
            for k in 0..4 {
                out.push(if k <= c.len() {
                    T[(n >> (18 - 6 * k) & 63) as usize] as char
                } else {
                    '='
                });
            }
        }
        out
    };
    let doc = |mode: u32, material: &str| {
        format!(
            r#"{{"asset": {{"version": "2.0"}}, "scene": 0, "scenes": [{{"nodes": [0]}}],
            "nodes": [{{"mesh": 0, "name": "panel"}}],
            "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0}}, "mode": {mode}{material}}}]}}],
            {}
            "buffers": [{{"byteLength": 48, "uri": "data:application/octet-stream;base64,{b64}"}}],
            "bufferViews": [{{"buffer": 0, "byteLength": 48}}],
            "accessors": [{{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
                "min": [0, 0, 0], "max": [1, 1, 0]}}]}}"#,
            if material.is_empty() {
                ""
            } else {
                r#""materials": [{"name": "lamp", "emissiveFactor": [1, 1, 1], "pbrMetallicRoughness": {"baseColorFactor": [0, 0, 0, 1]}}],"#
            }
        )
    };
    // LINES only
    let e = load_gltf(write(&d, "lines.gltf", &doc(1, ", \"material\": 0"))).unwrap_err();
    assert!(
        e.to_string().contains("no triangles") && e.to_string().contains("panel"),
        "{e}"
    );
    // TRIANGLE_STRIP: two triangles, both facing +z
    let s = load_gltf(write(&d, "strip.gltf", &doc(5, ", \"material\": 0"))).unwrap();
    assert_eq!(s.faces.len(), 2);
    assert!(s.faces.iter().all(|f| f.normal.z > 0.99), "{:?}", s.faces);
    assert!((s.total_area() - 1.0).abs() < 1e-6);
    // TRIANGLE_FAN over 0 1 3 2 would be needed for the quad; over 0 1 2 3 it gives (1 2 0), (2 3 0)
    let s = load_gltf(write(&d, "fan.gltf", &doc(6, ", \"material\": 0"))).unwrap();
    assert_eq!(s.faces.len(), 2);
    // the default material is white (ρ = 1): clamped, named; it does not emit, so the scene is refused
    // for having no light — the message for that is still the light's
    let e = load_gltf(write(&d, "default.gltf", &doc(4, "")))
        .unwrap()
        .check_lit()
        .unwrap_err();
    assert!(matches!(e, SceneError::NoEmitter { .. }), "{e}");
}
