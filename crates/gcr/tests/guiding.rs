//! Guided bounces (`PathSettings::guiding`, `estimator/guide.rs`) change the sampling, never the
//! answer: in the furnace (B = E/(1 − ρ) exactly, every bounce guided by what the rounds learned)
//! and in the Cornell box (against the unguided gather), with honest standard errors.

use gcr::{Domain, Emitters, GatherMode, Gathered, Guiding, PathSettings, SolveConfig, Trained};
use glam::DVec3;
use scene_sampler::{KernelSampler, Scene, SceneBvh, SurfaceSampler, builtin};

/// B at `n` area-spread points of `scene` by the paths gather to `target`, guided or not.
fn gather(scene: &Scene, n: usize, target: f64, (guiding, seed): (Guiding, u64)) -> Vec<Gathered> {
    let bvh = SceneBvh::new(scene);
    let domain = Domain::ThreeD(KernelSampler::new(scene, &bvh));
    let points: Vec<(DVec3, DVec3, u32)> = SurfaceSampler::new(scene)
        .spread(n, |_| true)
        .into_iter()
        .map(|q| (q.point, q.normal, q.face))
        .collect();
    let config = SolveConfig {
        gather: GatherMode::Paths,
        paths: PathSettings {
            target_error: Some(target),
            guiding,
            ..PathSettings::default()
        },
        seed,
        ..SolveConfig::default()
    };
    let trained = Trained::without_networks(&domain, &config);
    gcr::radiosity_at_points(&domain, &trained, &Emitters::new(&domain), &config, &points).unwrap()
}

/// In the furnace every point's guided B is an unbiased estimate of E/(1 − ρ): the mean over
/// 300 points is within 4 standard errors of it, and the standard errors predict the errors
/// (Σ error² / Σ σ² in [0.5, 2]). Rounds to 0.5 % run several guided rounds.
#[test]
fn guided_bounces_are_unbiased_in_the_furnace() {
    let scene = builtin("furnace").unwrap().into_3d().unwrap();
    let (e, rho) = (scene.faces[0].emission.0[0], scene.faces[0].rho.0[0]);
    let exact = e / (1.0 - rho);
    let g = gather(&scene, 300, 0.005, (Guiding::On, 1));
    let (mut sum, mut var, mut sq) = (0.0, 0.0, 0.0);
    for p in &g {
        let (b, s) = (p.radiosity[0], p.std_error[0]);
        assert!(b.is_finite() && s.is_finite() && s > 0.0, "B {b}, σ {s}");
        sum += b;
        var += s * s;
        sq += (b - exact).powi(2);
    }
    let n = g.len() as f64;
    let (mean, se) = (sum / n, var.sqrt() / n);
    assert!(
        (mean - exact).abs() < 4.0 * se,
        "mean {mean} vs {exact} (±{se})"
    );
    let ratio = sq / var;
    assert!((0.5..2.0).contains(&ratio), "Σ error² / Σ σ² = {ratio}");
    assert!(g.iter().any(|p| p.rays > 64), "one round only");
}

/// In the Cornell box (an emitting face: the guided MIS weights of shadow rays and bounces), the
/// guided and unguided gathers agree at 300 points within their standard errors: per band, the
/// summed difference is within 4 of its standard error, and the squared differences are about the
/// variances the standard errors claim (Σ (a − b)² / Σ (σ_a² + σ_b²) in [0.5, 2]; a ratio of sums:
/// a point's σ has one degree of freedom, so its own z² is heavy-tailed).
#[test]
fn guided_and_unguided_agree_in_the_cornell_box() {
    let scene = builtin("cornell-box").unwrap().into_3d().unwrap();
    let (a, b) = (
        gather(&scene, 300, 0.01, (Guiding::On, 1)),
        gather(&scene, 300, 0.01, (Guiding::Off, 2)),
    );
    for k in 0..3 {
        let (mut d, mut sq, mut var) = (0.0, 0.0, 0.0);
        for (p, q) in a.iter().zip(&b) {
            d += p.radiosity[k] - q.radiosity[k];
            sq += (p.radiosity[k] - q.radiosity[k]).powi(2);
            var += p.std_error[k].powi(2) + q.std_error[k].powi(2);
        }
        assert!(
            d.abs() < 4.0 * var.sqrt(),
            "band {k}: Σ difference {d} (±{})",
            var.sqrt()
        );
        let ratio = sq / var;
        assert!(
            (0.5..2.0).contains(&ratio),
            "band {k}: Σ (a − b)² / Σ σ² = {ratio}"
        );
    }
}

/// `Guiding::Auto` on a scene the pilot round finds easy is exactly `Off`: the same bits. The
/// Cornell box to 2 % (far below `GUIDING_FROM` rays per point), and to 0.1 %, where the pilot
/// predicts more than `GUIDING_FROM` rays but each ray varies little (below `GUIDING_VARIANCE`:
/// guided it took twice as long).
#[test]
fn automatic_guiding_leaves_an_easy_scene_alone() {
    let scene = builtin("cornell-box").unwrap().into_3d().unwrap();
    for target in [0.02, 0.001] {
        let (a, b) = (
            gather(&scene, 200, target, (Guiding::Auto, 1)),
            gather(&scene, 200, target, (Guiding::Off, 1)),
        );
        assert!(a.iter().all(|p| !p.guided));
        assert!(a.iter().zip(&b).all(|(p, q)| p.radiosity == q.radiosity));
    }
}

/// The decision's two conditions ([`Guiding::pays`]): enough rays predicted and enough variance
/// per ray, each alone not enough.
#[test]
fn guiding_pays_for_many_rays_of_hard_light_only() {
    // the pilot's 64 rays: a relative error of 0.3 (6 per ray), 0.02 (0.026 per ray)
    assert!(Guiding::pays(64, 0.3, gcr::GUIDING_FROM));
    assert!(!Guiding::pays(64, 0.3, gcr::GUIDING_FROM - 1));
    assert!(!Guiding::pays(64, 0.02, 20 * gcr::GUIDING_FROM));
    let v = gcr::GUIDING_VARIANCE;
    assert!(Guiding::pays(
        64,
        (v / 64.0).sqrt() * 1.01,
        gcr::GUIDING_FROM
    ));
    assert!(!Guiding::pays(
        64,
        (v / 64.0).sqrt() * 0.99,
        gcr::GUIDING_FROM
    ));
}

/// Guided rounds give the same bits on one thread or three: the guides are learned from every
/// group's records merged in the groups' order, and each group's from its own rays.
#[test]
fn guided_rounds_are_deterministic_across_thread_counts() {
    let scene = builtin("cornell-box").unwrap().into_3d().unwrap();
    let on = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| gather(&scene, 300, 0.01, (Guiding::On, 1)))
    };
    let (one, three) = (on(1), on(3));
    assert!(
        one.iter()
            .zip(&three)
            .all(|(p, q)| p.radiosity == q.radiosity && p.std_error == q.std_error)
    );
    assert!(one.iter().all(|p| p.guided));
}
