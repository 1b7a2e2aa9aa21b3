//! The `irradiance` group (issue 18, "done when": `rtrace -I` style work-plane grids give irradiance
//! that agrees with Mitsuba's at the same points). Writes `benchmarks-irradiance.md`.
//!
//! Per 3-D built-in, two work planes in the air (an 8 × 8 grid over the middle 80 % of the scene's
//! bounds in x and z, at 30 % and 70 % of its height, facing +y; points within 3·10⁻³ of the
//! diagonal of a surface left out), irradiance E = ∫ L cos θ dω by
//! * `gcr` — [`gcr::irradiance_at_points`], the default paths gather to a 1 % target (no networks);
//! * the `baselines` path tracer — [`baselines::pointwise::irradiance_reference_at`] to a 0.3 %
//!   relative standard error per point (the reference);
//! * Mitsuba 3 — `xtask/py/mitsuba_irradiance.py`: a tiny white square at each point facing n, and a
//!   radiancemeter looking at it (one batch sensor): its exitance πL is E, by Mitsuba's own path
//!   tracer with next-event estimation; two seeds per run (σ from their difference), at 2 × 64 …
//!   2 × 4096 spp (skipped with a note without `mitsuba`).
//!
//! Each is compared with the reference: relative L2 difference, its own estimated noise ‖σ‖/‖E‖, and
//! Σ d² / Σ (σ² + σ_ref²) (≈ 1 when two estimates differ by their noise alone).

use super::field::{Peer, mitsuba_runs, write_mitsuba_faces};
use crate::ctx::Ctx;
use anyhow::{Result, bail};
use baselines::Adaptive;
use gcr::{Domain, Emitters, GatherMode, Gathered, Guiding, PathSettings, SolveConfig, Trained};
use glam::DVec3;
use scene_sampler::{KernelSampler, Scene, SceneBvh};
use std::fmt::Write;
use std::time::Instant;

/// Values with standard errors, per point and band.
pub(super) struct Estimates {
    pub(super) mean: Vec<[f64; 3]>,
    pub(super) se: Vec<[f64; 3]>,
}

/// The work planes of `scene` (module docs), `n`×`n` points each.
fn work_planes(scene: &Scene, n: usize) -> Vec<(DVec3, DVec3)> {
    let (lo, hi) = scene.bounds;
    let at = |f: f64, a: f64, b: f64| a + (0.1 + 0.8 * f) * (b - a);
    let mut out = Vec::new();
    for h in [0.3, 0.7] {
        let y = lo.y + h * (hi.y - lo.y);
        for j in 0..n {
            for i in 0..n {
                let (u, v) = ((i as f64 + 0.5) / n as f64, (j as f64 + 0.5) / n as f64);
                let p = DVec3::new(at(u, lo.x, hi.x), y, at(v, lo.z, hi.z));
                // Mitsuba's radiancemeter sits 10⁻³ of the diagonal above its point: a point
                // closer than that to a surface would measure the surface instead.
                let near = scene.faces.iter().map(|f| f.closest_point(p).distance(p));
                if near.fold(f64::INFINITY, f64::min) > 3e-3 * scene.diagonal() {
                    out.push((p, DVec3::Y));
                }
            }
        }
    }
    out
}

/// (relative L2 difference, own noise ‖σ‖/‖E_ref‖, Σ d² / Σ (σ² + σ_ref²)).
pub(super) fn compare(a: &Estimates, r: &Estimates) -> (f64, f64, f64) {
    let (mut d2, mut own, mut var, mut norm) = (0.0, 0.0, 0.0, 0.0);
    for i in 0..r.mean.len() {
        for b in 0..3 {
            d2 += (a.mean[i][b] - r.mean[i][b]).powi(2);
            own += a.se[i][b].powi(2);
            var += a.se[i][b].powi(2) + r.se[i][b].powi(2);
            norm += r.mean[i][b].powi(2);
        }
    }
    ((d2 / norm).sqrt(), (own / norm).sqrt(), d2 / var)
}

/// The `baselines` path tracer's irradiance at `points` (the reference).
pub(super) fn reference_irradiance(
    scene: &Scene,
    bvh: &SceneBvh,
    points: &[(DVec3, DVec3)],
    adaptive: &Adaptive,
) -> Result<Estimates> {
    let r = baselines::pointwise::irradiance_reference_at(scene, bvh, points, adaptive)?;
    Ok(Estimates {
        mean: r.iter().map(|e| e.estimate.mean).collect(),
        se: r.iter().map(|e| e.estimate.std_error).collect(),
    })
}

/// gcr's irradiance at `points`: the default paths gather to `target`, no networks.
pub(super) fn gcr_irradiance(
    scene: &Scene,
    points: &[(DVec3, DVec3)],
    target: f64,
) -> Result<Estimates> {
    let g = gcr_gathered(scene, points, target, Guiding::default())?;
    Ok(Estimates {
        mean: g.iter().map(|x| x.radiosity).collect(),
        se: g.iter().map(|x| x.std_error).collect(),
    })
}

/// Irradiance at `points` by the default paths gather to `target`, guided as `guiding`.
pub(super) fn gcr_gathered(
    scene: &Scene,
    points: &[(DVec3, DVec3)],
    target: f64,
    guiding: Guiding,
) -> Result<Vec<Gathered>> {
    let bvh = SceneBvh::new(scene);
    let domain = Domain::ThreeD(KernelSampler::new(scene, &bvh));
    let config = SolveConfig {
        gather: GatherMode::Paths,
        paths: PathSettings {
            target_error: Some(target),
            guiding,
            ..PathSettings::default()
        },
        ..SolveConfig::default()
    };
    let trained = Trained::without_networks(&domain, &config);
    let emitters = Emitters::new(&domain);
    Ok(gcr::irradiance_at_points(
        &domain, &trained, &emitters, &config, points,
    )?)
}

/// One Mitsuba run: samples per point, seconds, estimates.
pub(super) type Run = (usize, f64, Estimates);

/// Mitsuba's estimates at `points` per spp with their seconds, or why it was skipped.
fn mitsuba(
    scene: &Scene,
    points: &[(DVec3, DVec3)],
    spp: &[usize],
) -> Result<std::result::Result<Vec<Run>, String>> {
    peer_lit(Peer::Mitsuba, scene, points, spp, "ldsampler", None)
}

/// A peer's irradiance at `points` per spp with their seconds, or why it was skipped: Mitsuba 3
/// with `sampler` or Cycles (`xtask/py/<peer>_irradiance.py`), beside the scene's emitting faces
/// the emitters of the JSON file `emitters` (`--emitters`: Mitsuba dicts, which the Cycles script
/// translates).
pub(super) fn peer_lit(
    peer: Peer,
    scene: &Scene,
    points: &[(DVec3, DVec3)],
    spp: &[usize],
    sampler: &str,
    emitters: Option<&std::path::Path>,
) -> Result<std::result::Result<Vec<Run>, String>> {
    let dir = std::env::temp_dir().join(format!(
        "gcr-irradiance-{}-{}-{}",
        std::process::id(),
        peer.solver(),
        emitters.map_or(0, |e| e.as_os_str().len())
    ));
    std::fs::create_dir_all(&dir)?;
    let (ff, pf, of) = (dir.join("faces.txt"), dir.join("points.txt"), dir.join("e"));
    write_mitsuba_faces(scene, &ff)?;
    let text: String = points
        .iter()
        .map(|(p, n)| format!("{} {} {} {} {} {}\n", p.x, p.y, p.z, n.x, n.y, n.z))
        .collect();
    std::fs::write(&pf, text)?;
    let flag = std::path::Path::new("--emitters");
    let files: Vec<&std::path::Path> = match emitters {
        Some(e) => vec![flag, e, &ff, &pf, &of],
        None => vec![&ff, &pf, &of],
    };
    let stdout = match peer.run("irradiance", sampler, &files, spp)? {
        Ok(o) => o,
        Err(why) => return Ok(Err(why)),
    };
    let mut runs = Vec::new();
    for (spp, seconds) in mitsuba_runs(&stdout)? {
        let text = std::fs::read_to_string(format!("{}.{spp}", of.display()))?;
        let rows: Vec<Vec<f64>> = text
            .lines()
            .map(|l| {
                l.split_whitespace()
                    .map(|x| x.parse().unwrap_or(f64::NAN))
                    .collect()
            })
            .collect();
        if rows.len() != points.len() || rows.iter().any(|r| r.len() != 6) {
            bail!(
                "{} wrote {} rows for {} points",
                peer.label(),
                rows.len(),
                points.len()
            );
        }
        let mean = rows.iter().map(|r| [r[0], r[1], r[2]]).collect();
        let se = rows.iter().map(|r| [r[3], r[4], r[5]]).collect();
        runs.push((spp, seconds, Estimates { mean, se }));
    }
    let _ = std::fs::remove_dir_all(&dir);
    Ok(Ok(runs))
}

/// Runs this group and writes `benchmarks-irradiance.md` into `ctx.out`.
pub fn run(ctx: &Ctx) -> Result<()> {
    let (scenes, n, spp): (&[&str], usize, &[usize]) = if ctx.quick {
        (&["wall-floor"], 3, &[16])
    } else {
        (
            &["cornell-box", "two-blockers", "wall-floor", "closed-room"],
            8,
            &[64, 256, 1024, 4096],
        )
    };
    let mut md = String::from(
        "| scene | solver | seconds | rel. L2 vs reference | its noise | Σd²/Σσ² |\n|---|---|---:|---:|---:|---:|\n",
    );
    let mut skipped = None;
    for name in scenes {
        let scene = scene_sampler::builtin(name)?.into_3d()?;
        let points = work_planes(&scene, n);
        // ⟨The reference: adaptive path tracing to 0.3 % per point⟩
        let t = Instant::now();
        let bvh = SceneBvh::new(&scene);
        let adaptive = Adaptive {
            rel_error: if ctx.quick { 0.02 } else { 0.003 },
            ..Adaptive::default()
        };
        let reference = reference_irradiance(&scene, &bvh, &points, &adaptive)?;
        let t_ref = t.elapsed().as_secs_f64();
        let noise = compare(&reference, &reference).1;
        writeln!(
            md,
            "| {name} | reference (baselines, 0.3 %), {} points | {t_ref:.2} | - | {:.4} | - |",
            points.len(),
            noise
        )?;
        // ⟨GCR: the default paths gather to 1 %⟩
        let t = Instant::now();
        let gcr_est = gcr_irradiance(&scene, &points, 0.01)?;
        let t_gcr = t.elapsed().as_secs_f64();
        let (d, own, ratio) = compare(&gcr_est, &reference);
        writeln!(
            md,
            "| {name} | gcr (paths, 1 %) | {t_gcr:.2} | {d:.4} | {own:.4} | {ratio:.2} |"
        )?;
        // ⟨Mitsuba 3⟩
        match mitsuba(&scene, &points, spp)? {
            Ok(runs) => {
                for (spp, seconds, est) in runs {
                    let (d, own, ratio) = compare(&est, &reference);
                    writeln!(
                        md,
                        "| {name} | mitsuba 3 (2 × {spp} spp) | {seconds:.2} | {d:.4} | {own:.4} | {ratio:.2} |"
                    )?;
                }
            }
            Err(why) => skipped = Some(why),
        }
        println!("irradiance: {name} done");
    }
    let note = skipped.map_or(String::new(), |why| format!("\nMitsuba skipped: {why}.\n"));
    let out = format!(
        "# Irradiance at work planes (`rtrace -I`) against Mitsuba 3 (issue 18)\n\n\
         Generated by `cargo xtask bench --only irradiance{quick}` (release; overwritten by it), {threads} \
         rayon threads. Per scene two work planes of {n}×{n} points in the air (30 % and 70 % of the \
         height, facing +y, points within 3·10⁻³ of the diagonal of a surface left out; \
         `xtask/src/bench/irradiance.rs`). Reference: the `baselines` path tracer \
         from a white receiver at each point, to a 0.3 % relative standard error per point. `its noise`: the \
         estimate's own ‖σ‖/‖E_ref‖; Σd²/Σσ² ≈ 1 when an estimate differs from the reference by the two \
         noises alone. Mitsuba: `scalar_rgb`, `path`, `ldsampler`: at each point a white square of \
         half-size 10⁻⁴ of the diagonal facing +y seen by a radiancemeter (its exitance is E), two renders \
         with different seeds (σ from their difference); times include loading its sensors, both \
         renders.\n\n{md}{note}",
        quick = if ctx.quick { " --quick" } else { "" },
        threads = rayon::current_num_threads(),
    );
    std::fs::write(ctx.out.join("benchmarks-irradiance.md"), out)?;
    Ok(())
}
