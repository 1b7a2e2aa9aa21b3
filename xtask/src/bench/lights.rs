//! The `lights` group (issue 31, "peers at the same points"): each light type of
//! `scene_sampler::lights` in the shipped side-lit room (`scenes/side-lit-room.obj`, its window
//! open), irradiance at its 20 work-plane points (`scenes/side-lit-room.pts`), by
//! * the `baselines` path tracer to a 0.3 % relative standard error per point (the reference);
//! * `gcr` — the default paths gather to a 1 % target;
//! * Mitsuba 3 — `xtask/py/mitsuba_irradiance.py --emitters` with the same light as Mitsuba's own
//!   emitter (`point`, `directional`, `constant`, the CIE overcast sky as an `envmap`, and an
//!   environment map read by both from one EXR file),
//!   `multijitter` (unbiased), skipped with a note without `mitsuba`;
//! * Blender Cycles — `xtask/py/cycles_irradiance.py --emitters`, the same dicts as Blender lights
//!   and worlds (`xtask/py/cycles_scene.py`), under the
//!   Python of `CYCLES_PYTHON`.
//!
//! Writes `benchmarks-lights.md`. Spot lights are left out: Mitsuba's spot falloff is not glTF's
//! (`crates/gcr/tests/lights.rs` checks ours against its closed form).

use super::field::Peer;
use super::irradiance::{compare, gcr_irradiance, peer_lit, reference_irradiance};
use crate::ctx::Ctx;
use anyhow::Result;
use baselines::Adaptive;
use glam::DVec3;
use scene_sampler::lights::lighting::Up;
use scene_sampler::{EnvMap, Light, PointLight, SceneBvh, Sky, SkyModel, Sun};
use std::f64::consts::PI;
use std::fmt::Write;
use std::sync::Arc;
use std::time::Instant;

/// A light of the bench: its name, ours, and Mitsuba's emitter as JSON.
struct Case {
    name: &'static str,
    light: Arc<dyn Light>,
    mitsuba: serde_json::Value,
}

fn cases(dir: &std::path::Path) -> Result<Vec<Case>> {
    let sun = Up::Y.direction(200.0, 25.0);
    let (e_h, e_n) = (10_000.0, 60_000.0);
    let l_z = 9.0 * e_h / (7.0 * PI);
    Ok(vec![
        Case {
            name: "point light, 800 cd",
            light: Arc::new(PointLight::new(DVec3::new(2.0, 2.6, 2.5), [800.0; 3]).unwrap()),
            mitsuba: serde_json::json!({"type": "point", "position": [2.0, 2.6, 2.5],
                                        "intensity": 800.0}),
        },
        Case {
            name: "sun (0° across), 60 000 lux at 25°",
            light: Arc::new(Sun::new(sun, [e_n; 3], 0.0).unwrap()),
            mitsuba: serde_json::json!({"type": "directional", "direction": (-sun).to_array(),
                                        "irradiance": e_n}),
        },
        Case {
            name: "constant environment (uniform sky and ground), L = 10 000/π",
            light: Arc::new(
                Sky::new(SkyModel::Uniform, DVec3::Y, [e_h; 3], [e_h / PI; 3]).unwrap(),
            ),
            mitsuba: serde_json::json!({"type": "constant", "radiance": e_h / PI}),
        },
        Case {
            name: "CIE overcast sky, 10 000 lux, black ground",
            light: Arc::new(Sky::new(SkyModel::CieOvercast, DVec3::Y, [e_h; 3], [0.0; 3]).unwrap()),
            mitsuba: serde_json::json!({"type": "cie-overcast", "zenith": l_z}),
        },
        {
            let file = clear_sky_map(dir, sun)?;
            Case {
                name: "environment map (512 × 256 EXR: CIE clear sky, 10 000 lux, grey ground)",
                light: Arc::new(EnvMap::read(&file, Up::Y.frame(), 0.0, 1.0)?),
                mitsuba: serde_json::json!({"type": "envmap", "filename": file}),
            }
        },
    ])
}

/// An equirectangular EXR (Mitsuba's `envmap` layout, which ours follows): the CIE clear sky of
/// 10 000 lux for the sun toward `sun` at texel centres, the ground at L = 1 000/π.
fn clear_sky_map(dir: &std::path::Path, sun: DVec3) -> Result<std::path::PathBuf> {
    let sky = Sky::new(
        SkyModel::CieClear { sun },
        DVec3::Y,
        [1e4; 3],
        [1e3 / PI; 3],
    )
    .ok_or_else(|| anyhow::anyhow!("clear sky"))?;
    let (w, h) = (512_u32, 256_u32);
    let img = image::Rgb32FImage::from_fn(w, h, |i, j| {
        let phi = 2.0 * PI * (f64::from(i) + 0.5) / f64::from(w);
        let theta = PI * (f64::from(j) + 0.5) / f64::from(h);
        let d = DVec3::new(
            theta.sin() * phi.sin(),
            theta.cos(),
            -theta.sin() * phi.cos(),
        );
        image::Rgb([(sky.escaped(d)[0] / PI) as f32; 3])
    });
    let file = dir.join("clear-sky.exr");
    img.save(&file)?;
    Ok(file)
}

/// Runs this group and writes `benchmarks-lights.md` into `ctx.out`.
pub fn run(ctx: &Ctx) -> Result<()> {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let base = scene_sampler::load(root.join("scenes/side-lit-room.obj"))?.into_3d()?;
    let points: Vec<(DVec3, DVec3)> =
        scene_sampler::read_probes(root.join("scenes/side-lit-room.pts"))?
            .iter()
            .map(|p| (p.point, p.normal))
            .collect();
    let (rel, spp): (f64, &[usize]) = if ctx.quick {
        (0.03, &[16])
    } else {
        (0.003, &[256, 1024, 4096])
    };
    let mut md = String::from(
        "| light | solver | seconds | rel. L2 vs reference | its noise | Σd²/Σσ² |\n|---|---|---:|---:|---:|---:|\n",
    );
    let mut skipped: Vec<String> = Vec::new();
    let dir = std::env::temp_dir().join(format!("gcr-lights-{}", std::process::id()));
    std::fs::create_dir_all(&dir)?;
    for (k, case) in cases(&dir)?.into_iter().enumerate() {
        let mut scene = base.clone();
        scene.add_lights([case.light.clone()]);
        let bvh = SceneBvh::new(&scene);
        // ⟨The reference⟩
        let t = Instant::now();
        let adaptive = Adaptive {
            rel_error: rel,
            max_paths: 4_000_000,
            ..Adaptive::default()
        };
        let reference = reference_irradiance(&scene, &bvh, &points, &adaptive)?;
        let t_ref = t.elapsed().as_secs_f64();
        let name = case.name;
        writeln!(
            md,
            "| {name} | reference (baselines, {:.1} %) | {t_ref:.2} | - | {:.4} | - |",
            100.0 * rel,
            compare(&reference, &reference).1
        )?;
        // ⟨GCR: the default paths gather to 1 %⟩
        let t = Instant::now();
        let ours = gcr_irradiance(&scene, &points, 0.01)?;
        let t_gcr = t.elapsed().as_secs_f64();
        let (d, own, ratio) = compare(&ours, &reference);
        writeln!(
            md,
            "| {name} | gcr (paths, 1 %) | {t_gcr:.2} | {d:.4} | {own:.4} | {ratio:.2} |"
        )?;
        // ⟨Mitsuba 3 and Cycles, each with its own light⟩
        let file = dir.join(format!("emitters{k}.json"));
        std::fs::write(&file, serde_json::to_string(&[&case.mitsuba])?)?;
        for peer in [Peer::Mitsuba, Peer::Cycles { guided: false }] {
            match peer_lit(peer, &scene, &points, spp, "multijitter", Some(&file))? {
                Ok(runs) => {
                    for (spp, seconds, est) in runs {
                        let (d, own, ratio) = compare(&est, &reference);
                        writeln!(
                            md,
                            "| {name} | {} (2 × {spp} spp) | {seconds:.2} | {d:.4} | {own:.4} | {ratio:.2} |",
                            peer.label()
                        )?;
                    }
                }
                Err(why) => {
                    let why = format!("{} skipped on {name}: {why}", peer.label());
                    println!("lights: {why}");
                    skipped.push(why);
                }
            }
        }
        println!("lights: {name} done");
    }
    let _ = std::fs::remove_dir_all(&dir);
    let note: String = skipped.iter().map(|why| format!("\n{why}.\n")).collect();
    let out = format!(
        "# Lights against Mitsuba 3 and Cycles (issue 31)\n\n\
         Generated by `cargo xtask bench --only lights{quick}` (release; overwritten by it), {threads} \
         rayon threads. The side-lit room (`scenes/side-lit-room.obj`, a 1.6 × 1.2 window open to \
         the outside) lit by one light at a time, irradiance at the 20 work-plane points of \
         `scenes/side-lit-room.pts` (0.8 m, facing up). Reference: the `baselines` path tracer, \
         which samples the lights through the same interface as gcr (an independent estimator, \
         not independent light code); Mitsuba 3 has its own emitters (`point`, `directional`, \
         `constant`, the overcast sky as a 512 × 256 `envmap`, and the same EXR as ours for the \
         environment map — Mitsuba interpolates it bilinearly, ours is constant per texel), \
         `scalar_rgb`, `path`, \
         `multijitter`, two seeds per run (σ from their difference), at each point a tiny white \
         square seen by a radiancemeter (`xtask/py/mitsuba_irradiance.py`); Blender Cycles' baker \
         (bpy 5.0.1, CPU, 2 threads, no clamping) with the same lights as Blender lights and \
         worlds (the skies and the map resampled into its 1024 × 512 world texture), two seeds per \
         run, at each point a tiny white probe (`xtask/py/cycles_irradiance.py`). `its noise`: the \
         estimate's own ‖σ‖/‖E_ref‖; Σd²/Σσ² ≈ 1 when an estimate differs from the reference by the \
         two noises alone. The relative L2 is dominated by the brightest points (the sun patch, \
         the window).\n\n{md}{note}",
        quick = if ctx.quick { " --quick" } else { "" },
        threads = rayon::current_num_threads(),
    );
    std::fs::write(ctx.out.join("benchmarks-lights.md"), out)?;
    Ok(())
}
