//! Issue 18 items 1 and 2: cameras (given, the scene's, automatic), resolution, views, linear
//! EXR images and the exposure, through `gcr solve`; bad camera values are errors before the
//! solve.

mod common;

use common::*;

use std::path::{Path, PathBuf};
use std::process::Output;

fn s(p: &Path) -> String {
    p.display().to_string()
}

fn ok(o: &Output) -> String {
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert!(o.status.success(), "failed: {err}");
    err
}

fn metrics(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// Share of pixels with any channel above 16 (of 255).
fn lit_share(path: &Path) -> f64 {
    let img = image::open(path).unwrap().to_rgb8();
    let lit = img.pixels().filter(|p| p.0.iter().any(|&c| c > 16)).count();
    lit as f64 / (img.width() * img.height()) as f64
}

/// An emitting square (Ke = 2, ρ = 0, so B = E = 2π exactly and L = B/π = 2) at y = 1 facing
/// down onto a grey floor at y = 0.
fn lamp_scene(d: &Path) -> PathBuf {
    std::fs::write(
        d.join("lamp.mtl"),
        "newmtl lamp\nKd 0 0 0\nKe 2 2 2\nnewmtl grey\nKd 0.5 0.5 0.5\n",
    )
    .unwrap();
    let obj = "mtllib lamp.mtl\n\
        v 0 1 0\nv 1 1 0\nv 1 1 1\nv 0 1 1\n\
        v 0 0 0\nv 1 0 0\nv 1 0 1\nv 0 0 1\n\
        o lamp\nusemtl lamp\nf 1 2 3\nf 1 3 4\n\
        o floor\nusemtl grey\nf 5 8 7\nf 5 7 6\n";
    let path = d.join("lamp.obj");
    std::fs::write(&path, obj).unwrap();
    path
}

/// The EXR holds linear radiance L = B/π: looking straight up at the lamp (B = E = 2π) its
/// pixels read 2; the image has the asked-for size, non-square.
#[test]
fn an_exr_image_holds_linear_radiance() {
    let d = dir("img", "exr");
    let scene = lamp_scene(&d);
    let exr = d.join("up.exr");
    let o = gcr(&[
        "solve",
        &s(&scene),
        "--cells",
        "20",
        "--quiet",
        "--image",
        &s(&exr),
        "--resolution",
        "64x48",
        "--camera-eye",
        "0.5,0.2,0.5",
        "--camera-target",
        "0.5,1,0.5",
        "--camera-up",
        "0,0,1",
        "--fov",
        "30",
    ]);
    ok(&o);
    let img = exr::prelude::read_first_rgba_layer_from_file(
        &exr,
        |res, _| (res.width(), vec![[0f32; 3]; res.width() * res.height()]),
        |(w, px), pos, (r, g, b, _a): (f32, f32, f32, f32)| px[pos.y() * *w + pos.x()] = [r, g, b],
    )
    .unwrap();
    let size = img.layer_data.size;
    assert_eq!((size.width(), size.height()), (64, 48));
    let (w, px) = &img.layer_data.channel_data.pixels;
    // The lamp (0.8 units away, 1 wide) covers the whole 30° view: every pixel is L = 2.
    for &p in [px[24 * w + 32], px[0], px[px.len() - 1]].iter() {
        for c in p {
            assert!((c - 2.0).abs() < 1e-4, "L = {c}, expected B/π = 2");
        }
    }
}

/// Reads an EXR's RGB pixels (row-major) and its width.
fn read_exr(path: &Path) -> (usize, Vec<[f32; 3]>) {
    let img = exr::prelude::read_first_rgba_layer_from_file(
        path,
        |res, _| (res.width(), vec![[0f32; 3]; res.width() * res.height()]),
        |(w, px), pos, (r, g, b, _a): (f32, f32, f32, f32)| px[pos.y() * *w + pos.x()] = [r, g, b],
    )
    .unwrap();
    img.layer_data.channel_data.pixels
}

/// `--image-mode pixel` gathers per pixel without the networks (`stopped_by: unused`, a given
/// camera) and agrees with the mesh raster of the same view: the lamp's pixels at L = 2 (all but
/// its outline, where the two filters' sub-samples differ),
/// the floor's mean within 5 % (the mesh's interpolation, the two filters at the floor's edge and
/// both estimators' noise), with the pixel gather's estimated error in the metrics.
#[test]
fn a_pixel_image_agrees_with_the_mesh_raster_and_needs_no_networks() {
    let d = dir("img", "pixel");
    let scene = lamp_scene(&d);
    let view = [
        "--resolution",
        "40x30",
        "--camera-eye",
        "0.5,0.6,-1.2",
        "--camera-target",
        "0.5,0.3,0.5",
        "--fov",
        "50",
    ];
    let mut images = Vec::new();
    let scene = s(&scene);
    for mode in ["mesh", "pixel"] {
        let (exr, m) = (
            d.join(format!("{mode}.exr")),
            d.join(format!("{mode}.json")),
        );
        // 16 sub-samples per pixel: box-filtered edges, as the raster's supersampling.
        let mut args = vec!["solve", &scene, "--quiet", "--image-mode", mode];
        args.extend(["--pixel-samples", if mode == "pixel" { "16" } else { "1" }]);
        let (exr_s, m_s) = (s(&exr), s(&m));
        args.extend(["--image", &exr_s, "--metrics", &m_s]);
        args.extend(view);
        ok(&gcr(&args));
        let m = metrics(&m);
        if mode == "pixel" {
            assert_eq!(m["stopped_by"], "unused");
            assert!(m["relative_std_error"].as_f64().unwrap() <= 0.02);
        }
        images.push(read_exr(&exr));
    }
    let (w, mesh) = &images[0];
    let (_, pixel) = &images[1];
    assert_eq!(mesh.len(), pixel.len());
    // Lamp pixels: L = 2 exactly in both (away from its outline, which the raster's
    // supersampling blends); floor pixels (0 < L < 1.9 in both) compared on average.
    let (mut floor_mesh, mut floor_pixel, mut n, mut lamp, mut exact) = (0.0, 0.0, 0, 0, 0);
    for (a, b) in mesh.iter().zip(pixel) {
        if a[0] == 2.0 {
            assert!(b[0] <= 2.0 + 1e-5, "lamp pixel: mesh {a:?}, pixel {b:?}");
            lamp += 1;
            exact += usize::from((b[0] - 2.0).abs() < 1e-5);
        } else if a[0] > 0.0 && a[0] < 1.9 && b[0] > 0.0 && b[0] < 1.9 {
            floor_mesh += f64::from(a[0]);
            floor_pixel += f64::from(b[0]);
            n += 1;
        }
    }
    assert!(
        n > 100 && lamp > 20,
        "{n} floor pixels, {lamp} lamp pixels of {}",
        w * 30
    );
    assert!(
        exact * 5 >= lamp * 4,
        "{exact} of {lamp} lamp pixels at L = 2"
    );
    let ratio = floor_pixel / floor_mesh;
    assert!((ratio - 1.0).abs() < 0.05, "floor: pixel / mesh = {ratio}");
}

/// `--exposure` is used and recorded; without it the automatic value is recorded and printed.
#[test]
fn the_exposure_is_recorded_in_the_metrics_and_printed() {
    let d = dir("img", "exposure");
    let m = d.join("m.json");
    let base = ["solve", "cornell-box", "--cells", "20", "--metrics", &s(&m)];
    let png = s(&d.join("i.png"));
    let err = ok(&gcr(
        &[&base[..], &["--image", &png, "--exposure", "2.5"]].concat()
    ));
    let j = metrics(&m);
    assert_eq!(j["exposure"], 2.5, "{j}");
    assert_eq!(j["exposure_source"], "given");
    assert!(err.contains("exposure: 2.5 (given"), "{err}");
    let err = ok(&gcr(&[&base[..], &["--image", &png]].concat()));
    let j = metrics(&m);
    let auto = j["exposure"].as_f64().unwrap();
    assert!(auto > 0.0 && auto.is_finite());
    assert_eq!(j["exposure_source"], "auto");
    let printed: f64 = err
        .split_once("exposure: ")
        .and_then(|(_, rest)| rest.split_once(" (auto"))
        .and_then(|(v, _)| v.parse().ok())
        .unwrap_or_else(|| panic!("no automatic exposure printed: {err}"));
    assert!(
        (printed - auto).abs() <= 1e-12 * auto,
        "{printed} vs {auto}"
    );
    // The image's camera is recorded: the built-in's own.
    assert_eq!(j["images"][0]["camera_source"], "scene");
    assert_eq!(j["images"][0]["width"], 512);
    // A brighter exposure makes a brighter image.
    let sum = |p: &str| {
        let img = image::open(p).unwrap().to_rgb8();
        img.pixels().map(|p| p.0[1] as u64).sum::<u64>()
    };
    let dim = sum(&png);
    ok(&gcr(&[
        &base[..],
        &["--image", &png, "--exposure", &(4.0 * auto).to_string()],
    ]
    .concat()));
    assert!(sum(&png) > dim);
}

/// The furnace is a closed box: the automatic camera goes inside and sees lit walls, where the
/// old camera outside the bounding box saw only back faces (100 % black). The scene file
/// without a camera gets the automatic camera by default.
#[test]
fn a_closed_room_with_the_automatic_camera_is_not_black() {
    let d = dir("img", "closed");
    for (scene, extra) in [("cornell-box", None), ("scenes/furnace.obj", None)]
        .into_iter()
        .chain([("furnace", Some("--auto-camera"))])
    {
        let png = d.join("f.png");
        let m = d.join("m.json");
        let (png_arg, m_arg) = (s(&png), s(&m));
        let mut args = vec!["solve", scene, "--cells", "20", "--quiet"];
        args.extend(["--image", &png_arg, "--metrics", &m_arg]);
        args.extend(extra);
        let err = ok(&gcr(&args));
        let j = metrics(&m);
        let source = j["images"][0]["camera_source"]
            .as_str()
            .unwrap()
            .to_string();
        if scene != "cornell-box" {
            assert_eq!(source, "automatic-inside", "{scene}: {j}");
            assert!(j["images"][0]["front_share"].as_f64().unwrap() > 0.99);
        }
        assert!(lit_share(&png) > 0.9, "{scene}: {:.2}", lit_share(&png));
        assert!(!err.contains("warning: image"), "{scene}: {err}");
    }
}

/// An open scene file (the Cornell box OBJ, no front wall) is framed tightly from outside.
#[test]
fn an_open_room_is_framed_tightly() {
    let d = dir("img", "open");
    let (png, m) = (d.join("o.png"), d.join("m.json"));
    let o = gcr(&[
        "solve",
        "scenes/cornell-box.obj",
        "--cells",
        "20",
        "--quiet",
        "--image",
        &s(&png),
        "--metrics",
        &s(&m),
    ]);
    ok(&o);
    let j = metrics(&m);
    assert!(j["images"][0]["front_share"].as_f64().unwrap() > 0.6, "{j}");
    assert!(lit_share(&png) > 0.6);
}

/// A camera looking away from everything writes its (black) image with a warning, on stderr and
/// in the metrics; a view of the same solve is written beside it.
#[test]
fn a_camera_looking_away_warns_and_views_share_the_solve() {
    let d = dir("img", "away");
    let (png, m, view) = (d.join("away.png"), d.join("m.json"), d.join("view.exr"));
    let view_arg = format!("0.278,0.273,-0.8;0.278,0.273,0;0,1,0;39={}", s(&view));
    let o = gcr(&[
        "solve",
        "cornell-box",
        "--cells",
        "20",
        "--image",
        &s(&png),
        "--metrics",
        &s(&m),
        "--camera-eye",
        "0.278,0.273,-0.8",
        "--camera-target",
        "0.278,0.273,-2",
        "--view",
        &view_arg,
    ]);
    let err = ok(&o);
    assert!(err.contains("warning: image"), "{err}");
    assert!(err.contains("away.png"), "{err}");
    assert!(lit_share(&png) < 0.01);
    let j = metrics(&m);
    let warnings = j["warnings"].as_array().unwrap();
    assert!(
        warnings
            .iter()
            .any(|w| w.as_str().unwrap().contains("away.png"))
    );
    assert_eq!(j["images"][1]["camera_source"], "view");
    assert!(j["images"][1]["front_share"].as_f64().unwrap() > 0.8);
    assert!(view.is_file());
}

/// Bad camera values: exit 1 with a clear message before the solve (nothing written), or 2 for
/// what does not parse; never a panic.
#[test]
fn bad_camera_values_are_errors_before_the_solve() {
    let d = dir("img", "bad");
    let png = s(&d.join("i.png"));
    let base = ["solve", "cornell-box", "--cells", "200", "--image", &png];
    let cases: [(&[&str], i32, &str); 12] = [
        (
            &["--camera-eye", "1,1,1", "--camera-target", "1,1,1"],
            1,
            "same point",
        ),
        (
            &["--camera-eye", "nan,0,0", "--camera-target", "0,0,1"],
            1,
            "not finite",
        ),
        (
            &["--camera-eye", "0,0,0", "--camera-target", "0,1,0"],
            1,
            "parallel",
        ),
        (
            &[
                "--camera-eye",
                "0,0,0",
                "--camera-target",
                "0,0,1",
                "--fov",
                "180",
            ],
            1,
            "(0, 180)",
        ),
        (&["--fov", "0"], 1, "(0, 180)"),
        (&["--resolution", "0x10"], 1, "1 to 16384"),
        (&["--resolution", "20000x10"], 1, "1 to 16384"),
        (&["--exposure", "-1"], 1, "exposure"),
        (&["--resolution", "big"], 2, "WIDTHxHEIGHT"),
        (&["--camera-eye", "0,0,0"], 2, "--camera-target"),
        (
            &["--camera-eye", "0,0", "--camera-target", "0,0,1"],
            2,
            "three numbers",
        ),
        (&["--view", "0,0,0=x.png"], 2, "EYE;TARGET"),
    ];
    for (extra, code, needle) in cases {
        let o = gcr(&[&base[..], extra].concat());
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(code), "{extra:?}: {err}");
        assert!(err.contains(needle), "{extra:?}: {err:?} lacks {needle:?}");
        assert!(
            !err.contains("panicked") && !err.contains("FEM"),
            "{extra:?}: {err}"
        );
    }
    let flat = gcr(&["solve", "flatland-corner", "--image", &png, "--fov", "30"]);
    assert_eq!(flat.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&flat.stderr).contains("needs a 3-D scene"));
    let exr = s(&d.join("i.exr"));
    let flat = gcr(&["solve", "flatland-corner", "--image", &exr]);
    assert_eq!(flat.status.code(), Some(1));
    assert!(std::fs::read_dir(&d).unwrap().next().is_none());
}

/// A glTF camera node is the image's camera by default (issue 18 item 1): the node's translation
/// is the eye, its local −Z the view direction, local +Y up, `yfov` the vertical field of view; the
/// metrics record it with source `scene`.
#[test]
fn a_gltf_camera_node_is_the_default_camera() {
    let d = dir("img", "gltf-camera");
    let scene = scene_sampler::builtin("cornell-box")
        .unwrap()
        .into_3d()
        .unwrap();
    let mut doc: serde_json::Value = serde_json::from_str(&scene_sampler::to_gltf(&scene)).unwrap();
    // A camera 0.8 in front of the box, turned 180° about y (−Z → +Z: it looks into the box),
    // with a 30° roll-free vertical field of view.
    let yfov = 30f64.to_radians();
    doc["cameras"] = serde_json::json!([{
        "type": "perspective",
        "perspective": {"yfov": yfov, "znear": 0.01, "aspectRatio": 1.0}
    }]);
    let nodes = doc["nodes"].as_array_mut().unwrap();
    nodes.push(serde_json::json!({
        "name": "cam", "camera": 0,
        "translation": [0.278, 0.273, -0.8], "rotation": [0.0, 1.0, 0.0, 0.0]
    }));
    let cam_node = nodes.len() - 1;
    doc["scenes"][0]["nodes"]
        .as_array_mut()
        .unwrap()
        .push(cam_node.into());
    let path = d.join("box.gltf");
    std::fs::write(&path, doc.to_string()).unwrap();
    let (png, m) = (d.join("box.png"), d.join("m.json"));
    ok(&gcr(&[
        "solve",
        &s(&path),
        "--quiet",
        "--quality",
        "draft",
        "--image-mode",
        "pixel",
        "--resolution",
        "32x32",
        "--image",
        &s(&png),
        "--metrics",
        &s(&m),
    ]));
    let image = &metrics(&m)["images"][0];
    assert_eq!(image["camera_source"], "scene");
    let v = |k: &str| -> Vec<f64> {
        (image[k].as_array().unwrap().iter())
            .map(|x| x.as_f64().unwrap())
            .collect()
    };
    let (eye, target, up) = (v("eye"), v("target"), v("up"));
    for (got, want) in eye.iter().zip([0.278, 0.273, -0.8]) {
        assert!((got - want).abs() < 1e-6, "eye {eye:?}");
    }
    let dir: Vec<f64> = target.iter().zip(&eye).map(|(t, e)| t - e).collect();
    let len = dir.iter().map(|x| x * x).sum::<f64>().sqrt();
    assert!((dir[2] / len - 1.0).abs() < 1e-6, "looks along +z: {dir:?}");
    assert!((up[1] - 1.0).abs() < 1e-6, "up {up:?}");
    let fov = image["fov_y_deg"].as_f64().unwrap();
    assert!((fov - 30.0).abs() < 1e-4, "fov {fov}");
    // Looking into the lit box: most of the image is lit.
    assert!(lit_share(&png) > 0.5, "{}", lit_share(&png));
}

/// A closed room of thick walls (an inner box facing in, an outer one facing out, as models of
/// buildings are) with a lamp inside: from outside the camera sees front faces that no light
/// reaches. The image reports them as not lit and warns; the automatic camera goes inside.
#[test]
fn unlit_outer_walls_are_not_lit_and_the_automatic_camera_goes_inside() {
    let d = dir("img", "closed");
    std::fs::write(
        d.join("room.mtl"),
        "newmtl lamp\nKd 0 0 0\nKe 5 5 5\nnewmtl wall\nKd 0.6 0.6 0.6\n",
    )
    .unwrap();
    let mut obj = String::from("mtllib room.mtl\n");
    for (lo, hi) in [(0.0, 2.0), (-0.1, 2.1)] {
        for z in [lo, hi] {
            for y in [lo, hi] {
                for x in [lo, hi] {
                    obj += &format!("v {x} {y} {z}\n");
                }
            }
        }
    }
    // the six sides of the inner box facing in, of the outer box (vertices 9–16) facing out
    obj += "o walls\nusemtl wall\n";
    for q in [
        [1, 2, 4, 3],
        [5, 7, 8, 6],
        [1, 5, 6, 2],
        [3, 4, 8, 7],
        [1, 3, 7, 5],
        [2, 6, 8, 4],
    ] {
        obj += &format!("f {} {} {} {}\n", q[0], q[1], q[2], q[3]);
        obj += &format!("f {} {} {} {}\n", q[3] + 8, q[2] + 8, q[1] + 8, q[0] + 8);
    }
    obj += "v 0.7 1.9 0.7\nv 1.3 1.9 0.7\nv 1.3 1.9 1.3\nv 0.7 1.9 1.3\n\
            o lamp\nusemtl lamp\nf 17 18 19 20\n";
    let path = d.join("room.obj");
    std::fs::write(&path, obj).unwrap();
    let (png, m) = (d.join("out.png"), d.join("m.json"));
    let run = |camera: &[&str]| {
        let mut args = vec![
            "solve",
            path.to_str().unwrap(),
            "--quality",
            "draft",
            "--resolution",
            "64x48",
            "--image",
            png.to_str().unwrap(),
            "--metrics",
            m.to_str().unwrap(),
        ];
        args.extend_from_slice(camera);
        let err = ok(&gcr(&args));
        (err, metrics(&m)["images"][0].clone())
    };
    let (err, outside) = run(&["--camera-eye", "1,1,-3", "--camera-target", "1,1,1"]);
    assert!(outside["front_share"].as_f64().unwrap() > 0.5, "{outside}");
    assert_eq!(outside["lit_share"].as_f64().unwrap(), 0.0, "{outside}");
    assert!(err.contains("no light reaches"), "{err}");
    assert!(err.contains("0 % of the pixels on lit surfaces"), "{err}");
    let (err, auto) = run(&[]);
    assert_eq!(auto["camera_source"], "automatic-inside", "{auto}");
    assert!(auto["lit_share"].as_f64().unwrap() > 0.9, "{auto}");
    assert!(!err.contains("warning"), "{err}");
}
