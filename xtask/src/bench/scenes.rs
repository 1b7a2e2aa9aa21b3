//! Benchmarks of the `scenes` group: BVH build and occlusion-ray throughput on generated scenes of 1k to 1M
//! triangles (`--quick`: 1k and 20k), on 1 and 2 threads: bare rays, `SceneBvh::visible`, and the
//! kernel sampler (parameterize + cosines + ray + G); and the peak resident memory of building a scene and
//! its BVH, measured per size in a child process ([`mem_probe`]). Writes `benchmarks-scenes.md` and the
//! plots `figures/scaling-rays.png` and `figures/scaling-memory.png`.

use crate::ctx::Ctx;
use anyhow::{Context, Result};
use std::fmt::Write;

/// Peak memory of one size, from [`mem_probe`]'s child process (bytes, Linux VmHWM).
#[derive(serde::Serialize, serde::Deserialize)]
pub struct MemProbe {
    /// Triangles in the scene.
    pub triangles: usize,
    /// Peak resident memory at the start of the child process.
    pub start: u64,
    /// … after building the scene (`random_boxes`: faces with normals, areas, materials).
    pub scene: u64,
    /// … after building its BVH (`BuildQuality::High`, the default).
    pub bvh: u64,
    /// … after creating the surface and kernel samplers (what a solve builds before its first ray).
    pub samplers: u64,
    /// Resident memory (VmRSS) after the scene is built (its transients freed).
    pub scene_rss: u64,
    /// Resident memory after the BVH build.
    pub bvh_rss: u64,
    /// Seconds for the BVH build.
    pub bvh_s: f64,
}

/// A `/proc/self/status` field in bytes (`VmHWM`, `VmRSS`), Linux only.
fn status_bytes(field: &str) -> Result<u64> {
    let status = std::fs::read_to_string("/proc/self/status")?;
    let line = status
        .lines()
        .find(|l| l.starts_with(field))
        .with_context(|| format!("{field} not in /proc/self/status (Linux only)"))?;
    let kb: u64 = line
        .split_whitespace()
        .nth(1)
        .context("malformed status line")?
        .parse()?;
    Ok(kb * 1024)
}

/// The hidden `xtask mem-probe N` subcommand: builds `random_boxes(N, 1)`, its BVH and samplers, reading
/// the process's peak resident memory after each step, and prints the result as one JSON line.
/// Run in a fresh process per size, so that each peak belongs to that size alone.
pub fn mem_probe(boxes: usize) -> Result<()> {
    // VmHWM, the number gcr reports as `peak_memory_bytes`.
    let peak = || status_bytes("VmHWM:");
    let start = peak()?;
    let scene = scene_sampler::random_boxes(boxes, 1);
    let after_scene = peak()?;
    let scene_rss = status_bytes("VmRSS:")?;
    let t = std::time::Instant::now();
    let bvh = scene_sampler::SceneBvh::new(&scene);
    let bvh_s = t.elapsed().as_secs_f64();
    let after_bvh = peak()?;
    let bvh_rss = status_bytes("VmRSS:")?;
    let surface = scene_sampler::SurfaceSampler::new(&scene);
    let kernel = scene_sampler::KernelSampler::new(&scene, &bvh);
    let after_samplers = peak()?;
    std::hint::black_box((&surface, &kernel));
    let probe = MemProbe {
        triangles: scene.faces.len(),
        start,
        scene: after_scene,
        bvh: after_bvh,
        samplers: after_samplers,
        scene_rss,
        bvh_rss,
        bvh_s,
    };
    println!("{}", serde_json::to_string(&probe)?);
    Ok(())
}

/// Runs [`mem_probe`] in a child process (this executable, hidden subcommand).
fn probe_in_child(boxes: usize) -> Result<MemProbe> {
    let exe = std::env::current_exe()?;
    let out = std::process::Command::new(exe)
        .args(["mem-probe", &boxes.to_string()])
        .output()?;
    anyhow::ensure!(
        out.status.success(),
        "mem-probe {boxes} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let line = String::from_utf8(out.stdout)?;
    Ok(serde_json::from_str(line.trim())?)
}

/// Runs this group's benchmarks and writes its report into `ctx.out`.
pub fn run(ctx: &Ctx) -> Result<()> {
    let sizes: &[(usize, usize)] = if ctx.quick {
        &[(1_000, 20_000), (20_000, 50_000)]
    } else {
        // 0 = the bare Cornell box (38 triangles)
        &[
            (0, 1_000_000),
            (1_000, 1_000_000),
            (10_000, 1_000_000),
            (100_000, 1_000_000),
            (1_000_000, 1_000_000),
        ]
    };
    let mut md = String::from(
        "# scene-sampler throughput\n\n\
         Command: `cargo xtask bench --only scenes` (release). Scene: `scene_sampler::random_boxes(N, 1)` \
         (Cornell box plus random boxes; N = 0 gives the bare Cornell box). Queries: random area-uniform surface-point pairs that face each other \
         (the ones the kernel traces); best of 3 runs each. *bare* = prepared f32 rays through \
         the BVH's occlusion traversal, no face skipping or offsets; *visible* = \
         `SceneBvh::visible`; *kernel* = `KernelSampler::sample` (parameterize 4 numbers, cosines, ray, G), one call per sample; \
         *samples* = the same samples, bit for bit, through the iterator `KernelSampler::samples` (chunks of 1024 per rayon task), which \
         prefetches the surface look-ups of the next three samples while one traces its ray (what gcr's batched sampling, \
         `Domain::rays`, uses); the last two columns: the same bare rays \
         through a BVH built with `medium_build` instead of `very_slow_build`. The machine is shared (2 cores): \
         numbers move by ±10 % between runs.\n\n\
         | triangles | threads | build (s) | bare (M rays/s) | visible (M/s) | kernel (M samples/s) | kernel / bare time | samples (M/s) | samples / bare time | facing pairs | visible pairs | medium build (s) | bare, medium BVH (M rays/s) |\n\
         |---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n",
    );
    let load = || std::fs::read_to_string("/proc/loadavg").unwrap_or_default();
    let load_before = load();
    // (label, [(triangles, M/s)]) for the plot.
    let mut series: Vec<(String, Vec<(f64, f64)>)> = Vec::new();
    let mut push = |label: String, x: usize, y: f64| {
        let x = x as f64;
        match series.iter_mut().find(|s| s.0 == label) {
            Some(s) => s.1.push((x, y)),
            None => series.push((label, vec![(x, y)])),
        }
    };
    for &(tris, queries) in sizes {
        let scene = scene_sampler::random_boxes(tris, 1);
        for threads in [1, 2] {
            let r = scene_sampler::bench::measure(&scene, queries, threads, 7);
            let line = format!(
                "| {} | {} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} | {:.0} % | {:.1} % | {:.2} | {:.2} |",
                r.triangles,
                r.threads,
                r.build_high_s,
                r.bare_rays_per_s / 1e6,
                r.visible_per_s / 1e6,
                r.kernel_samples_per_s / 1e6,
                r.kernel_over_bare,
                r.samples_per_s / 1e6,
                r.samples_over_bare,
                100.0 * r.facing_fraction,
                100.0 * r.visible_fraction,
                r.build_medium_s,
                r.bare_medium_rays_per_s / 1e6
            );
            println!("scenes: {line}");
            writeln!(md, "{line}")?;
            let t = if threads == 1 { "thread" } else { "threads" };
            push(
                format!("bare rays, {threads} {t}"),
                r.triangles,
                r.bare_rays_per_s / 1e6,
            );
            push(
                format!("kernel samples, {threads} {t}"),
                r.triangles,
                r.kernel_samples_per_s / 1e6,
            );
            push(
                format!("kernel samples (prefetching iterator), {threads} {t}"),
                r.triangles,
                r.samples_per_s / 1e6,
            );
        }
    }
    writeln!(
        md,
        "\nLoad average (`/proc/loadavg`) before the throughput runs: {}; after: {}. Other jobs on the \
         machine lower the 2-thread numbers most.",
        load_before.trim(),
        load().trim()
    )?;
    // The same ratios in thread CPU time, less disturbed by other jobs.
    let (cpu_queries, cpu_rounds) = if ctx.quick { (20_000, 3) } else { (150_000, 5) };
    writeln!(
        md,
        "\n### The same ratios in thread CPU time\n\n\
         `scene_sampler::bench::cpu_ratio(scene, {cpu_queries}, {cpu_rounds}, 7)` (also \
         `cargo run --release -p scene-sampler --example kernel_cpu_ratio -- N {cpu_queries} {cpu_rounds}`): one \
         thread, the four passes alternate {cpu_rounds} times over the same {cpu_queries} facing pairs, each \
         keeps its fastest round, timed in the thread's CPU time (`clock_gettime(CLOCK_THREAD_CPUTIME_ID)`), which does not \
         count time spent waiting for a core. Other jobs still share the caches.\n\n\
         | triangles | bare (ns/ray) | visible (ns) | kernel (ns/sample) | samples (ns/sample) | kernel / bare | samples / bare |\n\
         |---:|---:|---:|---:|---:|---:|---:|"
    )?;
    for &(tris, _) in sizes {
        let scene = scene_sampler::random_boxes(tris, 1);
        let t = scene_sampler::bench::cpu_ratio(&scene, cpu_queries, cpu_rounds, 7);
        let line = format!(
            "| {} | {:.0} | {:.0} | {:.0} | {:.0} | {:.2} | {:.2} |",
            scene.faces.len(),
            t.bare,
            t.visible,
            t.kernel,
            t.samples,
            t.kernel / t.bare,
            t.samples / t.bare
        );
        println!("scenes (cpu): {line}");
        writeln!(md, "{line}")?;
    }
    let figures = ctx.out.join("figures");
    std::fs::create_dir_all(&figures)?;
    crate::plot::loglog(
        &figures.join("scaling-rays.png"),
        "Occlusion rays per second against scene size (random_boxes)",
        "triangles",
        "million rays (kernel samples) per second",
        &series,
    )?;

    // Peak memory, one child process per size.
    let mem_sizes: &[usize] = if ctx.quick {
        &[1_000, 20_000]
    } else {
        &[1_000, 10_000, 100_000, 1_000_000]
    };
    writeln!(
        md,
        "\n## Peak resident memory against scene size\n\n\
         Command: the same (`cargo xtask bench --only scenes`); plot `docs/results/figures/scaling-memory.png`. \
         Each size runs in its own child process (`xtask mem-probe N`, hidden), which builds \
         `random_boxes(N, 1)` in memory (no file is parsed), then its BVH (`BuildQuality::High`), then the surface \
         and kernel samplers, and reads the process's peak resident set (`VmHWM`, the same number `gcr` \
         reports as `peak_memory_bytes`) after each step, and the resident set (`VmRSS`) after the scene and \
         after the BVH (what stays allocated; the allocator may keep freed pages). *per triangle* = (peak after \
         the samplers − peak at start) / triangles. The peak after the scene already includes the generator's \
         transients, which is why it can equal the later peaks.\n\n\
         | triangles | peak at start (MiB) | peak after scene (MiB) | peak after BVH (MiB) | peak after samplers (MiB) | resident after scene (MiB) | resident after BVH (MiB) | BVH build (s) | peak per triangle (bytes) |\n\
         |---:|---:|---:|---:|---:|---:|---:|---:|---:|"
    )?;
    let mib = |b: u64| b as f64 / (1024.0 * 1024.0);
    let mut mem_series: Vec<(String, Vec<(f64, f64)>)> = vec![
        ("peak (VmHWM): scene + BVH + samplers".into(), Vec::new()),
        ("resident after the scene (VmRSS)".into(), Vec::new()),
        ("resident after the BVH (VmRSS)".into(), Vec::new()),
    ];
    for &boxes in mem_sizes {
        let p = probe_in_child(boxes)?;
        let per = (p.samplers.saturating_sub(p.start)) as f64 / p.triangles as f64;
        let line = format!(
            "| {} | {:.1} | {:.1} | {:.1} | {:.1} | {:.1} | {:.1} | {:.2} | {:.0} |",
            p.triangles,
            mib(p.start),
            mib(p.scene),
            mib(p.bvh),
            mib(p.samplers),
            mib(p.scene_rss),
            mib(p.bvh_rss),
            p.bvh_s,
            per
        );
        println!("scenes memory: {line}");
        writeln!(md, "{line}")?;
        let x = p.triangles as f64;
        mem_series[0].1.push((x, mib(p.samplers)));
        mem_series[1].1.push((x, mib(p.scene_rss)));
        mem_series[2].1.push((x, mib(p.bvh_rss)));
    }
    crate::plot::loglog(
        &figures.join("scaling-memory.png"),
        "Memory of scene + BVH build against scene size (one process per size)",
        "triangles",
        "resident memory (MiB)",
        &mem_series,
    )?;
    writeln!(
        md,
        "\n![rays per second](figures/scaling-rays.png)\n\n![peak memory](figures/scaling-memory.png)"
    )?;
    std::fs::write(ctx.out.join("benchmarks-scenes.md"), md)?;
    Ok(())
}
