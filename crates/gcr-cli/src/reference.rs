//! `gcr reference`: adaptive path tracing (`baselines`) at the probes until a relative standard
//! error (or a path cap).

use crate::args::ReferenceArgs;
use anyhow::{Context, Result};
use gcr::output::{ProbeQuantity, ProbeSettings};
use gcr::output::{StagedFiles, check_target};
use scene_sampler::probe::default_tolerance;
use scene_sampler::{AnyScene, SceneBvh};
use std::time::Instant;

/// Runs `gcr reference`: B (or irradiance) per probe to `--probe-out`, a summary on stderr.
pub fn run(args: &ReferenceArgs) -> Result<()> {
    let start = Instant::now();
    let adaptive = baselines::Adaptive {
        rel_error: args.rel_error,
        max_paths: args.max_paths,
        seed: args.seed,
        ..baselines::Adaptive::default()
    };
    check_target(&args.probe_out, "probe", None)?;
    if let Some(std_out) = &args.std_out {
        check_target(std_out, "standard error", None)?;
    }
    let loaded = scene_sampler::load_or_builtin_with(&args.scene, &args.input.load_options())
        .with_context(|| format!("loading scene `{}`", args.scene))?;
    for w in loaded.warnings() {
        eprintln!("warning: {w}");
    }
    let probes = &args.probes;
    let source = probes.display().to_string();
    let settings = ProbeSettings {
        quantity: args.probe_quantity,
        tolerance: args.probe_tolerance,
        outdoor_illuminance: args.lights.outdoor_illuminance(),
    };
    settings.validate()?;
    let loaded = args
        .lights
        .light(loaded, false)
        .with_context(|| format!("lighting `{}`", args.scene))?;
    let (estimates, grey) = match loaded {
        AnyScene::ThreeD(s) if settings.quantity.is_irradiance() => {
            let at: Vec<_> = (scene_sampler::read_probes(probes)?.iter())
                .map(|p| (p.point, p.normal))
                .collect();
            let bvh = SceneBvh::new(&s);
            let est = baselines::pointwise::irradiance_reference_at(&s, &bvh, &at, &adaptive)?;
            (est, false)
        }
        AnyScene::ThreeD(s) => {
            let tol = settings
                .tolerance
                .unwrap_or(default_tolerance(s.diagonal()));
            let points = (scene_sampler::read_probes(probes)?.iter())
                .map(|p| s.snap_probe(p, tol, &source))
                .collect::<Result<Vec<_>, _>>()?;
            let bvh = SceneBvh::new(&s);
            let est = baselines::pointwise::reference_at(&s, &bvh, &points, &adaptive)?;
            (est, false)
        }
        AnyScene::Flatland(_) if settings.quantity.is_irradiance() => {
            anyhow::bail!("the irradiance reference is for 3-D scenes (`gcr solve` has Flatland's)")
        }
        AnyScene::Flatland(s) => {
            let tol = settings
                .tolerance
                .unwrap_or(default_tolerance(s.diagonal()));
            let points = (scene_sampler::read_flat_probes(probes)?.iter())
                .map(|p| s.snap_probe(p, tol, &source))
                .collect::<Result<Vec<_>, _>>()?;
            let vis = scene_sampler::FlatVisibility::new(&s);
            let est = baselines::flatland::reference_at(&s, &vis, &points, &adaptive)?;
            (est, s.bands == 1)
        }
    };
    let bands = |v: [f64; 3]| {
        if grey {
            format!("{}", v[0])
        } else {
            format!("{} {} {}", v[0], v[1], v[2])
        }
    };
    // daylight factors in percent of the outdoor illuminance (checked positive by `validate`)
    let scale = match (settings.quantity, settings.outdoor_illuminance) {
        (ProbeQuantity::DaylightFactor, Some(e)) => 100.0 / e,
        _ => 1.0,
    };
    let (mut out, mut std) = (String::new(), String::new());
    for e in &estimates {
        out.push_str(&format!("{}\n", bands(e.estimate.mean.map(|v| v * scale))));
        std.push_str(&format!(
            "{} {} {}\n",
            bands(e.estimate.std_error.map(|v| v * scale)),
            e.estimate.paths,
            e.rel_error
        ));
    }
    let mut staged = StagedFiles::new();
    staged.write_bytes(&args.probe_out, out.as_bytes())?;
    if let Some(std_out) = &args.std_out {
        staged.write_bytes(std_out, std.as_bytes())?;
    }
    staged.commit()?;
    summarize(&estimates, args.rel_error, start);
    Ok(())
}

/// The closing lines: probes, paths, the worst relative error bound (∞ where no path found
/// light), and the probes (1-based lines) that missed the target at the path cap.
fn summarize(estimates: &[baselines::AdaptiveEstimate], target: f64, start: Instant) {
    let paths: usize = estimates.iter().map(|e| e.estimate.paths).sum();
    let worst = estimates.iter().map(|e| e.rel_error).fold(0.0, f64::max);
    eprintln!(
        "reference: {} probes, {paths} paths, worst relative standard error {worst:.4}, {:.1} s",
        estimates.len(),
        start.elapsed().as_secs_f64()
    );
    let missed: Vec<String> = (estimates.iter().enumerate())
        .filter(|(_, e)| !e.target_met)
        .map(|(i, e)| format!("{} ({:.4})", i + 1, e.rel_error))
        .collect();
    if !missed.is_empty() {
        eprintln!(
            "warning: {} of {} probes missed the target {target} at the path cap (line and \
             relative error; raise --max-paths): {}",
            missed.len(),
            estimates.len(),
            missed.join(", ")
        );
    }
}
