//! Kernel-sample vs bare-ray time in thread CPU time, one thread (see `scene_sampler::bench::cpu_ratio`): less
//! disturbed by other jobs than the wall-time `ray_throughput`, for before/after comparisons on a shared machine.
//!
//! `cargo run --release -p scene-sampler --example kernel_cpu_ratio -- [triangles] [queries] [rounds]`

fn main() {
    let mut args = std::env::args().skip(1);
    let tris: usize = args.next().and_then(|a| a.parse().ok()).unwrap_or(100_000);
    let queries: usize = args.next().and_then(|a| a.parse().ok()).unwrap_or(200_000);
    let rounds: usize = args.next().and_then(|a| a.parse().ok()).unwrap_or(5);
    let scene = scene_sampler::random_boxes(tris, 1);
    let t = scene_sampler::bench::cpu_ratio(&scene, queries, rounds, 7);
    println!(
        "{} triangles: bare {:.0} ns | visible {:.0} ns | kernel {:.0} ns | samples {:.0} ns | visible/bare {:.3} | kernel/bare {:.3} | samples/bare {:.3}",
        scene.faces.len(),
        t.bare,
        t.visible,
        t.kernel,
        t.samples,
        t.visible / t.bare,
        t.kernel / t.bare,
        t.samples / t.bare
    );
}
