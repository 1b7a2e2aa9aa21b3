//! Output files of `gcr solve` (issue 17): every input and output path is checked before the
//! solve, outputs are all-or-nothing (temporary files beside the targets, renamed at the end), and
//! every write error — the last buffered chunk's included — is reported, naming the file.

mod common;

use common::*;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// A cell budget whose solve takes long enough (over 0.1 s) to print the progress line: an
/// error that comes with no progress line was found before the solve.
const SOLVE_REPORTS: &str = "200";

fn s(p: &Path) -> String {
    p.display().to_string()
}

/// Fails with a clear message naming `needle`, without a panic, and (`before_solve`) without
/// having started the solve: the progress line (which names the FEM steps) never appeared.
fn assert_fails(o: &Output, needle: &str, before_solve: bool) {
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "succeeded: {err}");
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains(needle),
        "message {err:?} does not name {needle:?}"
    );
    assert!(!err.contains("panicked"), "{err}");
    if before_solve {
        assert!(!err.contains("FEM"), "reported only after solving: {err}");
    }
}

/// Issue 17 item 8: a bad probe line (or a probe off the scene) is reported before the solve,
/// and nothing is written.
#[test]
fn a_bad_probe_file_is_reported_before_the_solve_and_nothing_is_written() {
    let d = dir("out", "probes");
    let inputs = dir("out", "probes-in");
    let bad_line = inputs.join("bad.txt");
    std::fs::write(&bad_line, "0.5 0 0.5 0 1 0\n0.5 0 x 0 1 0\n").unwrap();
    let off_surface = inputs.join("off.txt");
    std::fs::write(&off_surface, "0.5 0.3 0.5 0 1 0\n").unwrap();
    for (probes, needle) in [(&bad_line, "bad.txt:2"), (&off_surface, "off.txt")] {
        let o = gcr(&[
            "solve",
            "cornell-box",
            "--cells",
            SOLVE_REPORTS,
            "--probes",
            &s(probes),
            "--probe-out",
            &s(&d.join("b.txt")),
            "--image",
            &s(&d.join("i.png")),
            "--metrics",
            &s(&d.join("m.json")),
        ]);
        assert_fails(&o, needle, true);
        assert!(entries(&d).is_empty(), "{:?}", entries(&d));
    }
}

/// Issue 17 items 8 and 9: `--probe-out b.txt --image i.png --mesh nodir/m.glb` fails before the
/// solve and leaves neither b.txt nor i.png.
#[test]
fn a_missing_output_directory_is_reported_before_the_solve_and_nothing_is_written() {
    let d = dir("out", "nodir");
    let o = gcr(&[
        "solve",
        "cornell-box",
        "--cells",
        SOLVE_REPORTS,
        "--probes",
        "scenes/cornell-box.probes.txt",
        "--probe-out",
        &s(&d.join("b.txt")),
        "--image",
        &s(&d.join("i.png")),
        "--mesh",
        &s(&d.join("nodir/m.glb")),
    ]);
    assert_fails(&o, "nodir", true);
    assert!(entries(&d).is_empty(), "{:?}", entries(&d));
}

/// Issue 17 item 9: `--image out.bmp` (unsupported) is an error before the solve, not a 0-byte
/// file; so are the other formats' wrong extensions and two outputs on one file.
#[test]
fn wrong_extensions_and_shared_targets_are_errors_before_the_solve() {
    let d = dir("out", "ext");
    let cases: [(&str, PathBuf, &str); 3] = [
        ("--image", d.join("out.bmp"), ".png"),
        ("--mesh", d.join("out.gltf"), ".glb"),
        ("--ply", d.join("out.txt"), ".ply"),
    ];
    for (flag, path, needle) in &cases {
        let o = gcr(&[
            "solve",
            "cornell-box",
            "--cells",
            SOLVE_REPORTS,
            flag,
            &s(path),
        ]);
        assert_fails(&o, needle, true);
    }
    let same = s(&d.join("same.png"));
    let o = gcr(&[
        "solve",
        "cornell-box",
        "--cells",
        SOLVE_REPORTS,
        "--image",
        &same,
        "--metrics",
        &same,
    ]);
    assert_fails(&o, "same.png", true);
    assert!(entries(&d).is_empty(), "{:?}", entries(&d));
}

/// Issue 17 item 9 and the .glb message: a write that fails after other outputs were produced
/// (the mesh to a full device) names the file and leaves none of the others.
#[test]
fn a_failed_write_names_the_file_and_leaves_no_other_output() {
    let d = dir("out", "full");
    let o = gcr(&[
        "solve",
        "cornell-box",
        "--cells",
        "20",
        "--quiet",
        "--probes",
        "scenes/cornell-box.probes.txt",
        "--probe-out",
        &s(&d.join("b.txt")),
        "--image",
        &s(&d.join("i.png")),
        "--metrics",
        &s(&d.join("m.json")),
        "--mesh",
        "/dev/full",
    ]);
    assert_fails(&o, "/dev/full", false);
    assert!(entries(&d).is_empty(), "{:?}", entries(&d));
}

/// Issue 17 item 5: a `.ply` whose last buffered chunk cannot be written (here: the file size
/// limit falls inside it) is an error, not exit 0 with a truncated file.
#[test]
fn a_ply_write_error_in_the_last_buffered_chunk_is_reported() {
    let d = dir("out", "ply");
    let args = ["solve", "cornell-box", "--cells", "20", "--quiet", "--ply"];
    let full = d.join("full.ply");
    let o = gcr(&[&args[..], &[&s(&full)]].concat());
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let size = std::fs::metadata(&full).unwrap().len();
    std::fs::remove_file(&full).unwrap();
    // Ignore SIGXFSZ so that writing past the limit is an EFBIG error instead of a kill.
    let cut = d.join("cut.ply");
    let o = Command::new("sh")
        .arg("-c")
        .arg(format!(
            "trap '' XFSZ; exec prlimit --fsize={} \"$0\" \"$@\"",
            size - 1
        ))
        .arg(env!("CARGO_BIN_EXE_gcr"))
        .args(args)
        .arg(&cut)
        .current_dir(ROOT)
        .output()
        .expect("sh and prlimit run");
    assert_fails(&o, "cut.ply", false);
    assert!(entries(&d).is_empty(), "{:?}", entries(&d));
}

/// A successful solve writes exactly the asked-for files (no temporary file left beside them),
/// and replaces an existing target.
#[test]
fn a_successful_solve_writes_exactly_its_outputs() {
    let d = dir("out", "ok");
    std::fs::write(d.join("m.json"), "old").unwrap();
    let o = gcr(&[
        "solve",
        "cornell-box",
        "--cells",
        "20",
        "--quiet",
        "--probes",
        "scenes/cornell-box.probes.txt",
        "--probe-out",
        &s(&d.join("b.txt")),
        "--image",
        &s(&d.join("i.png")),
        "--mesh",
        &s(&d.join("m.glb")),
        "--ply",
        &s(&d.join("m.ply")),
        "--metrics",
        &s(&d.join("m.json")),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(entries(&d), ["b.txt", "i.png", "m.glb", "m.json", "m.ply"]);
    let json = std::fs::read_to_string(d.join("m.json")).unwrap();
    // the new metrics replaced "old"; no output read the networks, so none was trained
    assert!(json.contains("\"scene\": \"cornell-box\""), "{json}");
    assert!(json.contains("\"stopped_by\": \"unused\""), "{json}");
}

/// The JSON chunk of a .glb.
fn glb_json(path: &std::path::Path) -> serde_json::Value {
    let bytes = std::fs::read(path).unwrap();
    let length = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    serde_json::from_slice(&bytes[20..20 + length]).unwrap()
}

/// A lightmap's .glb keeps the materials of an OBJ object with several `usemtl` (the sun patch
/// room is one object: floor 0.4, walls 0.7, ceiling 0.8); one primitive per part and page with
/// the mean albedo made Cycles' bake of the written file 1.7× too bright off the sun patch.
#[test]
fn a_lightmap_keeps_each_material_of_an_object() {
    let d = dir("out", "lightmap-materials");
    let glb = d.join("room.glb");
    let o = gcr(&[
        "solve",
        "scenes/sun-patch-room.obj",
        "--sun",
        "180,30,80000",
        "--quality",
        "draft",
        "--quiet",
        "--lightmap",
        &s(&glb),
        "--lightmap-size",
        "64",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let root = glb_json(&glb);
    let mut albedos: Vec<f64> = (root["materials"].as_array().unwrap().iter())
        .map(|m| {
            m["pbrMetallicRoughness"]["baseColorFactor"][0]
                .as_f64()
                .unwrap()
        })
        .collect();
    albedos.sort_by(f64::total_cmp);
    albedos.dedup_by(|a, b| (*a - *b).abs() < 1e-9);
    let want = [0.4, 0.7, 0.8];
    assert_eq!(albedos.len(), 3, "{albedos:?}");
    for (a, w) in albedos.iter().zip(want) {
        assert!((a - w).abs() < 1e-6, "{albedos:?}");
    }
}

/// `--lightmap out.glb`: the .glb (TEXCOORD_1 on every primitive, the page as a PNG through
/// MOZ_lightmap) and its linear EXR page beside it, the lightmap in the metrics; bad lightmap
/// settings and a Flatland scene are refused before the solve, writing nothing.
#[test]
fn a_lightmap_bake_writes_the_glb_and_its_pages() {
    let d = dir("out", "lightmap");
    let glb = d.join("room.glb");
    let metrics = d.join("m.json");
    let args = [
        "solve",
        "cornell-box",
        "--quality",
        "draft",
        "--quiet",
        "--lightmap",
        &s(&glb),
        "--lightmap-size",
        "128",
        "--metrics",
        &s(&metrics),
    ];
    let o = gcr(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(entries(&d), ["m.json", "room-lightmap-0.exr", "room.glb"]);
    let (doc, _, images) = gltf::import(&glb).expect("a valid glb");
    assert!(doc.extensions_used().any(|e| e == "MOZ_lightmap"));
    for mesh in doc.meshes() {
        for p in mesh.primitives() {
            assert!(p.get(&gltf::Semantic::TexCoords(1)).is_some(), "TEXCOORD_1");
        }
    }
    assert_eq!((images[0].width, images[0].height), (128, 128));
    let m: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&metrics).unwrap()).unwrap();
    assert_eq!(m["lightmap"]["pages"], 1);
    assert!(m["lightmap"]["texels"].as_u64().unwrap() > 5000);
    let exr = image::open(d.join("room-lightmap-0.exr")).expect("an EXR page");
    assert_eq!(exr.width(), 128);

    // The PNG page × MOZ_lightmap.intensity, sRGB-decoded, is the EXR page within one 8-bit step,
    // the brightest texel included (nothing clips), and the material is Lambertian as solved.
    let exr = exr.to_rgb32f();
    let root = glb_json(&glb);
    let json = &root["materials"][0]["extensions"];
    let intensity = json["MOZ_lightmap"]["intensity"].as_f64().unwrap();
    assert_eq!(json["KHR_materials_specular"]["specularFactor"], 0.0);
    let decode = |v: u8| {
        let v = f64::from(v) / 255.0;
        if v <= 0.04045 {
            v / 12.92
        } else {
            ((v + 0.055) / 1.055).powf(2.4)
        }
    };
    let png = &images[0];
    assert_eq!(png.format, gltf::image::Format::R8G8B8);
    let peak = exr.pixels().flat_map(|p| p.0).fold(0.0f32, f32::max);
    for (i, p) in exr.pixels().enumerate() {
        for c in 0..3 {
            let (want, code) = (f64::from(p.0[c]), png.pixels[3 * i + c]);
            let got = decode(code) * intensity;
            let step =
                (decode(code.saturating_add(1)) - decode(code.saturating_sub(1))) * intensity;
            assert!(
                (got - want).abs() <= step,
                "texel {i}: {got} from the PNG, {want} in the EXR"
            );
        }
    }
    let brightest = png.pixels.iter().copied().max().unwrap();
    assert_eq!(
        brightest, 255,
        "the brightest texel maps to 1 (peak {peak})"
    );

    let bad = dir("out", "lightmap-bad");
    let target = s(&bad.join("x.glb"));
    let o = gcr(&[
        "solve",
        "cornell-box",
        "--lightmap",
        &target,
        "--lightmap-size",
        "8",
    ]);
    assert_fails(&o, "page size", true);
    let o = gcr(&[
        "solve",
        "cornell-box",
        "--lightmap",
        &target,
        "--lightmap-density",
        "-1",
    ]);
    assert_fails(&o, "texel density", true);
    let huge = [
        "solve",
        "cornell-box",
        "--lightmap",
        &target,
        "--lightmap-density",
        "1e6",
    ];
    assert_fails(&gcr(&huge), "lower the texel density", false);
    let o = gcr(&["solve", "flatland-corner", "--lightmap", &target]);
    assert_fails(&o, "3-D scene", true);
    assert!(entries(&bad).is_empty());
}

/// A glTF that has lightmap coordinates (`TEXCOORD_1`: here a bake's own output) keeps them: its
/// bake lays nothing out, writes the same coordinates and says so in the metrics.
#[test]
fn a_lightmap_reuses_the_inputs_texcoord_1() {
    let d = dir("out", "lightmap-reuse");
    let bake = |scene: &str, glb: &std::path::Path, metrics: &std::path::Path| {
        let args = [
            "solve",
            scene,
            "--quality",
            "draft",
            "--quiet",
            "--lightmap",
            &s(glb),
            "--lightmap-size",
            "128",
            "--metrics",
            &s(metrics),
        ];
        let o = gcr(&args);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let m: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(metrics).unwrap()).unwrap();
        m["lightmap"].clone()
    };
    // every TEXCOORD_1 corner of a .glb, sorted (the faces may come in another order)
    let uv1 = |glb: &std::path::Path| {
        let (doc, buffers, _) = gltf::import(glb).unwrap();
        let mut all = Vec::new();
        for mesh in doc.meshes() {
            for p in mesh.primitives() {
                let r = p.reader(|b| Some(&buffers[b.index()]));
                all.extend(
                    r.read_tex_coords(1)
                        .unwrap()
                        .into_f32()
                        .map(|[u, v]| (u.to_bits(), v.to_bits())),
                );
            }
        }
        all.sort_unstable();
        all
    };
    let (first, again) = (d.join("first.glb"), d.join("again.glb"));
    let m1 = bake("cornell-box", &first, &d.join("m1.json"));
    assert_eq!(m1["uv_source"], "unwrapped");
    let m2 = bake(&s(&first), &again, &d.join("m2.json"));
    assert_eq!(m2["uv_source"], "input", "{m2}");
    assert_eq!(
        (m2["charts"].as_u64(), m2["width"].as_u64()),
        (Some(0), Some(128))
    );
    assert!(m2["texels"].as_u64().unwrap() > 5000, "{m2}");
    assert_eq!(uv1(&again), uv1(&first));
}
