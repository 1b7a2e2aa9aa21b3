//! The `guiding` group (issue 32): the default paths gather with guided bounces
//! (`Guiding::Auto`, the program's default) against the same gather unguided (`Guiding::Off`),
//! irradiance at 2 000 points, time to a 2 % and a 1 % target, on the shipped hard-indirect rooms
//! (a door gap, a sun patch, a spot aimed at the ceiling) and on two built-ins.
//!
//! Writes `benchmarks-guiding.md`. Both runs estimate their own error (honest: the furnace and
//! the Cornell box tests of `crates/gcr/tests/guiding.rs`); `Σd²/Σσ²` between the two runs checks
//! that they agree (≈ 1 when they differ by their noises alone).

use super::field::Peer;
use crate::ctx::Ctx;
use anyhow::Result;
use gcr::{Gathered, Guiding};
use glam::DVec3;
use scene_sampler::Scene;
use scene_sampler::lights::lighting::Up;
use std::fmt::Write;
use std::time::Instant;

/// A case: its name, the scene, the points (position, normal), and the scene's lights as
/// Mitsuba 3 emitters (`None`: not compared with Mitsuba).
struct Case {
    name: &'static str,
    scene: Scene,
    points: Vec<(DVec3, DVec3)>,
    mitsuba: Option<serde_json::Value>,
}

/// A `nx` × `nz` grid over x0..x1 × z0..z1 at height y, facing `n`.
fn grid(
    (x0, x1, nx): (f64, f64, usize),
    (z0, z1, nz): (f64, f64, usize),
    y: f64,
    n: DVec3,
) -> Vec<(DVec3, DVec3)> {
    let mut out = Vec::with_capacity(nx * nz);
    for i in 0..nx {
        for j in 0..nz {
            let x = x0 + (x1 - x0) * (i as f64 + 0.5) / nx as f64;
            let z = z0 + (z1 - z0) * (j as f64 + 0.5) / nz as f64;
            out.push((DVec3::new(x, y, z), n));
        }
    }
    out
}

/// `n` × `n` points at 0.8 m in each room of `scenes/many-rooms.obj` (5 × 4 rooms of 4 m at a
/// pitch of 4.1 m), facing up.
fn many_rooms_points(n: usize, unlit_only: bool) -> Vec<(DVec3, DVec3)> {
    let mut out = Vec::new();
    for i in 0..5 {
        // the lamps are in the rooms with i + j even (`xtask/py/make_light_scenes.py`)
        for j in (0..4).filter(|j| !unlit_only || (i + j) % 2 == 1) {
            let (x0, z0) = (4.1 * i as f64 + 0.1, 4.1 * j as f64 + 0.1);
            out.extend(grid((x0, x0 + 4.0, n), (z0, z0 + 4.0, n), 0.8, DVec3::Y));
        }
    }
    out
}

/// `scenes/many-rooms.obj` (no lighting file: its lamps are emitting faces).
fn many_rooms() -> Result<Scene> {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes");
    Ok(scene_sampler::load(root.join("many-rooms.obj"))?.into_3d()?)
}

/// A shipped scene with its lighting file (`scenes/<stem>.obj`, `scenes/<stem>.lights.json`).
fn shipped(stem: &str) -> Result<Scene> {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes");
    let mut scene = scene_sampler::load(root.join(format!("{stem}.obj")))?.into_3d()?;
    let lighting = scene_sampler::Lighting::read(&root.join(format!("{stem}.lights.json")))?;
    scene.add_lights(lighting.lights()?);
    Ok(scene)
}

fn cases(quick: bool) -> Result<Vec<Case>> {
    // `GUIDING_POINTS=20000`: about that many points a case instead of 2 000 (the grids' sides
    // scaled by the square root of the ratio)
    let scale = std::env::var("GUIDING_POINTS")
        .ok()
        .and_then(|n| n.parse::<f64>().ok())
        .map_or(1.0, |n| (n / 2000.0).sqrt());
    let side = |n: usize| ((n as f64 * scale).round() as usize).max(2);
    let (a, b) = if quick {
        (10, 10)
    } else {
        (side(50), side(40))
    };
    let builtin = |name: &str| -> Result<Scene> { Ok(scene_sampler::builtin(name)?.into_3d()?) };
    Ok(vec![
        Case {
            name: "door gap: work plane in the unlit room",
            scene: shipped("door-gap")?,
            points: grid((4.15, 8.05, a), (0.05, 2.95, b), 0.8, DVec3::Y),
            mitsuba: Some(
                serde_json::json!({"type": "point", "position": [2.0, 2.2, 1.0],
                                             "intensity": 100.0}),
            ),
        },
        Case {
            name: "sun patch room: under the ceiling, facing down",
            scene: shipped("sun-patch-room")?,
            points: grid((0.05, 5.95, b), (0.05, 7.95, a), 2.95, -DVec3::Y),
            // the lighting file's sun (azimuth 180°, elevation 30°, 80 000 lux) as a delta
            // direction (ours is a 0.53° disc: the same irradiance but at shadow edges)
            mitsuba: Some(serde_json::json!({"type": "directional",
                "direction": (-Up::Y.direction(180.0, 30.0)).to_array(), "irradiance": 80_000.0})),
        },
        Case {
            name: "sun patch room: work plane",
            scene: shipped("sun-patch-room")?,
            points: grid((0.05, 5.95, b), (0.05, 7.95, a), 0.8, DVec3::Y),
            mitsuba: None,
        },
        Case {
            name: "uplight room: work plane",
            scene: shipped("uplight-room")?,
            points: grid((0.05, 5.95, a), (0.05, 5.95, b), 0.8, DVec3::Y),
            mitsuba: None,
        },
        Case {
            name: "many rooms: work planes in 20 rooms, 10 lamps",
            scene: many_rooms()?,
            points: many_rooms_points(if quick { 2 } else { side(10) }, false),
            // the lamps are emitting faces: no emitter beside the mesh's
            mitsuba: Some(serde_json::json!([])),
        },
        Case {
            name: "many rooms: work planes in the 10 unlit rooms",
            scene: many_rooms()?,
            points: many_rooms_points(if quick { 2 } else { side(14) }, true),
            mitsuba: Some(serde_json::json!([])),
        },
        Case {
            name: "cornell-box: above the blocks",
            scene: builtin("cornell-box")?,
            points: grid((0.01, 0.54, a), (0.01, 0.55, b), 0.4, DVec3::Y),
            mitsuba: None,
        },
        Case {
            name: "closed-room: above the block",
            scene: builtin("closed-room")?,
            points: grid((0.05, 3.95, a), (0.05, 2.95, b), 1.6, DVec3::Y),
            mitsuba: None,
        },
    ])
}

/// Irradiance at `points` to `target`, guided as `guiding`: the values and the seconds.
fn run(
    scene: &Scene,
    points: &[(DVec3, DVec3)],
    target: f64,
    guiding: Guiding,
) -> Result<(Vec<Gathered>, f64)> {
    let t = Instant::now();
    let g = super::irradiance::gcr_gathered(scene, points, target, guiding)?;
    Ok((g, t.elapsed().as_secs_f64()))
}

/// Σ (a − b)² / Σ (σ_a² + σ_b²) over points and bands.
fn agreement(a: &[Gathered], b: &[Gathered]) -> f64 {
    let (mut d, mut v) = (0.0, 0.0);
    for (p, q) in a.iter().zip(b) {
        for k in 0..gcr::BANDS {
            d += (p.radiosity[k] - q.radiosity[k]).powi(2);
            v += p.std_error[k].powi(2) + q.std_error[k].powi(2);
        }
    }
    d / v
}

/// Runs this group and writes `benchmarks-guiding.md` into `ctx.out`.
pub fn run_group(ctx: &Ctx) -> Result<()> {
    let targets: &[f64] = if ctx.quick { &[0.05] } else { &[0.02, 0.01] };
    // `GUIDING_MODE=on`: the guided column forced on (what `GUIDING_FROM` is chosen by) instead
    // of the default `auto`; `GUIDING_PEERS=off`: no peer rows
    let forced = std::env::var("GUIDING_MODE").is_ok_and(|m| m == "on");
    let (mode, label) = if forced {
        (Guiding::On, "on")
    } else {
        (Guiding::Auto, "auto")
    };
    let peers = std::env::var("GUIDING_PEERS").map_or(true, |p| p != "off");
    let mut skipped: Vec<String> = Vec::new();
    let mut md = format!(
        "| scene, points | target | unguided: s, rays/point, est. error | guided ({label}): s, rays/point, est. error | time guided / unguided | Σd²/Σσ² |\n|---|---:|---|---|---:|---:|\n"
    );
    // `GUIDING_CASES=door,sun`: only the cases whose names contain one of these
    let only = std::env::var("GUIDING_CASES").ok();
    let wanted = |name: &str| {
        (only.as_deref()).is_none_or(|o| o.split(',').any(|w| name.contains(w.trim())))
    };
    for case in cases(ctx.quick)?.into_iter().filter(|c| wanted(c.name)) {
        for &target in targets {
            let (off, t_off) = run(&case.scene, &case.points, target, Guiding::Off)?;
            let (auto, t_auto) = run(&case.scene, &case.points, target, mode)?;
            let describe = |g: &[Gathered], t: f64| {
                let rays = g.iter().map(|x| x.rays).max().unwrap_or(0);
                let e = gcr::relative_std_error(g).unwrap_or(0.0);
                format!("{t:.1}, {rays}, {:.2} %", 100.0 * e)
            };
            writeln!(
                md,
                "| {}, {} | {:.0} % | {} | {} | {:.2} | {:.2} |",
                case.name,
                case.points.len(),
                100.0 * target,
                describe(&off, t_off),
                describe(&auto, t_auto),
                t_auto / t_off,
                agreement(&off, &auto),
            )?;
            println!("guiding: {} at {:.0} % done", case.name, 100.0 * target);
        }
        if let Some(emitter) = case.mitsuba.as_ref().filter(|_| peers) {
            for peer in [
                Peer::Mitsuba,
                Peer::Cycles { guided: false },
                Peer::Cycles { guided: true },
            ] {
                match peer_rows(peer, &case, emitter, ctx.quick)? {
                    Ok(rows) => md += &rows,
                    Err(why) => skipped.push(format!("{} skipped: {why}", peer.label())),
                }
            }
        }
    }
    let out = format!(
        "# Guided bounces against unguided (issue 32)\n\n\
         Generated by `cargo xtask bench --only guiding{quick}` (release; overwritten by it), \
         {threads} rayon threads, one run each. Irradiance (`--probe-quantity irradiance`) at \
         grids of points by the default paths gather to each target: unguided (`--guiding off`) \
         and with the program's default `--guiding auto`, which draws from the table of the \
         surfaces the lights reach directly where a trial round says it halves the variance per \
         ray (`estimator/secondary.rs`), guides the bounces when the pilot round finds hard light \
         (at least 8 192 rays per point predicted to the target at a relative variance of at \
         least 3 per ray, `Guiding::pays`), and is otherwise exactly unguided (same bits, same \
         time up to noise). The scenes: `scenes/door-gap.obj`, \
         `scenes/sun-patch-room.obj`, `scenes/uplight-room.obj` with their lighting files, \
         `scenes/many-rooms.obj` (its lamps are emitting faces; `xtask/py/make_light_scenes.py`), \
         and two built-ins. `rays/point` is the most any \
         point got (65 536 is the cap: the target was not met); `est. error` is the gather's own \
         estimate (relative L2 over the points, standard error). Σd²/Σσ²: the squared \
         differences between the two runs over the variances they claim (≈ 1: they agree). \
         Peer rows (the hard rooms), the same lights as their own emitters, two seeds per run (σ \
         from their difference, seconds for both): Mitsuba 3 (`scalar_rgb`, `path`, \
         `multijitter`: `xtask/py/mitsuba_irradiance.py`) and Blender Cycles' baker without and \
         with its path guiding (Open PGL; CPU, 2 threads, no clamping: \
         `xtask/py/cycles_irradiance.py`, run under `CYCLES_PYTHON`); their own relative error \
         at that time, and the time they would take to 2 % and 1 % if the error falls as \
         1/√spp (extrapolated, not run). `GUIDING_CASES=door,sun` runs only the cases whose \
         names contain one of the words; `GUIDING_MODE=on` forces the guided column on \
         (`--guiding on`), `GUIDING_PEERS=off` leaves the peers out, `GUIDING_POINTS=20000` \
         sets about that many points a case. \
         Design and what was tried: docs/design/estimator.md, \"Guiding\".\n\n{md}{note}",
        quick = if ctx.quick { " --quick" } else { "" },
        threads = rayon::current_num_threads(),
        note = (skipped.iter())
            .map(|why| format!("\n{why}.\n"))
            .collect::<String>(),
    );
    std::fs::write(ctx.out.join("benchmarks-guiding.md"), out)?;
    Ok(())
}

/// A peer at the case's points with `emitter`: a table row per run (or why it was skipped).
fn peer_rows(
    peer: Peer,
    case: &Case,
    emitter: &serde_json::Value,
    quick: bool,
) -> Result<std::result::Result<String, String>> {
    let dir = std::env::temp_dir().join(format!(
        "gcr-guiding-{}-{}",
        std::process::id(),
        peer.solver()
    ));
    std::fs::create_dir_all(&dir)?;
    let file = dir.join("emitters.json");
    // one emitter, or a list of them (empty: the mesh's emitting faces only)
    let list = match emitter {
        serde_json::Value::Array(list) => list.clone(),
        one => vec![one.clone()],
    };
    std::fs::write(&file, serde_json::to_string(&list)?)?;
    let spp: &[usize] = if quick { &[16] } else { &[256, 2048] };
    let runs = super::irradiance::peer_lit(
        peer,
        &case.scene,
        &case.points,
        spp,
        "multijitter",
        Some(&file),
    )?;
    let _ = std::fs::remove_dir_all(&dir);
    let runs = match runs {
        Ok(r) => r,
        Err(why) => return Ok(Err(why)),
    };
    let mut rows = String::new();
    for (spp, seconds, est) in runs {
        let (mut v, mut b) = (0.0, 0.0);
        for (m, s) in est.mean.iter().zip(&est.se) {
            for k in 0..3 {
                v += s[k] * s[k];
                b += m[k] * m[k];
            }
        }
        let e = (v / b).sqrt();
        let at = |target: f64| seconds * (e / target).powi(2);
        writeln!(
            rows,
            "| {}, {}: {}, 2 × {spp} spp | - | {seconds:.1} s, {:.2} % | to 2 %: {:.0} s, to 1 %: {:.0} s (extrapolated) | - | - |",
            case.name,
            case.points.len(),
            peer.label(),
            100.0 * e,
            at(0.02),
            at(0.01),
        )?;
    }
    Ok(Ok(rows))
}
