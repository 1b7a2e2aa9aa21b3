//! The dissertation's algorithm (sec. 3.3–3.9, fig. 3.1): the kernel network's output layer
//! learns K·s by the delta rule (eq. 2.8); each FEM step projects the kernel collection onto the
//! Gaussian base and every sample's strength is updated from it.

use super::networks::freeze_kernel;
use super::run::Run;
use super::training::Trainer;
use crate::fem::sender_integrals;
use crate::kernel_cells::KernelCells;
use crate::network::GrowingNetwork;

/// A FEM step: freeze the kernel, its sender integrals c_o, step the base, update the strengths.
pub(super) fn step(kernel: &impl GrowingNetwork, shading: &impl GrowingNetwork, run: &mut Run) {
    let frozen = freeze_kernel(kernel, run.domain.dim(), run.domain.bands());
    let sender = sender_integrals(&frozen, &run.surface, run.fem_settings.support_tolerance);
    run.base_step(frozen, sender, shading);
    run.update_strengths();
}

/// The final FEM steps ([`crate::config::SolveConfig::final_fem_steps`], at least one), each
/// followed by a sweep that re-learns the new targets without growing. Returns the frozen
/// kernel and its sender integrals.
pub(super) fn finish(
    kernel: &mut impl GrowingNetwork,
    shading: &impl GrowingNetwork,
    trainer: &mut Trainer,
    run: &mut Run,
) -> (KernelCells, Vec<f64>) {
    let (dim, bands) = (run.domain.dim(), run.domain.bands());
    for _ in 0..run.config.final_fem_steps.max(1) {
        step(kernel, shading, run);
        trainer.sweep(kernel, &run.samples, &mut run.rng);
    }
    let frozen = freeze_kernel(kernel, dim, bands);
    let sender = sender_integrals(&frozen, &run.surface, run.fem_settings.support_tolerance);
    (frozen, sender)
}
