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
    let loaded = scene_sampler::load_or_builtin(&args.scene)
        .with_context(|| format!("loading scene `{}`", args.scene))?;
    for w in loaded.warnings() {
        eprintln!("warning: {w}");
    }
    match loaded {
        AnyScene::ThreeD(s) => {
            let bvh = SceneBvh::new(&s);
            let domain = Domain::ThreeD(KernelSampler::new(&s, &bvh));
            solve_and_write(&domain, args, &config, started)
        }
        AnyScene::Flatland(s) => {
            let domain = Domain::Flat(FlatKernelSampler::new(&s));
            solve_and_write(&domain, args, &config, started)
        }
    }
}

/// Checks the outputs (paths, probes) first, so that a bad one is reported before the solve.
fn solve_and_write(
    domain: &Domain,
    args: &SolveArgs,
    config: &SolveConfig,
    started: Instant,
) -> Result<()> {
    let plan = OutputPlan::new(domain, args.outputs())
        .with_context(|| format!("checking the outputs for `{}`", args.scene))?;
    let mut progress = ProgressLine::new(args.quiet);
    let trained = gcr::solve(domain, config, &mut |p| progress.update(p))?;
    progress.solved();
    for w in &trained.metrics.warnings {
        eprintln!("warning: {w}");
    }
    let metrics = write_outputs(domain, &trained, config, &plan, &args.scene, started)?;
    progress.done(&metrics);
    Ok(())
}
