//! Material maps beyond albedo. Cut-outs (`scene_sampler::cutout`): an OBJ grille (`map_d`, grey
//! stripes) and a glTF grille (`alphaMode` MASK, the base colour texture's alpha) let rays through
//! their transparent stripes and stop them on the solid ones; `d` below 0.5 drops a material's
//! faces; BLEND is read as MASK with a warning; OPAQUE ignores alpha. glTF `emissiveTexture`: each
//! face emits the texture's mean over its texture-coordinate triangle.

mod common;

use common::base64;
use glam::DVec3;
use scene_sampler::{SceneBvh, load};
use std::path::PathBuf;

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("cutouts-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// A floor (y = 0, 4 × 4) and a grille above it (y = 1, x, z ∈ [1, 3]) whose texture u runs
/// along x: stripes of 2 texels of an 8-texel row, transparent at x ∈ [1, 1.5) and [2, 2.5).
const GRILLE_OBJ: &str = "mtllib grille.mtl
v 0 0 0
v 4 0 0
v 4 0 4
v 0 0 4
v 1 1 1
v 3 1 1
v 3 1 3
v 1 1 3
v 0 2 0
v 4 2 0
v 4 2 4
vt 0 0
vt 1 0
vt 1 1
vt 0 1
o floor
usemtl floor
f 1 4 3 2
o grille
usemtl grille
f 5/1 8/4 7/3 6/2
o ghost
usemtl ghost
f 9 11 10
";

const STRIPES: [u8; 8] = [0, 0, 255, 255, 0, 0, 255, 255];

/// Which face a ray straight down from (x, 1.5, 2) hits first (the ghost is above, at y = 2).
fn hit_below(bvh: &SceneBvh, x: f64) -> Option<u32> {
    bvh.closest_hit(DVec3::new(x, 1.5, 2.0), -DVec3::Y, f64::INFINITY, u32::MAX)
        .map(|h| h.face)
}

#[test]
fn an_obj_grille_lets_rays_through_its_transparent_stripes() {
    let d = dir("obj");
    image::GrayImage::from_raw(8, 1, STRIPES.to_vec())
        .unwrap()
        .save(d.join("mask.png"))
        .unwrap();
    std::fs::write(
        d.join("grille.mtl"),
        "newmtl floor\nKd 0.5 0.5 0.5\nnewmtl grille\nKd 0.5 0.5 0.5\nmap_d mask.png\n\
         newmtl ghost\nKd 0.5 0.5 0.5\nd 0.3\n",
    )
    .unwrap();
    std::fs::write(d.join("grille.obj"), GRILLE_OBJ).unwrap();
    let scene = load(d.join("grille.obj")).unwrap().into_3d().unwrap();
    assert_eq!(
        scene.faces.len(),
        4,
        "floor 2, grille 2; the ghost (d 0.3) dropped"
    );
    assert!(
        scene.warnings.iter().any(|w| w.contains("dropped 1 face")),
        "{:?}",
        scene.warnings
    );
    assert_eq!(scene.masks.len(), 1);
    let bvh = SceneBvh::new(&scene);
    let floor = |f: Option<u32>| f.is_some_and(|f| scene.faces[f as usize].v[0].y == 0.0);
    for (x, open) in [
        (1.1, true),
        (1.4, true),
        (1.6, false),
        (1.9, false),
        (2.2, true),
        (2.8, false),
    ] {
        assert_eq!(floor(hit_below(&bvh, x)), open, "x = {x}");
        // a shadow ray from the floor up toward a light at infinity
        let from = scene_sampler::SurfacePoint {
            point: DVec3::new(x, 0.0, 2.0),
            normal: DVec3::Y,
            face: 0,
        };
        assert_eq!(bvh.escapes(&from, DVec3::Y), open, "escapes at x = {x}");
    }
    // a `vt nan` is refused, naming the object (it read ρ = 0 in silence)
    std::fs::write(d.join("nan.obj"), GRILLE_OBJ.replace("vt 1 1", "vt nan 1")).unwrap();
    let e = load(d.join("nan.obj")).unwrap_err().to_string();
    assert!(
        e.contains("`grille`") && e.contains("not a finite number"),
        "{e}"
    );
    // `d` out of range is refused, naming the line
    std::fs::write(d.join("grille.mtl"), "newmtl floor\nd 1.5\n").unwrap();
    let e = load(d.join("grille.obj")).unwrap_err().to_string();
    assert!(e.contains("line 2") && e.contains("`d`"), "{e}");
}

/// The grille as glTF: a floor and a grille primitive whose material has `alpha_mode`, the
/// stripes in the alpha of an RGBA base colour texture.
fn gltf_grille(d: &std::path::Path, alpha_mode: &str) -> PathBuf {
    let grille = serde_json::json!({"name": "grille", "alphaMode": alpha_mode, "alphaCutoff": 0.5,
                                    "pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}});
    gltf_two_quads(d, &format!("grille-{alpha_mode}"), grille)
}

/// A floor (y = 0, 4 × 4, u = v = 0) and a quad above it (y = 1, x, z ∈ [1, 3], u = (x − 1)/2)
/// of material `upper`, texture 0 the RGBA stripes (grey, alpha [`STRIPES`]) clamped to the edge.
fn gltf_two_quads(d: &std::path::Path, name: &str, upper: serde_json::Value) -> PathBuf {
    let pos: [[f32; 3]; 8] = [
        [0., 0., 0.],
        [0., 0., 4.],
        [4., 0., 4.],
        [4., 0., 0.],
        [1., 1., 1.],
        [1., 1., 3.],
        [3., 1., 3.],
        [3., 1., 1.],
    ];
    let uv: [[f32; 2]; 8] = [[0., 0.]; 4]
        .into_iter()
        .chain([[0., 1.], [0., 0.], [1., 0.], [1., 1.]])
        .collect::<Vec<_>>()
        .try_into()
        .unwrap();
    let idx: [u16; 12] = [0, 1, 2, 0, 2, 3, 0, 1, 2, 0, 2, 3];
    let mut buf: Vec<u8> = pos.iter().flatten().flat_map(|v| v.to_le_bytes()).collect();
    buf.extend(uv.iter().flatten().flat_map(|v| v.to_le_bytes()));
    buf.extend(idx.iter().flat_map(|v| v.to_le_bytes()));
    let rgba: Vec<u8> = STRIPES.iter().flat_map(|&a| [a, a, a, a]).collect();
    let mut png = Vec::new();
    image::RgbaImage::from_raw(8, 1, rgba)
        .unwrap()
        .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .unwrap();
    // views: positions (floor, grille), texture coordinates (floor, grille), indices (each 0..4)
    let accessor = |view: u32, offset: u32, ty: &str, component: u32, count: u32| {
        serde_json::json!({"bufferView": view, "byteOffset": offset, "componentType": component,
                           "count": count, "type": ty})
    };
    let mut accessors = vec![
        accessor(0, 0, "VEC3", 5126, 4),
        accessor(1, 0, "VEC2", 5126, 4),
        accessor(2, 0, "SCALAR", 5123, 6),
        accessor(0, 48, "VEC3", 5126, 4),
        accessor(1, 32, "VEC2", 5126, 4),
        accessor(2, 12, "SCALAR", 5123, 6),
    ];
    accessors[0]["min"] = serde_json::json!([0, 0, 0]);
    accessors[0]["max"] = serde_json::json!([4, 0, 4]);
    accessors[3]["min"] = serde_json::json!([1, 1, 1]);
    accessors[3]["max"] = serde_json::json!([3, 1, 3]);
    let json = serde_json::json!({
        "asset": {"version": "2.0"},
        "scene": 0, "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [
            {"attributes": {"POSITION": 0, "TEXCOORD_0": 1}, "indices": 2, "material": 0},
            {"attributes": {"POSITION": 3, "TEXCOORD_0": 4}, "indices": 5, "material": 1}]}],
        "materials": [{"name": "floor"}, upper],
        "samplers": [{"wrapS": 33071, "wrapT": 33071}],
        "textures": [{"source": 0, "sampler": 0}],
        "images": [{"uri": format!("data:image/png;base64,{}", base64(&png))}],
        "buffers": [{"byteLength": buf.len(),
                     "uri": format!("data:application/octet-stream;base64,{}", base64(&buf))}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 96},
            {"buffer": 0, "byteOffset": 96, "byteLength": 64},
            {"buffer": 0, "byteOffset": 160, "byteLength": 24}],
        "accessors": accessors
    });
    let path = d.join(format!("{name}.gltf"));
    std::fs::write(&path, serde_json::to_string(&json).unwrap()).unwrap();
    path
}

#[test]
fn a_gltf_mask_cuts_and_blend_is_read_as_mask_with_a_warning() {
    let d = dir("gltf");
    for (mode, cut, warned) in [
        ("MASK", true, false),
        ("BLEND", true, true),
        ("OPAQUE", false, false),
    ] {
        let scene = load(gltf_grille(&d, mode)).unwrap().into_3d().unwrap();
        let bvh = SceneBvh::new(&scene);
        let floor = |f: Option<u32>| f.is_some_and(|f| scene.faces[f as usize].v[0].y == 0.0);
        for (x, open) in [(1.2, true), (1.7, false), (2.3, true), (2.7, false)] {
            assert_eq!(floor(hit_below(&bvh, x)), open && cut, "{mode}: x = {x}");
        }
        let blend = scene.warnings.iter().any(|w| w.contains("BLEND"));
        assert_eq!(blend, warned, "{mode}: {:?}", scene.warnings);
    }
}

/// An emissive texture (the stripes: texels 0 and 1 in linear, mean 1/2 over u ∈ [0, 1]) gives
/// each face the texture's mean over its texture triangle: the upper quad's two triangles see the
/// stripes weighted toward u = 0 and toward u = 1, so they differ, and their mean is the
/// texture's, 1/2 × emissiveFactor × π × strength; the floor (no texture) emits nothing.
#[test]
fn an_emissive_texture_emits_its_mean_per_face() {
    let d = dir("emissive");
    let lamp = serde_json::json!({"name": "lamp", "emissiveFactor": [1.0, 0.5, 0.25],
        "emissiveTexture": {"index": 0},
        "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 4.0}}});
    let mut path = gltf_two_quads(&d, "lamp", lamp);
    let mut json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    json["extensionsUsed"] = serde_json::json!(["KHR_materials_emissive_strength"]);
    path.set_file_name("lamp2.gltf");
    std::fs::write(&path, json.to_string()).unwrap();
    let scene = load(&path).unwrap().into_3d().unwrap();
    let lit: Vec<_> = scene.faces.iter().filter(|f| f.v[0].y == 1.0).collect();
    assert_eq!(lit.len(), 2);
    assert!(
        scene
            .faces
            .iter()
            .filter(|f| f.v[0].y == 0.0)
            .all(|f| f.emission.is_zero())
    );
    for (k, factor) in [1.0, 0.5, 0.25].into_iter().enumerate() {
        let full = std::f64::consts::PI * 4.0 * factor;
        let (a, b) = (lit[0].emission.0[k] / full, lit[1].emission.0[k] / full);
        assert!(((a + b) / 2.0 - 0.5).abs() < 5e-3, "band {k}: {a} {b}");
        assert!(
            (a - b).abs() > 0.02,
            "band {k}: the triangles see different stripes: {a} {b}"
        );
    }
    assert!(
        scene.warnings.iter().any(|w| w.contains("emissiveTexture")),
        "{:?}",
        scene.warnings
    );
}

/// OBJ `map_Ke` (#31): a lamp quad whose two triangles map onto the white and the black half of
/// its emissive texture emits Ke·π on the first and nothing on the second (it was dropped in
/// silence: both emitted Ke·π); without `Ke` the texture alone (Ke 1 1 1); without `vt` the
/// uniform Ke, with a warning.
#[test]
fn an_obj_emissive_texture_emits_its_mean_per_face() {
    let d = dir("map_ke");
    // 8 × 1: white on the left (u < 0.5), black on the right; the triangles stay between
    // texel centres of one colour, so that the bilinear lookups see only it
    image::GrayImage::from_raw(8, 1, vec![255, 255, 255, 255, 0, 0, 0, 0])
        .unwrap()
        .save(d.join("ke.png"))
        .unwrap();
    // the lamp (y = 1, facing down): triangle 1 over u ∈ [0.1, 0.4], triangle 2 over [0.6, 0.9]
    let obj = |lamp_vt: bool| {
        let f = |a: usize, b: usize, c: usize| match lamp_vt {
            true => format!("f {a}/{a} {b}/{b} {c}/{c}\n"),
            false => format!("f {a} {b} {c}\n"),
        };
        let vt = match lamp_vt {
            true => {
                "vt 0 0\nvt 0 0\nvt 0 0\nvt 0 0\n\
                     vt 0.1 0.5\nvt 0.1 0.5\nvt 0.4 0.5\nvt 0.4 0.5\n\
                     vt 0.6 0.5\nvt 0.6 0.5\nvt 0.9 0.5\nvt 0.9 0.5\n"
            }
            false => "",
        };
        format!(
            "mtllib l.mtl\nv 0 0 0\nv 2 0 0\nv 2 0 2\nv 0 0 2\n\
             v 0 1 0\nv 0 1 2\nv 1 1 2\nv 1 1 0\nv 1 1 0\nv 1 1 2\nv 2 1 2\nv 2 1 0\n{vt}\
             o floor\nusemtl floor\nf 1 4 3\nf 1 3 2\no lamp\nusemtl lamp\n{}{}",
            f(5, 7, 6),
            f(9, 11, 10)
        )
    };
    let load_with = |mtl: &str, vt: bool| {
        std::fs::write(d.join("l.mtl"), mtl).unwrap();
        std::fs::write(d.join("l.obj"), obj(vt)).unwrap();
        load(d.join("l.obj")).unwrap().into_3d().unwrap()
    };
    let lamp = |s: &scene_sampler::Scene| -> Vec<f64> {
        (s.faces.iter())
            .filter(|f| f.v[0].y == 1.0)
            .map(|f| f.emission.0[0])
            .collect()
    };
    let pi = std::f64::consts::PI;
    let floor = "newmtl floor\nKd 0.5 0.5 0.5\n";
    let s = load_with(
        &format!("{floor}newmtl lamp\nKd 0 0 0\nKe 2 2 2\nmap_Ke ke.png\n"),
        true,
    );
    assert_eq!(lamp(&s), [2.0 * pi, 0.0]);
    let s = load_with(
        &format!("{floor}newmtl lamp\nKd 0 0 0\nmap_Ke ke.png\n"),
        true,
    );
    assert_eq!(lamp(&s), [pi, 0.0]);
    let s = load_with(
        &format!("{floor}newmtl lamp\nKd 0 0 0\nKe 2 2 2\nmap_Ke ke.png\n"),
        false,
    );
    assert_eq!(lamp(&s), [2.0 * pi, 2.0 * pi]);
    assert!(
        s.warnings
            .iter()
            .any(|w| w.contains("object `lamp`") && w.contains("no `vt`")),
        "{:?}",
        s.warnings
    );
}

/// A face of a textured material without `vt`, in a file that has `vt`: tobj gives its corners
/// another corner's coordinates (here the first `vt`, on the texture's black half: ρ = 0 in
/// silence); a warning names the line and the material.
#[test]
fn textured_faces_without_vt_are_named() {
    let d = dir("no_vt");
    image::GrayImage::from_raw(8, 1, vec![255, 255, 255, 255, 0, 0, 0, 0])
        .unwrap()
        .save(d.join("t.png"))
        .unwrap();
    std::fs::write(
        d.join("l.mtl"),
        "newmtl a\nKd 0.5 0.5 0.5\nmap_Kd t.png\nnewmtl lamp\nKd 0 0 0\nKe 1 1 1\n",
    )
    .unwrap();
    let obj = "mtllib l.mtl\nv 0 0 0\nv 0 0 2\nv 2 0 2\nv 0 1 0\nv 2 1 0\nv 0 1 2\n\
               vt 0.6 0.5\nvt 0.7 0.5\nvt 0.8 0.5\no a\nusemtl a\nf 1 2 3\nf 1/1 2/2 3/3\n\
               o lamp\nusemtl lamp\nf 4 5 6\n";
    std::fs::write(d.join("l.obj"), obj).unwrap();
    let s = load(d.join("l.obj")).unwrap().into_3d().unwrap();
    let warned: Vec<_> = (s.warnings.iter())
        .filter(|w| w.contains("without `vt`"))
        .collect();
    assert_eq!(warned.len(), 1, "{:?}", s.warnings);
    assert!(
        warned[0].contains("l.obj:13: 1 face(s) of textured material `a`"),
        "{}",
        warned[0]
    );
}

/// A `doubleSided` material's faces get back faces (reversed winding, the same material and
/// texture), so a ray from below lands on a face that faces it; `LoadOptions::single_sided` and
/// one-sided materials leave the faces as they are; a back the file already models is not doubled.
#[test]
fn double_sided_faces_get_a_back() {
    let d = dir("double");
    let upper = serde_json::json!({"name": "sheet", "doubleSided": true,
        "pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}});
    let path = gltf_two_quads(&d, "double", upper);
    let scene = load(&path).unwrap().into_3d().unwrap();
    assert_eq!(scene.faces.len(), 6, "floor 2, sheet 2 + 2 backs");
    assert!(
        scene
            .warnings
            .iter()
            .any(|w| w.contains("2 face(s) of doubleSided"))
    );
    let bvh = SceneBvh::new(&scene);
    let up = bvh.closest_hit(DVec3::new(2.2, 0.5, 2.1), DVec3::Y, f64::INFINITY, u32::MAX);
    let down = bvh.closest_hit(
        DVec3::new(2.2, 1.5, 2.1),
        -DVec3::Y,
        f64::INFINITY,
        u32::MAX,
    );
    let normal = |h: Option<scene_sampler::Hit>| scene.faces[h.unwrap().face as usize].normal;
    assert_eq!(normal(up), -DVec3::Y, "from below: the back");
    assert_eq!(normal(down), DVec3::Y, "from above: the front");
    let back = scene.faces.iter().find(|f| f.normal == -DVec3::Y).unwrap();
    assert!(back.texture.is_some(), "the back keeps the texture");
    let one = scene_sampler::LoadOptions {
        single_sided: true,
        ..Default::default()
    };
    let single = scene_sampler::load_with(&path, &one)
        .unwrap()
        .into_3d()
        .unwrap();
    assert_eq!(single.faces.len(), 4);
    // a file that models the back itself: nothing added
    let mut again = scene.clone();
    assert_eq!(
        again.add_back_faces(|_| true),
        2,
        "only the floor lacks a back"
    );
}

/// `KHR_texture_transform` moves the texture coordinates a texture reads: an offset of a quarter
/// turns the grille's open stripes solid and its solid ones open (u' = u + 1/4, clamped).
#[test]
fn a_texture_transform_moves_the_stripes() {
    let d = dir("transform");
    let grille = serde_json::json!({"name": "grille", "alphaMode": "MASK",
        "pbrMetallicRoughness": {"baseColorTexture": {"index": 0,
            "extensions": {"KHR_texture_transform": {"offset": [0.25, 0.0]}}}}});
    let path = gltf_two_quads(&d, "transform", grille);
    let mut json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    json["extensionsUsed"] = serde_json::json!(["KHR_texture_transform"]);
    std::fs::write(&path, json.to_string()).unwrap();
    let scene = load(&path).unwrap().into_3d().unwrap();
    let bvh = SceneBvh::new(&scene);
    let floor = |f: Option<u32>| f.is_some_and(|f| scene.faces[f as usize].v[0].y == 0.0);
    for (x, open) in [(1.2, false), (1.7, true), (2.2, false), (2.7, false)] {
        assert_eq!(floor(hit_below(&bvh, x)), open, "x = {x}");
    }
}
