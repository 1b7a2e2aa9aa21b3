//! Loaders on the files in `scenes/`, glTF node transforms, and every malformed-input case giving its error.

use glam::{DVec2, DVec3};
use scene_sampler::*;
use std::path::{Path, PathBuf};

fn scenes_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes")
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("scene-sampler-test-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d.join(name)
}

fn emitted_power(s: &Scene) -> Spectrum {
    s.faces
        .iter()
        .fold(Spectrum::ZERO, |a, f| a + f.emission * f.area)
}

fn close(a: f64, b: f64, rel: f64) -> bool {
    (a - b).abs() <= rel * a.abs().max(b.abs()).max(1e-300)
}

/// Every 3-D built-in, read back from its OBJ and glTF files in `scenes/`, matches the built-in (to f32
/// rounding): triangle count, total area, emitted power per band, band count, per-face normals.
#[test]
fn scenes_dir_files_match_builtins() {
    let dir = scenes_dir();
    for name in BUILTIN_NAMES {
        match builtin(name).unwrap() {
            AnyScene::ThreeD(b) => {
                for ext in ["obj", "gltf"] {
                    let s = load(dir.join(format!("{name}.{ext}")))
                        .unwrap()
                        .into_3d()
                        .unwrap();
                    assert_eq!(s.faces.len(), b.faces.len(), "{name}.{ext}");
                    assert_eq!(s.bands, b.bands, "{name}.{ext}");
                    assert!(close(s.total_area(), b.total_area(), 1e-6), "{name}.{ext}");
                    let (p, q) = (emitted_power(&s), emitted_power(&b));
                    for k in 0..3 {
                        assert!(
                            close(p.0[k], q.0[k], 1e-5),
                            "{name}.{ext}: power {p:?} vs {q:?}"
                        );
                    }
                    let n_ok = s
                        .faces
                        .iter()
                        .zip(&b.faces)
                        .filter(|(x, y)| x.normal.dot(y.normal) > 0.999)
                        .count();
                    if ext == "obj" {
                        assert_eq!(
                            n_ok,
                            b.faces.len(),
                            "{name}.obj keeps face order and winding"
                        );
                    }
                    assert!(s.warnings.is_empty(), "{name}.{ext}: {:?}", s.warnings);
                }
                let probes = read_probes(dir.join(format!("{name}.probes.txt"))).unwrap();
                let snapped = b.snap_probes(&probes, "probes").unwrap();
                assert_eq!(snapped.len(), probes.len());
            }
            AnyScene::Flatland(b) => {
                let s = load(dir.join(format!("{name}.json")))
                    .unwrap()
                    .into_flatland()
                    .unwrap();
                assert_eq!(s.segments, b.segments);
                assert_eq!(s.bands, b.bands);
                assert_eq!(s.view, b.view);
                let probes = read_flat_probes(dir.join(format!("{name}.probes.txt"))).unwrap();
                for (p, q) in b
                    .snap_probes(&probes, "probes")
                    .unwrap()
                    .iter()
                    .zip(&b.segments)
                {
                    assert_eq!(p.normal, q.normal);
                }
            }
        }
    }
}

#[test]
fn builtins_are_sane() {
    let c = builtin("cornell-box").unwrap().into_3d().unwrap();
    assert_eq!(c.bands, 3);
    assert_eq!(c.emitters().len(), 2);
    // the light: 130 mm × 105 mm, E = π·(17, 12, 4)
    let area: f64 = c.emitters().iter().map(|&i| c.faces[i].area).sum();
    assert!(close(area, 0.130 * 0.105, 1e-12));
    assert!(close(
        c.faces[c.emitters()[0]].emission.0[0],
        17.0 * std::f64::consts::PI,
        1e-15
    ));
    assert!(c.warnings.is_empty(), "{:?}", c.warnings);
    // every wall normal points into the room, every block normal away from its block
    let centre = DVec3::new(0.278, 0.274, 0.28);
    for f in &c.faces {
        let name = &c.objects[f.object as usize];
        if !name.contains("block") {
            assert!(f.normal.dot(centre - f.centroid()) > 0.0, "{name}");
        }
    }
    for name in ["wall-floor", "two-blockers", "furnace"] {
        let s = builtin(name).unwrap().into_3d().unwrap();
        assert_eq!(s.bands, 1, "{name}");
        assert!(s.warnings.is_empty(), "{name}: {:?}", s.warnings);
    }
    let f = builtin("furnace").unwrap().into_3d().unwrap();
    assert!(
        f.faces
            .iter()
            .all(|x| x.normal.dot(DVec3::splat(0.5) - x.centroid()) > 0.0)
    );
    let fc = builtin("flatland-corner").unwrap().into_flatland().unwrap();
    assert_eq!(fc.segments[0].normal, DVec2::X);
    assert_eq!(fc.segments[1].normal, DVec2::Y);
    assert!(matches!(
        builtin("nope"),
        Err(SceneError::UnknownBuiltin { .. })
    ));
    assert!(builtin("flatland-corner").unwrap().into_3d().is_err());
    let big = random_boxes(20_000, 1);
    assert!(
        big.faces.len() > 19_000 && big.faces.len() <= 20_000,
        "{}",
        big.faces.len()
    );
}

/// glTF node transforms (translation, scale, rotation, mirroring) are applied, and windings follow mirroring.
#[test]
fn gltf_node_transforms() {
    let b = builtin("wall-floor").unwrap().into_3d().unwrap();
    let mut doc: serde_json::Value = serde_json::from_str(&to_gltf(&b)).unwrap();
    // put all nodes under a parent that translates by (1,2,3), scales by 2 and mirrors x
    let n = doc["nodes"].as_array().unwrap().len();
    doc["nodes"]
        .as_array_mut()
        .unwrap()
        .push(serde_json::json!({
            "name": "parent", "children": (0..n).collect::<Vec<_>>(),
            "translation": [1.0, 2.0, 3.0], "scale": [-2.0, 2.0, 2.0]
        }));
    doc["scenes"][0]["nodes"] = serde_json::json!([n]);
    let p = tmp("transformed.gltf");
    std::fs::write(&p, serde_json::to_string(&doc).unwrap()).unwrap();
    let s = load_gltf(&p).unwrap();
    assert!(close(s.total_area(), 4.0 * b.total_area(), 1e-6));
    assert!(
        (s.bounds.0 - DVec3::new(-1.0, 2.0, 3.0)).length() < 1e-6,
        "{:?}",
        s.bounds
    );
    assert!(
        (s.bounds.1 - DVec3::new(1.0, 4.0, 5.0)).length() < 1e-6,
        "{:?}",
        s.bounds
    );
    // floor still faces up, light still faces down (winding flipped with the mirror)
    let up = s.faces.iter().filter(|f| f.normal.y > 0.99).count();
    let down = s.faces.iter().filter(|f| f.normal.y < -0.99).count();
    assert_eq!((up, down), (2, 2));
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
}

fn write(name: &str, text: &str) -> PathBuf {
    let p = tmp(name);
    std::fs::write(&p, text).unwrap();
    p
}

const MTL: &str =
    "newmtl white\nKd 0.5 0.5 0.5\nnewmtl light\nKd 0 0 0\nKe 1 1 1\nnewmtl bad\nKd 1.2 0.5 0.5\n";

fn obj(body: &str, name: &str) -> Result<Scene> {
    write(&format!("{name}.mtl"), MTL);
    load_obj(write(
        &format!("{name}.obj"),
        &format!("mtllib {name}.mtl\n{body}"),
    ))
}

#[test]
fn malformed_inputs_give_errors() {
    let msg = |e: SceneError| e.to_string();
    // missing file, unsupported format
    assert!(matches!(
        load("/nonexistent/x.obj"),
        Err(SceneError::Io { .. })
    ));
    assert!(matches!(
        load("/nonexistent/x.glb"),
        Err(SceneError::Io { .. })
    ));
    assert!(matches!(
        load("/nonexistent/x.json"),
        Err(SceneError::Io { .. })
    ));
    assert!(matches!(
        load(write("x.ply", "ply")),
        Err(SceneError::UnsupportedFormat { .. })
    ));
    // malformed OBJ / glTF / JSON
    let e = obj("v 0 0 zero\nf 1 1 1\n", "garbage").unwrap_err();
    assert!(matches!(e, SceneError::Parse { .. }), "{e}");
    let e = load(write("bad.gltf", "{\"asset\": 7}")).unwrap_err();
    assert!(matches!(e, SceneError::Parse { .. }), "{e}");
    let e = load(write("bad.glb", "glTF\x02\0\0\0garbage")).unwrap_err();
    assert!(matches!(e, SceneError::Parse { .. }), "{e}");
    let e = load(write("bad.json", "{\"segments\": [{\"a\": [0, 0]}]}")).unwrap_err();
    assert!(matches!(e, SceneError::Parse { .. }) && msg(e).contains("bad.json"));
    // non-finite coordinates
    let e = obj(
        "usemtl light\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv nan 0 0\nf 1 2 3\nf 1 2 4\n",
        "nan",
    )
    .unwrap_err();
    assert!(matches!(e, SceneError::NonFinite { face: 1, .. }), "{e}");
    assert!(msg(e).contains("nan.obj"));
    // reflectance ≥ 1: clamped to RHO_MAX, one warning naming the material (issue 17)
    let s = obj(
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl light\nf 1 2 3\nusemtl bad\nf 1 3 2\n",
        "rho",
    )
    .unwrap();
    assert_eq!(s.faces[1].rho, Spectrum([RHO_MAX, 0.5, 0.5]));
    let w: Vec<_> = s
        .warnings
        .iter()
        .filter(|w| w.contains("clamped"))
        .collect();
    assert!(
        w.len() == 1 && w[0].contains("material `bad`"),
        "{:?}",
        s.warnings
    );
    // no emitter: loads (lights may be given), and is refused by the check the solvers make,
    // with a message that says how to light it
    let dark = obj("usemtl white\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "dark").unwrap();
    let e = dark.check_lit().unwrap_err();
    assert!(matches!(e, SceneError::NoEmitter { .. }), "{e}");
    assert!(e.to_string().contains("--sun"), "{e}");
    let mut lit = dark.clone();
    lit.lights.push(std::sync::Arc::new(
        scene_sampler::Sun::new(glam::DVec3::Z, [1.0; 3], 0.53).unwrap(),
    ));
    lit.check_lit().unwrap();
    // degenerate faces dropped with a count; all degenerate: error
    let s = obj(
        "usemtl light\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 2 0 0\nf 1 2 3\nf 1 2 4\n",
        "degen",
    )
    .unwrap();
    assert_eq!(s.faces.len(), 1);
    assert!(
        s.warnings
            .iter()
            .any(|w| w.contains("dropped 1 degenerate")),
        "{:?}",
        s.warnings
    );
    let e = obj(
        "usemtl light\nv 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n",
        "alldegen",
    )
    .unwrap_err();
    assert!(matches!(e, SceneError::NoFaces { dropped: 1, .. }), "{e}");
    // inconsistent windings reported
    let s = obj(
        "usemtl light\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3\nf 2 4 3\nf 1 2 4\n",
        "wind",
    );
    let s = s.unwrap();
    assert!(
        s.warnings
            .iter()
            .any(|w| w.contains("inconsistent windings")),
        "{:?}",
        s.warnings
    );
    let ok = obj(
        "usemtl light\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3\nf 2 4 3\n",
        "windok",
    )
    .unwrap();
    assert!(ok.warnings.is_empty(), "{:?}", ok.warnings);
    // Flatland: ρ out of range, negative emission, NaN, no emitter
    let f = |t: &str| FlatlandScene::from_json("t", "t.json", t);
    // ρ ≥ 1: clamped with a warning naming the segment (issue 17)
    let s = f(r#"{"segments": [{"a": [0,0], "b": [1,0], "rho": [0.5, 1.0, 0.5], "emission": 1}]}"#)
        .unwrap();
    assert_eq!(s.segments[0].rho, Spectrum([0.5, RHO_MAX, 0.5]));
    assert!(
        s.warnings.len() == 1 && s.warnings[0].contains("segment 0"),
        "{:?}",
        s.warnings
    );
    let e =
        f(r#"{"segments": [{"a": [0,0], "b": [1,0], "rho": 0.5, "emission": -1}]}"#).unwrap_err();
    assert!(
        matches!(&e, SceneError::BadMaterial { material, .. } if material == "segment 0"),
        "{e}"
    );
    let e =
        f(r#"{"segments": [{"a": [0,0], "b": [1,0], "rho": 0.5, "emission": 0}]}"#).unwrap_err();
    assert!(matches!(e, SceneError::NoEmitter { .. }), "{e}");
    let e =
        f(r#"{"segments": [{"a": [0,0], "b": [0,0], "rho": 0.5, "emission": 1}]}"#).unwrap_err();
    assert!(matches!(e, SceneError::NoFaces { dropped: 1, .. }), "{e}");
    let nan = Segment::new(
        DVec2::new(f64::NAN, 0.0),
        DVec2::X,
        Spectrum::ZERO,
        Spectrum::ONE,
        0,
        0,
    );
    let e = FlatlandScene::new("t", "t", vec![nan], vec![], None, false).unwrap_err();
    assert!(matches!(e, SceneError::NonFinite { face: 0, .. }), "{e}");
    let rgb =
        f(r#"{"segments": [{"a": [0,0], "b": [1,0], "rho": [0.1, 0.2, 0.3], "emission": 1}]}"#)
            .unwrap();
    assert_eq!(rgb.bands, 3);
}

#[test]
fn probe_errors() {
    let scene = builtin("cornell-box").unwrap().into_3d().unwrap();
    let e = parse_probes("p.txt", "0 0 0 0 1 0\n0 0 0 1\n").unwrap_err();
    assert!(matches!(e, SceneError::ProbeParse { line: 2, .. }), "{e}");
    assert!(e.to_string().starts_with("p.txt:2:"));
    let e = parse_probes("p.txt", "0 0 x 0 1 0\n").unwrap_err();
    assert!(matches!(e, SceneError::ProbeParse { line: 1, .. }), "{e}");
    let e = parse_probes("p.txt", "0 0 0 0 0 0\n").unwrap_err();
    assert!(e.to_string().contains("zero normal"));
    assert!(matches!(
        read_probes("/nonexistent/p.txt"),
        Err(SceneError::Io { .. })
    ));
    // comments, blank lines; snapping within tolerance, the normal picks the side
    let ps = parse_probes(
        "p.txt",
        "# floor\n\n0.3 0.00001 0.3 0 1 0\n0.3 0.2 0.3 0 1 0\n0.3 0.0 0.3 0 -1 0\n",
    )
    .unwrap();
    assert_eq!(ps.len(), 3);
    let tol = 1e-4;
    let p = scene.snap_probe(&ps[0], tol, "p.txt").unwrap();
    assert_eq!(p.point.y, 0.0);
    assert_eq!(p.normal, DVec3::Y);
    let e = scene.snap_probe(&ps[1], tol, "p.txt").unwrap_err();
    assert!(
        matches!(e, SceneError::ProbeOffSurface { line: 4, .. }),
        "{e}"
    );
    // the floor's back side faces down: the nearest downward-facing surface is far away
    assert!(scene.snap_probe(&ps[2], tol, "p.txt").is_err());
    let fp = parse_flat_probes("f.txt", "0.5 0 0 1\n0.5 0.1 0 1\n").unwrap();
    let fl = builtin("flatland-corner").unwrap().into_flatland().unwrap();
    assert_eq!(fl.snap_probe(&fp[0], 1e-6, "f.txt").unwrap().segment, 1);
    assert!(fl.snap_probe(&fp[1], 1e-6, "f.txt").is_err());
    assert!(parse_flat_probes("f.txt", "1 2 3\n").is_err());
}
