//! The README's main command, run in-process (`gcr_cli::run`) with its outputs in a temporary
//! directory: the image decodes at its size and is lit, the .glb parses with the `gltf` crate and
//! matches the metrics, and the metrics JSON has the fields a user reads.

use gcr_tests::{fresh_dir, workspace_path};
use std::path::Path;

/// The first `cargo run … -p gcr-cli -- solve …` line of the top README, as `gcr` arguments.
fn readme_main_command() -> Vec<String> {
    let readme = std::fs::read_to_string(workspace_path("README.md")).unwrap();
    let line = readme
        .lines()
        .find(|l| l.starts_with("cargo run --release -p gcr-cli -- solve "))
        .expect("the README shows the main command");
    let args = line.split_once(" -- ").unwrap().1;
    std::iter::once("gcr")
        .chain(args.split_whitespace())
        .map(String::from)
        .collect()
}

/// The value after `flag` in `args`.
fn value_after<'a>(args: &'a [String], flag: &str) -> &'a str {
    let i = args.iter().position(|a| a == flag).unwrap();
    &args[i + 1]
}

#[test]
fn the_readmes_main_command_writes_a_lit_image_a_valid_mesh_and_metrics() {
    let dir = fresh_dir("readme");
    let mut args = readme_main_command();
    assert_eq!(&args[1..3], ["solve", "cornell-box"], "{args:?}");
    for flag in ["--image", "--mesh", "--metrics"] {
        let i = args.iter().position(|a| a == flag).expect(flag);
        args[i + 1] = dir.join(&args[i + 1]).display().to_string();
    }
    args.push("--quiet".into());
    gcr_cli::run(&args).unwrap();

    let metrics: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(value_after(&args, "--metrics")).unwrap())
            .unwrap();
    assert_eq!(metrics["scene"], "cornell-box");
    assert_eq!(metrics["gather"], "paths");
    assert_eq!(metrics["bands"], 3);
    // nothing in the main command reads the networks: none is trained
    assert_eq!(metrics["kernel_cells"], 0, "{metrics}");
    assert_eq!(metrics["stopped_by"], "unused", "{metrics}");
    assert!(
        metrics["seconds"]["total"].as_f64().unwrap() > 0.0,
        "{metrics}"
    );
    // The default gather corrects every ray: no share of B comes from the networks, and it ran
    // to the default quality's 2 %.
    assert_eq!(metrics["network_share"].as_f64().unwrap(), 0.0, "{metrics}");
    assert_eq!(metrics["target_error"].as_f64().unwrap(), 0.02);
    let e = metrics["relative_std_error"].as_f64().unwrap();
    assert!(e > 0.0 && e <= 0.02, "estimated error {e}");
    // `--guiding auto`'s trial ran before the mesh's last gather, and the Cornell box, whose
    // light plain paths find, keeps no table
    let trial = &metrics["guiding_trial"];
    let v = trial["variance_per_ray"].as_f64().unwrap();
    assert!(v > 0.0 && v.is_finite(), "{trial}");
    assert_eq!(trial["table_kept"], false, "{trial}");

    check_image(Path::new(value_after(&args, "--image")));
    check_mesh(Path::new(value_after(&args, "--mesh")), &metrics);
}

/// 512² pixels, and most of them lit: the camera looks into the box, whose walls fill the view.
fn check_image(path: &Path) {
    let img = image::open(path).unwrap().to_rgb8();
    assert_eq!(img.dimensions(), (512, 512));
    let lit = img.pixels().filter(|p| p.0.iter().any(|&c| c > 16)).count();
    let share = lit as f64 / (512.0 * 512.0);
    assert!(share > 0.5, "only {:.0} % of the pixels lit", 100.0 * share);
}

/// Positions and COLOR_0 on every vertex (over all the bake's primitives: one per input part),
/// counts as in the metrics, colours finite and some lit.
fn check_mesh(path: &Path, metrics: &serde_json::Value) {
    let (doc, buffers, _) = gltf::import(path).unwrap();
    let (mut positions, mut colours, mut indices) = (0, Vec::new(), 0);
    for prim in doc.meshes().flat_map(|m| m.primitives()) {
        let reader = prim.reader(|b| Some(&buffers[b.index()]));
        let n = reader.read_positions().unwrap().count();
        let c: Vec<[f32; 3]> = reader.read_colors(0).unwrap().into_rgb_f32().collect();
        let i: Vec<u32> = reader.read_indices().unwrap().into_u32().collect();
        assert_eq!(c.len(), n);
        assert!(i.iter().all(|&i| (i as usize) < n));
        positions += n;
        indices += i.len();
        colours.extend(c);
    }
    let vertices = metrics["output_vertices"].as_u64().unwrap() as usize;
    let triangles = metrics["output_triangles"].as_u64().unwrap() as usize;
    assert!(vertices > 0);
    assert_eq!(positions, vertices);
    assert_eq!(colours.len(), vertices);
    assert_eq!(indices, 3 * triangles);
    assert!(colours.iter().flatten().all(|c| c.is_finite() && *c >= 0.0));
    assert!(
        colours
            .iter()
            .filter(|c| c.iter().any(|&v| v > 0.05))
            .count()
            > vertices / 2
    );
}
