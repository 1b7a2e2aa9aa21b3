//! The solve: from a scene's kernel domain to trained networks and their last FEM step (figs.
//! 1.2, 3.1 and B.1 of the dissertation, with the corrections of MATH.md).
//!
//! [`train`] is the main loop, as named steps:
//!
//! 1. shoot the initial samples with s = E ([`samples`]);
//! 2. train the kernel network on K·s and the shading network on the receivers ([`training`]);
//! 3. grow the sample set with the network ([`samples`]);
//! 4. every N insertions, a FEM step ([`schedule`]): either the dissertation's delta-rule output
//!    layer with its Gaussian base ([`delta_rule`], sec. 3.3–3.9) or the projected kernel
//!    ([`projected`] and [`propagate`], beyond the dissertation), guarded by [`guards`];
//! 5. at the budget, final FEM steps with the networks' size frozen.
//!
//! The networks are created and frozen into the FEM's view in [`networks`].

mod delta_rule;
mod guards;
mod networks;
mod projected;
mod propagate;
mod samples;
mod schedule;
mod training;

pub use networks::{freeze_kernel, freeze_shading, make_networks};
pub use samples::Sample;

use crate::cell_lanes::Collection;
use crate::config::{OutputFit, SolveConfig};
use crate::domain::Domain;
use crate::element::Bands;
use crate::fem::{Base, FemSettings, FemSolution, SceneSurface, fem_step};
use crate::kernel_cells::KernelCells;
use crate::metrics::Metrics;
use crate::network::GrowingNetwork;
use crate::shooting::SenderDensity;
use glam::DVec3;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use schedule::Schedule;
use std::sync::Arc;
use std::time::Instant;
use thiserror::Error;
use training::Trainer;

/// Why a solve could not run.
#[derive(Debug, Error)]
pub enum SolveError {
    /// A setting is out of range.
    #[error(transparent)]
    Config(#[from] crate::config::ConfigError),
    /// The networks could not be created.
    #[error("network: {0}")]
    Network(#[from] isgcs::IsgcsError),
    /// The kernel projection kept breaking the maximum-principle bound on B.
    #[error("numerically unstable solve: {0}")]
    Unstable(String),
    /// No ray of the scene connects two surfaces: there is nothing to carry light.
    #[error(
        "no ray of the scene connects two surfaces ({shots} shot, all left the scene or hit \
         nothing): nothing to solve (is the scene a single surface, or open everywhere?)"
    )]
    NoRays {
        /// Rays shot.
        shots: u64,
    },
}

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

/// The state after training: everything the gathers need.
pub struct Trained {
    /// The kernel network frozen.
    pub kernel: KernelCells,
    /// Sender integrals c_o of the frozen kernel.
    pub sender: Vec<f64>,
    /// The last FEM step.
    pub fem: FemSolution,
    /// The samples at the end.
    pub samples: Vec<Sample>,
    /// Metrics of the solve (`gcr::output::write_outputs` completes them with the gather and
    /// output phases).
    pub metrics: Metrics,
    /// The kernel collection through `kernel` and `sender`, prepared for many points.
    collection: Collection,
}

impl Trained {
    /// A solution without networks, for a gather that reads none
    /// ([`SolveConfig::reads_networks`]: the paths gather with every ray corrected) and outputs
    /// that need no output mesh (probes): the kernel and the base are empty (B_refl from them is
    /// 0), no sample was shot, and the metrics say `stopped_by: "unused"`.
    pub fn without_networks(domain: &Domain, config: &SolveConfig) -> Self {
        let fem_settings = FemSettings {
            surface_dim: domain.surface_dim(),
            ..FemSettings::default()
        };
        let empty = SceneSurface::new(Vec::new(), Vec::new(), 1.0);
        let base = Base::new(Default::default(), fem_settings, Arc::new(empty));
        Self {
            kernel: KernelCells::default(),
            sender: Vec::new(),
            fem: FemSolution {
                base,
                gamma: Vec::new(),
                rejected: 0,
            },
            samples: Vec::new(),
            collection: Collection::default(),
            metrics: Metrics {
                bands: domain.bands(),
                seed: config.seed,
                threads: rayon::current_num_threads(),
                stopped_by: "unused".into(),
                ..Default::default()
            },
        }
    }

    /// B_refl at a point by the kernel collection (fig. 4.13c).
    pub fn reflected_kernel(&self, y: DVec3, n: DVec3) -> Bands {
        self.collection.at(y, n)
    }
}

/// Validates the configuration, builds the networks and trains them (figs. 1.2, 3.1, B.1).
pub fn solve(
    domain: &Domain,
    config: &SolveConfig,
    observer: &mut dyn FnMut(&Progress),
) -> Result<Trained, SolveError> {
    config.validate()?;
    let (mut kernel, mut shading) = make_networks(domain, config)?;
    train(domain, &mut kernel, &mut shading, config, observer)
}

/// Runs the training loop with FEM steps until the budget is reached (fig. B.1).
pub fn train(
    domain: &Domain,
    kernel: &mut impl GrowingNetwork,
    shading: &mut impl GrowingNetwork,
    config: &SolveConfig,
    observer: &mut dyn FnMut(&Progress),
) -> Result<Trained, SolveError> {
    let mut run = Run::new(domain, config);
    let mut trainer = Trainer::default();
    let mut schedule = Schedule::new(config);
    let base_used = config.needs_base();

    // ⟨Shoot the initial sample set, s = E (fig. 3.1); check that light can flow⟩
    run.add_samples(run.initial_sample_count());
    run.check_flow()?;

    loop {
        // ⟨Stop at the cell or time budget⟩
        let elapsed = run.start.elapsed().as_secs_f64();
        if let Some(reason) = schedule.stop(kernel.cell_count(), elapsed) {
            run.metrics.stopped_by = reason.into();
            break;
        }
        // ⟨Train both networks on a batch of samples⟩
        trainer.batch(kernel, shading, &mut run, base_used);
        // ⟨Grow the sample set with the network: shoot, or resample critical regions (sec. 2.5)⟩
        let wanted =
            (config.samples_per_cell * kernel.cell_count().max(1)).max(run.initial_sample_count());
        if run.samples.len() < wanted {
            let add = (wanted - run.samples.len()).min(512);
            match config.output_fit {
                OutputFit::Projection => run.add_samples(add),
                OutputFit::DeltaRule => run.resample_critical(kernel, add),
            }
        }
        // ⟨A FEM step every N kernel insertions⟩
        if schedule.fem_due(
            kernel.insertions(),
            kernel.cell_count(),
            shading.cell_count(),
        ) {
            let tf = Instant::now();
            match config.output_fit {
                OutputFit::Projection => projected::fem_step(kernel, shading, &mut run)?,
                OutputFit::DeltaRule => delta_rule::fem_step(kernel, shading, &mut run),
            }
            let took = tf.elapsed().as_secs_f64();
            run.metrics.seconds.fem += took;
            schedule.fem_took(took, kernel.cell_count());
        }
        // ⟨Report progress⟩
        run.report("training", kernel, shading, observer, false);
    }

    // ⟨Final FEM steps: the networks keep their size from here on⟩
    kernel.set_growing(false);
    shading.set_growing(false);
    run.report("final", kernel, shading, observer, true);
    let tf = Instant::now();
    let (frozen, sender) = match config.output_fit {
        OutputFit::Projection => projected::finish(kernel, shading, &mut run)?,
        OutputFit::DeltaRule => delta_rule::finish(kernel, shading, &mut trainer, &mut run),
    };
    run.metrics.seconds.fem += tf.elapsed().as_secs_f64();

    // ⟨Assemble the trained state⟩
    Ok(run.finish(frozen, sender, &trainer, kernel, shading))
}

/// The last FEM step and the frozen kernel network it integrated, with its sender integrals:
/// new samples take their strengths from it.
struct Current {
    /// The kernel collection through the frozen kernel and its sender integrals.
    collection: Collection,
    fem: FemSolution,
}

/// The state of one solve that every step reads or updates.
struct Run<'a> {
    domain: &'a Domain<'a>,
    config: &'a SolveConfig,
    /// The loop's random choices (which sample to train on, new samples' seeds).
    rng: ChaCha8Rng,
    samples: Vec<Sample>,
    /// Rays shot so far, including those that left the scene (the projection's MC estimates
    /// divide by it).
    shots: u64,
    metrics: Metrics,
    /// The last FEM step with the kernel it integrated.
    current: Option<Current>,
    /// The scene surface S every FEM integral runs over.
    surface: Arc<SceneSurface>,
    fem_settings: FemSettings,
    density: SenderDensity,
    start: Instant,
    last_report: Instant,
}

impl<'a> Run<'a> {
    fn new(domain: &'a Domain<'a>, config: &'a SolveConfig) -> Self {
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
    fn base_step(
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
    fn report(
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
    fn finish(
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
