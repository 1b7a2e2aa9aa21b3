//! Lights other than emitting faces by two independent estimators: `gcr`'s paths gather (with
//! its shared neighbour paths and sky portals) against the `baselines` path-traced reference, at
//! the work plane of the shipped side-lit room lit by a sun through its window, a CIE overcast
//! sky and a lamp. Each point is compared relative to its value (a sun patch is 40× the rest).

use baselines::Adaptive;
use gcr::{Domain, Emitters, Trained};
use glam::DVec3;
use scene_sampler::{KernelSampler, Lighting, SceneBvh};

#[test]
fn gcr_and_the_reference_agree_under_sun_sky_and_lamp() {
    let mut scene = scene_sampler::load(gcr_tests::workspace_path("scenes/side-lit-room.obj"))
        .unwrap()
        .into_3d()
        .unwrap();
    let lighting: Lighting = serde_json::from_str(
        r#"{ "sun": { "azimuth": 160, "elevation": 35, "illuminance": 50000 },
             "sky": { "model": "cie-overcast", "illuminance": 10000 },
             "portals": [ [[1.2, 0.9, 5], [2.8, 0.9, 5], [2.8, 2.1, 5], [1.2, 2.1, 5]] ],
             "point_lights": [ { "position": [0.5, 2.8, 0.5], "intensity": 2000 } ] }"#,
    )
    .unwrap();
    scene.add_lights(lighting.lights().unwrap());
    let at: Vec<(DVec3, DVec3)> =
        scene_sampler::read_probes(gcr_tests::workspace_path("scenes/side-lit-room.pts"))
            .unwrap()
            .iter()
            .map(|p| (p.point, p.normal))
            .collect();
    let bvh = SceneBvh::new(&scene);
    let reference = baselines::pointwise::irradiance_reference_at(
        &scene,
        &bvh,
        &at,
        &Adaptive {
            rel_error: 0.01,
            ..Adaptive::default()
        },
    )
    .unwrap();
    let domain = Domain::ThreeD(KernelSampler::new(&scene, &bvh));
    let config = gcr_tests::paths_to(0.002);
    let trained = Trained::without_networks(&domain, &config);
    let got = gcr::irradiance_at_points(&domain, &trained, &Emitters::new(&domain), &config, &at)
        .unwrap();
    // Σ (d/r)² against Σ (σ_gcr² + σ_ref²)/r²: the two agree within their noise at every point
    let (mut d2, mut var) = (0.0, 0.0);
    for (g, r) in got.iter().zip(&reference) {
        let (a, b) = (g.radiosity[0], r.estimate.mean[0]);
        assert!(b > 0.0 && a > 0.0, "lit: {a} {b}");
        d2 += ((a - b) / b).powi(2);
        var += (g.std_error[0].powi(2) + r.estimate.std_error[0].powi(2)) / (b * b);
    }
    let ratio = d2 / var;
    let rms = (d2 / at.len() as f64).sqrt();
    eprintln!("Σ d² / Σ σ² = {ratio:.3}, rms relative difference {rms:.4}");
    assert!(
        ratio < 3.0,
        "Σ d² / Σ σ² = {ratio} (rms relative difference {rms:.4})"
    );
}
