//! The `rays` group (issue 36 item 2): our BVH's ray throughput against Embree's on the same
//! triangles and the same rays. Scenes: the Cornell box cut into 10⁵ and 10⁶ triangles
//! (`tessellated-cornell-N`), 10⁵ random boxes (`random-boxes-100000`, incoherent clutter) and a
//! public model, the temple compound (124 580 triangles of halls, roofs and pagodas over a
//! courtyard: `public_models.rs`; `RAYS_TEMPLE=off` leaves it out).
//! Rays, 2²⁰ of each kind:
//! * **coherent**: a pinhole camera's primary rays (1024²) from inside the box toward its back
//!   (the temple: from the edge of its bounds across the compound);
//! * **incoherent**: from points spread over the surfaces, cosine-distributed about the normal
//!   (the gathers' secondary rays), lifted 10⁻⁴ of the diagonal off the surface.
//!
//! Queries: closest hit (`SceneBvh::closest_hit`, unbounded) and occlusion of the first half of the
//! diagonal (`SceneBvh::segment_clear`), single-threaded and on 2 threads (rayon), against
//! `embreex` (Embree 4; `xtask/py/embree_rays.py`, the same float32 triangles and rays, one
//! process per thread). Both report their hits and the sum of hit distances: agreement is
//! checked. `EMBREE_PYTHON` names the Python that has embreex (default `python3`); without it the
//! Embree columns say so. Writes `benchmarks-rays.md`. Never run by `cargo test`.

use crate::ctx::Ctx;
use anyhow::{Context, Result};
use glam::DVec3;
use rayon::prelude::*;
use scene_sampler::{Scene, SceneBvh, SurfaceSampler, cosine_hemisphere};
use std::fmt::Write;
use std::path::Path;
use std::time::Instant;

/// One ray set: origins and unit directions.
struct Rays {
    name: &'static str,
    rays: Vec<(DVec3, DVec3)>,
}

/// Our timings on one ray set and thread count.
#[derive(Default)]
struct Timing {
    intersect: f64,
    occluded: f64,
    hits: usize,
    t_sum: f64,
    occluded_count: usize,
}

/// A pinhole camera's primary rays, `side²` of them, from `eye` toward `target` (40° across).
fn camera_rays(eye: DVec3, target: DVec3, side: usize) -> Vec<(DVec3, DVec3)> {
    let w = (target - eye).normalize();
    let u = w.cross(DVec3::Y).normalize();
    let v = u.cross(w);
    let half = (20f64).to_radians().tan();
    (0..side * side)
        .map(|i| {
            let (x, y) = ((i % side) as f64 + 0.5, (i / side) as f64 + 0.5);
            let (sx, sy) = (
                (2.0 * x / side as f64 - 1.0) * half,
                (1.0 - 2.0 * y / side as f64) * half,
            );
            (eye, (w + u * sx + v * sy).normalize())
        })
        .collect()
}

/// Cosine rays from `n` points spread over the surfaces (lifted off them), a Halton pair each.
fn surface_rays(scene: &Scene, n: usize) -> Vec<(DVec3, DVec3)> {
    let lift = 1e-4 * scene.diagonal();
    let halton = |mut i: usize, b: usize| {
        let (mut f, mut r) = (1.0, 0.0);
        while i > 0 {
            f /= b as f64;
            r += f * (i % b) as f64;
            i /= b;
        }
        r
    };
    SurfaceSampler::new(scene)
        .spread(n, |_| true)
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let dir = cosine_hemisphere(p.normal, [halton(i + 1, 2), halton(i + 1, 3)]);
            (p.point + p.normal * lift, dir)
        })
        .collect()
}

/// Our BVH on `rays` with `threads` threads.
fn ours(bvh: &SceneBvh, rays: &[(DVec3, DVec3)], tmax: f64, threads: usize) -> Result<Timing> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()?;
    pool.install(|| {
        // best of three runs of each query kind (the machine's other load only slows a run)
        let mut best = Timing {
            intersect: f64::INFINITY,
            occluded: f64::INFINITY,
            ..Timing::default()
        };
        for _ in 0..3 {
            let t0 = Instant::now();
            let hits: Vec<Option<f64>> = rays
                .par_iter()
                .with_min_len(1024)
                .map(|&(o, d)| bvh.closest_hit(o, d, f64::INFINITY, u32::MAX).map(|h| h.t))
                .collect();
            let t1 = Instant::now();
            let blocked = rays
                .par_iter()
                .with_min_len(1024)
                .filter(|&&(o, d)| !bvh.segment_clear(o, o + d * tmax, u32::MAX, u32::MAX))
                .count();
            let t2 = Instant::now();
            best = Timing {
                intersect: best.intersect.min((t1 - t0).as_secs_f64()),
                occluded: best.occluded.min((t2 - t1).as_secs_f64()),
                hits: hits.iter().flatten().count(),
                t_sum: hits.iter().flatten().sum(),
                occluded_count: blocked,
            };
        }
        Ok(best)
    })
}

/// Writes `scene`'s triangles and `rays` as float32 for the Embree script.
fn write_inputs(scene: &Scene, rays: &[(DVec3, DVec3)], tris: &Path, out: &Path) -> Result<()> {
    let f32s = |vs: &mut Vec<u8>, p: DVec3| {
        for c in p.to_array() {
            vs.extend_from_slice(&(c as f32).to_le_bytes());
        }
    };
    let mut t = Vec::with_capacity(scene.faces.len() * 36);
    for f in &scene.faces {
        for v in f.v {
            f32s(&mut t, v);
        }
    }
    std::fs::write(tris, t)?;
    let mut r = Vec::with_capacity(rays.len() * 24);
    for &(o, d) in rays {
        f32s(&mut r, o);
        f32s(&mut r, d);
    }
    std::fs::write(out, r)?;
    Ok(())
}

/// Embree's timing on the files, or why it was skipped.
fn embree(tris: &Path, rays: &Path, tmax: f64, threads: usize) -> Result<Result<Timing, String>> {
    let python = std::env::var("EMBREE_PYTHON").unwrap_or_else(|_| "python3".into());
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("py/embree_rays.py");
    let out = std::process::Command::new(&python)
        .arg(&script)
        .args([tris.as_os_str(), rays.as_os_str()])
        .args([tmax.to_string(), threads.to_string()])
        .output()
        .with_context(|| format!("running {python}"))?;
    let text = String::from_utf8_lossy(&out.stdout);
    let Some(line) = text.lines().last() else {
        return Ok(Err(format!(
            "no output: {}",
            String::from_utf8_lossy(&out.stderr)
        )));
    };
    let v: serde_json::Value = serde_json::from_str(line)?;
    if let Some(why) = v["skipped"].as_str() {
        return Ok(Err(why.to_string()));
    }
    let f = |k: &str| v[k].as_f64().unwrap_or(f64::NAN);
    Ok(Ok(Timing {
        intersect: f("intersect"),
        occluded: f("occluded"),
        hits: f("hits") as usize,
        t_sum: f("t_sum"),
        occluded_count: f("occluded_count") as usize,
    }))
}

/// Runs this group and writes `benchmarks-rays.md` into `ctx.out`.
pub fn run(ctx: &Ctx) -> Result<()> {
    let (sizes, side): (&[&str], usize) = if ctx.quick {
        (&["tessellated-cornell-10000"], 128)
    } else {
        (
            &[
                "tessellated-cornell-100000",
                "tessellated-cornell-1000000",
                "random-boxes-100000",
            ],
            1024,
        )
    };
    let dir = std::env::temp_dir().join(format!("gcr-rays-{}", std::process::id()));
    let mut builds = String::new();
    std::fs::create_dir_all(&dir)?;
    let mut md = String::from(
        "# Ray throughput: our BVH against Embree\n\n\
         Generated by `EMBREE_PYTHON=… cargo xtask bench --only rays` (release; `embreex` from pip \
         in that Python). Million rays per second (Mrays/s), closest hit and occlusion, on the \
         same float32 triangles and rays, best of three runs each; `ratio` = ours / Embree's (the target is ≥ 0.7). Embree \
         runs one process per thread (its `embreex` loop is single-threaded C), ours rayon \
         threads. `agree`: hits and mean hit distance equal within 0.1 %.\n\n\
         | scene | triangles | rays | threads | ours hit | Embree hit | ratio | ours occl. | Embree occl. | ratio | agree |\n\
         |---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    let mut scenes: Vec<(String, Scene)> = Vec::new();
    for name in sizes {
        scenes.push((name.to_string(), scene_sampler::builtin(name)?.into_3d()?));
    }
    // a public model (`RAYS_TEMPLE=off` leaves it out; skipped with a note when not fetchable)
    let mut skipped = String::new();
    if !ctx.quick && std::env::var("RAYS_TEMPLE").map_or(true, |v| v != "off") {
        match super::public_models::temple_compound()
            .and_then(|p| Ok(scene_sampler::load(&p)?.into_3d()?))
        {
            Ok(scene) => scenes.push(("temple compound (public)".into(), scene)),
            Err(why) => writeln!(skipped, "- temple compound (public): skipped ({why:#}).")?,
        }
    }
    for (name, scene) in &scenes {
        let t = Instant::now();
        let bvh = SceneBvh::new(scene);
        let build = t.elapsed().as_secs_f64();
        let tmax = 0.5 * scene.diagonal();
        let (lo, hi) = scene.bounds;
        let eye = DVec3::new(
            0.5 * (lo.x + hi.x),
            0.5 * (lo.y + hi.y),
            hi.z - 0.05 * (hi.z - lo.z),
        );
        let target = DVec3::new(0.5 * (lo.x + hi.x), 0.4 * (lo.y + hi.y), lo.z);
        for set in [
            Rays {
                name: "coherent",
                rays: camera_rays(eye, target, side),
            },
            Rays {
                name: "incoherent",
                rays: surface_rays(scene, side * side),
            },
        ] {
            let (tris, rays) = (dir.join("tris.f32"), dir.join("rays.f32"));
            write_inputs(scene, &set.rays, &tris, &rays)?;
            for threads in [1, 2] {
                let a = ours(&bvh, &set.rays, tmax, threads)?;
                let b = embree(&tris, &rays, tmax, threads)?;
                let mr = |s: f64| set.rays.len() as f64 / s / 1e6;
                let row = match &b {
                    Ok(b) => {
                        let agree = (a.hits as f64 - b.hits as f64).abs() <= 1e-3 * a.hits as f64
                            && (a.t_sum / a.hits.max(1) as f64 - b.t_sum / b.hits.max(1) as f64)
                                .abs()
                                <= 1e-3 * a.t_sum / a.hits.max(1) as f64
                            && (a.occluded_count as f64 - b.occluded_count as f64).abs()
                                <= 1e-3 * set.rays.len() as f64;
                        format!(
                            "{:.2} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} | {}",
                            mr(a.intersect),
                            mr(b.intersect),
                            b.intersect / a.intersect,
                            mr(a.occluded),
                            mr(b.occluded),
                            b.occluded / a.occluded,
                            if agree { "yes" } else { "NO" }
                        )
                    }
                    Err(why) => format!(
                        "{:.2} | – | – | {:.2} | – | – | ({why})",
                        mr(a.intersect),
                        mr(a.occluded)
                    ),
                };
                writeln!(
                    md,
                    "| {name} | {} | {} | {threads} | {row} |",
                    scene.faces.len(),
                    set.name
                )?;
                println!("rays {name} {} {threads}: {row}", set.name);
            }
        }
        writeln!(
            builds,
            "- {name}: our BVH built in {build:.2} s; its node test: {}.",
            bvh.node_test()
        )?;
    }
    std::fs::remove_dir_all(&dir).ok();
    md.push('\n');
    md.push_str(&builds);
    md.push_str(&skipped);
    std::fs::write(ctx.out.join("benchmarks-rays.md"), md)?;
    Ok(())
}
