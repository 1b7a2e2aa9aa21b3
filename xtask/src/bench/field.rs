//! The `field` group (issue 16, item 1): B over the whole scene. Every solver produces B at N area-uniform
//! points of the reflecting faces of each 3-D scene; the error is the relative L2 over a fixed subset of
//! those points (and the colour bands) against an adaptive path-traced reference; the time is everything
//! from the scene to the N values. Writes `benchmarks-field.md` and `figures/field-<scene>-<N>.png`.
//!
//! * **Points**: [`SurfaceSampler::spread`] (an R2 set through the area parameterisation) over the faces
//!   that do not emit (the lights have ρ = 0 and B = E exactly there: left out, they would only add exact
//!   values). The error subset is the first 1000 of them (an R2 set itself, the same at every N: `spread` is
//!   prefix-consistent, so one cached reference serves every N).
//! * **Reference**: [`baselines::pointwise::reference_at`] (next-event estimation) at the subset, every band
//!   of every point to the target relative standard error (or its path cap; the report counts those), cached
//!   in `$CARGO_TARGET_DIR/field-refs/<scene>-<hash>.txt` (default `target/`) so that reruns skip it.
//! * **Solvers**: GCR's default (`gcr default`: the paths gather run to each of the target errors 10, 5, 2,
//!   1 %, no networks, paths shared between neighbouring points: what `gcr solve` does for points; `gcr alone`
//!   the same without the sharing), GCR's gathers from a solve (kernel cells × gather
//!   rays, ray and paths gathers; one solve per cell count, timed once and added to each gather), our path tracer (fixed paths per point), HR + final gather (16 rays per leaf, as in
//!   `compare`), Mitsuba 3 through `xtask/py/mitsuba_field.py` (skipped with a note when `mitsuba` is
//!   not importable), and Blender Cycles' baker without and with its path guiding through
//!   `xtask/py/cycles_field.py` under the Python that `CYCLES_PYTHON` names (bpy 5.0.1 needs Python
//!   3.11; skipped with a note when unset or bpy is missing). Every time includes building the scene
//!   and its BVH (measured once, added); a peer's adds its own scene and sensors or probes.
//!
//! `FIELD_SCENES=cornell-box,closed-room` restricts the scenes; `FIELD_N=20000,2000` the point counts;
//! `FIELD_SOLVERS=gcr-default,pt` the solvers (gcr-default, gcr-alone, gcr-rays, gcr-paths, pt, hr, mitsuba,
//! cycles, cycles-guided);
//! `FIELD_CELLS=300` GCR's cell counts;
//! `FIELD_CORRECTED=0.25` the fraction of the `paths` gather's rays that get a path-traced correction.

use super::gcr::{Curve, plot_curves};
use crate::ctx::Ctx;
use anyhow::{Context, Result, bail};
use baselines::Adaptive;
use baselines::hierarchical::{TriHr, TriHrConfig, budget};
use gcr::{
    Domain, Emitters, GatherMode, GatherSamples, PathSettings, SolveConfig, radiosity_at_points,
};
use rayon::prelude::*;
use scene_sampler::{KernelSampler, Scene, SceneBvh, SurfacePoint, SurfaceSampler};
use std::fmt::Write;
use std::hash::{Hash, Hasher};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Sizes of one run.
struct Plan {
    scenes: Vec<String>,
    counts: Vec<usize>,
    subset: usize,
    ref_error: f64,
    ref_max_paths: usize,
    cells: &'static [usize],
    rays: &'static [usize],
    /// Rays per point of GCR's `paths` gather (shadow = cosine rays; `FIELD_CORRECTED` of them,
    /// default a quarter, corrected).
    path_rays: &'static [usize],
    paths: &'static [usize],
    hr: &'static [f64],
    spp: &'static [usize],
    /// Target errors of GCR's default (the paths gather run to a target).
    targets: &'static [f64],
}

fn plan(quick: bool) -> Plan {
    let env_list = |k: &str| {
        std::env::var(k).ok().map(|s| {
            s.split(',')
                .map(|x| x.trim().to_string())
                .collect::<Vec<_>>()
        })
    };
    if quick {
        Plan {
            scenes: env_list("FIELD_SCENES").unwrap_or_else(|| vec!["wall-floor".into()]),
            counts: vec![1000],
            subset: 100,
            ref_error: 0.02,
            ref_max_paths: 100_000,
            cells: &[100],
            rays: &[64],
            path_rays: &[8],
            paths: &[16, 64],
            hr: &[4e-3],
            spp: &[16, 64],
            targets: &[0.1],
        }
    } else {
        Plan {
            scenes: env_list("FIELD_SCENES").unwrap_or_else(|| {
                [
                    "cornell-box",
                    "two-blockers",
                    "wall-floor",
                    "closed-room",
                    "tessellated-cornell-100000",
                ]
                .map(String::from)
                .to_vec()
            }),
            counts: env_list("FIELD_N")
                .map(|v| v.iter().filter_map(|s| s.parse().ok()).collect())
                .unwrap_or_else(|| vec![20_000, 2_000]),
            subset: 1000,
            ref_error: 0.003,
            ref_max_paths: 2_000_000,
            cells: &[100, 300, 1000],
            rays: &[64, 256, 1024],
            path_rays: &[16, 64, 256, 1024],
            paths: &[4, 16, 64, 256, 1024],
            hr: &[4e-3, 1e-3],
            spp: &[4, 16, 64, 256, 1024],
            targets: &[0.1, 0.05, 0.02, 0.01],
        }
    }
}

/// Whether `FIELD_SOLVERS` (a comma list of gcr-default, gcr-alone, gcr-rays, gcr-paths, pt, hr, mitsuba,
/// cycles, cycles-guided; all
/// when unset)
/// selects `solver`.
fn selected(solver: &str) -> bool {
    std::env::var("FIELD_SOLVERS").map_or(true, |v| v.split(',').any(|s| s.trim() == solver))
}

/// The fraction of the `paths` gather's rays corrected by paths: `FIELD_CORRECTED`, default 0.25.
fn corrected_fraction() -> f64 {
    std::env::var("FIELD_CORRECTED")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(0.25)
}

/// `‖v − r‖₂ / ‖r‖₂` over points and bands.
pub(super) fn rel_l2(v: &[[f64; 3]], r: &[[f64; 3]]) -> f64 {
    let (mut n, mut d) = (0.0, 0.0);
    for (a, b) in v.iter().zip(r) {
        for k in 0..3 {
            n += (a[k] - b[k]).powi(2);
            d += b[k] * b[k];
        }
    }
    (n / d.max(1e-300)).sqrt()
}

/// The reference at the subset and what it cost.
struct Reference {
    values: Vec<[f64; 3]>,
    note: String,
}

/// Where the benches cache their references: `$CARGO_TARGET_DIR/field-refs` (default `target/`).
pub(super) fn cache_dir() -> PathBuf {
    let target = std::env::var("CARGO_TARGET_DIR").unwrap_or_else(|_| "target".into());
    Path::new(&target).join("field-refs")
}

/// The adaptive NEE reference at `points`, from the cache when it holds one for these points and settings.
fn reference(
    name: &str,
    scene: &Scene,
    bvh: &SceneBvh,
    points: &[SurfacePoint],
    ad: &Adaptive,
) -> Result<Reference> {
    let mut h = std::collections::hash_map::DefaultHasher::new();
    (
        name,
        scene.faces.len(),
        points.len(),
        ad.rel_error.to_bits(),
        ad.max_paths,
        ad.batch,
        ad.min_paths,
        ad.seed,
        "nee-v1",
    )
        .hash(&mut h);
    for p in points {
        for x in [
            p.point.x, p.point.y, p.point.z, p.normal.x, p.normal.y, p.normal.z,
        ] {
            x.to_bits().hash(&mut h);
        }
    }
    let dir = cache_dir();
    let file = dir.join(format!("{name}-{:016x}.txt", h.finish()));
    if let Ok(text) = std::fs::read_to_string(&file) {
        let mut lines = text.lines();
        let note = lines
            .next()
            .unwrap_or("")
            .trim_start_matches("# ")
            .to_string();
        let values: Vec<[f64; 3]> = lines
            .map(|l| {
                let v: Vec<f64> = l
                    .split_whitespace()
                    .take(3)
                    .map(|x| x.parse().unwrap_or(f64::NAN))
                    .collect();
                [v[0], v[1], v[2]]
            })
            .collect();
        if values.len() == points.len() && values.iter().flatten().all(|x| x.is_finite()) {
            println!("field: {name} reference from {}", file.display());
            return Ok(Reference {
                values,
                note: format!("{note} (cached in {})", file.display()),
            });
        }
    }
    let t = Instant::now();
    let est = baselines::pointwise::reference_at(scene, bvh, points, ad)?;
    let seconds = t.elapsed().as_secs_f64();
    let paths: usize = est.iter().map(|e| e.estimate.paths).sum();
    let missed: Vec<&baselines::AdaptiveEstimate> = est.iter().filter(|e| !e.target_met).collect();
    let dark = missed
        .iter()
        .filter(|e| e.estimate.mean.iter().all(|&m| m == 0.0))
        .count();
    let worst_lit = missed
        .iter()
        .map(|e| e.rel_error)
        .filter(|x| x.is_finite())
        .fold(0.0, f64::max);
    // the reference's own noise as a relative L2 over the subset
    let values: Vec<[f64; 3]> = est.iter().map(|e| e.estimate.mean).collect();
    let noisy: Vec<[f64; 3]> = est
        .iter()
        .map(|e| [0, 1, 2].map(|k| e.estimate.mean[k] + e.estimate.std_error[k]))
        .collect();
    let note = format!(
        "reference: NEE path tracer, adaptive to {:.2} % per band per point (cap {} paths) at {} points: {seconds:.1} s, \
         {:.1} M paths; {} points at the cap ({dark} of them dark: B = 0, no path found light; the others up to {:.2} %); \
         its standard error as a relative L2 over the subset: {:.3} %",
        100.0 * ad.rel_error,
        ad.max_paths,
        points.len(),
        paths as f64 / 1e6,
        missed.len(),
        100.0 * worst_lit,
        100.0 * rel_l2(&noisy, &values)
    );
    std::fs::create_dir_all(&dir)?;
    let mut out = format!("# {note}\n");
    for e in &est {
        let m = e.estimate.mean;
        let s = e.estimate.std_error;
        writeln!(
            out,
            "{:e} {:e} {:e} {:e} {:e} {:e} {}",
            m[0], m[1], m[2], s[0], s[1], s[2], e.estimate.paths
        )?;
    }
    std::fs::write(&file, out)?;
    println!("field: {name} {note}");
    Ok(Reference { values, note })
}

fn push(c: &mut Curve, scene: &str, n: usize, budget: usize, seconds: f64, error: f64) {
    c.record(&format!("field: {scene} N={n}"), budget, seconds, error);
}

fn pick(values: &[[f64; 3]], subset: &[usize]) -> Vec<[f64; 3]> {
    subset.iter().map(|&i| values[i]).collect()
}

/// Writes the scene's triangles for the Mitsuba scripts to `path` (`xtask/py/mitsuba_scene.py`
/// documents the format): corners, ρ, and the emitted radiance Ke = E/π; for a textured scene also
/// each row's texture (−1: none) and its corners' texture coordinates, ρ then the texture's factor,
/// and the textures' linear texels in `<path>.textures`.
pub(super) fn write_mitsuba_faces(scene: &Scene, path: &Path) -> Result<()> {
    let textured = !scene.textures.is_empty();
    let mut faces = String::new();
    for f in &scene.faces {
        for v in f.v {
            write!(faces, "{} {} {} ", v.x, v.y, v.z)?;
        }
        let r = f.texture.map_or(f.rho.0, |t| t.factor.0);
        let e = f.emission.0.map(|x| x / std::f64::consts::PI);
        write!(
            faces,
            "{} {} {} {} {} {}",
            r[0], r[1], r[2], e[0], e[1], e[2]
        )?;
        match (textured, f.texture) {
            (false, _) => {}
            (true, None) => write!(faces, " -1 0 0 0 0 0 0")?,
            (true, Some(t)) => {
                write!(faces, " {}", t.texture)?;
                for uv in t.uv {
                    write!(faces, " {} {}", uv.x, uv.y)?;
                }
            }
        }
        faces.push('\n');
    }
    std::fs::write(path, faces)?;
    if textured {
        let mut text = String::new();
        for t in &scene.textures {
            let (w, h) = t.size();
            write!(text, "{w} {h}")?;
            for px in t.texels() {
                write!(text, " {} {} {}", px[0], px[1], px[2])?;
            }
            text.push('\n');
        }
        std::fs::write(format!("{}.textures", path.display()), text)?;
    }
    Ok(())
}

/// Runs `xtask/py/<script>` with Mitsuba's `sampler`, `files` and the sample counts: its stdout,
/// or why Mitsuba is missing (the script's exit code 3). `ldsampler` had the lowest error at equal
/// spp but is biased (a furnace 0.4 % too bright, `xtask/py/mitsuba_scene.py`); `multijitter` is not.
pub(super) fn run_mitsuba(
    script: &str,
    sampler: &str,
    files: &[&Path],
    spp: &[usize],
) -> Result<std::result::Result<Vec<u8>, String>> {
    run_script("python3", script, &["--sampler", sampler], files, spp)
}

/// Runs `xtask/py/<script>` with `python` and `options`, `files` and the sample counts: its
/// stdout, or why the peer is missing (the script's exit code 3).
fn run_script(
    python: &str,
    script: &str,
    options: &[&str],
    files: &[&Path],
    spp: &[usize],
) -> Result<std::result::Result<Vec<u8>, String>> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("py")
        .join(script);
    let out = std::process::Command::new(python)
        .arg(&path)
        .args(options)
        .args(files)
        .args(spp.iter().map(|s| s.to_string()))
        .output()
        .with_context(|| format!("running {python}"))?;
    if out.status.code() == Some(3) {
        return Ok(Err(String::from_utf8_lossy(&out.stderr).trim().to_string()));
    }
    if !out.status.success() {
        bail!("{script} failed: {}", String::from_utf8_lossy(&out.stderr));
    }
    Ok(Ok(out.stdout))
}

/// The `spp=… scene=… load=… render=…` lines the Mitsuba scripts print: (spp, seconds), the seconds
/// being the scene's meshes, the sensors and the render (not the interpreter's start and import).
pub(super) fn mitsuba_runs(stdout: &[u8]) -> Result<Vec<(usize, f64)>> {
    let mut runs = Vec::new();
    for line in String::from_utf8_lossy(stdout).lines() {
        // Mitsuba's log may end its colour codes on the same line, before `spp=`.
        let Some(at) = line.find("spp=") else {
            continue;
        };
        let kv: std::collections::HashMap<&str, &str> = line[at..]
            .split_whitespace()
            .filter_map(|t| t.split_once('='))
            .collect();
        let (Some(s), Some(sc), Some(ld), Some(rd)) = (
            kv.get("spp"),
            kv.get("scene"),
            kv.get("load"),
            kv.get("render"),
        ) else {
            continue;
        };
        let seconds = sc.parse::<f64>()? + ld.parse::<f64>()? + rd.parse::<f64>()?;
        runs.push((s.parse()?, seconds));
    }
    Ok(runs)
}

/// A file of `r g b` lines (NaN where a value does not parse).
pub(super) fn read_values(path: &Path) -> Result<Vec<[f64; 3]>> {
    let text = std::fs::read_to_string(path).with_context(|| format!("{}", path.display()))?;
    Ok(text
        .lines()
        .map(|l| {
            let mut v = l.split_whitespace().map(|x| x.parse().unwrap_or(f64::NAN));
            [(); 3].map(|_| v.next().unwrap_or(f64::NAN))
        })
        .collect())
}

/// A peer renderer, run through its scripts under `xtask/py/` (`mitsuba_<what>.py`,
/// `cycles_<what>.py`).
#[derive(Clone, Copy, PartialEq)]
pub(super) enum Peer {
    /// Mitsuba 3 (`mitsuba_field.py`, `python3`).
    Mitsuba,
    /// Blender Cycles (`cycles_field.py`, the Python of `CYCLES_PYTHON`: bpy needs Python 3.11),
    /// with or without its path guiding (Open PGL).
    Cycles {
        /// Whether Cycles' path guiding is on.
        guided: bool,
    },
}

impl Peer {
    /// Runs its script for `what` (`field`, `irradiance`) with `files` and the sample counts
    /// (Mitsuba with `sampler`): the script's stdout, or why the peer is missing.
    pub(super) fn run(
        self,
        what: &str,
        sampler: &str,
        files: &[&Path],
        spp: &[usize],
    ) -> Result<std::result::Result<Vec<u8>, String>> {
        match self {
            Peer::Mitsuba => run_mitsuba(&format!("mitsuba_{what}.py"), sampler, files, spp),
            Peer::Cycles { guided } => match std::env::var("CYCLES_PYTHON") {
                Err(_) => Ok(Err(
                    "CYCLES_PYTHON (a Python 3.11 with `pip install bpy==5.0.1`) not set".into(),
                )),
                Ok(python) => {
                    let options: &[&str] = if guided { &["--guiding"] } else { &[] };
                    run_script(&python, &format!("cycles_{what}.py"), options, files, spp)
                }
            },
        }
    }

    /// The curve's label.
    pub(super) fn label(self) -> &'static str {
        match self {
            Peer::Mitsuba => "mitsuba 3",
            Peer::Cycles { guided: false } => "cycles",
            Peer::Cycles { guided: true } => "cycles guided",
        }
    }

    /// Its `FIELD_SOLVERS` name.
    pub(super) fn solver(self) -> &'static str {
        match self {
            Peer::Mitsuba => "mitsuba",
            Peer::Cycles { guided: false } => "cycles",
            Peer::Cycles { guided: true } => "cycles-guided",
        }
    }
}

/// A peer's radiosity at `points` at each of `spp`: one curve, or the reason it was skipped.
#[allow(clippy::too_many_arguments)]
fn peer(
    which: Peer,
    scene: &Scene,
    name: &str,
    points: &[SurfacePoint],
    subset: &[usize],
    reference: &[[f64; 3]],
    spp: &[usize],
    setup: f64,
) -> Result<std::result::Result<Curve, String>> {
    let dir = std::env::temp_dir().join(format!(
        "gcr-field-{}-{name}-{}-{}",
        std::process::id(),
        points.len(),
        which.solver()
    ));
    std::fs::create_dir_all(&dir)?;
    // Cycles reads each point's face (its reflectance turns the baked light into B)
    let with_face = which != Peer::Mitsuba;
    let mut pts = String::new();
    for p in points {
        let (y, n) = (p.point, p.normal);
        write!(pts, "{} {} {} {} {} {}", y.x, y.y, y.z, n.x, n.y, n.z)?;
        if with_face {
            write!(pts, " {}", p.face)?;
        }
        pts.push('\n');
    }
    let (ff, pf, of) = (dir.join("faces.txt"), dir.join("points.txt"), dir.join("b"));
    write_mitsuba_faces(scene, &ff)?;
    std::fs::write(&pf, pts)?;
    let files = [ff.as_path(), &pf, &of];
    let stdout = match which {
        Peer::Mitsuba => run_mitsuba("mitsuba_field.py", "ldsampler", &files, spp)?,
        Peer::Cycles { guided } => match std::env::var("CYCLES_PYTHON") {
            Err(_) => {
                Err("CYCLES_PYTHON (a Python 3.11 with `pip install bpy==5.0.1`) not set".into())
            }
            Ok(python) => {
                let options: &[&str] = if guided { &["--guiding"] } else { &[] };
                run_script(&python, "cycles_field.py", options, &files, spp)?
            }
        },
    };
    let stdout = match stdout {
        Ok(o) => o,
        Err(why) => return Ok(Err(why)),
    };
    let mut c = Curve::new(which.label());
    for (spp, seconds) in mitsuba_runs(&stdout)? {
        let values = read_values(Path::new(&format!("{}.{spp}", of.display())))?;
        if values.len() != points.len() {
            bail!(
                "{} wrote {} values for {} points",
                which.label(),
                values.len(),
                points.len()
            );
        }
        push(
            &mut c,
            name,
            points.len(),
            spp,
            setup + seconds,
            rel_l2(&pick(&values, subset), reference),
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
    Ok(Ok(c))
}

/// Every solver on one scene at `n` points.
fn one(name: &str, n: usize, p: &Plan) -> Result<(Vec<Curve>, String)> {
    let t = Instant::now();
    let scene = scene_sampler::builtin(name)?.into_3d()?;
    let bvh = SceneBvh::new(&scene);
    let setup = t.elapsed().as_secs_f64();
    let points =
        SurfaceSampler::new(&scene).spread(n, |q| scene.faces[q.face as usize].emission.is_zero());
    // The first `subset` points: `spread` is prefix-consistent (point i does not depend on N), so they are
    // the same R2 set at every N and one cached reference serves all point counts.
    let subset: Vec<usize> = (0..p.subset.min(points.len())).collect();
    let sub_points: Vec<SurfacePoint> = subset.iter().map(|&i| points[i]).collect();
    let ad = Adaptive {
        rel_error: p.ref_error,
        batch: 1024,
        min_paths: 4096,
        max_paths: p.ref_max_paths,
        seed: 0x5EED,
    };
    let r = reference(name, &scene, &bvh, &sub_points, &ad)?;
    let score = |v: &[[f64; 3]]| rel_l2(&pick(v, &subset), &r.values);
    let mut curves = Vec::new();

    // GCR: one solve per cell count, each gather from it
    let domain = Domain::ThreeD(KernelSampler::new(&scene, &bvh));
    let emitters = Emitters::new(&domain);
    let at: Vec<_> = points.iter().map(|q| (q.point, q.normal, q.face)).collect();
    let mut gcr_curves: Vec<Curve> = p
        .rays
        .iter()
        .map(|r| Curve::new(&format!("gcr rays {r}")))
        .collect();
    let mut path_curves: Vec<Curve> = p
        .path_rays
        .iter()
        .map(|r| Curve::new(&format!("gcr paths {r}")))
        .collect();
    let (use_rays, use_paths) = (selected("gcr-rays"), selected("gcr-paths"));
    let corrected = corrected_fraction();
    let cells_env: Option<Vec<usize>> = std::env::var("FIELD_CELLS")
        .ok()
        .map(|v| v.split(',').filter_map(|c| c.trim().parse().ok()).collect());
    for &cells in cells_env
        .as_deref()
        .unwrap_or(p.cells)
        .iter()
        .filter(|_| use_rays || use_paths)
    {
        let config = SolveConfig {
            kernel_cells: cells,
            shading_cells: (cells / 2).max(3),
            gather: if use_paths {
                GatherMode::Paths
            } else {
                GatherMode::Rays
            },
            ..SolveConfig::default()
        };
        let t = Instant::now();
        let trained = gcr::solve(&domain, &config, &mut |_| {})?;
        let solve_s = t.elapsed().as_secs_f64();
        for (c, &rays) in path_curves
            .iter_mut()
            .zip(p.path_rays)
            .filter(|_| use_paths)
        {
            let config = SolveConfig {
                gather: GatherMode::Paths,
                gather_samples: GatherSamples {
                    direct: rays,
                    indirect: rays,
                },
                paths: PathSettings {
                    corrections: ((rays as f64 * corrected).round() as usize).max(1),
                    ..PathSettings::default()
                },
                ..config
            };
            let t = Instant::now();
            let g = radiosity_at_points(&domain, &trained, &emitters, &config, &at)?;
            let seconds = setup + solve_s + t.elapsed().as_secs_f64();
            let v: Vec<[f64; 3]> = g.iter().map(|g| g.radiosity).collect();
            let sd: Vec<[f64; 3]> = g.iter().map(|g| g.std_error).collect();
            // The error the per-point standard errors predict, ‖σ‖₂/‖B_ref‖₂ (no bias).
            let norm = |v: &[[f64; 3]]| v.iter().flatten().map(|x| x * x).sum::<f64>().sqrt();
            let predicted = norm(&pick(&sd, &subset)) / norm(&r.values).max(1e-300);
            println!(
                "field: {name} gcr paths {rays} cells={cells}: predicted error {predicted:.4}"
            );
            push(c, name, n, cells, seconds, score(&v));
        }
        for (c, &rays) in gcr_curves.iter_mut().zip(p.rays).filter(|_| use_rays) {
            let config = SolveConfig {
                gather: GatherMode::Rays,
                gather_samples: GatherSamples {
                    direct: rays,
                    indirect: rays,
                },
                ..config
            };
            let t = Instant::now();
            let v: Vec<[f64; 3]> = radiosity_at_points(&domain, &trained, &emitters, &config, &at)?
                .into_iter()
                .map(|g| g.radiosity)
                .collect();
            push(
                c,
                name,
                n,
                cells,
                setup + solve_s + t.elapsed().as_secs_f64(),
                score(&v),
            );
        }
    }
    curves.extend(gcr_curves.into_iter().filter(|_| use_rays));
    curves.extend(path_curves.into_iter().filter(|_| use_paths));

    // GCR as `gcr solve` runs by default: the paths gather to a target error from a 16-ray pilot,
    // with every ray corrected, so no network is trained (nothing reads them at points), and paths
    // shared between neighbouring points; `gcr alone`: the same with every point alone
    // (`--share-paths 1`), the default before the sharing
    for (label, solver, neighbours) in [
        (
            "gcr default",
            "gcr-default",
            PathSettings::default().neighbours,
        ),
        ("gcr alone", "gcr-alone", 1),
    ] {
        if !selected(solver) {
            continue;
        }
        let mut curve = Curve::new(label);
        for &target in p.targets {
            let config = SolveConfig {
                gather: GatherMode::Paths,
                gather_samples: GatherSamples {
                    direct: 16,
                    indirect: 16,
                },
                paths: PathSettings {
                    target_error: Some(target),
                    neighbours,
                    ..PathSettings::default()
                },
                ..SolveConfig::default()
            };
            let t = Instant::now();
            let trained = gcr::Trained::without_networks(&domain, &config);
            let g = radiosity_at_points(&domain, &trained, &emitters, &config, &at)?;
            let seconds = setup + t.elapsed().as_secs_f64();
            let v: Vec<[f64; 3]> = g.iter().map(|g| g.radiosity).collect();
            let rays = g.iter().map(|g| g.rays).max().unwrap_or(0);
            println!(
                "field: {name} {label} target {:.1} %: {rays} rays per point, estimated {:.2} %",
                100.0 * target,
                100.0 * gcr::relative_std_error(&g).unwrap_or(0.0)
            );
            push(&mut curve, name, n, rays, seconds, score(&v));
        }
        curves.push(curve);
    }

    let mut pt = Curve::new("path tracer (NEE)");
    for &paths in p.paths.iter().filter(|_| selected("pt")) {
        let t = Instant::now();
        let v: Vec<[f64; 3]> = baselines::pointwise::radiosity_at(&scene, &bvh, &points, paths, 11)
            .into_iter()
            .map(|e| e.mean)
            .collect();
        push(
            &mut pt,
            name,
            n,
            paths,
            setup + t.elapsed().as_secs_f64(),
            score(&v),
        );
    }
    curves.push(pt);

    let mut hr_curve = Curve::new("HR + gather");
    if scene.faces.len() <= 20_000 && selected("hr") {
        let (mut e_max, mut rho_max) = (0.0f64, 0.0f64);
        for f in &scene.faces {
            e_max = e_max.max(f.emission.max());
            rho_max = rho_max.max(f.rho.max());
        }
        for &frac in p.hr {
            let config = TriHrConfig {
                epsilon: frac * e_max * rho_max,
                min_area: budget::min_area_for(&scene, 20_000),
                max_links: 300_000,
                ..TriHrConfig::default()
            };
            let t = Instant::now();
            let hr = match TriHr::solve(&scene, config) {
                Ok(hr) => hr,
                Err(e) => {
                    println!("field: {name} HR ε = {:.3e}: {e}", config.epsilon);
                    continue;
                }
            };
            let v: Vec<[f64; 3]> = points
                .par_iter()
                .enumerate()
                .map(|(i, q)| hr.gather_at(q, 16, i as u64).map(|r| r.0))
                .collect::<Result<_, _>>()?;
            push(
                &mut hr_curve,
                name,
                n,
                hr.link_count(),
                setup + t.elapsed().as_secs_f64(),
                score(&v),
            );
        }
    }
    curves.push(hr_curve);
    // solvers `FIELD_SOLVERS` left out have no runs: no row, no line in the plot
    curves.retain(|c| !c.points.is_empty());

    let mut note = r.note.clone();
    for which in [
        Peer::Mitsuba,
        Peer::Cycles { guided: false },
        Peer::Cycles { guided: true },
    ] {
        if !selected(which.solver()) {
            continue;
        }
        match peer(
            which, &scene, name, &points, &subset, &r.values, p.spp, setup,
        )? {
            Ok(c) => curves.push(c),
            Err(why) => {
                println!("field: {name} {} skipped: {why}", which.label());
                write!(note, "; {} skipped: {why}", which.label())?;
            }
        }
    }
    Ok((
        curves,
        format!("{note}; scene + BVH {setup:.3} s (in every time)"),
    ))
}

/// Runs this group's benchmarks and writes `benchmarks-field.md` into `ctx.out`.
pub fn run(ctx: &Ctx) -> Result<()> {
    let p = plan(ctx.quick);
    let start = Instant::now();
    let figs = ctx.out.join("figures");
    std::fs::create_dir_all(&figs)?;
    let targets = [0.10, 0.05, 0.02, 0.01];
    let mut summary = String::from(
        "| scene | N | solver | to 10 % (s) | to 5 % (s) | to 2 % (s) | to 1 % (s) |\n|---|---:|---|---:|---:|---:|---:|\n",
    );
    let mut ratios = String::from(
        "| scene | N | target | best GCR (s) | GCR curve | best other (s) | other | GCR / best other |\n|---|---:|---:|---:|---|---:|---|---:|\n",
    );
    let mut md = String::new();
    for name in &p.scenes {
        for &n in &p.counts {
            let t = Instant::now();
            let (curves, note) = one(name, n, &p)?;
            println!("field: {name} N={n} {:.1} s", t.elapsed().as_secs_f64());
            let png = format!("field-{name}-{n}.png");
            plot_curves(
                &figs.join(&png),
                &format!("{name}, {n} points: error against time"),
                "relative L2 error at the points",
                &curves,
            )?;
            for c in &curves {
                let cell = |x: f64| {
                    c.time_to(x)
                        .map_or("not reached".into(), |s| format!("{s:.2}"))
                };
                writeln!(
                    summary,
                    "| {name} | {n} | {} | {} | {} | {} | {} |",
                    c.name,
                    cell(0.10),
                    cell(0.05),
                    cell(0.02),
                    cell(0.01)
                )?;
            }
            for &x in &targets {
                let best = |gcr: bool| {
                    curves
                        .iter()
                        .filter(|c| c.name.starts_with("gcr") == gcr)
                        .filter_map(|c| c.time_to(x).map(|s| (s, c.name.clone())))
                        .min_by(|a, b| a.0.total_cmp(&b.0))
                };
                let (g, o) = (best(true), best(false));
                let f = |v: &Option<(f64, String)>| {
                    v.as_ref()
                        .map_or("not reached".into(), |(s, _)| format!("{s:.2}"))
                };
                let ratio = match (&g, &o) {
                    (Some((a, _)), Some((b, _))) => format!("{:.2}", a / b),
                    (None, Some(_)) => "GCR does not reach it".into(),
                    (Some(_), None) => "only GCR reaches it".into(),
                    _ => "-".into(),
                };
                writeln!(
                    ratios,
                    "| {name} | {n} | {:.0} % | {} | {} | {} | {} | {ratio} |",
                    100.0 * x,
                    f(&g),
                    g.as_ref().map_or("-", |v| v.1.as_str()),
                    f(&o),
                    o.as_ref().map_or("-", |v| v.1.as_str())
                )?;
            }
            writeln!(
                md,
                "### {name}, N = {n}\n\n| solver | budget | seconds | rel. L2 error |\n|---|---:|---:|---:|"
            )?;
            for c in &curves {
                for q in &c.points {
                    writeln!(
                        md,
                        "| {} | {} | {:.3} | {:.2} % |",
                        c.name,
                        q.budget,
                        q.seconds,
                        100.0 * q.error
                    )?;
                }
            }
            writeln!(md, "\n{note}.\n\n![{name} {n}](figures/{png})\n")?;
        }
    }
    let out = format!(
        "# Whole-scene field benchmark (issue 16)\n\n\
         Generated by `{env}cargo xtask bench --only field{quick}` (release; overwritten by it). {threads} rayon threads; \
         compare ratios within one run. Total run time {total:.0} s.\n\n\
         Every solver produces B at N points spread area-uniformly (R2 set, `SurfaceSampler::spread`) over the faces that \
         do not emit; the error is the relative L2 `‖B̃ − B_ref‖₂/‖B_ref‖₂` over a fixed subset of {subset} of them and the \
         three bands, against the NEE path tracer run adaptively to {refe:.1} % relative standard error per band and point. \
         Times: from the built-in scene (its construction and BVH, measured once and added to every solver) to the N values. \
         `gcr default`: what `gcr solve` does for points by default — the paths gather (every ray corrected, so no network \
         is trained) run to the target errors 10, 5, 2, 1 % from a 16-ray pilot, paths shared between up to 16 neighbouring \
         points (`crates/gcr/src/estimator/neighbours.rs`); budget = rays per point it took. `gcr alone`: the same with every point \
         alone (`--share-paths 1`). \
         Other GCR curves: budget = kernel cells (shading cells = half), one solve per cell count (its time in every curve), curve \
         per gather ray count (direct = indirect = rays): `gcr rays R` the ray gather, `gcr paths R` the consistent \
         gather with {corrected_pct:.0} % of its rays corrected by paths (`FIELD_CORRECTED`; at 100 % the networks \
         are not read); path tracer: paths per point; HR + gather: links (ε = c·max E·max ρ, \
         16 gather rays per leaf; not run above 20 000 input triangles); Mitsuba 3 (`scalar_rgb`, `path` integrator \
         unbounded depth, `ldsampler`, one `batch` sensor of radiancemeters, one render per spp): budget = spp, time = its \
         meshes + sensors + render as the script measures them (not the interpreter start and import).\n\n\
         ## Time to reach 10 / 5 / 2 / 1 % (log-log interpolated between runs)\n\n{summary}\n\
         ## GCR against the best other solver\n\n{ratios}\n## Every run\n\n{md}",
        quick = if ctx.quick { " --quick" } else { "" },
        env = [
            "FIELD_SCENES",
            "FIELD_N",
            "FIELD_SOLVERS",
            "FIELD_CELLS",
            "FIELD_CORRECTED"
        ]
        .iter()
        .filter_map(|k| std::env::var(k).ok().map(|v| format!("{k}={v} ")))
        .collect::<String>(),
        threads = rayon::current_num_threads(),
        total = start.elapsed().as_secs_f64(),
        subset = p.subset,
        refe = 100.0 * p.ref_error,
        corrected_pct = 100.0 * corrected_fraction(),
    );
    std::fs::write(ctx.out.join("benchmarks-field.md"), out)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rel_l2_is_relative_over_points_and_bands() {
        let r = [[1.0, 2.0, 2.0], [0.0; 3]];
        let v = [[1.0, 2.0, 2.0], [0.3, 0.0, 0.4]];
        assert!((rel_l2(&v, &r) - 0.5 / 3.0).abs() < 1e-15);
    }
}
