//! Invalid glTF accessors are refused, naming the accessor (issue 35, items 4 and 6): each case
//! here loaded before as wrong geometry with no word (an index accessor longer than its view, or
//! with a stride on its view, read as non-indexed: half of every quad gone; a sparse index past
//! the count ignored) or panicked (a byteStride smaller than the element; a POSITION naming an
//! accessor that does not exist, inside the parser's guard, with the panic text printed). Valid
//! strides and sparse accessors still load, and a rotation that is not a unit quaternion is
//! normalised with a warning.

mod common;

use common::{base64, count_panics, panics};
use scene_sampler::*;
use serde_json::{Value, json};
use std::path::PathBuf;
use std::sync::atomic::{AtomicUsize, Ordering};

/// A floor quad (two triangles, indexed) at y = 0 facing up and a lamp quad at y = 1 facing down,
/// as little-endian bytes: floor positions (48), lamp positions (48), floor indices (12), lamp
/// indices (12), then room for a sparse substitution: index 1 (u16, padded to 4) and (0.5, 0, 0.5).
fn buffer() -> Vec<u8> {
    let floor: [f32; 12] = [0., 0., 0., 1., 0., 0., 1., 0., 1., 0., 0., 1.];
    let lamp: [f32; 12] = [0., 1., 0., 0., 1., 1., 1., 1., 1., 1., 1., 0.];
    let idx: [u16; 12] = [0, 2, 1, 0, 3, 2, 0, 2, 1, 0, 3, 2];
    let mut b: Vec<u8> = floor
        .iter()
        .chain(&lamp)
        .flat_map(|f| f.to_le_bytes())
        .collect();
    b.extend(idx.iter().flat_map(|i| i.to_le_bytes()));
    b.extend([1u8, 0, 0, 0]);
    b.extend([0.5f32, 0.0, 0.5].iter().flat_map(|f| f.to_le_bytes()));
    b
}

/// The valid document over [`buffer`] (embedded as a data URI).
fn document() -> Value {
    let b = buffer();
    let uri = format!("data:application/octet-stream;base64,{}", base64(&b));
    json!({
        "asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0, 1]}],
        "nodes": [{"name": "floor", "mesh": 0}, {"name": "lamp", "mesh": 1}],
        "meshes": [
            {"name": "floor", "primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "material": 0}]},
            {"name": "lamp", "primitives": [{"attributes": {"POSITION": 2}, "indices": 3, "material": 1}]}
        ],
        "materials": [
            {"pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.5, 0.5, 1.0]}},
            {"pbrMetallicRoughness": {"baseColorFactor": [0.0, 0.0, 0.0, 1.0]}, "emissiveFactor": [1.0, 1.0, 1.0]}
        ],
        "buffers": [{"uri": uri, "byteLength": b.len()}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 48},
            {"buffer": 0, "byteOffset": 96, "byteLength": 12},
            {"buffer": 0, "byteOffset": 48, "byteLength": 48},
            {"buffer": 0, "byteOffset": 108, "byteLength": 12},
            {"buffer": 0, "byteOffset": 120, "byteLength": 2},
            {"buffer": 0, "byteOffset": 124, "byteLength": 12}
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
             "min": [0.0, 0.0, 0.0], "max": [1.0, 0.0, 1.0]},
            {"bufferView": 1, "componentType": 5123, "count": 6, "type": "SCALAR"},
            {"bufferView": 2, "componentType": 5126, "count": 4, "type": "VEC3",
             "min": [0.0, 1.0, 0.0], "max": [1.0, 1.0, 1.0]},
            {"bufferView": 3, "componentType": 5123, "count": 6, "type": "SCALAR"}
        ]
    })
}

/// Loads `doc` (written to its own temp file): the scene or the error message; asserts that
/// nothing panicked on the way, not even inside a guard.
fn load_doc(doc: &Value) -> std::result::Result<Scene, String> {
    static COUNT: AtomicUsize = AtomicUsize::new(0);
    count_panics();
    let p: PathBuf = std::env::temp_dir().join(format!(
        "gcr-accessors-{}-{}.gltf",
        std::process::id(),
        COUNT.fetch_add(1, Ordering::Relaxed)
    ));
    std::fs::write(&p, doc.to_string()).unwrap();
    let before = panics();
    let result = load_gltf(&p).map_err(|e| e.to_string());
    let _ = std::fs::remove_file(&p);
    assert_eq!(panics(), before, "a panic while loading");
    result
}

/// The error of loading `doc` changed by `change`; asserts every `words` are in it.
fn refused(change: impl FnOnce(&mut Value), words: &[&str]) -> String {
    let mut doc = document();
    change(&mut doc);
    let err = load_doc(&doc).expect_err("loaded an invalid file");
    for w in words {
        assert!(err.contains(w), "`{w}` not in: {err}");
    }
    err
}

#[test]
fn the_valid_document_loads_both_quads() {
    let scene = load_doc(&document()).unwrap();
    assert_eq!(scene.faces.len(), 4);
    let floor: f64 = scene
        .faces
        .iter()
        .filter(|f| f.emission.max() == 0.0)
        .map(|f| f.area)
        .sum();
    assert!((floor - 1.0).abs() < 1e-12, "floor area {floor}");
}

#[test]
fn a_stride_smaller_than_the_element_is_refused() {
    refused(
        |d| d["bufferViews"][0]["byteStride"] = json!(4),
        &["accessor 0 (POSITION)", "byteStride 4", "12 bytes"],
    );
}

#[test]
fn a_position_naming_no_accessor_is_refused_without_a_panic() {
    refused(
        |d| d["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = json!(99),
        &["POSITION names accessor 99", "4 accessors"],
    );
}

#[test]
fn an_index_accessor_longer_than_its_view_is_refused() {
    refused(
        |d| d["accessors"][1]["count"] = json!(12),
        &[
            "mesh `floor`: accessor 1 (indices)",
            "need 24 bytes",
            "bufferView 1 has 12",
        ],
    );
}

#[test]
fn a_stride_on_an_index_view_is_refused() {
    refused(
        |d| d["bufferViews"][1]["byteStride"] = json!(4),
        &["accessor 1 (indices)", "byteStride", "tightly packed"],
    );
}

#[test]
fn a_view_past_its_buffer_is_refused() {
    refused(
        |d| d["bufferViews"][0]["byteOffset"] = json!(120),
        &["accessor 0 (POSITION)", "bufferView 0"],
    );
}

#[test]
fn attributes_of_different_counts_are_refused() {
    refused(
        |d| {
            d["meshes"][0]["primitives"][0]["attributes"]["TEXCOORD_0"] = json!(4);
            d["accessors"].as_array_mut().unwrap().push(json!(
                {"bufferView": 0, "componentType": 5126, "count": 6, "type": "VEC2"}
            ));
        },
        &["accessor 4 (TEXCOORD_0)", "same count"],
    );
}

/// The sparse substitution of [`buffer`] (vertex `index` ← (0.5, 0, 0.5)) on the floor's positions.
fn sparse_at(d: &mut Value, index: u8) {
    let b = buffer();
    let mut b2 = b.clone();
    b2[120] = index;
    d["buffers"][0]["uri"] = json!(format!(
        "data:application/octet-stream;base64,{}",
        base64(&b2)
    ));
    d["accessors"][0]["sparse"] = json!({"count": 1,
        "indices": {"bufferView": 4, "componentType": 5123}, "values": {"bufferView": 5}});
    d["accessors"][0]["max"] = json!([1.0, 0.0, 1.0]);
}

#[test]
fn a_sparse_index_past_the_count_is_refused() {
    refused(
        |d| sparse_at(d, 7),
        &["accessor 0 (POSITION)", "sparse index 0 is 7", "count 4"],
    );
}

#[test]
fn valid_strides_and_sparse_substitutions_load() {
    // positions interleaved with padding: stride 16 over the same 4 vertices
    let mut doc = document();
    let floor: [f32; 16] = [
        0., 0., 0., 9., 1., 0., 0., 9., 1., 0., 1., 9., 0., 0., 1., 9.,
    ];
    let mut b = buffer();
    b.extend(floor.iter().flat_map(|f| f.to_le_bytes()));
    doc["buffers"][0] = json!({"uri": format!("data:application/octet-stream;base64,{}", base64(&b)),
                               "byteLength": b.len()});
    doc["bufferViews"][0] =
        json!({"buffer": 0, "byteOffset": 136, "byteLength": 64, "byteStride": 16});
    let strided = load_doc(&doc).unwrap();
    let plain = load_doc(&document()).unwrap();
    assert_eq!(strided.faces.len(), 4);
    for (a, b) in strided.faces.iter().zip(&plain.faces) {
        assert_eq!(a.v, b.v);
    }
    // vertex 1 moved to (0.5, 0, 0.5) by a sparse substitution: the floor's area halves
    let mut doc = document();
    sparse_at(&mut doc, 1);
    let scene = load_doc(&doc).unwrap();
    let floor: f64 = scene
        .faces
        .iter()
        .filter(|f| f.emission.max() == 0.0)
        .map(|f| f.area)
        .sum();
    assert!((floor - 0.5).abs() < 1e-12, "floor area {floor}");
}

#[test]
fn a_rotation_of_length_two_is_normalised_with_a_warning() {
    let mut doc = document();
    let half = std::f64::consts::FRAC_1_SQRT_2;
    doc["nodes"][0]["rotation"] = json!([half, 0.0, 0.0, half]);
    let unit = load_doc(&doc).unwrap();
    assert!(unit.warnings.iter().all(|w| !w.contains("rotation")));
    doc["nodes"][0]["rotation"] = json!([2.0 * half, 0.0, 0.0, 2.0 * half]);
    let long = load_doc(&doc).unwrap();
    assert!(
        long.warnings
            .iter()
            .any(|w| w.contains("node 0: rotation") && w.contains("length 2.000000")),
        "{:?}",
        long.warnings
    );
    for (a, b) in unit.faces.iter().zip(&long.faces) {
        for k in 0..3 {
            assert!((a.v[k] - b.v[k]).length() < 1e-6, "{:?} vs {:?}", a.v, b.v);
        }
    }
    doc["nodes"][0]["rotation"] = json!([0.0, 0.0, 0.0, 0.0]);
    let err = load_doc(&doc).err().unwrap();
    assert!(
        err.contains("node 0: rotation") && err.contains("unit quaternion"),
        "{err}"
    );
}
