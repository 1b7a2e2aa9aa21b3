//! Irradiance (`rtrace -I`) by `gcr` against the `baselines` path-traced reference at a work
//! plane in the air of the Cornell box and at floor points: two independent estimators of
//! E = ∫ L cos dω (the gather's Sobol rounds to a target; adaptive path tracing).

use baselines::Adaptive;
use gcr::{Domain, Emitters, Trained};
use glam::DVec3;
use scene_sampler::{KernelSampler, SceneBvh};

#[test]
fn gcr_irradiance_agrees_with_the_path_traced_reference() {
    let scene = scene_sampler::builtin("cornell-box")
        .unwrap()
        .into_3d()
        .unwrap();
    let bvh = SceneBvh::new(&scene);
    // A 4×4 work plane 0.4 above the floor facing up, and 4 floor points facing up.
    let mut at: Vec<(DVec3, DVec3)> = (0..16)
        .map(|i| {
            let (x, z) = (
                0.08 + 0.13 * f64::from(i % 4),
                0.08 + 0.13 * f64::from(i / 4),
            );
            (DVec3::new(x, 0.4, z), DVec3::Y)
        })
        .collect();
    at.extend(
        [0.05, 0.5]
            .iter()
            .flat_map(|&x| [0.05, 0.5].map(|z| (DVec3::new(x, 0.0, z), DVec3::Y))),
    );
    let reference = baselines::pointwise::irradiance_reference_at(
        &scene,
        &bvh,
        &at,
        &Adaptive {
            rel_error: 0.005,
            ..Adaptive::default()
        },
    )
    .unwrap();
    let domain = Domain::ThreeD(KernelSampler::new(&scene, &bvh));
    let config = gcr_tests::paths_to(0.005);
    let trained = Trained::without_networks(&domain, &config);
    let emitters = Emitters::new(&domain);
    let got = gcr::irradiance_at_points(&domain, &trained, &emitters, &config, &at).unwrap();
    // Σ (gcr − ref)² against Σ (σ_gcr² + σ_ref²): the two agree within their noise.
    let (mut d2, mut var, mut norm) = (0.0, 0.0, 0.0);
    for (g, r) in got.iter().zip(&reference) {
        for b in 0..3 {
            d2 += (g.radiosity[b] - r.estimate.mean[b]).powi(2);
            var += g.std_error[b].powi(2) + r.estimate.std_error[b].powi(2);
            norm += r.estimate.mean[b].powi(2);
        }
    }
    let ratio = d2 / var;
    eprintln!(
        "Σ d² / Σ σ² = {ratio:.3}, relative L2 difference {:.4}",
        (d2 / norm).sqrt()
    );
    assert!(
        ratio < 3.0,
        "Σ d² / Σ σ² = {ratio} (relative L2 difference {:.4})",
        (d2 / norm).sqrt()
    );
    assert!((d2 / norm).sqrt() < 0.02, "{}", (d2 / norm).sqrt());
}
