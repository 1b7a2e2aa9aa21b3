//! What the front ends (the `gcr` program, the Python package) share: the settings and their
//! defaults ([`SolveOptions`]), probes at a caller's points placed as a probe file's
//! ([`place_probes`]), and images as numbers equal to the `.exr` files
//! ([`render_linear`] against [`write_outputs`]).

use gcr::output::{
    ImageMode, ImageSettings, OutputPaths, OutputPlan, ProbePoints, ProbeSettings, place_probes,
    render_linear, write_outputs,
};
use gcr::{Domain, Quality, SolveConfig, SolveOptions};
use glam::DVec3;
use scene_sampler::{KernelSampler, SceneBvh};
use std::path::Path;
use std::time::Instant;

/// The built-in Cornell box.
fn cornell_box() -> scene_sampler::Scene {
    scene_sampler::builtin("cornell-box")
        .unwrap()
        .into_3d()
        .unwrap()
}

fn workspace(relative: &str) -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .join(relative)
}

#[test]
fn the_default_options_are_the_programs_preset() {
    let options = SolveOptions::default();
    let preset = SolveConfig::preset(Quality::Good);
    assert_eq!(format!("{:?}", options.config()), format!("{preset:?}"));
    // the default gather reads no network: nothing is trained unless an output reads them
    assert!(!options.trains_networks(&options.config(), false));
    assert!(options.trains_networks(&options.config(), true));
    let rays = SolveOptions {
        gather: gcr::GatherMode::Rays,
        ..options
    };
    assert!(rays.trains_networks(&rays.config(), false));
    let draft = SolveOptions {
        quality: Some(Quality::Draft),
        ..SolveOptions::default()
    };
    assert_eq!(draft.config().paths.target_error, Some(0.05));
}

#[test]
fn points_are_placed_as_a_probe_files_lines() {
    let scene = cornell_box();
    let bvh = SceneBvh::new(&scene);
    let domain = Domain::ThreeD(KernelSampler::new(&scene, &bvh));
    let file = workspace("scenes/cornell-box.probes.txt");
    let dir = std::env::temp_dir().join(format!("gcr-front-ends-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let paths = OutputPaths {
        probes_in: Some(file.clone()),
        probe_out: Some(dir.join("out.txt")),
        ..OutputPaths::default()
    };
    let plan = OutputPlan::new(&domain, paths).unwrap();
    let rows: Vec<[f64; 6]> = (std::fs::read_to_string(&file).unwrap().lines())
        .map(|l| {
            let v: Vec<f64> = l.split_whitespace().map(|w| w.parse().unwrap()).collect();
            v.try_into().unwrap()
        })
        .collect();
    let probes = ProbePoints::ThreeD(scene_sampler::probes_from_rows("points", &rows).unwrap());
    let placed = place_probes(&domain, &probes, &ProbeSettings::default(), "points").unwrap();
    assert_eq!(placed, plan.probes());
    // a point off the surfaces is named by its row
    let mut off = rows.clone();
    off[1][1] += 0.05;
    let probes = ProbePoints::ThreeD(scene_sampler::probes_from_rows("points", &off).unwrap());
    let e = place_probes(&domain, &probes, &ProbeSettings::default(), "points").unwrap_err();
    assert!(e.to_string().starts_with("points:2: probe is"), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// The linear image of both modes equals the `.exr` file the output stage writes.
#[test]
fn images_as_numbers_are_the_exr_files() {
    let scene = cornell_box();
    let bvh = SceneBvh::new(&scene);
    let domain = Domain::ThreeD(KernelSampler::new(&scene, &bvh));
    let options = SolveOptions {
        quality: Some(Quality::Draft),
        ..SolveOptions::default()
    };
    let config = options.config();
    let trained = gcr::solve_for_outputs(&domain, &options, &config, false, &mut |_| {}).unwrap();
    let dir = std::env::temp_dir().join(format!("gcr-front-ends-exr-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for mode in [ImageMode::Mesh, ImageMode::Pixel] {
        let settings = ImageSettings {
            width: 24,
            height: 16,
            mode,
            ..ImageSettings::default()
        };
        let linear = render_linear(&domain, &trained, &config, &settings).unwrap();
        let path = dir.join(format!("{mode:?}.exr"));
        let paths = OutputPaths {
            image: Some(path.clone()),
            ..OutputPaths::default()
        };
        let plan = OutputPlan::with_images(&domain, paths, settings).unwrap();
        write_outputs(
            &domain,
            &trained,
            &config,
            &plan,
            "cornell-box",
            Instant::now(),
        )
        .unwrap();
        let file = exr::prelude::read_first_rgba_layer_from_file(
            &path,
            |size, _| vec![[0f32; 3]; size.width() * size.height()],
            |px, pos, (r, g, b, _): (f32, f32, f32, f32)| px[pos.y() * 24 + pos.x()] = [r, g, b],
        )
        .unwrap();
        assert_eq!(
            file.layer_data.channel_data.pixels, linear.radiance.radiance,
            "{mode:?}"
        );
        assert_eq!(linear.camera_source, "scene");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// A mesh-mode image alone gathers B only on the faces its camera sees (and refines them no finer
/// than its pixels): the picture is the whole output mesh's, within the gathers' noise.
#[test]
fn an_image_alone_shows_what_the_whole_mesh_shows() {
    let scene = cornell_box();
    let bvh = SceneBvh::new(&scene);
    let domain = Domain::ThreeD(KernelSampler::new(&scene, &bvh));
    let options = SolveOptions::default();
    let config = options.config();
    let trained = gcr::solve_for_outputs(&domain, &options, &config, false, &mut |_| {}).unwrap();
    // a camera low over the floor, toward the tall block: the ceiling, the light and the block
    // fronts facing away are not seen
    let camera = gcr::output::PinholeCamera {
        eye: DVec3::new(0.5, 0.15, 0.05),
        target: DVec3::new(0.35, 0.05, 0.7),
        up: DVec3::Y,
        fov_y_degrees: 50.0,
    };
    let settings = ImageSettings {
        width: 48,
        height: 32,
        camera: gcr::output::CameraChoice::Given(camera),
        ..ImageSettings::default()
    };
    let seen = render_linear(&domain, &trained, &config, &settings).unwrap();
    let (whole, _) = gcr::output_mesh(
        &domain,
        &trained,
        &config,
        gcr::RetriangulateLimits::default(),
    )
    .unwrap();
    let exposure = gcr::output::Exposure { scale: 1.0 };
    let reference = gcr::output::render_image(&whole, Some(&scene), &camera, &exposure, 48, 32, 2);
    let pi = std::f64::consts::PI;
    let (mut diff, mut total) = (0.0, 0.0);
    for (l, r) in seen
        .radiance
        .radiance
        .iter()
        .zip(reference.pixels.chunks(3))
    {
        let a = exposure.srgb8([0, 1, 2].map(|c| f64::from(l[c]) * pi));
        for c in 0..3 {
            diff += (f64::from(a[c]) - f64::from(r[c])).abs();
            total += f64::from(r[c]);
        }
    }
    assert!(total > 0.0);
    assert!(
        diff / total < 0.05,
        "the view's mesh differs from the whole mesh by {:.1} % of the image",
        100.0 * diff / total
    );
}
