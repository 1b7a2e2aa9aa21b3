//! Running mean and standard error per colour band, and the adaptive stopping rule shared by the 3-D and
//! Flatland path tracers.

use crate::error::{BaselineError, check_range};

/// Radiosity estimate at one point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Estimate {
    /// Mean B per band.
    pub mean: [f64; 3],
    /// Standard error of the mean per band.
    pub std_error: [f64; 3],
    /// Paths used.
    pub paths: usize,
}

impl Estimate {
    /// The largest relative standard error over the bands with a positive mean (0 if every mean is 0).
    ///
    /// A band with mean 0 is skipped here, so this is *not* a bound on the error of a zero estimate; the
    /// adaptive mode's verdict is [`AdaptiveEstimate::rel_error`] (∞ for a zero mean where B can be positive).
    pub fn rel_error(&self) -> f64 {
        (0..3)
            .filter(|&b| self.mean[b] > 0.0)
            .map(|b| self.std_error[b] / self.mean[b])
            .fold(0.0, f64::max)
    }
}

/// Sums of values and squares per band.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Accumulator {
    sum: [f64; 3],
    sq: [f64; 3],
    n: usize,
}

impl Accumulator {
    pub(crate) fn add(&mut self, v: [f64; 3]) {
        for b in 0..3 {
            self.sum[b] += v[b];
            self.sq[b] += v[b] * v[b];
        }
        self.n += 1;
    }
    /// Mean and standard error of the mean (sample variance with n − 1). Needs n ≥ 2.
    pub(crate) fn estimate(&self) -> Estimate {
        let n = self.n as f64;
        let mean = self.sum.map(|s| s / n);
        let std_error =
            [0, 1, 2].map(|b| ((self.sq[b] / n - mean[b] * mean[b]).max(0.0) / (n - 1.0)).sqrt());
        Estimate {
            mean,
            std_error,
            paths: self.n,
        }
    }
}

/// The adaptive mode of the path tracers: batches of paths per point until the estimate provably meets the
/// relative standard error target, or `max_paths` paths were traced.
///
/// # Stopping rule
/// After each batch, once at least `min_paths` paths are in, a point stops when
/// [`relative_error_bound`] ≤ `rel_error`. The bound counts every band that *can* be positive at the point
/// (see [`AdaptiveEstimate::rel_error`]): a band with mean 0 there has **no** bound (∞), since a mean of 0 from
/// n paths only says that the probability of a path reaching light is below ≈ 3/n (rule of three, 95 %), not
/// that B is small relative to its error. So a point whose first batch found no light keeps going, to the cap
/// if need be, and is then reported as having missed the target — it never stops on "0 ≤ target·0".
///
/// Once a band has k > 0 non-zero paths, its sample relative error cannot be small by luck alone: for
/// non-negative contributions, Cauchy–Schwarz on the empirical distribution gives
/// `(Σx)² ≤ k·Σx²`, hence `se/mean ≥ √((n − k)/(k·(n − 1)))` ≈ `1/√k` for k ≪ n; meeting a target r needs
/// k ≳ (1 − k/n)/r² light-carrying paths (10⁴ for 1 %), enough for the variance estimate to be trusted.
/// `min_paths` guards the other end: a point where almost every path carries light (an emitter) with a few
/// rare large contributions not yet seen.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Adaptive {
    /// Target relative standard error (e.g. 0.01), in `(0, 1)`.
    pub rel_error: f64,
    /// Paths per batch (≥ 2); the error is checked after each batch.
    pub batch: usize,
    /// Paths every point traces before the target is checked at all (≥ 2, ≤ `max_paths`); rounded up to
    /// whole batches.
    pub min_paths: usize,
    /// Path cap per point (≥ `batch`, ≥ `min_paths`).
    pub max_paths: usize,
    /// Seed; each point has its own stream derived from it and the point's coordinates (not its index, so a
    /// probe's value does not depend on its line in the probe file).
    pub seed: u64,
}

impl Default for Adaptive {
    /// 1 % relative error, batches of 256, at least 4096 and at most 10⁶ paths, seed 1.
    fn default() -> Self {
        Adaptive {
            rel_error: 0.01,
            batch: 256,
            min_paths: 4096,
            max_paths: 1_000_000,
            seed: 1,
        }
    }
}

/// An adaptive estimate with its verdict: the estimate, the bound on its relative standard error that the
/// stopping rule used, and whether that bound met the target.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AdaptiveEstimate {
    /// Mean, standard error per band and path count.
    pub estimate: Estimate,
    /// The largest relative standard error over the bands that can be positive at the point: `se/mean`, or
    /// `f64::INFINITY` for such a band whose mean is 0 (no path reached light: nothing bounds its relative
    /// error). Bands that are exactly 0 at the point — the scene emits nothing in them, or the point's face
    /// neither emits nor reflects in them — are left out (their estimate is exact).
    pub rel_error: f64,
    /// `rel_error ≤` the target. False means the path cap was reached first: the caller must say so.
    pub target_met: bool,
}

/// The bound of [`AdaptiveEstimate::rel_error`] for `e`, where `live[b]` says whether band `b` can be
/// positive at the point (a band with a positive mean always counts).
pub fn relative_error_bound(e: &Estimate, live: [bool; 3]) -> f64 {
    (0..3)
        .filter(|&b| live[b] || e.mean[b] > 0.0)
        .map(|b| {
            if e.mean[b] > 0.0 {
                e.std_error[b] / e.mean[b]
            } else {
                f64::INFINITY
            }
        })
        .fold(0.0, f64::max)
}

impl Adaptive {
    /// Checks the parameters.
    pub fn validate(&self) -> Result<(), BaselineError> {
        check_range("rel_error", self.rel_error, 0.0, 1.0, "0 < rel_error < 1")?;
        if self.batch < 2 {
            return Err(BaselineError::InvalidParameter {
                name: "batch",
                value: self.batch as f64,
                expected: "at least 2 paths per batch",
            });
        }
        if self.min_paths < 2 {
            return Err(BaselineError::InvalidParameter {
                name: "min_paths",
                value: self.min_paths as f64,
                expected: "at least 2 paths before the target is checked",
            });
        }
        if self.max_paths < self.batch || self.max_paths < self.min_paths {
            return Err(BaselineError::InvalidParameter {
                name: "max_paths",
                value: self.max_paths as f64,
                expected: "max_paths >= batch and max_paths >= min_paths",
            });
        }
        Ok(())
    }

    /// Runs `path` in batches until the target (by [`relative_error_bound`] with `live`) or the cap is
    /// reached. `path` draws from its own stream.
    pub(crate) fn run(
        &self,
        live: [bool; 3],
        mut path: impl FnMut() -> [f64; 3],
    ) -> AdaptiveEstimate {
        let mut acc = Accumulator::default();
        loop {
            for _ in 0..self.batch.min(self.max_paths - acc.n) {
                acc.add(path());
            }
            let estimate = acc.estimate();
            let rel_error = relative_error_bound(&estimate, live);
            let target_met = rel_error <= self.rel_error;
            if (target_met && acc.n >= self.min_paths) || acc.n >= self.max_paths {
                return AdaptiveEstimate {
                    estimate,
                    rel_error,
                    target_met,
                };
            }
        }
    }
}

/// Fixed-count mode: `paths.max(2)` paths.
pub(crate) fn run_fixed(paths: usize, mut path: impl FnMut() -> [f64; 3]) -> Estimate {
    let mut acc = Accumulator::default();
    for _ in 0..paths.max(2) {
        acc.add(path());
    }
    acc.estimate()
}

/// Russian roulette of the path tracers after three bounces: survival probability = the largest
/// throughput, the survivors' throughput divided by it, so that no weight exceeds 1 (finite
/// variance at any ρ < 1; a cap at 0.95 made the weights grow by ρ/0.95 per bounce above ρ = 0.95,
/// an infinite variance at ρ = 0.99). False when the path ends (also when nothing is reflected any
/// more).
pub(crate) fn survives_roulette(
    throughput: &mut [f64; 3],
    depth: usize,
    rng: &mut impl rand::Rng,
) -> bool {
    let q = throughput.iter().cloned().fold(0.0, f64::max).min(1.0);
    if q <= 0.0 {
        return false;
    }
    if depth >= 3 {
        if rng.random::<f64>() >= q {
            return false;
        }
        throughput.iter_mut().for_each(|t| *t /= q);
    }
    true
}

/// The per-point random stream of the path tracers, keyed by the seed and the point's own coordinates
/// (`words`: the f64 bits of position and normal), so that it depends neither on the thread count nor on
/// where the point stands in its list (a probe's value does not change when lines of its file are added,
/// removed or reordered). `-0.0` and `0.0` give the same stream.
pub(crate) fn point_rng(seed: u64, words: &[f64]) -> rand_chacha::ChaCha8Rng {
    use rand::SeedableRng;
    // splitmix64 finalizer over the words, chained (Steele, Lea, Flood 2014).
    fn mix(mut z: u64) -> u64 {
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    let mut h = mix(seed.wrapping_add(0x9E37_79B9_7F4A_7C15));
    for &w in words {
        h = mix(h ^ (w + 0.0).to_bits()).wrapping_add(0x9E37_79B9_7F4A_7C15);
    }
    rand_chacha::ChaCha8Rng::seed_from_u64(h)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn accumulator_matches_the_textbook_formulas() {
        let mut a = Accumulator::default();
        for v in [1.0, 2.0, 4.0, 7.0] {
            a.add([v, 2.0 * v, 0.0]);
        }
        let e = a.estimate();
        assert!((e.mean[0] - 3.5).abs() < 1e-12);
        // sample variance = ((2.5² + 1.5² + 0.5² + 3.5²) / 3) = 7; se = sqrt(7/4)
        assert!((e.std_error[0] - (7.0f64 / 4.0).sqrt()).abs() < 1e-12);
        assert!((e.std_error[1] - 2.0 * (7.0f64 / 4.0).sqrt()).abs() < 1e-12);
        assert_eq!(e.std_error[2], 0.0);
        assert!((e.rel_error() - (7.0f64 / 4.0).sqrt() / 3.5).abs() < 1e-12);
    }

    #[test]
    fn adaptive_rejects_bad_parameters() {
        let ok = Adaptive::default();
        assert!(ok.validate().is_ok());
        for bad in [
            Adaptive {
                rel_error: 0.0,
                ..ok
            },
            Adaptive {
                rel_error: f64::NAN,
                ..ok
            },
            Adaptive { batch: 1, ..ok },
            Adaptive {
                max_paths: 10,
                ..ok
            },
        ] {
            assert!(bad.validate().is_err(), "{bad:?}");
        }
    }

    #[test]
    fn adaptive_stops_at_the_cap_or_the_target() {
        let a = Adaptive {
            rel_error: 1e-6,
            batch: 10,
            min_paths: 10,
            max_paths: 35,
            seed: 0,
        };
        let mut k = 0.0;
        let e = a.run([true; 3], || {
            k += 1.0;
            [k, k, k]
        });
        assert_eq!(e.estimate.paths, 35);
        assert!(!e.target_met && e.rel_error > 1e-6);
        let b = Adaptive {
            rel_error: 0.5,
            ..a
        };
        let e = b.run([true; 3], || [1.0; 3]);
        assert_eq!(e.estimate.paths, 10);
        assert!(e.target_met && e.rel_error == 0.0);
        // the minimum path count holds even when the first batch already meets the target
        let c = Adaptive { min_paths: 25, ..b };
        assert_eq!(c.run([true; 3], || [1.0; 3]).estimate.paths, 30);
        assert!(Adaptive { min_paths: 1, ..a }.validate().is_err());
        assert!(Adaptive { min_paths: 36, ..a }.validate().is_err());
    }

    /// Issue 17: a point whose first batch found no light stopped with B = 0, because `0 ≤ target·0`.
    #[test]
    fn a_zero_mean_never_meets_the_target() {
        let a = Adaptive {
            rel_error: 0.01,
            batch: 256,
            min_paths: 256,
            max_paths: 100_000,
            seed: 0,
        };
        // light is reached only from the 300th path on, then by one path in four
        let mut n = 0u32;
        let e = a.run([true; 3], || {
            n += 1;
            if n >= 300 && n % 4 == 0 {
                [1.0; 3]
            } else {
                [0.0; 3]
            }
        });
        assert!(e.estimate.mean[0] > 0.2, "{e:?}");
        assert!(e.target_met && e.rel_error <= 0.01, "{e:?}");
        // never any light: runs to the cap, bound infinite, target missed
        let e = a.run([true; 3], || [0.0; 3]);
        assert_eq!(e.estimate.paths, 100_000);
        assert!(!e.target_met && e.rel_error == f64::INFINITY);
        // a band that cannot be positive (no emission in it) is exact at 0 and does not hold the point back
        let e = a.run([true, false, false], || [1.0, 0.0, 0.0]);
        assert!(e.target_met && e.estimate.paths == 256);
        // but an impossible band that turns out positive still counts
        let mut k = 0.0;
        let e = a.run([false; 3], || {
            k += 1.0;
            [0.0, 0.0, k]
        });
        assert!(e.rel_error > 0.0 && e.rel_error.is_finite());
    }

    #[test]
    fn the_bound_is_infinite_for_a_zero_mean_where_b_can_be_positive() {
        let e = Estimate {
            mean: [0.5, 0.0, 0.0],
            std_error: [0.05, 0.0, 0.0],
            paths: 100,
        };
        assert_eq!(e.rel_error(), 0.1);
        assert_eq!(relative_error_bound(&e, [true, false, false]), 0.1);
        assert_eq!(relative_error_bound(&e, [true, true, false]), f64::INFINITY);
    }

    #[test]
    fn point_streams_depend_on_coordinates_not_order() {
        use rand::Rng;
        let mut a = point_rng(3, &[0.5, 0.0, 1.0]);
        let mut b = point_rng(3, &[0.5, -0.0, 1.0]);
        assert_eq!(a.random::<u64>(), b.random::<u64>());
        let mut c = point_rng(3, &[0.5, 0.0, 1.0 + f64::EPSILON]);
        let mut d = point_rng(4, &[0.5, 0.0, 1.0]);
        let x = point_rng(3, &[0.5, 0.0, 1.0]).random::<u64>();
        assert_ne!(x, c.random::<u64>());
        assert_ne!(x, d.random::<u64>());
    }
}
