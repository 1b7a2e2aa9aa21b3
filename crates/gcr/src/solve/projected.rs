//! The projected kernel (beyond the dissertation): the kernel network only places the cells;
//! their weights are a Galerkin projection of K·s on shot rays ([`crate::projection`]), and the
//! light is propagated by bouncing through the kernel collection ([`super::propagate`]).

use super::error::SolveError;
use super::propagate::{FINAL_BOUNCES, Propagated, TRAINING_BOUNCES, propagate};
use super::run::Run;
use crate::config::StrengthFrom;
use crate::kernel_cells::KernelCells;
use crate::network::GrowingNetwork;

/// A FEM step during training: a few bounces through the projected kernel, then the base step
/// (empty unless something reads the base).
pub(super) fn step(
    kernel: &impl GrowingNetwork,
    shading: &impl GrowingNetwork,
    run: &mut Run,
) -> Result<(), SolveError> {
    let p = propagate(kernel, run, TRAINING_BOUNCES, false)?;
    record(run, &p);
    run.base_step(p.kernel, p.sender, shading);
    if run.config.strength_from == StrengthFrom::Base {
        run.update_strengths();
    }
    Ok(())
}

/// The final step: one Gram matrix, then bounces until the strengths settle (each bounce is
/// cheap), and the base step. Returns the projected kernel and its sender integrals.
pub(super) fn finish(
    kernel: &impl GrowingNetwork,
    shading: &impl GrowingNetwork,
    run: &mut Run,
) -> Result<(KernelCells, Vec<f64>), SolveError> {
    let p = propagate(kernel, run, FINAL_BOUNCES, true)?;
    record(run, &p);
    run.metrics.final_bounces = p.bounces;
    run.metrics.energy_balance = run.config.energy_correction.then_some(p.energy_balance);
    // The bounces and the gathers use c_o; the base step may replace its copy by c̄_o.
    run.base_step(p.kernel.clone(), p.sender.clone(), shading);
    Ok((p.kernel, p.sender))
}

fn record(run: &mut Run, p: &Propagated) {
    let m = &mut run.metrics;
    m.bounces += p.bounces;
    m.direct_solves += p.direct_solves;
    m.diverging_bounces_stopped += usize::from(p.diverged);
    m.stabilized_projections += p.stabilized;
    m.unsupported_cells = p.unsupported;
}
