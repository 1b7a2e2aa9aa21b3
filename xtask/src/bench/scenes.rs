//! Benchmarks of the `scenes` group: BVH build and occlusion-ray throughput on generated scenes of 100k (and,
//! without `--quick`, 1M) triangles, on 1 and 2 threads: bare obvhs rays, `SceneBvh::visible`, and the
//! kernel sampler (parameterize + cosines + ray + G). Writes `benchmarks-scenes.md`.

use crate::Ctx;
use anyhow::Result;
use std::fmt::Write;

/// Runs this group's benchmarks and writes its report into `ctx.out`.
pub fn run(ctx: &Ctx) -> Result<()> {
    let sizes: &[(usize, usize)] = if ctx.quick {
        &[(20_000, 50_000)]
    } else {
        // 0 = the bare Cornell box (38 triangles)
        &[(0, 1_000_000), (100_000, 1_000_000), (1_000_000, 1_000_000)]
    };
    let mut md = String::from(
        "# scene-sampler throughput\n\n\
         Command: `cargo xtask bench --only scenes` (release). Scene: `scene_sampler::random_boxes(N, 1)` \
         (Cornell box plus random boxes; N = 0 gives the bare Cornell box). Queries: random area-uniform surface-point pairs that face each other \
         (the ones the kernel traces); best of 3 runs each. *bare obvhs* = prepared f32 rays through \
         `CwBvh::ray_traverse_miss` + `Triangle::intersect`, as obvhs's examples drive it; *visible* = \
         `SceneBvh::visible`; *kernel* = `KernelSampler::sample` (parameterize 4 numbers, cosines, ray, G); the last two columns: the same bare rays \
         through a BVH built with `medium_build` instead of `very_slow_build`.\n\n\
         | triangles | threads | build (s) | bare obvhs (M rays/s) | visible (M/s) | kernel (M samples/s) | kernel / bare time | facing pairs | visible pairs | medium build (s) | bare obvhs, medium BVH (M rays/s) |\n\
         |---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n",
    );
    for &(tris, queries) in sizes {
        let scene = scene_sampler::random_boxes(tris, 1);
        for threads in [1, 2] {
            let r = scene_sampler::bench::measure(&scene, queries, threads, 7);
            let line = format!(
                "| {} | {} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} | {:.0} % | {:.1} % | {:.2} | {:.2} |",
                r.triangles,
                r.threads,
                r.build_high_s,
                r.bare_rays_per_s / 1e6,
                r.visible_per_s / 1e6,
                r.kernel_samples_per_s / 1e6,
                r.kernel_over_bare,
                100.0 * r.facing_fraction,
                100.0 * r.visible_fraction,
                r.build_medium_s,
                r.bare_medium_rays_per_s / 1e6
            );
            println!("scenes: {line}");
            writeln!(md, "{line}")?;
        }
    }
    std::fs::write(ctx.out.join("benchmarks-scenes.md"), md)?;
    Ok(())
}
