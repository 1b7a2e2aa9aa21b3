//! Benchmarks of the `compare` group: time against error for every solver on the same probes of the
//! same scene against one high-accuracy reference, in one run (issue #6). Writes `benchmarks.md` and
//! one log-log plot of error against seconds per scene (`figures/comparison-bench-<scene>.png`).
//! `--quick` writes into `ctx.out` too (by default docs/): do not commit quick output.
//!
//! * **Flatland** (`flatland-corner`, `flatland-blocker`): reference = [`ExactSolver`] on a fine mesh
//!   (final gather at the probes). Solvers: GCR (kernel and ray gathers), classical radiosity (the same
//!   exact-form-factor solver on a coarse mesh, linear interpolation between element centres), HR
//!   (leaf value at the probe) and the Flatland path tracer.
//! * **3-D** (`wall-floor`, `cornell-box`, `two-blockers`): reference = the pointwise path tracer with
//!   many paths per probe. Solvers: GCR (kernel and ray gathers), classical radiosity (uniform mesh,
//!   element value), HR (leaf value, and a final gather at the probe), the path tracer.
//!
//! **Error**: relative L2 over probes and bands of B against the reference, normalised by the
//! reference's reflected part `B − E`, at probes on surfaces that reflect (ρ > 0). In 3-D that is every
//! non-emitting probe (the lights have ρ = 0); in `flatland-corner` both segments emit and reflect, and
//! the normalisation keeps the exact emission out of the score.
//!
//! Progressive refinement (3-D only) shoots on the finest classical mesh that fits, stopped at 10 %, 3 %,
//! 1 % and 0.1 % unshot power; its budget is the number of shots (form factor columns).

use super::gcr::{Curve, Point, scene_and_probes};
use crate::ctx::Ctx;
use anyhow::Result;
use baselines::classical::{ClassicalOptions, FormFactorOptions, Mesh};
use baselines::flatland::{ExactOptions, ExactSolver};
use baselines::hierarchical::{FlatHr, FlatHrConfig, TriHr, TriHrConfig, budget, solve_for_links};
use baselines::progressive::ProgressiveOptions;
use gcr::{Domain, Emitters, GatherMode, SolveConfig, radiosity_at_points};
use glam::{DVec2, DVec3};
use rayon::prelude::*;
use scene_sampler::{FlatKernelSampler, FlatPoint, FlatlandScene, KernelSampler, SceneBvh};
use std::fmt::Write;
use std::time::Instant;

/// `‖values − reference‖₂ / ‖reference − emission‖₂` over probes and bands (module docs).
fn reflected_l2(values: &[[f64; 3]], reference: &[[f64; 3]], emission: &[[f64; 3]]) -> f64 {
    let (mut num, mut den) = (0.0, 0.0);
    for ((v, r), e) in values.iter().zip(reference).zip(emission) {
        for b in 0..3 {
            num += (v[b] - r[b]).powi(2);
            den += (r[b] - e[b]).powi(2);
        }
    }
    (num / den.max(1e-300)).sqrt()
}

fn d3(v: DVec2) -> DVec3 {
    DVec3::new(v.x, v.y, 0.0)
}

/// Budgets of one run: (GCR cells, classical element lengths as fractions of the scene diagonal,
/// HR budgets (Flatland: links; 3-D: ε as a fraction of max E · max ρ), path counts).
struct Budgets {
    gcr: &'static [usize],
    classical: &'static [f64],
    hr: &'static [f64],
    paths: &'static [usize],
}

/// Times `f` in seconds.
fn timed<T>(f: impl FnOnce() -> T) -> (T, f64) {
    let t = Instant::now();
    let v = f();
    (v, t.elapsed().as_secs_f64())
}

/// Appends a point and prints it.
fn push(curve: &mut Curve, scene: &str, budget: usize, seconds: f64, error: f64) {
    curve.record(&format!("compare: {scene}"), budget, seconds, error);
}

/// GCR on any domain: one solve per budget, then each gather at the probes.
fn gcr_curves(
    scene: &str,
    domain: &Domain,
    probes: &[(DVec3, DVec3, u32)],
    score: &dyn Fn(&[[f64; 3]]) -> f64,
    budgets: &[usize],
) -> Result<Vec<Curve>> {
    let emitters = Emitters::new(domain);
    let gathers = [GatherMode::Kernel, GatherMode::Rays];
    let mut curves: Vec<Curve> = gathers
        .iter()
        .map(|g| Curve::new(&format!("gcr {}", g.name())))
        .collect();
    for &cells in budgets {
        let config = SolveConfig {
            kernel_cells: cells,
            shading_cells: (cells / 2).max(3),
            ..SolveConfig::default()
        };
        let (trained, solve_s) = timed(|| gcr::solve(domain, &config, &mut |_| {}));
        let trained = trained?;
        for (c, &gather) in curves.iter_mut().zip(&gathers) {
            let config = SolveConfig { gather, ..config };
            let (values, gather_s) = timed(|| {
                radiosity_at_points(domain, &trained, &emitters, &config, probes).map(|b| {
                    b.into_iter()
                        .map(|g| g.radiosity)
                        .collect::<Vec<[f64; 3]>>()
                })
            });
            let values = values?;
            push(c, scene, cells, solve_s + gather_s, score(&values));
        }
    }
    Ok(curves)
}

/// Probes spread by arc length over the reflecting segments of a Flatland scene.
fn flat_probes(scene: &FlatlandScene, ks: &FlatKernelSampler, count: usize) -> Vec<FlatPoint> {
    (0..4 * count)
        .map(|i| ks.sampler.sample((i as f64 + 0.5) / (4 * count) as f64))
        .filter(|p| scene.segments[p.segment as usize].rho.max() > 0.0)
        .step_by(4)
        .collect()
}

/// One Flatland scene: every solver's curve, the reference's time and its self-check.
fn flatland(name: &str, b: &Budgets, probes: usize) -> Result<(Vec<Curve>, String)> {
    let scene = scene_sampler::builtin(name)?.into_flatland()?;
    let ks = FlatKernelSampler::new(&scene);
    let points = flat_probes(&scene, &ks, probes);
    let emission: Vec<[f64; 3]> = points
        .iter()
        .map(|p| scene.segments[p.segment as usize].emission.0)
        .collect();
    let gather = |s: &ExactSolver| -> Result<Vec<[f64; 3]>> {
        Ok(points
            .par_iter()
            .map(|p| s.gather(p))
            .collect::<Result<_, _>>()?)
    };
    // Reference: fine mesh, and a check against one twice as coarse.
    let fine = 0.002 * scene.diagonal();
    let (reference, ref_s) = timed(|| -> Result<_> {
        let s = ExactSolver::new(
            &scene,
            &ExactOptions {
                element_length: fine,
                ..ExactOptions::default()
            },
        )?;
        gather(&s)
    });
    let reference = reference?;
    let coarse = ExactSolver::new(
        &scene,
        &ExactOptions {
            element_length: 2.0 * fine,
            ..ExactOptions::default()
        },
    )?;
    let check = reflected_l2(&gather(&coarse)?, &reference, &emission);
    let note = format!(
        "reference: `ExactSolver` with elements of {fine:.4} (0.002 × diagonal), final gather at {} probes, \
         {ref_s:.2} s; the same at twice the element length differs from it by {:.2e}",
        points.len(),
        check
    );
    println!("compare: {name} {note}");
    let score = |v: &[[f64; 3]]| reflected_l2(v, &reference, &emission);

    let domain = Domain::Flat(FlatKernelSampler::new(&scene));
    let probes3: Vec<(DVec3, DVec3, u32)> = points
        .iter()
        .map(|p| (d3(p.point), d3(p.normal), p.segment))
        .collect();
    let mut curves = gcr_curves(name, &domain, &probes3, &score, b.gcr)?;

    let mut classical = Curve::new("classical");
    for &frac in b.classical {
        let (v, s) = timed(|| -> Result<Vec<[f64; 3]>> {
            let solver = ExactSolver::new(
                &scene,
                &ExactOptions {
                    element_length: frac * scene.diagonal(),
                    tolerance: 1e-9,
                    ..ExactOptions::default()
                },
            )?;
            Ok(points
                .iter()
                .map(|p| solver.interpolate(p))
                .collect::<Result<_, _>>()?)
        });
        let elements = scene
            .segments
            .iter()
            .map(|sg| (sg.length / (frac * scene.diagonal())).ceil() as usize)
            .sum();
        push(&mut classical, name, elements, s, score(&v?));
    }
    curves.push(classical);

    let mut hr = Curve::new("HR");
    for &links in b.hr {
        let links = links as usize;
        let base = FlatHrConfig {
            min_length: budget::min_length_for(&scene, links),
            ..FlatHrConfig::default()
        };
        let Ok(found) = solve_for_links(&scene, links, base, 0.05) else {
            println!("compare: {name} HR budget {links} not reached");
            continue;
        };
        // Timed: one solve at the ε the budget search found (not the search itself).
        let (v, s) = timed(|| -> Result<Vec<[f64; 3]>> {
            let hr = FlatHr::solve(
                &scene,
                FlatHrConfig {
                    epsilon: found.epsilon,
                    ..base
                },
            )?;
            Ok(points
                .iter()
                .map(|p| hr.radiosity_at(p).map(|r| r.0))
                .collect::<Result<_, _>>()?)
        });
        push(&mut hr, name, found.hr.link_count(), s, score(&v?));
    }
    curves.push(hr);

    let mut pt = Curve::new("path tracer");
    for &paths in b.paths {
        let (v, s) =
            timed(|| baselines::flatland::path_trace_at(&scene, &ks.vis, &points, paths, 11));
        let v: Vec<[f64; 3]> = v?.into_iter().map(|e| e.mean).collect();
        push(&mut pt, name, paths, s, score(&v));
    }
    curves.push(pt);
    Ok((curves, note))
}

/// One 3-D scene: every solver's curve and the reference's description.
fn three_d(
    name: &str,
    b: &Budgets,
    probes: usize,
    reference_paths: usize,
) -> Result<(Vec<Curve>, String)> {
    let (scene, points) = scene_and_probes(name, probes)?;
    let bvh = SceneBvh::new(&scene);
    // The path tracer's cost per path grows with the scene's depth complexity: on the million-triangle
    // scene 500 000 paths per probe take 6 minutes; 200 000 keep its noise near 1.5 %.
    let reference_paths = if scene.faces.len() > HR_MAX_FACES {
        reference_paths.min(200_000)
    } else {
        reference_paths
    };
    let (est, ref_s) = timed(|| {
        baselines::pointwise::radiosity_at(&scene, &bvh, &points, reference_paths, 0x5EED)
    });
    let reference: Vec<[f64; 3]> = est.iter().map(|e| e.mean).collect();
    let emission: Vec<[f64; 3]> = points
        .iter()
        .map(|p| scene.faces[p.face as usize].emission.0)
        .collect();
    // The reference's own noise as a relative L2: ‖std error‖ / ‖B − E‖.
    let noise = reflected_l2(
        &est.iter()
            .zip(&reference)
            .map(|(e, r)| [0, 1, 2].map(|k| r[k] + e.std_error[k]))
            .collect::<Vec<_>>(),
        &reference,
        &emission,
    );
    let note = format!(
        "reference: path tracer, {reference_paths} paths per probe at {} probes, {ref_s:.1} s; its standard \
         error as a relative L2 is {:.2} %",
        points.len(),
        100.0 * noise
    );
    println!("compare: {name} {note}");
    let score = |v: &[[f64; 3]]| reflected_l2(v, &reference, &emission);

    let domain = Domain::ThreeD(KernelSampler::new(&scene, &bvh));
    let probes3: Vec<(DVec3, DVec3, u32)> =
        points.iter().map(|p| (p.point, p.normal, p.face)).collect();
    let mut curves = gcr_curves(name, &domain, &probes3, &score, b.gcr)?;

    let mut classical = Curve::new("classical");
    for &frac in b.classical {
        let opts = ClassicalOptions {
            element_size: frac * scene.diagonal(),
            form_factors: FormFactorOptions {
                visibility_rays: 8,
                ..FormFactorOptions::default()
            },
            ..ClassicalOptions::default()
        };
        let elements = match Mesh::new(&scene, opts.element_size) {
            Ok(mesh) => mesh.elements.len(),
            Err(e) => {
                println!("compare: {name} classical skipped: {e}");
                continue;
            }
        };
        if elements > 3000 {
            println!(
                "compare: {name} classical {elements} elements: skipped (too slow for the run)"
            );
            continue;
        }
        let (v, s) = timed(|| -> Result<Vec<[f64; 3]>> {
            Ok(baselines::classical::solve(&scene, &bvh, &opts)?.at_points(&points)?)
        });
        push(&mut classical, name, elements, s, score(&v?));
    }
    curves.push(classical);

    // Progressive refinement on the finest classical mesh that fits, stopped at decreasing
    // fractions of unshot power: its budget axis is the number of shots (form factor columns).
    let mut progressive = Curve::new("progressive");
    if let Some(&frac) =
        b.classical.iter().rev().find(|&&f| {
            Mesh::new(&scene, f * scene.diagonal()).is_ok_and(|m| m.elements.len() <= 3000)
        })
    {
        for tolerance in [0.1, 0.03, 0.01, 0.001] {
            let opts = ProgressiveOptions {
                classical: ClassicalOptions {
                    element_size: frac * scene.diagonal(),
                    form_factors: FormFactorOptions {
                        visibility_rays: 8,
                        ..FormFactorOptions::default()
                    },
                    ..ClassicalOptions::default()
                },
                tolerance,
                ..ProgressiveOptions::default()
            };
            let (v, s) = timed(|| -> Result<(usize, Vec<[f64; 3]>)> {
                let sol = baselines::progressive::solve(&scene, &bvh, &opts)?;
                Ok((sol.shots, sol.at_points(&points)?))
            });
            let (shots, v) = v?;
            push(&mut progressive, name, shots, s, score(&v));
        }
    }
    curves.push(progressive);

    let (mut e_max, mut rho_max) = (0.0f64, 0.0f64);
    for f in &scene.faces {
        e_max = e_max.max(f.emission.max());
        rho_max = rho_max.max(f.rho.max());
    }
    let (mut leaf, mut gathered) = (Curve::new("HR leaf"), Curve::new("HR gather"));
    // HR links every pair of input polygons before it refines (O(n²) initial links): on the
    // million-triangle scene that is 10¹² links, so it is not run there.
    let hr_budgets = if scene.faces.len() > HR_MAX_FACES {
        println!(
            "compare: {name} HR skipped: {} input polygons (initial linking is quadratic; limit {HR_MAX_FACES})",
            scene.faces.len()
        );
        &[][..]
    } else {
        b.hr
    };
    for &frac in hr_budgets {
        let config = TriHrConfig {
            epsilon: frac * e_max * rho_max,
            min_area: budget::min_area_for(&scene, 20_000),
            max_links: 300_000,
            ..TriHrConfig::default()
        };
        let (hr, solve_s) = timed(|| TriHr::solve(&scene, config));
        let hr = match hr {
            Ok(hr) => hr,
            Err(e) => {
                println!("compare: {name} HR ε = {:.3e}: {e}", config.epsilon);
                continue;
            }
        };
        let links = hr.link_count();
        let (v, s) = timed(|| -> Result<Vec<[f64; 3]>> {
            Ok(points
                .iter()
                .map(|p| hr.radiosity_at(p).map(|r| r.0))
                .collect::<Result<_, _>>()?)
        });
        push(&mut leaf, name, links, solve_s + s, score(&v?));
        let (v, s) = timed(|| -> Result<Vec<[f64; 3]>> {
            Ok(points
                .par_iter()
                .enumerate()
                .map(|(i, p)| hr.gather_at(p, 16, i as u64).map(|r| r.0))
                .collect::<Result<_, _>>()?)
        });
        push(&mut gathered, name, links, solve_s + s, score(&v?));
    }
    curves.push(leaf);
    curves.push(gathered);

    let mut pt = Curve::new("path tracer");
    for &paths in b.paths {
        let (est, s) =
            timed(|| baselines::pointwise::radiosity_at(&scene, &bvh, &points, paths, 11));
        let v: Vec<[f64; 3]> = est.into_iter().map(|e| e.mean).collect();
        push(&mut pt, name, paths, s, score(&v));
    }
    curves.push(pt);
    Ok((curves, note))
}

/// Writes one log-log plot of error against seconds ([`super::gcr::plot_curves`]). Runs with an
/// error above 1000 % (diverged, listed in the tables) are left out and the title says so.
/// Largest scene (input polygons) HR runs on in this benchmark.
const HR_MAX_FACES: usize = 20_000;

fn plot_curves(path: &std::path::Path, title: &str, curves: &[Curve]) -> Result<()> {
    let ok = |p: &Point| p.error.is_finite() && p.error <= 10.0;
    let dropped = curves.iter().flat_map(|c| &c.points).any(|p| !ok(p));
    let title = if dropped {
        format!("{title} (diverged runs left out)")
    } else {
        title.to_string()
    };
    let curves: Vec<Curve> = curves
        .iter()
        .map(|c| Curve {
            name: c.name.clone(),
            points: c.points.iter().copied().filter(ok).collect(),
        })
        .collect();
    super::gcr::plot_curves(
        path,
        &title,
        "relative L2 error of B at the probes",
        &curves,
    )
}

/// Seconds with three significant digits (the Flatland runs take micro- to milliseconds).
fn secs(s: f64) -> String {
    if s >= 1.0 {
        format!("{s:.2}")
    } else {
        format!("{s:.2e}")
    }
}

/// An error as a percentage; values above 1000 % are marked as diverged.
fn pct(e: f64) -> String {
    if e.is_finite() && e <= 10.0 {
        format!("{:.2} %", 100.0 * e)
    } else {
        format!("diverged ({e:.1e})")
    }
}

/// Markdown table of every run of one scene.
fn markdown(curves: &[Curve]) -> String {
    let mut md =
        String::from("| solver | budget | seconds | rel. L2 error |\n|---|---:|---:|---:|\n");
    for c in curves {
        for p in &c.points {
            let _ = writeln!(
                md,
                "| {} | {} | {} | {} |",
                c.name,
                p.budget,
                secs(p.seconds),
                pct(p.error)
            );
        }
    }
    md
}

/// The shortest measured time among the runs whose error is at most `target` (no interpolation:
/// with noisy timings a log-log interpolation between runs can come out non-monotone).
fn time_to(curve: &Curve, target: f64) -> Option<f64> {
    curve
        .points
        .iter()
        .filter(|p| p.error <= target)
        .map(|p| p.seconds)
        .min_by(f64::total_cmp)
}

/// Is this scene a Flatland one?
fn is_flat(name: &str) -> bool {
    name.starts_with("flatland")
}

/// Runs this group's benchmarks and writes its report into `ctx.out`.
/// The generated scene of about a million triangles (issue #6): the Cornell box cut into a million
/// small triangles ([`scene_sampler::builtin::tessellated_cornell`]), whose radiosity is the Cornell
/// box's: what changes against `cornell-box` is the cost of the polygon count alone.
const LARGE_SCENE: &str = "tessellated-cornell-1000000";

pub fn run(ctx: &Ctx) -> Result<()> {
    let (scenes, flat, three, probes, reference_paths): (&[&str], Budgets, Budgets, usize, usize) =
        if ctx.quick {
            (
                &["flatland-corner", "wall-floor"],
                Budgets {
                    gcr: &[16, 40],
                    classical: &[0.2, 0.1],
                    hr: &[16.0, 50.0],
                    paths: &[10, 100],
                },
                Budgets {
                    gcr: &[30],
                    classical: &[0.4],
                    hr: &[4e-3],
                    paths: &[10, 100],
                },
                40,
                2000,
            )
        } else {
            (
                &[
                    "flatland-corner",
                    "flatland-blocker",
                    "wall-floor",
                    "cornell-box",
                    "two-blockers",
                    LARGE_SCENE,
                ],
                Budgets {
                    gcr: &[16, 50, 150, 500],
                    classical: &[0.2, 0.1, 0.05, 0.02],
                    hr: &[16.0, 50.0, 150.0, 500.0],
                    paths: &[10, 100, 1000, 10_000],
                },
                Budgets {
                    gcr: &[50, 100, 200, 400],
                    classical: &[0.25, 0.15, 0.1, 0.07],
                    hr: &[4e-3, 2e-3, 1e-3, 5e-4],
                    paths: &[10, 30, 100, 300, 1000, 3000],
                },
                200,
                500_000,
            )
        };
    let start = Instant::now();
    let figs = ctx.out.join("figures");
    std::fs::create_dir_all(&figs)?;
    let mut md = String::new();
    let mut summary = String::from(
        "| scene | solver | to 10 % (s) | to 5 % (s) | to 2 % (s) |\n|---|---|---:|---:|---:|\n",
    );
    for &name in scenes {
        let t = Instant::now();
        let (curves, note) = if is_flat(name) {
            flatland(name, &flat, probes)?
        } else {
            three_d(name, &three, probes, reference_paths)?
        };
        println!("compare: {name} {:.1} s", t.elapsed().as_secs_f64());
        let png = format!("comparison-bench-{name}.png");
        plot_curves(
            &figs.join(&png),
            &format!("{name}: error against time"),
            &curves,
        )?;
        for c in &curves {
            // A solver with no run on this scene (skipped: too large for it) is "not run".
            let missing = if c.points.is_empty() {
                "not run"
            } else {
                "not reached"
            };
            let cell = |x: f64| time_to(c, x).map_or(missing.into(), secs);
            writeln!(
                summary,
                "| {name} | {} | {} | {} | {} |",
                c.name,
                cell(0.10),
                cell(0.05),
                cell(0.02)
            )?;
        }
        writeln!(md, "### {name}\n")?;
        md.push_str(&markdown(&curves));
        writeln!(md, "\n{note}.\n\n![{name}](figures/{png})\n")?;
    }
    let cpu = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|t| {
            t.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split(':').nth(1))
                .map(|m| m.trim().to_string())
        })
        .unwrap_or_else(|| "unknown CPU".into());
    let out = format!(
        "# Time against error: GCR, classical radiosity, HR and the path tracer\n\n\
         Generated by `cargo xtask bench --only compare{quick}` (release build; this file is overwritten by it). \
         Machine: {cpu}, {threads} rayon threads, shared with other jobs: absolute times are noisy, compare \
         ratios within one run. Total run time: {total:.0} s. Whole-scene output (B at 20 000 points) and the \
         consistent `paths` gather: `docs/results/benchmarks-field.md`, `docs/design/estimator.md`.\n\n\
         **Error**: relative L2 over probes and colour bands of B against one reference per scene, normalised \
         by the reference's reflected part `B − E`, at probes on reflecting surfaces (ρ > 0): \
         `‖B̃ − B_ref‖₂ / ‖B_ref − E‖₂`. Flatland: {probes} probes spaced by arc length, reference = \
         `baselines::flatland::ExactSolver` on a fine mesh with a final gather. 3-D: {probes} probes spread \
         area-uniformly over the non-emitting faces, reference = the pointwise path tracer with \
         {reference_paths} paths per probe (another seed than the path-tracer runs).\n\n\
         **Budgets**: GCR = kernel cells (shading cells = half; seconds = solve + gather at the probes; \
         `kernel` gather = B_refl read off the kernel network, `rays` = the ray gather); classical = elements \
         (Flatland: exact crossed-strings form factors, linear interpolation between element centres; 3-D: uniform \
         mesh, 8 visibility rays per pair, the element's value); HR = links (Flatland: ε found for the link budget, \
         time of one solve at that ε, leaf value; 3-D: fixed ε = c·max E·max ρ, time of the solve plus the leaf \
         value (`HR leaf`) or a final gather with 16 rays per leaf (`HR gather`)); path tracer = paths per probe \
         (its time grows with the number of probes, the others' hardly); progressive refinement (3-D) = shots on \
         the finest classical mesh of the run, stopped at 10 / 3 / 1 / 0.1 % unshot power, the element's value.\n\n\
         **The million-triangle scene** (`{large}`, the Cornell box cut into a million triangles): classical \
         radiosity and progressive refinement are not run (their mesh has at least one element per input \
         triangle, so a million elements and 10¹² form factors), nor is HR (10¹² initial links); its reference \
         uses at most 200 000 paths per probe.\n\n\
         ## Time to reach 10 / 5 / 2 % (seconds of the fastest run at or below the error)\n\n{summary}\n\
         ## Every run\n\n{md}",
        quick = if ctx.quick { " --quick" } else { "" },
        large = LARGE_SCENE,
        threads = rayon::current_num_threads(),
        total = start.elapsed().as_secs_f64(),
    );
    std::fs::write(ctx.out.join("benchmarks.md"), out)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_error_is_normalised_by_the_reflected_part() {
        // reference B = E + 1 at both probes; values off by 0.5 at one of them
        let reference = [[3.0; 3], [1.0; 3]];
        let emission = [[2.0; 3], [0.0; 3]];
        let values = [[3.5; 3], [1.0; 3]];
        let e = reflected_l2(&values, &reference, &emission);
        // ‖diff‖ = sqrt(3·0.25), ‖B − E‖ = sqrt(6)
        assert!((e - (0.75f64 / 6.0).sqrt()).abs() < 1e-15);
    }

    #[test]
    fn time_to_takes_the_fastest_run_that_reaches_the_target() {
        let mut c = Curve::new("x");
        for (budget, seconds, error) in [(1, 0.3, 0.2), (2, 0.2, 0.04), (3, 0.5, 0.01)] {
            c.points.push(Point {
                budget,
                seconds,
                error,
            });
        }
        assert_eq!(time_to(&c, 0.1), Some(0.2));
        assert_eq!(time_to(&c, 0.02), Some(0.5));
        assert_eq!(time_to(&c, 0.001), None);
    }
}
