//! `gcr reference`: adaptive path tracing (`baselines`) at the probes until a relative standard
//! error (or a path cap).

use crate::args::ReferenceArgs;
use anyhow::{Context, Result};
use gcr::output::staged::{StagedFiles, check_target};
use scene_sampler::{AnyScene, SceneBvh};
use std::time::Instant;

/// Runs `gcr reference`: B per probe to `--probe-out`, a summary on stderr.
pub fn run(args: &ReferenceArgs) -> Result<()> {
    let start = Instant::now();
    let adaptive = baselines::Adaptive {
        rel_error: args.rel_error,
        max_paths: args.max_paths,
        seed: args.seed,
        ..baselines::Adaptive::default()
    };
    check_target(&args.probe_out, "probe", None)?;
    let loaded = scene_sampler::load_or_builtin(&args.scene)
        .with_context(|| format!("loading scene `{}`", args.scene))?;
    for w in loaded.warnings() {
        eprintln!("warning: {w}");
    }
    let probes = &args.probes;
    let source = probes.display().to_string();
    let (estimates, grey) = match loaded {
        AnyScene::ThreeD(s) => {
            let points = s.snap_probes(&scene_sampler::read_probes(probes)?, &source)?;
            let bvh = SceneBvh::new(&s);
            let est = baselines::pointwise::radiosity_adaptive(&s, &bvh, &points, &adaptive)?;
            (est, false)
        }
        AnyScene::Flatland(s) => {
            let points = s.snap_probes(&scene_sampler::read_flat_probes(probes)?, &source)?;
            let vis = scene_sampler::FlatVisibility::new(&s);
            let est = baselines::flatland::path_trace_adaptive(&s, &vis, &points, &adaptive)?;
            (est, s.bands == 1)
        }
    };
    let mut out = String::new();
    let (mut paths, mut worst) = (0usize, 0.0f64);
    for e in &estimates {
        if grey {
            out.push_str(&format!("{}\n", e.mean[0]));
        } else {
            out.push_str(&format!("{} {} {}\n", e.mean[0], e.mean[1], e.mean[2]));
        }
        paths += e.paths;
        for b in 0..3 {
            if e.mean[b] > 0.0 {
                worst = worst.max(e.std_error[b] / e.mean[b]);
            }
        }
    }
    let mut staged = StagedFiles::new();
    staged.write_bytes(&args.probe_out, out.as_bytes())?;
    staged.commit()?;
    eprintln!(
        "reference: {} probes, {paths} paths, worst relative standard error {:.4}, {:.1} s",
        estimates.len(),
        worst,
        start.elapsed().as_secs_f64()
    );
    Ok(())
}
