//! Scenes with nothing to solve get a clear error or a warning, never a panic or a silent
//! black result (issue: "cannot sample empty range" on a single emitting triangle; an all-black
//! result without a word when every light faces away).

use gcr::{Domain, SolveConfig, SolveError};
use glam::DVec3;
use scene_sampler::{Face, KernelSampler, Scene, SceneBvh, Spectrum};

fn solve(faces: Vec<Face>) -> Result<gcr::Trained, SolveError> {
    let scene = Scene::new("test", "test", faces, vec!["o".into()], None).unwrap();
    let bvh = SceneBvh::new(&scene);
    let domain = Domain::ThreeD(KernelSampler::new(&scene, &bvh));
    let config = SolveConfig {
        kernel_cells: 20,
        ..SolveConfig::default()
    };
    gcr::solve(&domain, &config, &mut |_| {})
}

fn quad(corners: [DVec3; 4], rho: f64, e: f64) -> Vec<Face> {
    let [a, b, c, d] = corners;
    [[a, b, c], [a, c, d]]
        .map(|v| Face::new(v, Spectrum::grey(rho), Spectrum::grey(e), 0, 0))
        .to_vec()
}

#[test]
fn a_single_emitting_triangle_is_an_error_not_a_panic() {
    let light = Face::new(
        [DVec3::ZERO, DVec3::X, DVec3::Y],
        Spectrum::grey(0.5),
        Spectrum::grey(1.0),
        0,
        0,
    );
    match solve(vec![light]) {
        Err(SolveError::NoRays { shots }) => assert!(shots > 0),
        Err(e) => panic!("expected NoRays, got {e}"),
        Ok(_) => panic!("expected NoRays, got a solution"),
    }
}

#[test]
fn lights_facing_away_from_the_scene_give_a_warning() {
    // A floor at y = 0 (normal +y) and a light above it at y = 1 whose normal points up, away
    // from the floor: no light reaches any surface.
    let floor = quad(
        [
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(0.0, 0.0, 1.0),
            DVec3::new(1.0, 0.0, 1.0),
            DVec3::new(1.0, 0.0, 0.0),
        ],
        0.5,
        0.0,
    );
    let light_up = quad(
        [
            DVec3::new(0.2, 1.0, 0.2),
            DVec3::new(0.2, 1.0, 0.8),
            DVec3::new(0.8, 1.0, 0.8),
            DVec3::new(0.8, 1.0, 0.2),
        ],
        0.5,
        1.0,
    );
    assert!(light_up[0].normal.y > 0.0 && floor[0].normal.y > 0.0);
    let trained = solve([floor, light_up].concat()).unwrap();
    assert!(
        trained
            .metrics
            .warnings
            .iter()
            .any(|w| w.contains("lights face away")),
        "warnings: {:?}",
        trained.metrics.warnings
    );
}
