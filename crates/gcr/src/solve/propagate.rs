//! The projected kernel's FEM step (beyond the dissertation): project K·s onto the frozen kernel
//! network's Gaussians ([`crate::projection`]), then iterate s ← E + B_refl(s) with the kernel
//! collection (fig. 4.13c), one light bounce per iteration, under the guards of [`super::guards`].

use super::error::SolveError;
use super::guards::{
    BounceWatch, DIRECT_LIMIT, STABILIZING_REJECTIONS, UNSTABLE_FACTOR, balance_broken,
    bound_excess, check_stable, ran_away,
};
use super::networks::freeze_kernel;
use super::run::Run;
use super::samples::kernel_strength;
use crate::cell_lanes::Collection;
use crate::element::{BANDS, Bands};
use crate::fem::{receiver_integrals, sender_integrals};
use crate::kernel_cells::KernelCells;
use crate::network::GrowingNetwork;
use crate::projection::{
    BounceOperator, KernelProjection, bounce_operator, closed_reflected_power,
    kernel_gram_excluding, kernel_reflected_power, kernel_support, sampled_reflected_power,
};
use crate::sample::Sample;
use glam::DVec3;
use nalgebra::{DMatrix, DVector};
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
    /// Direct solves of the linearized bounce ([`direct_weights`]) that were used.
    pub direct_solves: usize,
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
    direct: bool,
) -> Result<Propagated, SolveError> {
    let config = run.config;
    let mut rejection = config.projection_rejection;
    let prepared = Frozen::new(kernel, run);
    let start: Vec<Bands> = run.samples.iter().map(|s| s.s).collect();
    let bound = run.domain.radiosity_bound();
    let direct = direct && prepared.kernel.len() <= config.direct_solve_cells;
    let mut p = propagate_at(&prepared, run, (max_bounces, direct), rejection);
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
        p = propagate_at(&prepared, run, (max_bounces, direct), rejection);
    }
    p.stabilized = stabilized;
    check_stable(&run.samples, &bound, config.projection_tolerance, rejection)?;
    Ok(p)
}

/// Projects K·s onto the frozen kernel's Gaussians at the relative pivot threshold `rejection`
/// and iterates `s ← E + B_refl(s)` with the kernel collection (one light bounce per iteration)
/// until the total strength changes by less than [`BOUNCE_TOLERANCE`] or `max_bounces` is
/// reached. With `direct`, and when the bounces would converge slowly ([`slow_bounces`]), the
/// bounces start from the fixed point of the linearized bounce ([`jump_to_fixed_point`]) and only
/// polish it (the clamp, the guards).
fn propagate_at(
    prepared: &Frozen,
    run: &mut Run,
    (max_bounces, direct): (usize, bool),
    rejection: f64,
) -> Propagated {
    let (domain, config, shots) = (run.domain, run.config, run.shots);
    let samples = &mut run.samples[..];
    let reflectance = |f, y| domain.reflectance_at(f, y);
    let fitter = Fitter {
        projection: KernelProjection::from_gram(
            &prepared.gram,
            config.projection_tolerance,
            rejection,
            &prepared.excluded,
        ),
        prepared,
        shots,
        closed: samples.iter().filter(|s| s.inv_px != 0.0).count() as u64 == shots,
        correct: config.energy_correction,
        reflectance: &reflectance,
    };
    let mut frozen = prepared.kernel.clone();
    let bound = domain.radiosity_bound();
    // ⟨Jump to the fixed point of the linearized bounce when bouncing would be slow⟩
    let jumped = direct
        && slow_bounces(samples, &reflectance)
        && jump_to_fixed_point(
            &fitter,
            &mut frozen,
            samples,
            &bound,
            config.projection_tolerance,
        );
    // ⟨Bounce until settled, guarded⟩
    let mut generated = jumped;
    let mut balance = 1.0;
    let total =
        |samples: &[Sample]| -> f64 { samples.iter().map(|s| s.s.iter().sum::<f64>()).sum() };
    let mut before = total(samples);
    let (mut bounces, mut diverged) = (0, false);
    let mut watch = BounceWatch::default();
    let sender = &prepared.sender;
    while bounces < max_bounces {
        // ⟨Fit the weights to the current strengths; stop at once on a broken balance⟩
        let measured = fitter.fit(&mut frozen, samples, generated);
        balance = measured.unwrap_or(balance);
        if measured.is_some_and(balance_broken) {
            diverged = true;
            watch.restore(samples);
            break;
        }
        // ⟨One bounce: s ← E + B_refl(s)⟩
        let collection = Collection::new(&frozen, sender);
        samples.par_iter_mut().for_each(|smp| {
            smp.s = kernel_strength(&smp.ray, &collection);
        });
        generated = true;
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
    // ⟨The weights that go with the final strengths⟩
    if let Some(b) = fitter.fit(&mut frozen, samples, generated) {
        balance = b;
    }
    Propagated {
        kernel: frozen,
        sender: sender.clone(),
        bounces,
        direct_solves: usize::from(jumped),
        energy_balance: balance,
        diverged,
        settled: watch.settled(),
        stabilized: 0,
        unsupported: prepared.excluded.iter().filter(|e| **e).count(),
    }
}

/// Whether the bounce iteration would be slow: its gain is about the flux-weighted reflectance
/// of the scene (what one bounce keeps of the power the samples carry), and it needs
/// ln(tolerance)/ln(gain) bounces; beyond [`SLOW_BOUNCES`] the direct solve pays (it costs
/// O(cells³), a bounce O(samples · cells)). Ordinary scenes (gain ≈ 0.5, 17 bounces) keep the
/// plain iteration.
fn slow_bounces(samples: &[Sample], reflectance: &(impl Fn(u32, DVec3) -> Bands + Sync)) -> bool {
    let (mut kept, mut carried) = ([0.0; BANDS], [0.0; BANDS]);
    for smp in samples.iter().filter(|s| s.inv_px != 0.0) {
        let rho = reflectance(smp.ray.face_y, smp.ray.y);
        for k in 0..BANDS {
            if smp.ray.kernel[k] > 0.0 {
                kept[k] += rho[k] * smp.s[k] * smp.inv_px;
                carried[k] += smp.s[k] * smp.inv_px;
            }
        }
    }
    let gain = (0..BANDS)
        .filter(|&k| carried[k] > 0.0)
        .map(|k| kept[k] / carried[k])
        .fold(0.0, f64::max);
    gain > 0.0 && gain < 1.0 && BOUNCE_TOLERANCE.ln() / gain.ln() > SLOW_BOUNCES || gain >= 1.0
}

/// Bounces beyond which [`slow_bounces`] calls the iteration slow (gain ≈ 0.83).
const SLOW_BOUNCES: f64 = 60.0;

/// The fit of the weights to the samples' strengths, with the energy correction.
struct Fitter<'a, R> {
    projection: KernelProjection,
    prepared: &'a Frozen,
    shots: u64,
    /// Every shot landed: the scene is closed.
    closed: bool,
    correct: bool,
    reflectance: &'a R,
}

impl<R: Fn(u32, DVec3) -> Bands + Sync> Fitter<'_, R> {
    /// Fits `frozen`'s weights to the strengths and applies the energy correction: the
    /// projection conserves energy only up to its fit error and the cells it rejects; with ρ near
    /// 1 the bounce iteration amplifies any excess (a ρ = 0.95 furnace ran away to 15× the exact
    /// B). Rescaling the weights so that the kernel reflects exactly the power the samples carry
    /// makes the iteration's gain that of the scene. In a closed scene whose strengths the current
    /// weights bounced (`generated`), the sampled power is the ratio estimator of
    /// [`closed_reflected_power`]: the raw Monte-Carlo power's error would be amplified by
    /// 1/(1 − ρ) as well. Returns the balance before the rescaling (None when not measured).
    fn fit(&self, frozen: &mut KernelCells, samples: &[Sample], generated: bool) -> Option<f64> {
        let Frozen {
            sender, receiver, ..
        } = self.prepared;
        let generated = (self.closed && generated && !receiver.is_empty())
            .then(|| kernel_reflected_power(frozen, sender, receiver));
        self.projection
            .fit(frozen, samples, self.shots, self.reflectance);
        if !self.correct {
            return None;
        }
        let sampled = match generated {
            Some(g) => closed_reflected_power(samples, self.shots, self.reflectance, g),
            None => sampled_reflected_power(samples, self.shots, self.reflectance),
        };
        let model = kernel_reflected_power(frozen, sender, receiver);
        let (mut num, mut den) = (0.0, 0.0);
        for k in 0..BANDS {
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
    }
}

/// Sets the weights and strengths to the fixed point of the linearized bounce
/// ([`direct_weights`]). A projected kernel with a mode of gain above 1 has a fixed point the
/// bounces never reach (measured: a ρ = 0.99 furnace, 100 cells, seed 4, 11× the bound): then, or
/// when the system is singular, everything stays as it was and `false` is returned.
fn jump_to_fixed_point<R: Fn(u32, DVec3) -> Bands + Sync>(
    fitter: &Fitter<R>,
    frozen: &mut KernelCells,
    samples: &mut [Sample],
    bound: &Bands,
    tolerance: f64,
) -> bool {
    let Frozen {
        sender,
        receiver,
        excluded,
        ..
    } = fitter.prepared;
    let shots = fitter.shots;
    let op = bounce_operator(
        frozen,
        sender,
        samples,
        shots,
        fitter.reflectance,
        (tolerance, excluded),
    );
    let start = start_correction(
        &fitter.projection,
        frozen,
        samples,
        (shots, sender, receiver),
        fitter.reflectance,
    );
    let q: Vec<f64> = if receiver.is_empty() {
        Vec::new()
    } else {
        sender.iter().zip(receiver).map(|(c, r)| c * r).collect()
    };
    let Some(v) = direct_weights(&fitter.projection, &op, (&q, fitter.closed), start) else {
        return false;
    };
    let (kept_v, kept_s) = (
        std::mem::replace(&mut frozen.v, v),
        samples.iter().map(|smp| smp.s).collect::<Vec<_>>(),
    );
    let collection = Collection::new(frozen, sender);
    samples.par_iter_mut().for_each(|smp| {
        smp.s = kernel_strength(&smp.ray, &collection);
    });
    if bound_excess(samples, bound) > DIRECT_LIMIT {
        frozen.v = kept_v;
        for (smp, s) in samples.iter_mut().zip(kept_s) {
            smp.s = s;
        }
        return false;
    }
    true
}

/// The energy correction factor per band that a fit of the current strengths would apply
/// (sampled over model power; 1 where either is not positive), the start of [`direct_weights`]'s
/// search. Leaves the fit's weights in `frozen`.
fn start_correction(
    projection: &KernelProjection,
    frozen: &mut KernelCells,
    samples: &[Sample],
    (shots, sender, receiver): (u64, &[f64], &[f64]),
    reflectance: &(impl Fn(u32, DVec3) -> Bands + Sync),
) -> Option<Bands> {
    if receiver.is_empty() {
        return None;
    }
    projection.fit(frozen, samples, shots, reflectance);
    let sampled = sampled_reflected_power(samples, shots, reflectance);
    let model = kernel_reflected_power(frozen, sender, receiver);
    let mut alpha = [1.0; BANDS];
    for k in 0..BANDS {
        let r = sampled[k] / model[k];
        if sampled[k] > 0.0 && model[k] > 0.0 && r.is_finite() {
            alpha[k] = r;
        }
    }
    Some(alpha)
}

/// Secant steps of the energy correction's outer fixed point before [`direct_weights`] gives up.
const CORRECTION_STEPS: usize = 40;
/// Relative change of the correction factor at which its outer fixed point counts as found.
const CORRECTION_TOLERANCE: f64 = 1e-12;

/// The weights of the fixed point of the linearized bounce (beyond the dissertation): with
/// `P = G⁻¹M` (a fit) and `T = P A` ([`BounceOperator`]), one fit after a bounce gives
/// `v' = α (P E + T v)`, whose fixed point solves, per band,
///
/// ```text
/// (I − α T) v = α P E,        α = (w·E + (Aᵀw)·v) / (q·(P E + T v))     (q_o = c_o r_o)
/// ```
///
/// α being the energy correction: the model's reflected power equals the sampled power. The
/// linear system is solved by LU for each α; α by secant steps on `α'(α) − α` from `start` (the
/// current fit's factor). Without the correction (`start` None) α = 1. `None` when a system is
/// singular or the correction does not settle (the caller keeps iterating the bounces).
fn direct_weights(
    projection: &KernelProjection,
    op: &BounceOperator,
    (q, closed): (&[f64], bool),
    start: Option<Bands>,
) -> Option<Vec<Bands>> {
    let m = op.me.len();
    let mut v = vec![[0.0; BANDS]; m];
    for k in 0..BANDS {
        let me: Vec<f64> = op.me.iter().map(|b| b[k]).collect();
        if me.iter().all(|x| *x == 0.0) {
            continue;
        }
        // ⟨T = G⁻¹ (M A) column by column, P E = G⁻¹ (M E)⟩
        let columns: Vec<DVector<f64>> = (0..m)
            .into_par_iter()
            .map(|p| DVector::from_vec(projection.solve(op.ma[k].column(p).as_slice())))
            .collect();
        let t = DMatrix::from_columns(&columns);
        let pe = DVector::from_vec(projection.solve(&me));
        let band = BandSystem {
            t: &t,
            pe: &pe,
            q,
            atw: op.atw.iter().map(|b| b[k]).collect(),
            we: op.we[k],
            closed: closed.then(|| (op.atu.iter().map(|b| b[k]).collect(), op.ue[k])),
        };
        let vk = match start {
            None => band.weights(1.0)?.0,
            Some(alpha) => band.corrected(alpha[k])?,
        };
        for (o, x) in vk.iter().enumerate() {
            v[o][k] = *x;
        }
    }
    v.iter().flatten().all(|x| x.is_finite()).then_some(v)
}

/// One band's linearized bounce ([`direct_weights`]).
struct BandSystem<'a> {
    t: &'a DMatrix<f64>,
    pe: &'a DVector<f64>,
    q: &'a [f64],
    atw: Vec<f64>,
    we: f64,
    /// In a closed scene, `(Aᵀu, u·E)` of the ratio estimator ([`closed_reflected_power`]).
    closed: Option<(Vec<f64>, f64)>,
}

impl BandSystem<'_> {
    /// `v = α (I − αT)⁻¹ P E` and the correction factor α' a fit of its bounce would apply.
    fn weights(&self, alpha: f64) -> Option<(DVector<f64>, f64)> {
        let m = self.pe.len();
        let system = DMatrix::identity(m, m) - self.t * alpha;
        let v = system.lu().solve(&(self.pe * alpha))?;
        if self.q.is_empty() {
            return Some((v, 1.0));
        }
        let raw = self.pe + self.t * &v;
        let model: f64 = raw.iter().zip(self.q).map(|(r, q)| r * q).sum();
        let dot = |a: &[f64]| v.iter().zip(a).map(|(v, a)| v * a).sum::<f64>();
        let sampled = self.we + dot(&self.atw);
        let sampled = match &self.closed {
            // ρ̂·(u·E + q·v), ρ̂ = (w·s)/(u·s) with s = E + A v.
            Some((atu, ue)) => sampled / (ue + dot(atu)) * (ue + dot(self.q)),
            None => sampled,
        };
        let next = sampled / model;
        (next.is_finite() && next > 0.0).then_some((v, next))
    }

    /// The weights at the correction's fixed point α = α'(α), by secant steps from `alpha`.
    fn corrected(&self, alpha: f64) -> Option<DVector<f64>> {
        let (mut a0, (_, n0)) = (alpha, self.weights(alpha)?);
        let mut h0 = n0 - a0;
        let mut a1 = n0;
        for _ in 0..CORRECTION_STEPS {
            let (v, n1) = self.weights(a1)?;
            let h1 = n1 - a1;
            if h1.abs() <= CORRECTION_TOLERANCE * a1 {
                return Some(v);
            }
            let slope = (h1 - h0) / (a1 - a0);
            let next = if slope.is_finite() && slope != 0.0 {
                a1 - h1 / slope
            } else {
                n1
            };
            (a0, h0) = (a1, h1);
            a1 = next;
        }
        None
    }
}
