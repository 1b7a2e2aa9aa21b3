//! Structure-aware fuzzing of the glTF loader and the image decoders (issue 35): where
//! `fuzz_loaders.rs` mutates bytes and lines, this mutates what a hostile glTF is made of —
//! accessors (counts, offsets, component types, sparse storage), buffer views (offsets, lengths,
//! strides), buffers (lengths, URIs), primitives (attributes, indices, modes), nodes (transforms,
//! children), materials, textures and images — and the headers of the PNG and JPEG it embeds.
//!
//! Every input must give `Ok` or an error: no panic at all, not even one a loader's guard
//! catches (a panic hook counts them), and memory stays bounded: the whole test binary runs
//! under a 3 GiB address-space limit, so a loader that allocates what a header claims aborts it.
//! Deterministic (ChaCha8, fixed seeds).

mod common;

use common::{base64, count_panics, panics};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use scene_sampler::*;
use serde_json::{Value, json};
use std::path::{Path, PathBuf};

/// Installs the panic counter and the address-space limit, once for the binary.
fn harness() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        count_panics();
        #[cfg(target_os = "linux")]
        {
            use rustix::process::{Resource, Rlimit, getrlimit, setrlimit};
            let limit = getrlimit(Resource::As);
            let bound = 3u64 << 30;
            let current = Some(limit.maximum.map_or(bound, |m| m.min(bound)));
            setrlimit(Resource::As, Rlimit { current, ..limit }).unwrap();
        }
    });
}

/// A `w`×`h` RGBA PNG (a gradient).
fn png(w: u32, h: u32) -> Vec<u8> {
    let img = image::RgbaImage::from_fn(w, h, |x, y| {
        image::Rgba([
            (x * 60) as u8,
            (y * 60) as u8,
            90,
            if x == 0 { 0 } else { 255 },
        ])
    });
    let mut out = std::io::Cursor::new(Vec::new());
    img.write_to(&mut out, image::ImageFormat::Png).unwrap();
    out.into_inner()
}

/// A `w`×`h` RGB JPEG.
fn jpeg(w: u32, h: u32) -> Vec<u8> {
    let img = image::RgbImage::from_fn(w, h, |x, y| {
        image::Rgb([(x * 60) as u8, (y * 60) as u8, 90])
    });
    let mut out = std::io::Cursor::new(Vec::new());
    img.write_to(&mut out, image::ImageFormat::Jpeg).unwrap();
    out.into_inner()
}

fn data_uri(mime: &str, bytes: &[u8]) -> String {
    format!("data:{mime};base64,{}", base64(bytes))
}

/// The base document: a floor quad (indexed, TEXCOORD_0) with a PNG base colour, its copy
/// above it as a cut-out (MASK) by the same texture; a lamp quad with a JPEG emissive texture and one vertex moved by a
/// sparse substitution; a node tree with a rotation, a scale and a matrix; a camera and a point
/// light.
fn document(png: &[u8], jpeg: &[u8]) -> Value {
    let floor: [f32; 12] = [0., 0., 0., 1., 0., 0., 1., 0., 1., 0., 0., 1.];
    let lamp: [f32; 12] = [0., 1., 0., 0., 1., 1., 1., 1., 1., 1., 1., 0.];
    let uv: [f32; 8] = [0., 0., 1., 0., 1., 1., 0., 1.];
    let idx: [u16; 6] = [0, 2, 1, 0, 3, 2];
    let mut b: Vec<u8> = floor
        .iter()
        .chain(&lamp)
        .chain(&uv)
        .flat_map(|f| f.to_le_bytes())
        .collect();
    b.extend(idx.iter().flat_map(|i| i.to_le_bytes()));
    b.extend([1u8, 0, 0, 0]); // sparse index 1 (u16, padded)
    b.extend([0.0f32, 1.0, 1.5].iter().flat_map(|f| f.to_le_bytes()));
    json!({
        "asset": {"version": "2.0"}, "scene": 0,
        "extensionsUsed": ["KHR_lights_punctual"],
        "extensions": {"KHR_lights_punctual": {"lights": [{"type": "point", "intensity": 10.0}]}},
        "scenes": [{"nodes": [0, 2]}],
        "nodes": [
            {"name": "floor", "mesh": 0, "children": [1, 4], "rotation": [0.0, 0.0, 0.0, 1.0]},
            {"name": "cam", "camera": 0, "translation": [0.5, 0.5, 3.0]},
            {"name": "lamp", "mesh": 1, "scale": [1.0, 1.0, 1.0], "children": [3]},
            {"name": "bulb", "matrix": [1,0,0,0, 0,1,0,0, 0,0,1,0, 0.5,0.5,0.5,1],
             "extensions": {"KHR_lights_punctual": {"light": 0}}},
            {"name": "grille", "mesh": 2, "translation": [0.0, 0.5, 0.0]}
        ],
        "cameras": [{"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.01}}],
        "meshes": [
            {"name": "floor", "primitives": [
                {"attributes": {"POSITION": 0, "TEXCOORD_0": 2}, "indices": 3, "material": 0}
            ]},
            {"name": "lamp", "primitives": [{"attributes": {"POSITION": 1, "TEXCOORD_0": 2}, "indices": 3, "material": 1}]},
            {"name": "grille", "primitives": [
                {"attributes": {"POSITION": 0, "TEXCOORD_0": 2}, "indices": 3, "material": 2, "mode": 4}
            ]}
        ],
        "materials": [
            {"pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.8, 0.8, 1.0], "baseColorTexture": {"index": 0}}},
            {"pbrMetallicRoughness": {"baseColorFactor": [0.0, 0.0, 0.0, 1.0]}, "emissiveFactor": [1.0, 1.0, 1.0],
             "emissiveTexture": {"index": 1}},
            {"alphaMode": "MASK", "alphaCutoff": 0.5, "doubleSided": true,
             "pbrMetallicRoughness": {"baseColorTexture": {"index": 0, "texCoord": 0}}}
        ],
        "textures": [{"source": 0, "sampler": 0}, {"source": 1}],
        "samplers": [{"wrapS": 33648, "wrapT": 10497}],
        "images": [{"uri": data_uri("image/png", png)}, {"uri": data_uri("image/jpeg", jpeg)}],
        "buffers": [{"uri": data_uri("application/octet-stream", &b), "byteLength": b.len()}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 96, "byteStride": 12},
            {"buffer": 0, "byteOffset": 96, "byteLength": 32},
            {"buffer": 0, "byteOffset": 128, "byteLength": 12},
            {"buffer": 0, "byteOffset": 140, "byteLength": 2},
            {"buffer": 0, "byteOffset": 144, "byteLength": 12}
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
             "min": [0.0, 0.0, 0.0], "max": [1.0, 0.0, 1.0]},
            {"bufferView": 0, "byteOffset": 48, "componentType": 5126, "count": 4, "type": "VEC3",
             "min": [0.0, 1.0, 0.0], "max": [1.0, 1.0, 1.0],
             "sparse": {"count": 1, "indices": {"bufferView": 3, "componentType": 5123},
                        "values": {"bufferView": 4}}},
            {"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC2"},
            {"bufferView": 2, "componentType": 5123, "count": 6, "type": "SCALAR"}
        ]
    })
}

/// Values a mutation writes: numbers at and past every boundary, wrong types, hostile URIs.
fn values() -> Vec<Value> {
    let mut v: Vec<Value> = [
        -1i64,
        0,
        1,
        2,
        3,
        4,
        5,
        6,
        7,
        8,
        11,
        12,
        13,
        16,
        47,
        48,
        96,
        99,
        252,
        256,
        5120,
        5121,
        5122,
        5123,
        5125,
        5126,
        65535,
        2147483647,
        4294967295,
        4294967296,
        9007199254740993,
    ]
    .iter()
    .map(|&n| json!(n))
    .collect();
    v.extend([
        json!(-0.0),
        json!(0.5),
        json!(1e300),
        json!(-1e300),
        json!(null),
        json!(true),
        json!("VEC3"),
        json!("SCALAR"),
        json!("MAT4"),
        json!("MASK"),
        json!("BLEND"),
        json!("x"),
        json!([]),
        json!({}),
        json!([0, 0, 0, 0]),
        json!([0, 0, 0, 2]),
        json!([1e30, 0, 0, 1]),
        json!([0, 1]),
        json!([1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 0]),
        json!("../secret.bin"),
        json!("/etc/passwd"),
        json!("file:///etc/passwd"),
        json!("%2e%2e/x"),
        json!("%ff%fe"),
        json!("/dev/zero"),
        json!("data:application/octet-stream;base64,AAAA"),
        json!("data:image/png;base64,iVBORw0KGgo="),
        json!("data:;base64,@@@@"),
    ]);
    v
}

/// Every place in `doc` (JSON pointers to values, objects and arrays), the root excluded.
fn sites(doc: &Value, at: String, out: &mut Vec<String>) {
    match doc {
        Value::Object(m) => {
            for (k, v) in m {
                let p = format!("{at}/{}", k.replace('~', "~0").replace('/', "~1"));
                out.push(p.clone());
                sites(v, p, out);
            }
        }
        Value::Array(a) => {
            for (i, v) in a.iter().enumerate() {
                let p = format!("{at}/{i}");
                out.push(p.clone());
                sites(v, p, out);
            }
        }
        _ => {}
    }
}

/// Keys a mutation may add to an object.
const KEYS: &[&str] = &[
    "byteStride",
    "sparse",
    "bufferView",
    "byteOffset",
    "count",
    "indices",
    "POSITION",
    "TEXCOORD_0",
    "TEXCOORD_1",
    "uri",
    "mimeType",
    "children",
    "mesh",
    "camera",
    "matrix",
    "rotation",
    "source",
    "texCoord",
    "mode",
    "material",
    "alphaMode",
    "normalized",
];

/// `doc` with 1–3 random mutations: a value replaced, a key removed, or a key added.
fn mutate(doc: &Value, rng: &mut ChaCha8Rng, values: &[Value]) -> Value {
    let mut d = doc.clone();
    for _ in 0..rng.random_range(1..=3) {
        let mut all = Vec::new();
        sites(&d, String::new(), &mut all);
        let site = &all[rng.random_range(0..all.len())];
        let value = values[rng.random_range(0..values.len())].clone();
        let (parent, last) = site.rsplit_once('/').unwrap();
        match rng.random_range(0..4) {
            0 => {
                if let Some(Value::Object(m)) = d.pointer_mut(parent) {
                    m.remove(last);
                }
            }
            1 => {
                if let Some(Value::Object(m)) = d.pointer_mut(site) {
                    m.insert(KEYS[rng.random_range(0..KEYS.len())].into(), value);
                }
            }
            _ => {
                if let Some(v) = d.pointer_mut(site) {
                    *v = value;
                }
            }
        }
    }
    d
}

/// Loads `bytes` written as `dir/name`: whether it loaded; a scene that loads must be usable.
fn try_load(dir: &Path, name: &str, bytes: &[u8]) -> bool {
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap();
    let loaded = load(&p);
    if name.starts_with("base") {
        if let Err(e) = &loaded {
            panic!("{e}");
        }
    }
    match loaded {
        Ok(AnyScene::ThreeD(s)) => {
            assert!(s.faces.iter().all(|f| f.area > 0.0 && f.normal.is_finite()));
            let _ = SceneBvh::with_quality(&s, BuildQuality::Medium);
            true
        }
        Ok(_) => true,
        Err(_) => false,
    }
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("gcr-fuzz-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn mutated_gltf_structure_never_panics() {
    harness();
    let dir = scratch("structure");
    let base = document(&png(4, 4), &jpeg(8, 8));
    assert!(
        try_load(&dir, "base.gltf", base.to_string().as_bytes()),
        "the base document loads"
    );
    let values = values();
    let mut rng = ChaCha8Rng::seed_from_u64(0x35);
    let (n, mut loaded) = (8000, 0);
    let before = panics();
    for i in 0..n {
        let doc = mutate(&base, &mut rng, &values);
        if try_load(&dir, "m.gltf", doc.to_string().as_bytes()) {
            loaded += 1;
        }
        assert_eq!(
            panics(),
            before,
            "input {i} panicked (guarded or not): {doc}"
        );
    }
    println!("structure fuzz: {n} mutated documents, {loaded} still loaded");
    assert!(
        loaded > n / 20 && loaded < n,
        "{loaded} of {n} loaded: the mutations miss"
    );
    let _ = std::fs::remove_dir_all(dir);
}

/// Mutates bytes of an image's header region (`head` bytes): the PNG IHDR and the chunk
/// lengths, the JPEG SOF dimensions and segment lengths.
fn mutate_header(image: &[u8], head: usize, rng: &mut ChaCha8Rng) -> Vec<u8> {
    let mut b = image.to_vec();
    for _ in 0..rng.random_range(1..=4) {
        let i = rng.random_range(0..head.min(b.len()));
        b[i] = match rng.random_range(0..3) {
            0 => 0xff,
            1 => 0,
            _ => rng.random(),
        };
    }
    b
}

#[test]
fn mutated_image_headers_never_panic_or_allocate_without_bound() {
    harness();
    let dir = scratch("images");
    let (png, jpeg) = (png(4, 4), jpeg(8, 8));
    let mut rng = ChaCha8Rng::seed_from_u64(0x36);
    let before = panics();
    let mut loaded = 0;
    for i in 0..600 {
        let (p, j) = match i % 2 {
            0 => (mutate_header(&png, 64, &mut rng), jpeg.clone()),
            _ => (png.clone(), mutate_header(&jpeg, 200, &mut rng)),
        };
        // through glTF (data URIs) and through OBJ (map_Kd beside it)
        let doc = document(&p, &j);
        loaded += usize::from(try_load(&dir, "i.gltf", doc.to_string().as_bytes()));
        std::fs::write(dir.join("t.png"), &p).unwrap();
        std::fs::write(dir.join("t.jpg"), &j).unwrap();
        std::fs::write(
            dir.join("s.mtl"),
            "newmtl a\nKd 0.8 0.8 0.8\nmap_Kd t.png\nnewmtl b\nKd 0.5 0.5 0.5\nmap_Kd t.jpg\n\
             newmtl lamp\nKd 0 0 0\nKe 1 1 1\n",
        )
        .unwrap();
        let obj = "mtllib s.mtl\nv 0 0 0\nv 0 0 1\nv 1 0 0\nvt 0 1\nvt 0 0\nvt 1 1\n\
                   usemtl a\nf 1/1 2/2 3/3\nusemtl b\nf 3/3 2/2 1/1\n\
                   v 0 1 0\nv 1 1 0\nv 0 1 1\nusemtl lamp\nf 4 5 6\n";
        loaded += usize::from(try_load(&dir, "s.obj", obj.as_bytes()));
        assert_eq!(panics(), before, "image input {i} panicked");
    }
    println!("image header fuzz: 1200 loads, {loaded} loaded");
    assert!(
        loaded > 0 && loaded < 1200,
        "{loaded} of 1200 loaded: the mutations miss"
    );
    let _ = std::fs::remove_dir_all(dir);
}
