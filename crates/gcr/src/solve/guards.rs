//! Stability guards of the projected kernel's bounce iteration (beyond the dissertation).
//!
//! The physical iteration s ← E + B_refl(s) contracts (gain ≤ ρ_max < 1), and every radiosity of
//! a sound solve obeys the maximum principle `B ≤ E_max / (1 − ρ_max)` per band
//! ([`crate::domain::Domain::radiosity_bound`]). A projected kernel can still carry a mode of gain
//! above 1; these guards see it and [`super::propagate`] acts on them. The measurements behind
//! each threshold are in `docs/design/gcr-algorithm.md` ("Stability guards").

use super::error::SolveError;
use crate::element::{BANDS, Bands};
use crate::sample::Sample;

/// Relative pivot thresholds a diverging projection is redone with, in turn, the gentlest
/// first (on wall-floor at 400 cells only 0.5 and 0.9 converged; on cornell-box at 1850–2000
/// cells 1e−3 was enough, where 0.5 dropped most cells). Each step refactors the same Gram matrix.
pub(super) const STABILIZING_REJECTIONS: [f64; 4] = [1e-3, 1e-1, 0.5, 0.9];

/// A projection whose kernel reflects more than this many times the power the samples carry, or
/// less than its inverse, is broken (sound ones measure 0.98–1.06; a broken one −195).
const BALANCE_LIMIT: f64 = 4.0;

/// A bounce iteration whose relative change fell below this before it started to grow again
/// counts as settled: its strengths at the smallest change are kept instead of redoing the
/// projection with fewer cells (a mode of gain just above 1 grows too slowly to matter).
const SETTLED_CHANGE: f64 = 1e-4;

/// A strength this far beyond the maximum-principle bound makes [`super::propagate`] redo the
/// projection with a higher rejection even when its bounces did not visibly diverge (a furnace
/// reaches the bound exactly, so 1 would be too tight).
const RESTABILIZE_FACTOR: f64 = 2.0;

/// A direct solve of the linearized bounce ([`super::propagate`]) whose strengths exceed the
/// maximum-principle bound this many times is the fixed point of a mode of gain above 1 (the
/// bounces would never reach it): it is dropped and the bounces go on from the strengths before.
/// Measured on ρ = 0.99 furnaces: sound fixed points peak at 2–3× the bound (corner ripple), the
/// unreachable one at 11×.
pub(super) const DIRECT_LIMIT: f64 = 5.0;

/// How far beyond the maximum-principle bound a strength may go (Monte-Carlo noise and the
/// projection's ringing stay far below this) before the solve counts as unstable.
pub(super) const UNSTABLE_FACTOR: f64 = 10.0;

/// The largest `|s_k| / bound_k` over the samples and bands (∞ for a non-finite strength; a zero
/// bound counts as the smallest positive number, so any strength in a dark band is an excess).
pub(super) fn bound_excess(samples: &[Sample], bound: &Bands) -> f64 {
    samples
        .iter()
        .flat_map(|s| (0..BANDS).map(move |k| (s.s[k].abs(), k)))
        .map(|(v, k)| {
            if v.is_finite() {
                v / bound[k].max(f64::MIN_POSITIVE)
            } else {
                f64::INFINITY
            }
        })
        .fold(0.0, f64::max)
}

/// Whether a measured energy balance (the kernel's reflected power over the samples') shows a
/// broken projection: outside [1/[`BALANCE_LIMIT`], [`BALANCE_LIMIT`]].
pub(super) fn balance_broken(balance: f64) -> bool {
    !(1.0 / BALANCE_LIMIT..=BALANCE_LIMIT).contains(&balance)
}

/// Whether a finished projection ran away and must be redone with a higher rejection: it
/// diverged before it had settled, or left a strength beyond [`RESTABILIZE_FACTOR`] × the bound
/// (a few training bounces are too few to see a slow divergence grow).
pub(super) fn ran_away(diverged: bool, settled: bool, samples: &[Sample], bound: &Bands) -> bool {
    (diverged && !settled) || bound_excess(samples, bound) > RESTABILIZE_FACTOR
}

/// The last guard: an error instead of a wrong picture when the strengths still break the bound
/// [`UNSTABLE_FACTOR`]-fold after every stabilizing rejection.
pub(super) fn check_stable(
    samples: &[Sample],
    bound: &Bands,
    tolerance: f64,
    rejection: f64,
) -> Result<(), SolveError> {
    let worst = bound_excess(samples, bound);
    if worst > UNSTABLE_FACTOR {
        return Err(SolveError::Unstable(format!(
            "the projected kernel's bounces give radiosities {worst:.1e} times the bound \
             E_max/(1 − ρ_max) of the scene (projection cut-off {tolerance:.0e}, rejection \
             {rejection:.0e}; the defaults of both, 1e-6, are the measured-safe ones)"
        )));
    }
    Ok(())
}

/// Watches the relative changes of the bounce iteration: a change that grows on two bounces in a
/// row is a divergence; the strengths after the smallest change are kept to go back to.
#[derive(Default)]
pub(super) struct BounceWatch {
    /// The last two changes (older, newer).
    changes: Option<(f64, f64)>,
    /// The smallest change so far and the strengths after it.
    best: Option<(f64, Vec<Bands>)>,
}

impl BounceWatch {
    /// Whether `change` continues a growth of the change on two bounces in a row.
    pub(super) fn diverging(&self, change: f64) -> bool {
        self.changes
            .is_some_and(|(older, newer)| change > newer && newer > older)
    }

    /// Records a bounce's change and, when it is the smallest yet, the strengths after it.
    pub(super) fn record(&mut self, change: f64, samples: &[Sample]) {
        let newer = self.changes.map_or(f64::INFINITY, |c| c.1);
        self.changes = Some((newer, change));
        if self.best.as_ref().is_none_or(|(c, _)| change < *c) {
            self.best = Some((change, samples.iter().map(|smp| smp.s).collect()));
        }
    }

    /// Puts back the strengths after the smallest change (nothing when none was recorded).
    pub(super) fn restore(&self, samples: &mut [Sample]) {
        if let Some((_, s)) = &self.best {
            for (smp, v) in samples.iter_mut().zip(s) {
                smp.s = *v;
            }
        }
    }

    /// Whether the smallest change was below [`SETTLED_CHANGE`].
    pub(super) fn settled(&self) -> bool {
        self.best.as_ref().is_some_and(|(c, _)| *c < SETTLED_CHANGE)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::domain::Ray;
    use glam::DVec3;

    fn sample(s: Bands) -> Sample {
        Sample {
            ray: Ray {
                x: DVec3::ZERO,
                nx: DVec3::Y,
                y: DVec3::ONE,
                ny: DVec3::NEG_Y,
                face_x: 0,
                face_y: 1,
                kernel: [0.0; BANDS],
                emission_x: [0.0; BANDS],
            },
            s,
            inv_px: 0.0,
        }
    }

    /// The unstable-solve test reads the worst ratio to the bound over every sample and band,
    /// takes magnitudes (a projection can ring negative), and flags non-finite strengths.
    #[test]
    fn bound_excess_finds_the_worst_strength() {
        let bound = [2.0, 4.0, 8.0];
        let (a, mut b) = ([1.0, 1.0, 1.0], [0.5, -12.0, 4.0]);
        assert_eq!(bound_excess(&[sample(a), sample(b)], &bound), 3.0);
        assert_eq!(bound_excess(&[], &bound), 0.0);
        b[2] = f64::NAN;
        assert_eq!(bound_excess(&[sample(a), sample(b)], &bound), f64::INFINITY);
        // A strength in a band the scene does not emit in is an excess of its own.
        let dark_bound = [2.0, 4.0, 0.0];
        assert!(bound_excess(&[sample([0.0, 0.0, 1e-3])], &dark_bound) > UNSTABLE_FACTOR);
    }

    /// Growth counts only on two bounces in a row; a single larger change after a small one is
    /// noise of the iteration.
    #[test]
    fn a_divergence_is_a_change_growing_twice_in_a_row() {
        let mut w = BounceWatch::default();
        let s = [sample([1.0; BANDS])];
        assert!(!w.diverging(0.5), "nothing recorded yet");
        w.record(0.5, &s);
        assert!(!w.diverging(0.6), "one growth is not yet a divergence");
        w.record(0.1, &s);
        w.record(0.2, &s);
        assert!(w.diverging(0.3));
        assert!(!w.diverging(0.15));
    }

    /// Restoring goes back to the strengths after the smallest change, and settling is judged on
    /// that smallest change.
    #[test]
    fn restore_returns_the_strengths_after_the_smallest_change() {
        let mut w = BounceWatch::default();
        let mut s = [sample([1.0; BANDS])];
        w.restore(&mut s);
        assert_eq!(s[0].s, [1.0; BANDS], "nothing recorded: unchanged");
        w.record(1e-2, &s);
        s[0].s = [2.0; BANDS];
        w.record(1e-5, &s);
        s[0].s = [3.0; BANDS];
        w.record(1e-3, &s);
        s[0].s = [9.0; BANDS];
        w.restore(&mut s);
        assert_eq!(s[0].s, [2.0; BANDS]);
        assert!(w.settled());
        let mut unsettled = BounceWatch::default();
        unsettled.record(1e-2, &s);
        assert!(!unsettled.settled());
    }

    /// The balance guard is symmetric in the ratio and accepts its limits.
    #[test]
    fn balance_outside_a_factor_four_is_broken() {
        assert!(!balance_broken(1.0));
        assert!(!balance_broken(4.0) && !balance_broken(0.25));
        assert!(balance_broken(4.1) && balance_broken(0.2));
        assert!(balance_broken(-195.0));
        assert!(balance_broken(f64::NAN));
    }

    /// A finished projection is redone when it diverged unsettled or left a strength twice the
    /// bound, and the solve errs beyond ten times the bound.
    #[test]
    fn runaway_and_unstable_thresholds() {
        let bound = [1.0; BANDS];
        let fine = [sample([1.5; BANDS])];
        let high = [sample([3.0; BANDS])];
        assert!(!ran_away(false, false, &fine, &bound));
        assert!(!ran_away(true, true, &fine, &bound));
        assert!(ran_away(true, false, &fine, &bound));
        assert!(ran_away(false, false, &high, &bound));
        assert!(check_stable(&high, &bound, 1e-6, 1e-6).is_ok());
        let wild = [sample([11.0; BANDS])];
        assert!(matches!(
            check_stable(&wild, &bound, 1e-6, 1e-6),
            Err(SolveError::Unstable(_))
        ));
    }
}
