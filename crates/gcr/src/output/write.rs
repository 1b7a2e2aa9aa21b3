//! The output stage of a solve: every file `gcr solve` writes, and the metrics of the run.
//!
//! [`write_outputs`] runs the steps in order — the probes ([`super::probes`]), the 3-D outputs
//! ([`super::views`]: the output mesh, images, the lightmap) or Flatland's images
//! ([`super::flatland`]) — each adding its files and gather statistics to one [`Stage`], and
//! writes every file at once through [`super::StagedFiles`]: either every output reaches its
//! target, or none does.

use super::OutputError;
use super::plan::OutputPlan;
use super::stage::Stage;
use crate::config::SolveConfig;
use crate::domain::Domain;
use crate::emitters::Emitters;
use crate::metrics::{Metrics, peak_memory_bytes};
use crate::solve::Trained;
use std::time::Instant;

/// Gathers, renders and writes every output of `plan` for a solution, and returns the run's
/// metrics: `trained.metrics` completed with the scene name, the gather, the output mesh, the
/// gather and output times, the total time since `started` and the peak memory (these are what
/// the metrics file holds). All files are written through [`super::StagedFiles`]: on an error
/// no target is created or changed.
pub fn write_outputs(
    domain: &Domain,
    trained: &Trained,
    config: &SolveConfig,
    plan: &OutputPlan,
    scene_name: &str,
    started: Instant,
) -> Result<Metrics, OutputError> {
    let paths = plan.paths();
    let mut metrics = trained.metrics.clone();
    metrics.scene = scene_name.to_string();
    metrics.gather = config.gather.name().to_string();
    metrics.scene_elements = domain.elements().len();
    let (files, gathers) = (super::StagedFiles::new(), Vec::new());
    let mut stage = Stage {
        files,
        metrics,
        gathers,
    };
    let emitters = Emitters::new(domain);
    // ⟨The probes⟩
    if let Some(path) = &paths.probe_out {
        let probes = (plan.probes(), &plan.probe_settings);
        super::probes::write_probes(
            domain,
            (trained, &emitters),
            config,
            probes,
            path,
            &mut stage,
        )?;
    }
    // ⟨The 3-D outputs (the mesh, images, the lightmap), or Flatland's images⟩
    if domain.scene_3d().is_some() {
        super::views::write_3d(domain, trained, config, plan, &mut stage)?;
    } else {
        super::flatland::write_images(domain, (trained, &emitters), config, plan, &mut stage)?;
    }
    // ⟨What the gathers measured, the times and memory; then every file at once⟩
    stage.record_gathers(config);
    let Stage {
        mut files,
        mut metrics,
        ..
    } = stage;
    metrics.seconds.total = started.elapsed().as_secs_f64();
    metrics.peak_memory_bytes = peak_memory_bytes();
    if let Some(path) = &paths.metrics {
        let json = serde_json::to_string_pretty(&metrics).map_err(OutputError::Metrics)?;
        files.write_bytes(path, json.as_bytes())?;
    }
    files.commit()?;
    Ok(metrics)
}
