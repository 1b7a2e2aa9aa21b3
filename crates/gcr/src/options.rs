//! A solve as the front ends ask for it (the `gcr solve` program's options, the Python package's
//! keyword arguments): [`SolveOptions`] holds what a user sets, with the program's defaults, and
//! turns it into the [`SolveConfig`] it runs ([`SolveOptions::config`]: the preset at the
//! quality, [`SolveConfig::preset`]); [`solve_for_outputs`] trains the networks only when
//! something reads them. One implementation for every front end, so that they run the same solve.

use crate::config::{
    GatherMode, GatherSamples, NetworkTarget, OutputFit, PathSettings, Quality, SolveConfig,
    SurfaceClusters,
};
use crate::domain::Domain;
use crate::solve::{Progress, SolveError, Trained};

/// The settings a user gives a solve; `None` and the defaults are the program's
/// (`gcr solve --help`).
#[derive(Clone, Debug, PartialEq)]
pub struct SolveOptions {
    /// `--quality`: the estimated relative error the paths gather runs to (default: good, unless
    /// `gather_rays` alone fixes the rays).
    pub quality: Option<Quality>,
    /// `--target-error`: that error as a fraction (wins over `quality`).
    pub target_error: Option<f64>,
    /// `--seed`.
    pub seed: u64,
    /// `--cells`: the kernel network's cell budget.
    pub cells: usize,
    /// `--shading-cells` (default: half the kernel's, at least 3).
    pub shading_cells: Option<usize>,
    /// `--time-budget` in seconds.
    pub time_budget: Option<f64>,
    /// `--gather`.
    pub gather: GatherMode,
    /// `--output-fit`.
    pub output_fit: OutputFit,
    /// `--network-target`.
    pub network_target: NetworkTarget,
    /// `--gather-rays`: shadow and cosine rays per point (alone: a fixed count; with a target,
    /// the first round's).
    pub gather_rays: Option<usize>,
    /// `--corrections` (default: every ray corrected).
    pub corrections: Option<usize>,
    /// `--share-paths`: at most this many neighbouring points share their paths (1: alone).
    pub share_paths: usize,
    /// `--guiding`: guided bounces ([`PathSettings::guiding`]).
    pub guiding: crate::Guiding,
    /// `--block-points` ([`PathSettings::block_points`]).
    pub block_points: usize,
    /// `--shard` ([`PathSettings::shard`]).
    pub shard: Option<crate::Shard>,
    /// `--keep-base`: train the shading network and its base even when nothing reads them.
    pub keep_base: bool,
    /// `--keep-networks`: train the networks even when nothing reads them.
    pub keep_networks: bool,
    /// `--kernel-facing`.
    pub kernel_facing: bool,
    /// `--cluster-min-elements` and `--cluster-theta`.
    pub surface_clusters: SurfaceClusters,
}

impl Default for SolveOptions {
    fn default() -> Self {
        let dissertation = SolveConfig::default();
        Self {
            quality: None,
            target_error: None,
            seed: dissertation.seed,
            cells: dissertation.kernel_cells,
            shading_cells: None,
            time_budget: None,
            gather: GatherMode::Paths,
            output_fit: OutputFit::default(),
            network_target: NetworkTarget::default(),
            gather_rays: None,
            corrections: None,
            share_paths: PathSettings::default().neighbours,
            guiding: PathSettings::default().guiding,
            block_points: PathSettings::default().block_points,
            shard: None,
            keep_base: false,
            keep_networks: false,
            kernel_facing: false,
            surface_clusters: SurfaceClusters::default(),
        }
    }
}

impl SolveOptions {
    /// The solver settings (not yet validated: [`SolveConfig::validate`]): the library's
    /// [`SolveConfig::preset`] at the quality, with the options given.
    pub fn config(&self) -> SolveConfig {
        let preset = SolveConfig::preset(self.quality.unwrap_or_default());
        // The paths gather runs to a target unless `gather_rays` alone fixes its rays (or another
        // gather is asked for).
        let target_error = self
            .target_error
            .or(match (self.quality, self.gather_rays) {
                (Some(q), _) => Some(q.target_error()),
                (None, None) if self.gather == GatherMode::Paths => preset.paths.target_error,
                (None, _) => None,
            });
        let rays = self.gather_rays.unwrap_or(if target_error.is_some() {
            preset.gather_samples.direct
        } else {
            GatherSamples::default().direct
        });
        SolveConfig {
            kernel_cells: self.cells,
            shading_cells: self.shading_cells.unwrap_or((self.cells / 2).max(3)),
            time_budget: self.time_budget,
            seed: self.seed,
            gather: self.gather,
            output_fit: self.output_fit,
            network_target: self.network_target,
            gather_samples: GatherSamples {
                direct: rays,
                indirect: rays,
            },
            paths: PathSettings {
                corrections: self.corrections.unwrap_or(preset.paths.corrections),
                target_error,
                neighbours: self.share_paths,
                guiding: self.guiding,
                block_points: self.block_points,
                shard: self.shard,
                ..preset.paths
            },
            skip_unused_base: !self.keep_base,
            kernel_facing: self.kernel_facing,
            surface_clusters: self.surface_clusters,
            ..preset
        }
    }

    /// Whether a solve with `config` trains the networks: when its gather reads them
    /// ([`SolveConfig::reads_networks`]), when an output does (`outputs_read_networks`:
    /// `OutputPlan::needs_networks`), or when told to keep them. Otherwise the solution has
    /// none ([`Trained::without_networks`]): the same values at points and pixels, less time.
    pub fn trains_networks(&self, config: &SolveConfig, outputs_read_networks: bool) -> bool {
        config.reads_networks() || outputs_read_networks || self.keep_networks
    }
}

/// Validates `config` and solves, training the networks only when
/// [`SolveOptions::trains_networks`] says so (`observer` then sees the training).
pub fn solve_for_outputs(
    domain: &Domain,
    options: &SolveOptions,
    config: &SolveConfig,
    outputs_read_networks: bool,
    observer: &mut dyn FnMut(&Progress),
) -> Result<Trained, SolveError> {
    if options.trains_networks(config, outputs_read_networks) {
        crate::solve::solve(domain, config, observer)
    } else {
        config.validate()?;
        Ok(Trained::without_networks(domain, config))
    }
}
