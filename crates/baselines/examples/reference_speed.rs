//! Speed of the pointwise reference (issue target: 1 % standard error at 100 Cornell-box probes in
//! under 60 s on 2 cores), at 100 area-uniform points of the non-emitting faces, two ways:
//!
//! * adaptive (`gcr reference`'s mode): per point, batches of paths until every colour band has at
//!   most 1 % relative standard error — the strictest reading: the blue band on the red wall is
//!   ~1 % of the red one and needs ~10⁶ paths;
//! * fixed paths per point, reporting the relative standard error of each point's grey value
//!   (mean over bands) and over all points and bands (relative L2).
//!
//! `cargo run --release -p baselines --example reference_speed -- [scene] [points] [rel_error] [paths]`

use baselines::Adaptive;
use baselines::pointwise::reference_at;
use scene_sampler::{SceneBvh, SurfaceSampler};
use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let name = args.get(1).map_or("cornell-box", |s| s.as_str());
    let count: usize = args.get(2).map_or(Ok(100), |s| s.parse())?;
    let rel_error: f64 = args.get(3).map_or(Ok(0.01), |s| s.parse())?;
    let fixed: usize = args.get(4).map_or(Ok(20_000), |s| s.parse())?;
    let scene = scene_sampler::builtin(name)?.into_3d()?;
    let bvh = SceneBvh::new(&scene);
    // Spread evenly over the surface, emitters left out.
    let points = SurfaceSampler::new(&scene)
        .spread(count, |p| scene.faces[p.face as usize].emission.is_zero());
    let adaptive = Adaptive {
        rel_error,
        ..Adaptive::default()
    };
    let t = Instant::now();
    let verdicts = reference_at(&scene, &bvh, &points, &adaptive)?;
    let seconds = t.elapsed().as_secs_f64();
    let paths: usize = verdicts.iter().map(|v| v.estimate.paths).sum();
    // the bound of the stopping rule: infinite at a point where no path found light
    let worst = verdicts.iter().map(|v| v.rel_error).fold(0.0, f64::max);
    let capped = verdicts.iter().filter(|v| !v.target_met).count();
    let dark = verdicts
        .iter()
        .filter(|v| v.estimate.mean.iter().all(|&m| m == 0.0))
        .count();
    println!(
        "{name}: {} points, target {:.2} %: {seconds:.1} s on {} threads, {paths} paths \
         ({:.0} per point, {:.2} M paths/s), largest relative standard error {:.3} %, {capped} \
         points at the path cap without meeting the target ({dark} of them found no light at all)",
        points.len(),
        100.0 * rel_error,
        rayon::current_num_threads(),
        paths as f64 / points.len() as f64,
        paths as f64 / seconds / 1e6,
        100.0 * worst
    );
    let t = Instant::now();
    let estimates = baselines::pointwise::radiosity_at(&scene, &bvh, &points, fixed, adaptive.seed);
    let seconds = t.elapsed().as_secs_f64();
    // Bands come from the same paths, so the grey value's error is at most the sum of theirs.
    let grey = estimates
        .iter()
        .map(|e| e.std_error.iter().sum::<f64>() / e.mean.iter().sum::<f64>())
        .fold(0.0, f64::max);
    let (num, den) = estimates.iter().fold((0.0, 0.0), |(n, d), e| {
        (
            n + e.std_error.iter().map(|s| s * s).sum::<f64>(),
            d + e.mean.iter().map(|m| m * m).sum::<f64>(),
        )
    });
    println!(
        "{name}: {} points, {fixed} paths each: {seconds:.1} s, largest relative standard error of \
         a point's grey value {:.3} %, relative L2 standard error over all points and bands {:.3} %",
        points.len(),
        100.0 * grey,
        100.0 * (num / den).sqrt()
    );
    Ok(())
}
