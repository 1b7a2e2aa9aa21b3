//! Irradiance probes (issue 18, item 6): E(y, n) = ∫ L cos θ dω at any point, as Radiance's
//! `rtrace -I`, against exact values.

use gcr::{Domain, Emitters, GatherError, GatherMode, PathSettings, SolveConfig, Trained};
use glam::DVec3;
use scene_sampler::{Face, KernelSampler, Scene, SceneBvh, Spectrum};
use std::f64::consts::PI;

/// The paths gather to a 0.5 % target, without networks (it reads none).
fn config() -> SolveConfig {
    SolveConfig {
        gather: GatherMode::Paths,
        paths: PathSettings {
            target_error: Some(0.005),
            ..PathSettings::default()
        },
        ..SolveConfig::default()
    }
}

fn irradiance(scene: &Scene, config: &SolveConfig, at: &[(DVec3, DVec3)]) -> Vec<gcr::Gathered> {
    let bvh = SceneBvh::new(scene);
    let domain = Domain::ThreeD(KernelSampler::new(scene, &bvh));
    let trained = Trained::without_networks(&domain, config);
    let emitters = Emitters::new(&domain);
    gcr::irradiance_at_points(&domain, &trained, &emitters, config, at).unwrap()
}

/// A light rectangle a×b (E = π, facing down, ρ = 0) at height c over a grey floor, and the
/// point-to-rectangle configuration factor F of a point at height h below its corner, looking
/// up (docs/design/math.md §8): the irradiance there is E·F, on the floor (h = 0) and in the air alike (the
/// floor is behind the point, and nothing reflects back onto it).
fn parallel_rectangle() -> (Scene, impl Fn(f64) -> f64) {
    let (a, b, c) = (1.0, 2.0, 1.5);
    let light = [
        DVec3::new(0.0, c, 0.0),
        DVec3::new(a, c, b),
        DVec3::new(0.0, c, b),
    ];
    let light2 = [
        DVec3::new(0.0, c, 0.0),
        DVec3::new(a, c, 0.0),
        DVec3::new(a, c, b),
    ];
    let floor = [
        DVec3::new(-3.0, 0.0, -3.0),
        DVec3::new(-3.0, 0.0, 3.0),
        DVec3::new(3.0, 0.0, 3.0),
    ];
    let e = Spectrum::grey(PI);
    let faces = vec![
        Face::new(light, Spectrum::ZERO, e, 0, 0),
        Face::new(light2, Spectrum::ZERO, e, 0, 0),
        Face::new(floor, Spectrum::grey(0.5), Spectrum::ZERO, 1, 1),
    ];
    let scene = Scene::new("pr", "test", faces, vec!["l".into(), "f".into()], None).unwrap();
    assert!(scene.faces[0].normal.y < 0.0, "light faces down");
    let exact = move |h: f64| {
        let (x, y) = (a / (c - h), b / (c - h));
        let f = 1.0 / (2.0 * PI)
            * (x / (1.0 + x * x).sqrt() * (y / (1.0 + x * x).sqrt()).atan()
                + y / (1.0 + y * y).sqrt() * (x / (1.0 + y * y).sqrt()).atan());
        PI * f
    };
    (scene, exact)
}

/// Below the light's corner, on the floor and in the air: E·F (converged to 10⁻⁴ of it at a
/// 0.03 % target when this was written; here at 0.5 %).
#[test]
fn irradiance_below_a_light_is_its_configuration_factor() {
    let (scene, exact) = parallel_rectangle();
    let heights = [0.0, 0.3, 0.9, 1.2];
    let at: Vec<_> = heights
        .iter()
        .map(|&h| (DVec3::new(0.0, h, 0.0), DVec3::Y))
        .collect();
    // One point's standard error rests on two replicates (one degree of freedom): the check is
    // against the exact value, at 5× the overall target (0.5 %).
    for (g, &h) in irradiance(&scene, &config(), &at).iter().zip(&heights) {
        let (want, got, se) = (exact(h), g.radiosity[0], g.std_error[0]);
        assert!(se > 0.0 && se < 0.02 * want, "h = {h}: σ = {se}");
        assert!(
            (got / want - 1.0).abs() < 0.025,
            "h = {h}: {got} vs {want} (σ = {se})"
        );
    }
}

/// A point that faces away from every light and surface gets 0; facing down onto the dark side
/// of nothing (the floor's back) too.
#[test]
fn irradiance_facing_nothing_is_zero() {
    let (scene, _) = parallel_rectangle();
    let at = [
        (DVec3::new(0.0, -0.5, 0.0), DVec3::NEG_Y),
        (DVec3::new(0.0, 0.5, 0.0), DVec3::NEG_Y),
    ];
    let got = irradiance(&scene, &config(), &at);
    assert_eq!(got[0].radiosity, [0.0; 3], "below the floor, facing down");
    // Above the floor facing down: the floor's lit front, B = ρ·E·F at its points.
    assert!(got[1].radiosity[0] > 0.0);
}

/// In a furnace (B = E/(1 − ρ) on every wall, uniform radiance) the irradiance at any point
/// inside, for any normal, is that B: unbiased over 100 points in the air with random normals,
/// with standard errors that predict the spread.
#[test]
fn irradiance_in_the_furnace_is_the_radiosity_everywhere() {
    let (e, rho) = (1.0, 0.8);
    let scene = scene_sampler::builtin::furnace(Spectrum::grey(e), Spectrum::grey(rho));
    let exact = e / (1.0 - rho);
    let at: Vec<_> = (1..=100u32)
        .map(|i| {
            let f = |k: f64| (f64::from(i) * k).fract();
            let p = DVec3::new(f(0.754_877_7), f(0.569_840_3), f(0.362_4)) * 0.8 + 0.1;
            let (z, phi) = (2.0 * f(0.618_034) - 1.0, 2.0 * PI * f(0.414_213_6));
            let r = (1.0 - z * z).sqrt();
            (p, DVec3::new(r * phi.cos(), r * phi.sin(), z))
        })
        .collect();
    let got = irradiance(&scene, &config(), &at);
    let (mut sum, mut var, mut err2) = (0.0, 0.0, 0.0);
    for g in &got {
        sum += g.radiosity[0];
        var += g.std_error[0].powi(2);
        err2 += (g.radiosity[0] - exact).powi(2);
    }
    let n = got.len() as f64;
    let mean = sum / n;
    assert!(
        (mean - exact).abs() < 4.0 * var.sqrt() / n,
        "mean {mean} vs {exact} (σ of the mean {})",
        var.sqrt() / n
    );
    let ratio = err2 / var;
    assert!((0.5..2.0).contains(&ratio), "Σ error² / Σ σ² = {ratio}");
}

/// The gathers that estimate radiosity at surface points only say so.
#[test]
fn irradiance_needs_the_paths_gather() {
    let (scene, _) = parallel_rectangle();
    let bvh = SceneBvh::new(&scene);
    let domain = Domain::ThreeD(KernelSampler::new(&scene, &bvh));
    let config = SolveConfig {
        gather: GatherMode::Rays,
        ..SolveConfig::default()
    };
    let trained = Trained::without_networks(&domain, &config);
    let emitters = Emitters::new(&domain);
    let at = [(DVec3::new(0.0, 0.3, 0.0), DVec3::Y)];
    let got = gcr::irradiance_at_points(&domain, &trained, &emitters, &config, &at);
    assert!(matches!(
        got,
        Err(GatherError::IrradianceNeedsPaths("rays"))
    ));
}
