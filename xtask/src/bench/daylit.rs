//! The `daylit` group (issue 31, "targets"): the field bench's question — time to an error over a
//! whole scene — on rooms lit by the sky and the sun through openings, GCR against Mitsuba 3 and
//! Blender Cycles with the same lights as their own emitters. Writes `benchmarks-daylit.md`.
//!
//! * **Cases**: the side-lit room (`scenes/side-lit-room.obj`, one 1.6 × 1.2 m window) under a CIE
//!   overcast sky of 10 000 lux (gcr with the window as its sky portal, as the guide runs it); the
//!   sun patch room (`scenes/sun-patch-room.obj`) under a sun of 80 000 lux at 30° through its
//!   window, given as a delta direction (0° across) because Mitsuba's `directional` is one; the
//!   atrium (`scenes/atrium.obj`, open to the sky through its roof) under the CIE overcast sky of
//!   10 000 lux with its roof opening as the portal (`scenes/atrium.lights.json`). Black ground
//!   everywhere (Mitsuba's overcast map is black below the horizon). The grille room
//!   (`scenes/grille-lamp.gltf`, an alpha-masked grille and a glTF point lamp; [`grille_room`]),
//!   whose grille the peers get as solid bars.
//! * **Points**: N points spread area-uniformly over every face (`SurfaceSampler::spread`, an R2
//!   set), lifted 2·10⁻³ of the diagonal along the face's normal, irradiance E over the
//!   hemisphere of that normal (a receiver: Mitsuba's and Cycles' tiny white probes need the air).
//!   The error: relative L2 over the first 1 000 of them (the same R2 set at every N) and the three
//!   bands against the `baselines` path tracer's irradiance, adaptive to 0.5 % per point and band,
//!   cached in `$CARGO_TARGET_DIR/field-refs/`, with the reference's own noise taken out
//!   (`√(d² − noise²)`, as independent noises add).
//! * **Solvers**: gcr's default paths gather ([`super::irradiance::gcr_gathered`]) to the targets
//!   10, 5, 2, 1 %; Mitsuba 3 (`xtask/py/mitsuba_irradiance.py`, `multijitter`) and Cycles
//!   (`xtask/py/cycles_irradiance.py` under `CYCLES_PYTHON`, without path guiding) at rising spp,
//!   two seeds per run (their mean; the seconds are both). Times to 10 / 5 / 2 / 1 % interpolated
//!   log-log between runs; a peer that did not reach a target is extrapolated from its last run as
//!   error ∝ 1/√time and marked `*`.
//!
//! `DAYLIT_N=2000` sets N (default 20 000); `DAYLIT_CASES=sun,atrium` runs the cases whose names
//! contain one of the words; `DAYLIT_SOLVERS=gcr,mitsuba,cycles` the solvers.

use super::field::{Peer, cache_dir, rel_l2};
use super::gcr::Curve;
use super::irradiance::{Estimates, gcr_gathered, peer_lit, reference_irradiance};
use crate::ctx::Ctx;
use anyhow::Result;
use baselines::Adaptive;
use gcr::Guiding;
use glam::DVec3;
use scene_sampler::{Lighting, Scene, SceneBvh, SurfaceSampler};
use std::fmt::Write;
use std::hash::{Hash, Hasher};
use std::path::Path;
use std::time::Instant;

/// A case: its name, the scene with its lights, and the lights as Mitsuba 3 emitters; `peers`:
/// the geometry the peers get when it is not the scene's own (cut-outs made solid geometry).
struct Case {
    name: &'static str,
    scene: Scene,
    emitters: serde_json::Value,
    peers: Option<Scene>,
}

/// The targets of gcr's runs and of the table.
const TARGETS: [f64; 4] = [0.1, 0.05, 0.02, 0.01];

/// Points of the error subset.
const SUBSET: usize = 1000;

/// `scenes/<stem>.obj` lit by `lighting` (a lighting file's JSON).
fn lit(stem: &str, lighting: serde_json::Value) -> Result<Scene> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes");
    let mut scene = scene_sampler::load(root.join(format!("{stem}.obj")))?.into_3d()?;
    scene.add_lights(serde_json::from_value::<Lighting>(lighting)?.lights()?);
    Ok(scene)
}

fn cases() -> Result<Vec<Case>> {
    let overcast = serde_json::json!({"model": "cie-overcast", "illuminance": 10_000.0,
                                      "ground_reflectance": 0.0});
    // the CIE overcast sky's zenith radiance for 10 000 lux horizontal: E_h = 7π L_z / 9
    let zenith = 9.0 * 10_000.0 / (7.0 * std::f64::consts::PI);
    let sun = scene_sampler::lights::lighting::Up::Y.direction(180.0, 30.0);
    Ok(vec![
        Case {
            name: "side-lit room, CIE overcast 10 000 lux",
            scene: lit(
                "side-lit-room",
                serde_json::json!({"up": "y", "sky": overcast,
                    "portals": [[[1.2, 0.9, 5.0], [2.8, 0.9, 5.0], [2.8, 2.1, 5.0], [1.2, 2.1, 5.0]]]}),
            )?,
            emitters: serde_json::json!([{"type": "cie-overcast", "zenith": zenith}]),
            peers: None,
        },
        Case {
            name: "sun patch room, sun 80 000 lux at 30°",
            scene: lit(
                "sun-patch-room",
                serde_json::json!({"up": "y", "sun": {"azimuth": 180.0, "elevation": 30.0,
                    "illuminance": 80_000.0, "diameter": 0.0}}),
            )?,
            emitters: serde_json::json!([{"type": "directional",
                "direction": (-sun).to_array(), "irradiance": 80_000.0}]),
            peers: None,
        },
        Case {
            name: "atrium, CIE overcast 10 000 lux",
            scene: lit(
                "atrium",
                serde_json::json!({"up": "y", "sky": overcast,
                    "portals": [[[3.0, 8.0, 3.0], [7.0, 8.0, 3.0], [7.0, 8.0, 7.0], [3.0, 8.0, 7.0]]]}),
            )?,
            emitters: serde_json::json!([{"type": "cie-overcast", "zenith": zenith}]),
            peers: None,
        },
        grille_room()?,
    ])
}

/// The public temple compound ([`super::public_models::temple_compound`]) under a sun of
/// 80 000 lux at 35° (azimuth 200°) and a CIE overcast sky of 10 000 lux (black ground); `Ok(None)`
/// with a note when the model cannot be fetched.
fn temple(notes: &mut String) -> Result<Option<Case>> {
    let (scene, emitters) = match temple_lit()? {
        Ok(lit) => lit,
        Err(why) => {
            writeln!(notes, "- temple compound: skipped ({why}).")?;
            return Ok(None);
        }
    };
    Ok(Some(Case {
        name: "temple compound (public, 124 580 triangles), sun 80 000 lux at 35° + CIE overcast 10 000 lux",
        scene,
        emitters,
        peers: None,
    }))
}

/// The temple compound with its sun and sky ([`temple`]), and the same lights as Mitsuba 3
/// emitters (`xtask/py/mitsuba_scene.py`); `Ok(Err(why))` when the model cannot be fetched.
pub(super) fn temple_lit() -> Result<std::result::Result<(Scene, serde_json::Value), String>> {
    let obj = match super::public_models::temple_compound() {
        Ok(obj) => obj,
        Err(e) => return Ok(Err(format!("{e:#}"))),
    };
    let mut scene = scene_sampler::load(&obj)?.into_3d()?;
    let overcast = serde_json::json!({"model": "cie-overcast", "illuminance": 10_000.0,
                                      "ground_reflectance": 0.0});
    let lighting = serde_json::json!({"up": "y", "sky": overcast, "sun": {"azimuth": 200.0,
        "elevation": 35.0, "illuminance": 80_000.0, "diameter": 0.0}});
    scene.add_lights(serde_json::from_value::<Lighting>(lighting)?.lights()?);
    let zenith = 9.0 * 10_000.0 / (7.0 * std::f64::consts::PI);
    let sun = scene_sampler::lights::lighting::Up::Y.direction(200.0, 35.0);
    let emitters = serde_json::json!([{"type": "directional", "direction": (-sun).to_array(),
        "irradiance": 80_000.0}, {"type": "cie-overcast", "zenith": zenith}]);
    Ok(Ok((scene, emitters)))
}

/// The grille room (`scenes/grille-lamp.gltf`): a 6 × 3 × 6 m room split by a double-sided
/// grille cut out by an alpha mask (glTF `MASK`), lit by its `KHR_lights_punctual` point lamp
/// (300 cd, colour (1, 0.9, 0.8)). Its spot is left out: Mitsuba's and Cycles' spot falloffs are
/// not glTF's (the spot is checked against exact values in `crates/gcr/tests/lights.rs`). The
/// peers get the grille as what its mask cuts: 12 bars z ∈ [0.5k + 0.25, 0.5k + 0.5], 1 mm thick,
/// of the grille's reflectance (the mask is made so that this is exact:
/// `xtask/py/make_light_scenes.py`).
fn grille_room() -> Result<Case> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes");
    let mut scene = scene_sampler::load(root.join("grille-lamp.gltf"))?.into_3d()?;
    scene
        .lights
        .retain(|l| l.describe().starts_with("point light"));
    anyhow::ensure!(
        scene.lights.len() == 1,
        "grille-lamp.gltf: one point lamp expected"
    );
    let grille = (scene.faces.iter().enumerate())
        .find(|(_, f)| f.cutout.is_some())
        .map(|(i, f)| (i as u32, f.object))
        .ok_or_else(|| anyhow::anyhow!("grille-lamp.gltf has no cut-out face"))?;
    // the bars' reflectance: the grille's at a solid point (z = 0.375, the middle of the first bar)
    let rho = scene.rho_at(grille.0, DVec3::new(3.0, 1.5, 0.375));
    let mut faces: Vec<scene_sampler::Face> = scene
        .faces
        .iter()
        .filter(|f| f.cutout.is_none())
        .cloned()
        .collect();
    let t = 0.0005;
    let quad = |faces: &mut Vec<scene_sampler::Face>, c: [DVec3; 4]| {
        for tri in [[c[0], c[1], c[2]], [c[0], c[2], c[3]]] {
            faces.push(scene_sampler::Face::new(
                tri,
                rho,
                scene_sampler::Spectrum::ZERO,
                grille.1,
                grille.1,
            ));
        }
    };
    let p = |x: f64, y: f64, z: f64| DVec3::new(x, y, z);
    for k in 0..12 {
        let (z0, z1) = (0.5 * k as f64 + 0.25, 0.5 * k as f64 + 0.5);
        // ±x sides (counter-clockwise seen from outside), then the bar's edges facing ±z
        quad(
            &mut faces,
            [
                p(3.0 + t, 0.0, z0),
                p(3.0 + t, 3.0, z0),
                p(3.0 + t, 3.0, z1),
                p(3.0 + t, 0.0, z1),
            ],
        );
        quad(
            &mut faces,
            [
                p(3.0 - t, 0.0, z0),
                p(3.0 - t, 0.0, z1),
                p(3.0 - t, 3.0, z1),
                p(3.0 - t, 3.0, z0),
            ],
        );
        quad(
            &mut faces,
            [
                p(3.0 - t, 0.0, z0),
                p(3.0 - t, 3.0, z0),
                p(3.0 + t, 3.0, z0),
                p(3.0 + t, 0.0, z0),
            ],
        );
        if z1 < 6.0 {
            quad(
                &mut faces,
                [
                    p(3.0 - t, 0.0, z1),
                    p(3.0 + t, 0.0, z1),
                    p(3.0 + t, 3.0, z1),
                    p(3.0 - t, 3.0, z1),
                ],
            );
        }
    }
    let objects = scene.objects.clone();
    let mut bars = Scene::new("grille-lamp-bars", "daylit bench", faces, objects, None)?;
    bars.lights = scene.lights.clone();
    Ok(Case {
        name: "grille room, point lamp 300 cd (glTF)",
        scene,
        emitters: serde_json::json!([{"type": "point", "position": [1.5, 2.4, 3.0],
            "intensity": {"type": "rgb", "value": [300.0, 270.0, 240.0]}}]),
        peers: Some(bars),
    })
}

/// Whether the comma list in `var` (everything when unset) has a word contained in `name`.
fn wanted(var: &str, name: &str) -> bool {
    std::env::var(var).map_or(true, |v| v.split(',').any(|w| name.contains(w.trim())))
}

/// N points spread over every face, lifted off it, facing its normal (module docs).
fn points(scene: &Scene, n: usize) -> Vec<(DVec3, DVec3)> {
    let lift = 2e-3 * scene.diagonal();
    (SurfaceSampler::new(scene).spread(n, |_| true).iter())
        .map(|q| (q.point + lift * q.normal, q.normal))
        .collect()
}

/// The reference at `points`, from the cache when it holds one for these points and settings.
fn reference(
    name: &str,
    scene: &Scene,
    points: &[(DVec3, DVec3)],
    ad: &Adaptive,
) -> Result<(Estimates, String)> {
    let mut h = std::collections::hash_map::DefaultHasher::new();
    (
        name,
        scene.faces.len(),
        ad.rel_error.to_bits(),
        ad.max_paths,
        ad.seed,
        "daylit-v1",
    )
        .hash(&mut h);
    for (p, n) in points {
        for x in [p.x, p.y, p.z, n.x, n.y, n.z] {
            x.to_bits().hash(&mut h);
        }
    }
    let dir = cache_dir();
    let file = dir.join(format!("daylit-{:016x}.txt", h.finish()));
    let parse = |text: &str| -> Option<Estimates> {
        let rows: Vec<Vec<f64>> = (text.lines().skip(1))
            .map(|l| {
                l.split_whitespace()
                    .filter_map(|x| x.parse().ok())
                    .collect()
            })
            .collect();
        (rows.len() == points.len() && rows.iter().all(|r| r.len() == 6)).then(|| Estimates {
            mean: rows.iter().map(|r| [r[0], r[1], r[2]]).collect(),
            se: rows.iter().map(|r| [r[3], r[4], r[5]]).collect(),
        })
    };
    if let Some(est) = std::fs::read_to_string(&file).ok().and_then(|t| parse(&t)) {
        return Ok((est, format!("cached in {}", file.display())));
    }
    let t = Instant::now();
    let bvh = SceneBvh::new(scene);
    let est = reference_irradiance(scene, &bvh, points, ad)?;
    let note = format!("{:.0} s", t.elapsed().as_secs_f64());
    let mut text = format!("# {name}: baselines irradiance reference, {note}\n");
    for (m, s) in est.mean.iter().zip(&est.se) {
        writeln!(
            text,
            "{:e} {:e} {:e} {:e} {:e} {:e}",
            m[0], m[1], m[2], s[0], s[1], s[2]
        )?;
    }
    std::fs::create_dir_all(&dir)?;
    std::fs::write(&file, text)?;
    Ok((est, note))
}

/// The reference's own noise, `‖σ_ref‖₂/‖E_ref‖₂` over the subset's points and the bands.
fn noise(r: &Estimates) -> f64 {
    let noisy: Vec<[f64; 3]> = (r.mean.iter().zip(&r.se))
        .map(|(m, s)| [0, 1, 2].map(|k| m[k] + s[k]))
        .collect();
    rel_l2(&noisy, &r.mean)
}

/// `‖a − r‖₂/‖r‖₂` over the subset's points and the bands, the reference's own noise taken out
/// (`√(d² − noise²)`: independent noises add in squares).
fn error(a: &[[f64; 3]], r: &Estimates) -> f64 {
    (rel_l2(a, &r.mean).powi(2) - noise(r).powi(2))
        .max(0.0)
        .sqrt()
}

/// Seconds `curve` takes to `target`: interpolated, else (`extrapolate`) from its last run as
/// error ∝ 1/√time, marked `true`; None when not reached and not extrapolated.
fn time(curve: &Curve, target: f64, extrapolate: bool) -> Option<(f64, bool)> {
    if let Some(t) = curve.time_to(target) {
        return Some((t, false));
    }
    let p = curve.points.last().filter(|_| extrapolate)?;
    Some((p.seconds * (p.error / target).powi(2), true))
}

/// The table's cell for `curve` at `target` ([`time`]; `*`: extrapolated).
fn cell(curve: &Curve, target: f64, extrapolate: bool) -> String {
    match time(curve, target, extrapolate) {
        Some((t, false)) => format!("{t:.2}"),
        Some((t, true)) if t < 10.0 => format!("{t:.2}*"),
        Some((t, true)) => format!("{t:.0}*"),
        None => "not reached".into(),
    }
}

/// Runs this group and writes `benchmarks-daylit.md` into `ctx.out`.
pub fn run(ctx: &Ctx) -> Result<()> {
    let n: usize = std::env::var("DAYLIT_N")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(if ctx.quick { 300 } else { 20_000 });
    let (mitsuba_spp, cycles_spp): (&[usize], &[usize]) = if ctx.quick {
        (&[4], &[4])
    } else {
        (&[16, 64, 256, 1024], &[16, 64, 256])
    };
    let ad = Adaptive {
        rel_error: if ctx.quick { 0.05 } else { 0.005 },
        max_paths: 1_000_000,
        ..Adaptive::default()
    };
    let mut table = String::new();
    let mut notes = String::new();
    let mut all = cases()?;
    if wanted("DAYLIT_CASES", "temple compound") {
        all.extend(temple(&mut notes)?);
    }
    for case in all.into_iter().filter(|c| wanted("DAYLIT_CASES", c.name)) {
        let pts = points(&case.scene, n);
        let sub = &pts[..SUBSET.min(pts.len())];
        let (reference, how) = reference(case.name, &case.scene, sub, &ad)?;
        writeln!(
            notes,
            "- {}: {} faces, {} points; reference at {} of them ({how}; its noise {:.2} %).",
            case.name,
            case.scene.faces.len(),
            pts.len(),
            sub.len(),
            100.0 * noise(&reference),
        )?;
        let mut curves: Vec<(Curve, bool)> = Vec::new();
        if wanted("DAYLIT_SOLVERS", "gcr") {
            let mut c = Curve::new("gcr default");
            for &target in &TARGETS {
                let t = Instant::now();
                let g = gcr_gathered(&case.scene, &pts, target, Guiding::default())?;
                let seconds = t.elapsed().as_secs_f64();
                let values: Vec<[f64; 3]> = g[..sub.len()].iter().map(|x| x.radiosity).collect();
                c.record(
                    case.name,
                    (100.0 * target) as usize,
                    seconds,
                    error(&values, &reference),
                );
            }
            curves.push((c, false));
        }
        let emitters = std::env::temp_dir().join(format!("gcr-daylit-{}.json", std::process::id()));
        std::fs::write(&emitters, serde_json::to_string(&case.emitters)?)?;
        for (peer, spp) in [
            (Peer::Mitsuba, mitsuba_spp),
            (Peer::Cycles { guided: false }, cycles_spp),
        ] {
            if !wanted("DAYLIT_SOLVERS", peer.solver()) {
                continue;
            }
            let geometry = case.peers.as_ref().unwrap_or(&case.scene);
            match peer_lit(peer, geometry, &pts, spp, "multijitter", Some(&emitters))? {
                Ok(runs) => {
                    let mut c = Curve::new(peer.label());
                    for (spp, seconds, est) in runs {
                        c.record(
                            case.name,
                            spp,
                            seconds,
                            error(&est.mean[..sub.len()], &reference),
                        );
                    }
                    curves.push((c, true));
                }
                Err(why) => writeln!(notes, "- {}: {} skipped: {why}", case.name, peer.label())?,
            }
        }
        let _ = std::fs::remove_file(&emitters);
        let best_peer = |target: f64| {
            (curves.iter().filter(|(_, peer)| *peer))
                .filter_map(|(c, _)| time(c, target, true))
                .min_by(|a, b| a.0.total_cmp(&b.0))
        };
        for (c, peer) in &curves {
            let cells: Vec<String> = TARGETS.iter().map(|&t| cell(c, t, *peer)).collect();
            let ratio = |target: f64| match (c.time_to(target), best_peer(target)) {
                (Some(t), Some((b, false))) if !*peer => format!("{:.3}", t / b),
                (Some(t), Some((b, true))) if !*peer => format!("{:.3}*", t / b),
                _ => "-".into(),
            };
            let runs: Vec<String> = (c.points.iter())
                .map(|p| format!("{:.1} s → {:.2} %", p.seconds, 100.0 * p.error))
                .collect();
            writeln!(
                table,
                "| {} | {} | {} | {} | {} | {} |",
                case.name,
                c.name,
                cells.join(" | "),
                ratio(0.02),
                ratio(0.01),
                runs.join(", "),
            )?;
        }
    }
    let out = format!(
        "# Daylit rooms: the whole room, gcr against Mitsuba 3 and Cycles (issue 31)\n\n\
         Generated by `cargo xtask bench --only daylit` (release; overwritten by it), 2 rayon threads, one \
         run each; module docs of `xtask/src/bench/daylit.rs` for the set-up. Irradiance at {n} points \
         spread area-uniformly over every face of each room (lifted 2·10⁻³ of the diagonal, facing the \
         face's normal); the error is the relative L2 over the first {SUBSET} of them and the three bands \
         against the `baselines` path tracer adaptive to {:.1} % per point and band, the reference's own \
         noise taken out (√(d² − noise²)). Seconds from the loaded \
         scene (gcr: its BVH and the gather; the peers: their scene, probes and both seeds' renders) to the \
         N values. `*`: extrapolated from the peer's last run as error ∝ 1/√time (not run). Last columns but \
         one: gcr's time over the best peer's, interpolated (the issue's target: ≤ 0.5).\n\n{notes}\n\
         | room | solver | to 10 % (s) | to 5 % (s) | to 2 % (s) | to 1 % (s) | gcr / best peer, 2 % | gcr / best peer, 1 % | runs (time → error) |\n\
         |---|---|---:|---:|---:|---:|---:|---:|---|\n{table}",
        100.0 * ad.rel_error,
    );
    std::fs::write(ctx.out.join("benchmarks-daylit.md"), out)?;
    Ok(())
}
