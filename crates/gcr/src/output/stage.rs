//! What the output stage has made so far, as its steps add to it.

use super::staged::StagedFiles;
use crate::config::SolveConfig;
use crate::estimator::GatherStats;
use crate::metrics::Metrics;

/// The output stage's state ([`super::write_outputs`]): the files staged (all written at the
/// end, or none), the run's metrics, and each output gather's statistics in the order the steps
/// ran them (recorded into the metrics at the end: [`Stage::record_gathers`], the last one
/// setting the error and ray count).
pub(super) struct Stage {
    /// The files, written when the stage commits.
    pub files: StagedFiles,
    /// The run's metrics so far.
    pub metrics: Metrics,
    /// What each output gather measured, in order.
    pub gathers: Vec<GatherStats>,
}

impl Stage {
    /// Adds what an output gather measured, with the trial recorded before it on this thread
    /// (`estimator::relay::take_trial`; the metrics' `guiding_trial`).
    pub(super) fn push_gather(&mut self, mut stats: GatherStats) {
        stats.trial = crate::estimator::relay::take_trial();
        self.gathers.push(stats);
    }

    /// Records what each output gather measured into the metrics, in order (the last output set
    /// wins: the mesh after the probes), the target they ran to, and their warnings
    /// ([`gather_warnings`]).
    pub(super) fn record_gathers(&mut self, config: &SolveConfig) {
        let metrics = &mut self.metrics;
        for stats in &self.gathers {
            metrics.network_share = stats.network_share;
            metrics.relative_std_error = stats.relative_std_error;
            metrics.gather_rays = stats.rays;
            metrics.guided = stats.guided;
            metrics.guiding_trial = stats.trial;
            metrics.target_error = config.paths.target_error;
            metrics.warnings.extend(gather_warnings(stats, config));
        }
    }
}

/// What the numbers of a gather cannot say: no light at all, a target the ray cap kept out of
/// reach (the warnings of the metrics and of `gcr solve`).
pub fn gather_warnings(stats: &GatherStats, config: &SolveConfig) -> Vec<String> {
    let mut warnings = Vec::new();
    if stats.dark {
        warnings.push(
            "every output point got 0: no light reaches them (a light inside closed geometry or \
             behind the surfaces, a sun below the horizon, or reflectance 0 everywhere?)"
                .into(),
        );
    }
    if let (Some(target), Some(error)) = (config.paths.target_error, stats.relative_std_error) {
        if error > target && stats.rays >= config.paths.max_rays {
            warnings.push(format!(
                "the target error {:.3} % was not met: {:.3} % at the cap of {} rays per point",
                100.0 * target,
                100.0 * error,
                config.paths.max_rays
            ));
        }
    }
    warnings
}
