//! The projected kernel's FEM step (beyond the dissertation): project K·s onto the frozen kernel
//! network's Gaussians ([`crate::projection`]), then iterate s ← E + B_refl(s) with the kernel
//! collection (fig. 4.13c), one light bounce per iteration, under the guards of [`super::guards`].

use super::guards::{
    BounceWatch, STABILIZING_REJECTIONS, UNSTABLE_FACTOR, balance_broken, bound_excess,
    check_stable, ran_away,
};
use super::networks::freeze_kernel;
use super::samples::{Sample, kernel_strength};
use super::{Run, SolveError};
use crate::element::{Bands, MAX_BANDS};
use crate::fem::{KernelCells, receiver_integrals, sender_integrals};
use crate::network::GrowingNetwork;
use crate::projection::{
    KernelProjection, kernel_gram_excluding, kernel_reflected_power, kernel_support,
    sampled_reflected_power,
};
use rayon::prelude::*;

/// Bounces per projection during training.
pub(super) const TRAINING_BOUNCES: usize = 4;
/// Bounce cap after training (reached only when ρ is close to 1).
pub(super) const FINAL_BOUNCES: usize = 200;
/// Relative change of the total strength below which the bounces stop.
const BOUNCE_TOLERANCE: f64 = 1e-5;

/// What [`propagate`] returns.
pub(super) struct Propagated {
    /// The projected kernel.
    pub kernel: KernelCells,
    /// Its sender integrals.
    pub sender: Vec<f64>,
    /// Bounces run.
    pub bounces: usize,
    /// Reflected power of the projected kernel over the power the samples carry, before the
    /// energy correction, in the last fit (1 when the projection conserves energy; 1 when the
    /// correction is off and nothing was measured).
    pub energy_balance: f64,
    /// The bounces started to diverge and were stopped at the smallest change.
    pub diverged: bool,
    /// The smallest change was small enough that a divergence from there is too slow to matter.
    settled: bool,
    /// Times the projection was redone with a higher rejection threshold because it diverged.
    pub stabilized: usize,
    /// Cells left out of the projection for want of samples in their support.
    pub unsupported: usize,
}

/// The frozen kernel network with everything a projection needs that does not depend on the
/// rejection threshold: computed once per network state, reused when [`propagate`] redoes the
/// projection at a higher rejection.
struct Frozen {
    /// The cells (their weights are overwritten by every fit).
    kernel: KernelCells,
    /// Sender integrals c_o.
    sender: Vec<f64>,
    /// Receiver integrals (empty without the energy correction).
    receiver: Vec<f64>,
    /// Cells left out for want of samples in their support.
    excluded: Vec<bool>,
    /// Their Gram matrix ([`crate::projection::kernel_gram_excluding`]).
    gram: nalgebra::DMatrix<f64>,
}

impl Frozen {
    fn new(kernel: &impl GrowingNetwork, run: &Run) -> Self {
        let (domain, config, samples) = (run.domain, run.config, &run.samples[..]);
        let scene = &*run.surface;
        let tol = config.projection_tolerance;
        let mut frozen = freeze_kernel(kernel, domain.dim(), domain.bands());
        if config.kernel_facing {
            let ends: Vec<_> = samples
                .iter()
                .map(|s| (s.ray.x, s.ray.nx, s.ray.y, s.ray.ny))
                .collect();
            frozen.assign_facing(&ends, config.breaking.max_normal_angle.cos());
        }
        let sender = sender_integrals(&frozen, scene, tol);
        // Cells without data (the tiny ones the network grows along edges) are left out: their
        // moment would be one sample's noise ([`crate::config::SolveConfig::projection_min_support`]).
        let min_support = config.projection_min_support;
        let excluded: Vec<bool> = if min_support > 0.0 {
            kernel_support(&frozen, samples, tol)
                .iter()
                .map(|&c| c < min_support)
                .collect()
        } else {
            Vec::new()
        };
        let receiver = if config.energy_correction {
            receiver_integrals(&frozen, scene, tol)
        } else {
            Vec::new()
        };
        let gram = kernel_gram_excluding(&frozen, scene, tol, &excluded);
        Self {
            kernel: frozen,
            sender,
            receiver,
            excluded,
            gram,
        }
    }
}

/// [`propagate_at`], guarded by the maximum principle ([`super::guards`]): a projection that ran
/// away is redone from the same starting strengths at the next of [`STABILIZING_REJECTIONS`];
/// when even the last leaves strengths [`UNSTABLE_FACTOR`]-fold beyond the bound, the solve
/// stops with an error instead of a wrong picture.
pub(super) fn propagate(
    kernel: &impl GrowingNetwork,
    run: &mut Run,
    max_bounces: usize,
) -> Result<Propagated, SolveError> {
    let config = run.config;
    let mut rejection = config.projection_rejection;
    let prepared = Frozen::new(kernel, run);
    let start: Vec<Bands> = run.samples.iter().map(|s| s.s).collect();
    let bound = run.domain.radiosity_bound();
    let mut p = propagate_at(&prepared, run, max_bounces, rejection);
    let mut stabilized = 0;
    for higher in STABILIZING_REJECTIONS {
        if !ran_away(p.diverged, p.settled, &run.samples, &bound) || higher <= rejection {
            break;
        }
        for (smp, s) in run.samples.iter_mut().zip(&start) {
            smp.s = *s;
        }
        rejection = higher;
        stabilized += 1;
        p = propagate_at(&prepared, run, max_bounces, rejection);
    }
    p.stabilized = stabilized;
    check_stable(&run.samples, &bound, config.projection_tolerance, rejection)?;
    Ok(p)
}

/// Projects K·s onto the frozen kernel's Gaussians at the relative pivot threshold `rejection`
/// and iterates `s ← E + B_refl(s)` with the kernel collection (one light bounce per iteration)
/// until the total strength changes by less than [`BOUNCE_TOLERANCE`] or `max_bounces` is
/// reached.
fn propagate_at(
    prepared: &Frozen,
    run: &mut Run,
    max_bounces: usize,
    rejection: f64,
) -> Propagated {
    let Frozen {
        kernel,
        sender,
        receiver,
        excluded,
        gram,
    } = prepared;
    let (domain, config, shots) = (run.domain, run.config, run.shots);
    let samples = &mut run.samples[..];
    let mut frozen = kernel.clone();
    let projection =
        KernelProjection::from_gram(gram, config.projection_tolerance, rejection, excluded);
    let reflectance = |f| domain.reflectance(f);
    let total =
        |samples: &[Sample]| -> f64 { samples.iter().map(|s| s.s.iter().sum::<f64>()).sum() };
    // The projection conserves energy only up to its fit error and the cells it rejects; with ρ
    // near 1 the bounce iteration amplifies any excess (a ρ = 0.95 furnace ran away to 15× the
    // exact B). Rescaling the weights so that the kernel reflects exactly the power the samples
    // carry makes the iteration's gain that of the scene. Returns the balance before the
    // rescaling (None when not measured).
    let fit = |frozen: &mut KernelCells, samples: &[Sample]| -> Option<f64> {
        projection.fit(frozen, samples, shots, &reflectance);
        if !config.energy_correction {
            return None;
        }
        let sampled = sampled_reflected_power(samples, shots, &reflectance);
        let model = kernel_reflected_power(frozen, sender, receiver);
        let (mut num, mut den) = (0.0, 0.0);
        for k in 0..MAX_BANDS {
            num += model[k];
            den += sampled[k];
            let ratio = sampled[k] / model[k];
            if sampled[k] > 0.0 && model[k] > 0.0 && ratio.is_finite() {
                for v in frozen.v.iter_mut() {
                    v[k] *= ratio;
                }
            }
        }
        (den > 0.0 && num.is_finite()).then_some(num / den)
    };
    let bound = domain.radiosity_bound();
    let mut balance = 1.0;
    let mut before = total(samples);
    let mut bounces = 0;
    let mut watch = BounceWatch::default();
    let mut diverged = false;
    while bounces < max_bounces {
        // ⟨Fit the weights to the current strengths; stop at once on a broken balance⟩
        let measured = fit(&mut frozen, samples);
        balance = measured.unwrap_or(balance);
        if measured.is_some_and(balance_broken) {
            diverged = true;
            watch.restore(samples);
            break;
        }
        // ⟨One bounce: s ← E + B_refl(s)⟩
        samples.par_iter_mut().for_each(|smp| {
            smp.s = kernel_strength(&smp.ray, &frozen, sender);
        });
        bounces += 1;
        // ⟨Stop when settled, go back to the smallest change when diverging⟩
        let after = total(samples);
        let change = (after - before).abs() / after.abs().max(1e-300);
        before = after;
        if change < BOUNCE_TOLERANCE {
            break;
        }
        if watch.diverging(change) || bound_excess(samples, &bound) > UNSTABLE_FACTOR {
            diverged = true;
            watch.restore(samples);
            break;
        }
        watch.record(change, samples);
    }
    // The weights that go with the final strengths.
    if let Some(b) = fit(&mut frozen, samples) {
        balance = b;
    }
    Propagated {
        kernel: frozen,
        sender: sender.clone(),
        bounces,
        energy_balance: balance,
        diverged,
        settled: watch.settled(),
        stabilized: 0,
        unsupported: excluded.iter().filter(|e| **e).count(),
    }
}
