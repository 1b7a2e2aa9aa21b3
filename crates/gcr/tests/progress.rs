//! Progress of the output gathers (`gcr::observe_gathers`, issue 36 item 5): the observer hears
//! every gather to a target that runs inside it, and only those.

use gcr::{Domain, Emitters, GatherMode, GatherProgress, PathSettings, SolveConfig, Trained};
use scene_sampler::{KernelSampler, SceneBvh, SurfaceSampler};
use std::sync::{Arc, Mutex};

#[test]
fn the_observer_hears_the_gather_to_its_end_and_nothing_after() {
    let scene_sampler::AnyScene::ThreeD(scene) = scene_sampler::builtin("cornell-box").unwrap()
    else {
        unreachable!("cornell-box is 3-D")
    };
    let bvh = SceneBvh::new(&scene);
    let domain = Domain::ThreeD(KernelSampler::new(&scene, &bvh));
    let config = SolveConfig {
        gather: GatherMode::Paths,
        paths: PathSettings {
            target_error: Some(0.05),
            ..PathSettings::default()
        },
        ..SolveConfig::default()
    };
    let trained = Trained::without_networks(&domain, &config);
    let points: Vec<_> = (SurfaceSampler::new(&scene)
        .spread(200, |_| true)
        .into_iter())
    .map(|q| (q.point, q.normal, q.face))
    .collect();
    let heard: Arc<Mutex<Vec<GatherProgress>>> = Arc::default();
    let sink = Arc::clone(&heard);
    let gather = || {
        gcr::radiosity_at_points(&domain, &trained, &Emitters::new(&domain), &config, &points)
            .unwrap()
    };
    let g = gcr::observe_gathers(move |p| sink.lock().unwrap().push(*p), gather);
    let estimate = gcr::relative_std_error(&g).unwrap();
    let heard = std::mem::take(&mut *heard.lock().unwrap());
    assert!(!heard.is_empty());
    let last = heard.last().unwrap();
    assert_eq!(last.phase, "gather");
    assert_eq!(last.points, 200);
    assert_eq!(last.target, 0.05);
    assert_eq!(last.done, 1.0, "{last:?}");
    assert_eq!(last.remaining, Some(0.0), "{last:?}");
    // the last round's bound, which met the target, bounds the estimate
    let bound = last.error.unwrap();
    assert!(bound <= 0.05 && estimate <= bound, "{bound} {estimate}");
    assert!(
        heard
            .windows(2)
            .all(|w| w[0].elapsed <= w[1].elapsed && w[0].rays <= w[1].rays)
    );
    // outside observe_gathers nothing is reported to it
    let again = Arc::new(Mutex::new(0));
    let count = Arc::clone(&again);
    gcr::observe_gathers(move |_| *count.lock().unwrap() += 1, || ());
    gather();
    assert_eq!(*again.lock().unwrap(), 0);
}
