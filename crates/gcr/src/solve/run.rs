//! The state of one solve that the loop's steps read and update, and what the observer sees.

use super::networks;
use super::trained::Trained;
use super::training::Trainer;
use crate::cell_lanes::Collection;
use crate::config::SolveConfig;
use crate::domain::Domain;
use crate::fem::{Base, FemSettings, FemSolution, SceneSurface, fem_step};
use crate::kernel_cells::KernelCells;
use crate::metrics::Metrics;
use crate::network::GrowingNetwork;
use crate::sample::Sample;
use crate::shooting::SenderDensity;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use std::sync::Arc;
use std::time::Instant;

/// What the observer sees during a solve.
#[derive(Clone, Copy, Debug, Default)]
pub struct Progress {
    /// Phase name: `"training"` while the networks grow, `"final"` for the final FEM steps.
    pub phase: &'static str,
    /// Kernel cells.
    pub kernel_cells: usize,
    /// Kernel cell budget.
    pub kernel_budget: usize,
    /// Shading cells.
    pub shading_cells: usize,
    /// Samples held.
    pub samples: usize,
    /// FEM steps so far.
    pub fem_steps: usize,
    /// Seconds since the start.
    pub elapsed: f64,
}

/// The last FEM step and the frozen kernel network it integrated, with its sender integrals:
/// new samples take their strengths from it.
pub(super) struct Current {
    /// The kernel collection through the frozen kernel and its sender integrals.
    pub(super) collection: Collection,
    pub(super) fem: FemSolution,
}

/// The state of one solve that every step reads or updates.
pub(super) struct Run<'a> {
    pub(super) domain: &'a Domain<'a>,
    pub(super) config: &'a SolveConfig,
    /// The loop's random choices (which sample to train on, new samples' seeds).
    pub(super) rng: ChaCha8Rng,
    pub(super) samples: Vec<Sample>,
    /// Rays shot so far, including those that left the scene (the projection's MC estimates
    /// divide by it).
    pub(super) shots: u64,
    pub(super) metrics: Metrics,
    /// The last FEM step with the kernel it integrated.
    pub(super) current: Option<Current>,
    /// The scene surface S every FEM integral runs over.
    pub(super) surface: Arc<SceneSurface>,
    pub(super) fem_settings: FemSettings,
    pub(super) density: SenderDensity,
    pub(super) start: Instant,
    pub(super) last_report: Instant,
}

impl<'a> Run<'a> {
    pub(super) fn new(domain: &'a Domain<'a>, config: &'a SolveConfig) -> Self {
        let metrics = Metrics {
            bands: domain.bands(),
            seed: config.seed,
            threads: rayon::current_num_threads(),
            output_fit: config.output_fit.name().into(),
            network_target: config.network_target.name().into(),
            ..Default::default()
        };
        let fem_settings = FemSettings {
            surface_dim: domain.surface_dim(),
            transfer: config.transfer,
            closed_forms: config.closed_forms,
            base_domain: config.base_domain,
            ..FemSettings::default()
        };
        let start = Instant::now();
        Self {
            domain,
            config,
            rng: ChaCha8Rng::seed_from_u64(config.seed),
            samples: Vec::new(),
            shots: 0,
            metrics,
            current: None,
            surface: Arc::new(SceneSurface::of_clustered(domain, config.surface_clusters)),
            fem_settings,
            density: SenderDensity::new(domain),
            start,
            last_report: start,
        }
    }

    /// One FEM step of the Gaussian base over the frozen `kernel` with its sender integrals
    /// (sec. 3.3–3.9), on the shading network frozen now (an empty base when nothing reads it);
    /// it becomes the current solution.
    pub(super) fn base_step(
        &mut self,
        kernel: KernelCells,
        mut sender: Vec<f64>,
        shading: &impl GrowingNetwork,
    ) {
        let geo = networks::freeze_base_geometry(
            shading,
            self.domain,
            self.config,
            self.config.needs_base(),
        );
        let base = Base::new(geo, self.fem_settings, self.surface.clone());
        let fem = fem_step(base, &kernel, &mut sender);
        self.current = Some(Current {
            collection: Collection::new(&kernel, &sender),
            fem,
        });
        self.metrics.fem_steps += 1;
    }

    /// Tells the observer where the solve is, at most every 0.1 s unless `now`.
    pub(super) fn report(
        &mut self,
        phase: &'static str,
        kernel: &impl GrowingNetwork,
        shading: &impl GrowingNetwork,
        observer: &mut dyn FnMut(&Progress),
        now: bool,
    ) {
        if !now && self.last_report.elapsed().as_secs_f64() <= 0.1 {
            return;
        }
        self.last_report = Instant::now();
        observer(&Progress {
            phase,
            kernel_cells: kernel.cell_count(),
            kernel_budget: self.config.kernel_cells,
            shading_cells: shading.cell_count(),
            samples: self.samples.len(),
            fem_steps: self.metrics.fem_steps,
            elapsed: self.start.elapsed().as_secs_f64(),
        });
    }

    /// The trained state with its metrics completed.
    pub(super) fn finish(
        mut self,
        kernel: KernelCells,
        sender: Vec<f64>,
        trainer: &Trainer,
        kernel_net: &impl GrowingNetwork,
        shading_net: &impl GrowingNetwork,
    ) -> Trained {
        let m = &mut self.metrics;
        m.seconds.kernel_training = trainer.kernel_seconds;
        m.seconds.shading_training = trainer.shading_seconds;
        m.training_steps = trainer.steps;
        m.kernel_cells = kernel_net.cell_count();
        m.shading_cells = shading_net.cell_count();
        m.samples = self.samples.len();
        let fem = self.current.expect("the final FEM step ran").fem;
        m.shading_triangles = fem.base.geo.simplices.len();
        m.rejected_base_components = fem.rejected;
        Trained {
            collection: Collection::new(&kernel, &sender),
            kernel,
            sender,
            fem,
            samples: self.samples,
            metrics: self.metrics,
        }
    }
}
