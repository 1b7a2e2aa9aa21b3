//! The solve: from a scene's kernel domain to trained networks and their last FEM step (figs.
//! 1.2, 3.1 and B.1 of the dissertation, with the corrections of docs/design/math.md).
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
//! The networks are created and frozen into the FEM's view in [`networks`]. The loop's state
//! (samples, metrics, the current FEM solution) is a [`run::Run`] that the steps update; the FEM
//! step proper is [`crate::fem::fem_step`], entered only through `Run::base_step`. What a solve
//! returns is a [`Trained`] (`trained.rs`); why it fails, a [`SolveError`] (`error.rs`).

mod delta_rule;
mod error;
mod guards;
mod networks;
mod projected;
mod propagate;
mod run;
mod samples;
mod schedule;
mod trained;
mod training;

pub use error::SolveError;
pub use networks::make_networks;
#[cfg(feature = "stages")]
pub use networks::{freeze_kernel, freeze_shading};
pub use run::Progress;
pub use trained::Trained;

use crate::config::{OutputFit, SolveConfig};
use crate::domain::Domain;
use crate::network::GrowingNetwork;
use run::Run;
use schedule::Schedule;
use std::time::Instant;
use training::Trainer;

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
    let mut trainer = Trainer::new(domain, config);
    let mut schedule = Schedule::new(config);

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
        trainer.batch(kernel, shading, &run.samples, &mut run.rng);
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
                OutputFit::Projection => projected::step(kernel, shading, &mut run)?,
                OutputFit::DeltaRule => delta_rule::step(kernel, shading, &mut run),
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
