//! glTF `KHR_lights_punctual` (issue 31, item 4): the lights of a glTF file are read with their
//! nodes' transforms, colours, spot cones and ranges, and a bad light is an error naming it.

use glam::DVec3;
use scene_sampler::{Face, Receiver, Scene, Spectrum, load_gltf, to_gltf};
use serde_json::{Value, json};

/// A floor (no emitter) written as glTF, with `lights` and one node per `(light, node fields)`.
fn gltf_with_lights(name: &str, lights: Value, nodes: &[(usize, Value)]) -> std::path::PathBuf {
    let c = |x: f64, z: f64| DVec3::new(x, 0.0, z);
    let r = Spectrum::grey(0.5);
    let faces = vec![
        Face::new(
            [c(-5.0, -5.0), c(-5.0, 5.0), c(5.0, 5.0)],
            r,
            Spectrum::ZERO,
            0,
            0,
        ),
        Face::new(
            [c(-5.0, -5.0), c(5.0, 5.0), c(5.0, -5.0)],
            r,
            Spectrum::ZERO,
            0,
            0,
        ),
    ];
    let floor = Scene::new("floor", "test", faces, vec!["floor".into()], None).unwrap();
    let mut doc: Value = serde_json::from_str(&to_gltf(&floor)).unwrap();
    doc["extensionsUsed"] = json!(["KHR_lights_punctual"]);
    doc["extensions"] = json!({ "KHR_lights_punctual": { "lights": lights } });
    for (light, fields) in nodes {
        let mut node = fields.clone();
        node["extensions"] = json!({ "KHR_lights_punctual": { "light": light } });
        let i = doc["nodes"].as_array().unwrap().len();
        doc["nodes"].as_array_mut().unwrap().push(node);
        doc["scenes"][0]["nodes"]
            .as_array_mut()
            .unwrap()
            .push(json!(i));
    }
    let dir = std::env::temp_dir().join(format!("gltf-lights-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(format!("{name}.gltf"));
    std::fs::write(&path, serde_json::to_string(&doc).unwrap()).unwrap();
    path
}

/// E at the origin of the floor, facing up, from each light (its sample's E·g/p).
fn irradiance_at_origin(scene: &Scene) -> Vec<[f64; 3]> {
    let at = Receiver {
        p: DVec3::ZERO,
        n: DVec3::Y,
    };
    (scene.lights.iter())
        .map(|l| {
            let s = l.sample(&at, [0.5; 2]).expect("reaches the origin");
            s.emission.map(|e| e * s.g / s.pdf)
        })
        .collect()
}

#[test]
fn point_spot_and_directional_lights_are_read_with_their_transforms() {
    let lights = json!([
        { "type": "point", "intensity": 100.0, "color": [1.0, 0.5, 0.25] },
        { "type": "spot", "intensity": 40.0,
          "spot": { "innerConeAngle": 0.2, "outerConeAngle": 0.5 } },
        { "type": "directional", "intensity": 1000.0 }
    ]);
    // the point 2 above the origin; the spot 1 above, rotated to shine down (−Z → −Y: +90° about
    // X); the sun from 60° above the horizon (its node rotated −30° about X: −Z tilted down)
    let (s45, c45) = (
        std::f64::consts::FRAC_PI_4.sin(),
        std::f64::consts::FRAC_PI_4.cos(),
    );
    let half = (-60f64 / 2.0).to_radians();
    let nodes = [
        (0, json!({ "translation": [0.0, 2.0, 0.0] })),
        (
            1,
            json!({ "translation": [0.0, 1.0, 0.0], "rotation": [-s45, 0.0, 0.0, c45] }),
        ),
        (2, json!({ "rotation": [half.sin(), 0.0, 0.0, half.cos()] })),
    ];
    let scene = load_gltf(gltf_with_lights("three", lights, &nodes)).unwrap();
    assert_eq!(scene.lights.len(), 3, "{:?}", scene.lights);
    assert_eq!(scene.bands, 3, "a coloured light makes the scene RGB");
    scene.check_lit().unwrap();
    let mut e = irradiance_at_origin(&scene);
    e.sort_by(|a, b| a[2].total_cmp(&b[2]));
    // point: I/d² per band times the colour: (25, 12.5, 6.25); spot on its axis: 40/1;
    // sun: 1000 · sin 60° (its disc's mean cosine, to 1e-6)
    let want = [
        [25.0, 12.5, 6.25],
        [40.0, 40.0, 40.0],
        [1000.0 * 60f64.to_radians().sin(); 3],
    ];
    for (got, want) in e.iter().zip(&want) {
        for k in 0..3 {
            assert!(
                (got[k] - want[k]).abs() < 1e-3 * want[k],
                "{got:?} vs {want:?}"
            );
        }
    }
}

#[test]
fn a_bad_light_is_an_error_naming_it() {
    let lights = json!([{ "type": "point", "name": "lamp", "intensity": -1.0 }]);
    let e = load_gltf(gltf_with_lights("bad", lights, &[(0, json!({}))])).unwrap_err();
    let m = e.to_string();
    assert!(
        m.contains("`lamp`") && m.contains("KHR_lights_punctual"),
        "{m}"
    );
    let lights = json!([{ "type": "point", "intensity": 1.0, "range": 0.0 }]);
    assert!(load_gltf(gltf_with_lights("range", lights, &[(0, json!({}))])).is_err());
    // a range is honoured: nothing beyond it
    let lights = json!([{ "type": "point", "intensity": 1.0, "range": 1.5 }]);
    let nodes = [(0, json!({ "translation": [0.0, 2.0, 0.0] }))];
    let scene = load_gltf(gltf_with_lights("ranged", lights, &nodes)).unwrap();
    let at = Receiver {
        p: DVec3::ZERO,
        n: DVec3::Y,
    };
    assert!(scene.lights[0].sample(&at, [0.5; 2]).is_none());
}
