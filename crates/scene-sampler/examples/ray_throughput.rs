//! Occlusion-ray and kernel-sample throughput on a generated scene (see `scene_sampler::bench`).
//!
//! `cargo run --release -p scene-sampler --example ray_throughput -- [triangles] [queries]`

fn main() {
    let mut args = std::env::args().skip(1);
    let tris: usize = args.next().and_then(|a| a.parse().ok()).unwrap_or(100_000);
    let queries: usize = args
        .next()
        .and_then(|a| a.parse().ok())
        .unwrap_or(1_000_000);
    let t = std::time::Instant::now();
    let scene = scene_sampler::random_boxes(tris, 1);
    println!(
        "generated {} triangles in {:.2} s",
        scene.faces.len(),
        t.elapsed().as_secs_f64()
    );
    for threads in [1, 2] {
        let r = scene_sampler::bench::measure(&scene, queries, threads, 7);
        println!(
            "{threads} thread(s): build {:.2} s | bare {:.2} M rays/s | SceneBvh::visible {:.2} M/s | \
             kernel {:.2} M samples/s | kernel/bare {:.2} | facing pairs {:.0} % | visible {:.1} %",
            r.build_high_s,
            r.bare_rays_per_s / 1e6,
            r.visible_per_s / 1e6,
            r.kernel_samples_per_s / 1e6,
            r.kernel_over_bare,
            100.0 * r.facing_fraction,
            100.0 * r.visible_fraction
        );
    }
}
