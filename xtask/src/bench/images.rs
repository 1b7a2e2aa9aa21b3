//! The `images` group (issue 18, "done when"): per-pixel images of the 3-D built-ins from their
//! cameras against Mitsuba 3. Writes `benchmarks-images.md`.
//!
//! * **Reference**: a Mitsuba 3 render of the same scene and camera (`xtask/py/mitsuba_image.py`:
//!   `perspective` sensor with `look_at`, `fov_axis = y`, box filter, `path` integrator,
//!   `multijitter`) at `REF_SPP` samples per pixel, cached in `$CARGO_TARGET_DIR/image-refs/`
//!   (default `target/`). Not `ldsampler`: it renders a furnace 0.4 % too bright whatever the spp
//!   (`xtask/py/mitsuba_scene.py`), a bias the earlier references carried.
//! * **Error**: relative MSE, Σ (L − L_ref)² / Σ L_ref² over pixels and bands (linear radiance).
//! * **Solvers**: `gcr solve --image-mode pixel` as the library runs it (the default paths gather to the
//!   target errors 10, 5, 2, 1 % of the pixels, no networks: a path tracer over each pixel's footprint), and
//!   Mitsuba at 4–1024 spp (`multijitter` also 2304) with each of its two best samplers,
//!   `ldsampler` (lower error at low spp, biased) and `multijitter`; GCR is compared with the
//!   better of the two at its time. Every
//!   time includes building the scene (GCR: its BVH; Mitsuba: its meshes and sensor, not the interpreter).
//!   The reference's own error is estimated from the 1024-spp render's (noise falls as 1/spp in MSE).
//!
//! Skipped with a note when `mitsuba` is not importable (the reference needs it).
//! `IMAGE_SCENES=cornell-box` restricts the scenes (`temple`: the public temple compound under the
//! daylit bench's sun and CIE overcast sky, not run by default); `IMAGE_TARGETS=0.1,0.05` sets GCR's
//! targets; `IMAGE_SEED=N` sets GCR's seed (a single run's
//! error on an emitter's outline is heavy-tailed: checker-room at 64 rays read 2.04e-4 with the
//! default seed, 3.0–4.0e-5 with seeds 2–5); `IMAGE_GCR_ONLY=1` runs GCR against the cached
//! reference without Mitsuba's runs. The 3-D built-ins (the generated ones at 10 000
//! random-box and 100 000 tessellated triangles) and `scenes/checker-room.obj`:
//! checkerboard albedo textures (`map_Kd`), given to Mitsuba as the same linear texels (`bitmap`, raw,
//! bilinear, repeat), from its bounding-box camera; and `sun-patch-room`, the hard-indirect view:
//! `scenes/sun-patch-room.obj` from inside, lit only by its lighting file's sun (a delta direction
//! for both) through the window.

use super::field::{mitsuba_runs, read_values, run_mitsuba, write_mitsuba_faces};
use super::gcr::{Curve, plot_curves};
use crate::ctx::Ctx;
use anyhow::{Context, Result, bail};
use gcr::output::PinholeCamera;
use gcr::output::render_pixels;
use gcr::{Domain, GatherMode, GatherSamples, PathSettings, SolveConfig, Trained};
use scene_sampler::{KernelSampler, Scene, SceneBvh};
use std::fmt::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The paths gather's first round per pixel (`gcr solve`'s default, 16).
const PILOT: usize = 16;

/// Samples per pixel of the cached Mitsuba reference.
const REF_SPP: usize = 4096;

/// Mitsuba's sampler for the reference: unbiased (module docs).
const REF_SAMPLER: &str = "multijitter";

/// Mitsuba's samplers compared with GCR, each a curve.
const SAMPLERS: [&str; 2] = ["ldsampler", "multijitter"];

/// Sizes of one run.
struct Plan {
    scenes: Vec<String>,
    size: (u32, u32),
    targets: Vec<f64>,
    spp: &'static [usize],
    /// More sample counts for the unbiased sampler only (`ldsampler` would round 2304 = 48² up to
    /// 4096, a square power of two): the longest GCR runs stay within Mitsuba's.
    spp_unbiased: &'static [usize],
    ref_spp: usize,
}

fn plan(quick: bool) -> Plan {
    let scenes = std::env::var("IMAGE_SCENES").ok().map(|s| {
        s.split(',')
            .map(|x| x.trim().to_string())
            .collect::<Vec<_>>()
    });
    let targets: Option<Vec<f64>> = std::env::var("IMAGE_TARGETS")
        .ok()
        .map(|s| s.split(',').filter_map(|x| x.trim().parse().ok()).collect());
    if quick {
        Plan {
            scenes: scenes.unwrap_or_else(|| vec!["wall-floor".into()]),
            size: (32, 32),
            targets: targets.unwrap_or_else(|| vec![0.05]),
            spp: &[16],
            spp_unbiased: &[],
            ref_spp: 256,
        }
    } else {
        Plan {
            scenes: scenes.unwrap_or_else(|| {
                [
                    "cornell-box",
                    "two-blockers",
                    "wall-floor",
                    "closed-room",
                    "furnace",
                    "tessellated-cornell-100000",
                    "random-boxes-10000",
                    "scenes/checker-room.obj",
                    SUN_PATCH,
                ]
                .map(String::from)
                .to_vec()
            }),
            size: (96, 96),
            targets: targets.unwrap_or_else(|| vec![0.1, 0.05, 0.02, 0.01]),
            spp: &[4, 16, 64, 256, 1024],
            spp_unbiased: &[2304],
            ref_spp: REF_SPP,
        }
    }
}

/// The error of an image `a` against the reference `r`: with `IMAGE_METRIC=pixel` the per-pixel
/// relative MSE image users and papers use, mean((a − r)²/(r² + 0.01)) over pixels and bands
/// (linear radiance); otherwise Σ (a − r)² / Σ r² over pixels and bands. The metric's ε = 0.01
/// assumes radiance of order 1 (the built-ins' mean is 0.02–0.64): an image whose reference's mean
/// is above 1 (the temple in cd/m², mean 970) is divided by that mean first, or a pixel the
/// reference saw as black and a ray saw a sliver of lit wall in would weigh 10⁸ times a lit one.
fn rel_mse(a: &[[f64; 3]], r: &[[f64; 3]]) -> f64 {
    if std::env::var("IMAGE_METRIC").is_ok_and(|m| m == "pixel") {
        let mean = r.iter().flatten().sum::<f64>() / (3 * r.len().max(1)) as f64;
        let s = 1.0 / mean.max(1.0);
        let sum: f64 = (a.iter().zip(r))
            .flat_map(|(x, y)| {
                (0..3).map(move |k| (s * (x[k] - y[k])).powi(2) / ((s * y[k]).powi(2) + 0.01))
            })
            .sum();
        return sum / (3 * r.len().max(1)) as f64;
    }
    let (mut n, mut d) = (0.0, 0.0);
    for (x, y) in a.iter().zip(r) {
        for k in 0..3 {
            n += (x[k] - y[k]).powi(2);
            d += y[k] * y[k];
        }
    }
    n / d.max(1e-300)
}

/// One Mitsuba render: samples per pixel, seconds, linear radiance per pixel.
type Render = (usize, f64, Vec<[f64; 3]>);

/// Mitsuba renders of `scene` from `camera` at each of `spp`, or the reason it was skipped.
fn mitsuba(
    scene: &Scene,
    camera: &PinholeCamera,
    (w, h): (u32, u32),
    (spp, sampler): (&[usize], &str),
    (tag, emitters): (&str, Option<&Path>),
) -> Result<std::result::Result<Vec<Render>, String>> {
    let dir = std::env::temp_dir().join(format!("gcr-images-{}-{tag}", std::process::id()));
    std::fs::create_dir_all(&dir)?;
    let (ff, cf, of) = (dir.join("faces.txt"), dir.join("camera.txt"), dir.join("l"));
    write_mitsuba_faces(scene, &ff)?;
    let (e, t, u) = (camera.eye, camera.target, camera.up);
    std::fs::write(
        &cf,
        format!(
            "{} {} {} {} {} {} {} {} {} {} {w} {h}\n",
            e.x, e.y, e.z, t.x, t.y, t.z, u.x, u.y, u.z, camera.fov_y_degrees
        ),
    )?;
    let flag = Path::new("--emitters");
    let files: Vec<&Path> = match emitters {
        Some(e) => vec![flag, e, &ff, &cf, &of],
        None => vec![&ff, &cf, &of],
    };
    let stdout = match run_mitsuba("mitsuba_image.py", sampler, &files, spp)? {
        Ok(o) => o,
        Err(why) => return Ok(Err(why)),
    };
    let mut runs = Vec::new();
    for (spp, seconds) in mitsuba_runs(&stdout)? {
        let values = read_values(&PathBuf::from(format!("{}.{spp}", of.display())))?;
        if values.len() != (w * h) as usize {
            bail!("mitsuba wrote {} pixels for {w}x{h}", values.len());
        }
        runs.push((spp, seconds, values));
    }
    let _ = std::fs::remove_dir_all(&dir);
    Ok(Ok(runs))
}

/// The cached Mitsuba reference of one scene and size (rendered when missing).
fn reference(
    name: &str,
    (scene, emitters): (&Scene, Option<&Path>),
    camera: &PinholeCamera,
    size: (u32, u32),
    spp: usize,
) -> Result<std::result::Result<Vec<[f64; 3]>, String>> {
    let target = std::env::var("CARGO_TARGET_DIR").unwrap_or_else(|_| "target".into());
    let dir = Path::new(&target).join("image-refs");
    std::fs::create_dir_all(&dir)?;
    let path = dir.join(format!(
        "{name}-{}x{}-{spp}-{REF_SAMPLER}.txt",
        size.0, size.1
    ));
    if path.exists() {
        println!("images: {name} reference from {}", path.display());
        return Ok(Ok(read_values(&path)?));
    }
    let t = Instant::now();
    let runs = match mitsuba(
        scene,
        camera,
        size,
        (&[spp], REF_SAMPLER),
        (&format!("{name}-ref"), emitters),
    )? {
        Ok(r) => r,
        Err(why) => return Ok(Err(why)),
    };
    let values = runs.into_iter().next().context("no reference render")?.2;
    let text: String = values
        .iter()
        .map(|v| format!("{:e} {:e} {:e}\n", v[0], v[1], v[2]))
        .collect();
    std::fs::write(&path, text)?;
    println!(
        "images: {name} reference at {spp} spp: {:.1} s",
        t.elapsed().as_secs_f64()
    );
    Ok(Ok(values))
}

/// The scene `name` (a built-in, a file, or `temple`: the public temple compound under the daylit
/// bench's sun and sky, `super::daylit::temple_lit`) and, for lights besides emitting faces, a
/// file of them as Mitsuba emitters; `Ok(Err(why))` when the scene cannot be had.
fn lit_scene(name: &str) -> Result<std::result::Result<(Scene, Option<PathBuf>), String>> {
    let (scene, emitters) = match name {
        "temple" => match super::daylit::temple_lit()? {
            Ok(lit) => lit,
            Err(why) => return Ok(Err(why)),
        },
        SUN_PATCH => sun_patch_room()?,
        _ => return Ok(Ok((scene_sampler::load_or_builtin(name)?.into_3d()?, None))),
    };
    let path = std::env::temp_dir().join(format!("gcr-images-{}-lights.json", std::process::id()));
    std::fs::write(&path, serde_json::to_string(&emitters)?)?;
    Ok(Ok((scene, Some(path))))
}

/// The hard-indirect view (issue 36): `scenes/sun-patch-room.obj`, lit only by the sun through
/// its window (`IMAGE_SCENES=sun-patch-room`).
const SUN_PATCH: &str = "sun-patch-room";

/// The sun patch room under its lighting file's sun made a delta direction for both renderers
/// (Mitsuba's `directional` has no disc; a disc's penumbra would differ at the patch's edges),
/// and the sun as a Mitsuba emitter.
fn sun_patch_room() -> Result<(Scene, serde_json::Value)> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes");
    let mut scene = scene_sampler::load(root.join("sun-patch-room.obj"))?.into_3d()?;
    let mut lighting = scene_sampler::Lighting::read(&root.join("sun-patch-room.lights.json"))?;
    let sun = lighting.sun.as_mut().context("the sun patch room's sun")?;
    sun.diameter = 0.0;
    let toward = lighting.up.direction(sun.azimuth, sun.elevation);
    let mitsuba = serde_json::json!([{"type": "directional",
        "direction": (-toward).to_array(), "irradiance": sun.illuminance}]);
    scene.add_lights(lighting.lights()?);
    Ok((scene, mitsuba))
}

/// Every solver on one scene: the curves, and a note.
fn one(name: &str, p: &Plan) -> Result<std::result::Result<(Vec<Curve>, String), String>> {
    let (scene, emitters) = match lit_scene(name)? {
        Ok(lit) => lit,
        Err(why) => return Ok(Err(why)),
    };
    let emitters = emitters.as_deref();
    let camera = match name {
        // the view `gcr solve` picks for it (`automatic-outside`, printed with --image): the
        // compound from above, where the bounding box's camera sees it edge-on from the ground
        "temple" => PinholeCamera {
            eye: glam::DVec3::new(186.425, 140.107, -1.041),
            target: glam::DVec3::new(-2.355, 7.922, -1.041),
            up: glam::DVec3::Y,
            fov_y_degrees: 40.0,
        },
        // `gcr solve`'s view of it (`automatic-inside`): the sun patch on the floor, the window
        SUN_PATCH => PinholeCamera {
            eye: glam::DVec3::new(5.25, 1.25, 1.583_333),
            target: glam::DVec3::new(4.542_893, 1.25, 2.290_44),
            up: glam::DVec3::Y,
            fov_y_degrees: 60.0,
        },
        _ => PinholeCamera::of_scene(&scene),
    };
    let name = &slug(name);
    let r = match reference(name, (&scene, emitters), &camera, p.size, p.ref_spp)? {
        Ok(r) => r,
        Err(why) => return Ok(Err(why)),
    };
    let label = format!("images: {name}");
    let mut curves = Vec::new();
    {
        let mut c = Curve::new("gcr pixel");
        for &target in &p.targets {
            let t = Instant::now();
            let bvh = SceneBvh::new(&scene);
            let domain = Domain::ThreeD(KernelSampler::new(&scene, &bvh));
            let config = SolveConfig {
                gather: GatherMode::Paths,
                gather_samples: GatherSamples {
                    direct: PILOT,
                    indirect: PILOT,
                },
                paths: PathSettings {
                    target_error: Some(target),
                    ..PathSettings::default()
                },
                seed: std::env::var("IMAGE_SEED")
                    .ok()
                    .and_then(|s| s.parse().ok())
                    .unwrap_or(SolveConfig::default().seed),
                ..SolveConfig::default()
            };
            let trained = Trained::without_networks(&domain, &config);
            let img = render_pixels(&domain, &trained, &config, &camera, (p.size.0, p.size.1, 1))?;
            let values: Vec<[f64; 3]> = img
                .radiance()
                .radiance
                .iter()
                .map(|l| l.map(f64::from))
                .collect();
            let seconds = t.elapsed().as_secs_f64();
            println!(
                "{label} gcr pixel target {:.0} %: {} rays per pixel, estimated {:.2} %",
                100.0 * target,
                img.stats.rays,
                100.0 * img.stats.relative_std_error.unwrap_or(0.0)
            );
            c.record(&label, img.stats.rays, seconds, rel_mse(&values, &r));
        }
        curves.push(c);
    }
    let mut note = format!("reference: Mitsuba 3 at {} spp ({REF_SAMPLER})", p.ref_spp);
    for sampler in SAMPLERS {
        if std::env::var("IMAGE_GCR_ONLY").is_ok() {
            break;
        }
        let mut spp = p.spp.to_vec();
        if sampler == REF_SAMPLER {
            spp.extend_from_slice(p.spp_unbiased);
        }
        match mitsuba(
            &scene,
            &camera,
            p.size,
            (&spp, sampler),
            (&format!("{name}-{sampler}"), emitters),
        )? {
            Ok(runs) => {
                let mut c = Curve::new(&format!("mitsuba 3 ({sampler})"));
                for (spp, seconds, values) in &runs {
                    c.record(&label, *spp, *seconds, rel_mse(values, &r));
                }
                if sampler == REF_SAMPLER {
                    // The reference's own relative MSE: its sampler's last render's, scaled by
                    // the spp ratio.
                    if let (Some(last), Some(q)) = (runs.last(), c.points.last()) {
                        write!(
                            note,
                            " (its own relative MSE ≈ {:.1e}, from the {}-spp render's)",
                            q.error * last.0 as f64 / p.ref_spp as f64,
                            last.0
                        )?;
                    }
                }
                curves.push(c);
            }
            Err(why) => {
                write!(note, "; Mitsuba curves skipped: {why}")?;
                break;
            }
        }
    }
    if let Some(file) = emitters {
        let _ = std::fs::remove_file(file);
    }
    Ok(Ok((curves, note)))
}

/// A scene's name for files and tables: a built-in's name, a file's stem.
fn slug(name: &str) -> String {
    Path::new(name)
        .file_stem()
        .map_or_else(|| name.to_string(), |s| s.to_string_lossy().into_owned())
}

/// The other curve's error at `seconds`, interpolated log-log between its runs (None outside).
fn error_at(c: &Curve, seconds: f64) -> Option<f64> {
    c.points.windows(2).find_map(|w| {
        let (a, b) = (w[0], w[1]);
        (a.seconds <= seconds && seconds <= b.seconds).then(|| {
            let f = (seconds.ln() - a.seconds.ln()) / (b.seconds.ln() - a.seconds.ln()).max(1e-12);
            (a.error.ln() + f * (b.error.ln() - a.error.ln())).exp()
        })
    })
}

/// Runs this group and writes `benchmarks-images.md` into `ctx.out`.
pub fn run(ctx: &Ctx) -> Result<()> {
    let p = plan(ctx.quick);
    let figs = ctx.out.join("figures");
    std::fs::create_dir_all(&figs)?;
    let mut md = String::new();
    let mut summary = String::from(
        "| scene | GCR run | seconds | GCR rel. MSE | Mitsuba rel. MSE at that time | ratio |\n|---|---|---:|---:|---:|---:|\n",
    );
    // every scene named is loadable, before any is run (a typo in `IMAGE_SCENES` would otherwise
    // lose the runs before it: the page is written at the end)
    for name in (p.scenes.iter()).filter(|n| !["temple", SUN_PATCH].contains(&n.as_str())) {
        scene_sampler::load_or_builtin(name).with_context(|| format!("images: scene `{name}`"))?;
    }
    for name in &p.scenes {
        let (curves, note) = match one(name, &p)? {
            Ok(x) => x,
            Err(why) => {
                println!("images: skipped: {why}");
                let text =
                    format!("# Per-pixel images against Mitsuba 3 (issue 18)\n\nSkipped: {why}.\n");
                std::fs::write(ctx.out.join("benchmarks-images.md"), text)?;
                return Ok(());
            }
        };
        let name = &slug(name);
        let png = format!("images-{name}.png");
        plot_curves(
            &figs.join(&png),
            &format!(
                "{name}, {}x{} pixels: relative MSE against time",
                p.size.0, p.size.1
            ),
            "per-pixel relative MSE",
            &curves,
        )?;
        writeln!(
            md,
            "### {name}\n\n| solver | budget | seconds | rel. MSE |\n|---|---:|---:|---:|"
        )?;
        for c in &curves {
            for q in &c.points {
                writeln!(
                    md,
                    "| {} | {} | {:.3} | {:.2e} |",
                    c.name, q.budget, q.seconds, q.error
                )?;
            }
        }
        writeln!(md, "\n{note}.\n\n![{name}](figures/{png})\n")?;
        let mitsuba: Vec<&Curve> = (curves.iter())
            .filter(|c| c.name.starts_with("mitsuba"))
            .collect();
        if !mitsuba.is_empty() {
            for c in curves.iter().filter(|c| c.name.starts_with("gcr")) {
                for q in &c.points {
                    // the better of Mitsuba's samplers at GCR's time; before its fastest run,
                    // that run's error (Mitsuba had more time: the ratio is an upper bound)
                    let other = (mitsuba.iter())
                        .filter_map(|m| error_at(m, q.seconds))
                        .min_by(f64::total_cmp);
                    let first = (mitsuba.iter())
                        .filter_map(|m| m.points.first())
                        .filter(|f| q.seconds < f.seconds)
                        .map(|f| f.error)
                        .min_by(f64::total_cmp);
                    let (theirs, ratio) = match (other, first) {
                        (Some(e), _) => (format!("{e:.2e}"), format!("{:.2}", q.error / e)),
                        (None, Some(e)) => (
                            format!("{e:.2e} (its fastest run, slower)"),
                            format!("≤ {:.2}", q.error / e),
                        ),
                        (None, None) => ("outside its runs".into(), "-".into()),
                    };
                    writeln!(
                        summary,
                        "| {name} | {} ({} rays) | {:.2} | {:.2e} | {theirs} | {ratio} |",
                        c.name, q.budget, q.seconds, q.error,
                    )?;
                }
            }
        }
    }
    let per_pixel = std::env::var("IMAGE_METRIC").is_ok_and(|m| m == "pixel");
    let out = format!(
        "# Per-pixel images against Mitsuba 3 (issue 18)\n\n\
         Generated by `{env}cargo xtask bench --only images{quick}` (release; overwritten by it), {threads} rayon \
         threads. Each built-in from its own camera at {w}×{h} pixels: `gcr --image-mode pixel` (the default \
         paths gather run to a target error, no networks) against Mitsuba 3 (`scalar_rgb`, `path`, box \
         filter; `ldsampler` and `multijitter`), both as linear radiance; error = {metric} against a \
         {ref_spp}-spp Mitsuba render of the same camera with `multijitter` (`ldsampler` renders a furnace \
         0.4 % too bright at any spp: `xtask/py/mitsuba_scene.py`). Ratio < 1: GCR's image is closer to \
         the reference than the better of Mitsuba's two samplers at the same time (log-log interpolated \
         between Mitsuba's runs; `≤`: GCR finished before Mitsuba's fastest run, which is compared).\n\n\
         ## Summary\n\n{summary}\n## Runs\n\n{md}",
        quick = if ctx.quick { " --quick" } else { "" },
        env = if per_pixel { "IMAGE_METRIC=pixel " } else { "" },
        metric = if per_pixel {
            "per-pixel relative MSE, mean((x − r)²/(r² + 0.01)) over pixels and bands (the metric \
             image users and papers use)"
        } else {
            "relative MSE, Σ (x − r)²/Σ r²"
        },
        threads = rayon::current_num_threads(),
        w = p.size.0,
        h = p.size.1,
        ref_spp = p.ref_spp,
    );
    std::fs::write(ctx.out.join("benchmarks-images.md"), out)?;
    Ok(())
}
