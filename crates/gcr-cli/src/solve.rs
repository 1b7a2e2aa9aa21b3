//! `gcr solve`: load the scene, check every output, solve, write all outputs at once.

use crate::args::SolveArgs;
use crate::progress::ProgressLine;
use anyhow::{Context, Result};
use gcr::output::{OutputPlan, write_outputs};
use gcr::{Domain, SolveConfig};
use scene_sampler::{AnyScene, FlatKernelSampler, KernelSampler, SceneBvh};
use std::time::Instant;

/// Runs `gcr solve`.
pub fn run(args: &SolveArgs) -> Result<()> {
    let config = args.config();
    config.validate()?;
    let started = Instant::now();
    let mut progress = ProgressLine::new(args.quiet);
    progress.step("loading", &args.scene);
    let loaded = scene_sampler::load_or_builtin_with(&args.scene, &args.input.load_options());
    // (cleared before an error too: the error's line must start the line)
    progress.step_done();
    let loaded = loaded.with_context(|| format!("loading scene `{}`", args.scene))?;
    let load = started.elapsed().as_secs_f64();
    for w in loaded.warnings() {
        eprintln!("warning: {w}");
    }
    // ⟨Lights beside the scene's own, then refuse a scene nothing lights⟩
    let loaded = args
        .lights
        .light(loaded, args.quiet)
        .with_context(|| format!("lighting `{}`", args.scene))?;
    // ⟨The scene as the estimators see it (a 3-D scene with its BVH, or Flatland)⟩
    let bvh;
    let built = Instant::now();
    let domain = match &loaded {
        AnyScene::ThreeD(s) => {
            progress.step("BVH", &format!("{} triangles", s.faces.len()));
            bvh = SceneBvh::new(s);
            progress.step_done();
            Domain::ThreeD(KernelSampler::new(s, &bvh))
        }
        AnyScene::Flatland(s) => Domain::Flat(FlatKernelSampler::new(s)),
    };
    let times = (load, built.elapsed().as_secs_f64());
    solve_and_write(&domain, (args, progress), &config, (started, times))
}

/// Checks the outputs (paths, probes) first, so that a bad one is reported before the solve.
fn solve_and_write(
    domain: &Domain,
    (args, mut progress): (&SolveArgs, ProgressLine),
    config: &SolveConfig,
    (started, (load, bvh)): (Instant, (f64, f64)),
) -> Result<()> {
    let (options, outputs) = (args.options(), args.outputs());
    let (images, probes, lightmap) = (
        args.images(),
        args.probe_settings(),
        args.lightmap_settings(),
    );
    let parts = gcr::output::shards::read_parts(&args.from_shards)?;
    let plan = OutputPlan::checked(domain, (outputs, images, probes), (lightmap, parts), config)
        .with_context(|| format!("checking the outputs for `{}`", args.scene))?;
    // ⟨Train the networks only when something reads them⟩
    let mut trained =
        gcr::solve_for_outputs(domain, &options, config, plan.needs_networks(), &mut |p| {
            progress.update(p)
        })?;
    (trained.metrics.seconds.load, trained.metrics.seconds.bvh) = (load, bvh);
    progress.solved();
    for w in &trained.metrics.warnings {
        eprintln!("warning: {w}");
    }
    let metrics = gcr::observe_gathers(progress.gathers(), || {
        write_outputs(domain, &trained, config, &plan, &args.scene, started)
    })?;
    for w in &metrics.warnings[trained.metrics.warnings.len().min(metrics.warnings.len())..] {
        eprintln!("warning: {w}");
    }
    progress.done(&metrics);
    if !args.quiet {
        print_images(&metrics);
    }
    Ok(())
}

/// The exposure and cameras used (also in the metrics), so that a run can be repeated.
fn print_images(m: &gcr::Metrics) {
    if let Some(e) = m.exposure {
        eprintln!(
            "exposure: {e} ({}; --exposure {e} repeats it)",
            m.exposure_source
        );
    }
    let v = |p: [f64; 3]| format!("{},{},{}", p[0], p[1], p[2]);
    for i in &m.images {
        eprintln!(
            "image {}: {}x{}, camera {} (--camera-eye {} --camera-target {} --camera-up {} \
             --fov {}), {:.0} % of the pixels on lit surfaces",
            i.path,
            i.width,
            i.height,
            i.camera_source,
            v(i.eye),
            v(i.target),
            v(i.up),
            i.fov_y_deg,
            100.0 * i.lit_share
        );
    }
}
