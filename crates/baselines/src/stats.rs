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

/// The adaptive mode of the path tracers: batches of paths per point until the relative standard error of
/// every band with a positive mean is at most `rel_error`, or `max_paths` paths were traced.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Adaptive {
    /// Target relative standard error (e.g. 0.01), in `(0, 1)`.
    pub rel_error: f64,
    /// Paths per batch (≥ 2); the error is checked after each batch, so this is also the minimum.
    pub batch: usize,
    /// Path cap per point (≥ `batch`).
    pub max_paths: usize,
    /// Seed; each point has its own stream derived from it and its index.
    pub seed: u64,
}

impl Default for Adaptive {
    /// 1 % relative error, batches of 256, at most 10⁶ paths, seed 1.
    fn default() -> Self {
        Adaptive {
            rel_error: 0.01,
            batch: 256,
            max_paths: 1_000_000,
            seed: 1,
        }
    }
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
        if self.max_paths < self.batch {
            return Err(BaselineError::InvalidParameter {
                name: "max_paths",
                value: self.max_paths as f64,
                expected: "max_paths >= batch",
            });
        }
        Ok(())
    }

    /// Runs `path` in batches until the target or the cap is reached. `path` draws from its own stream.
    pub(crate) fn run(&self, mut path: impl FnMut() -> [f64; 3]) -> Estimate {
        let mut acc = Accumulator::default();
        loop {
            for _ in 0..self.batch.min(self.max_paths - acc.n) {
                acc.add(path());
            }
            let e = acc.estimate();
            if e.rel_error() <= self.rel_error || acc.n >= self.max_paths {
                return e;
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

/// The per-point random stream of the path tracers: independent of the thread count.
pub(crate) fn point_rng(seed: u64, index: usize) -> rand_chacha::ChaCha8Rng {
    use rand::SeedableRng;
    rand_chacha::ChaCha8Rng::seed_from_u64(
        seed ^ (index as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15),
    )
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
            max_paths: 35,
            seed: 0,
        };
        let mut k = 0.0;
        let e = a.run(|| {
            k += 1.0;
            [k, k, k]
        });
        assert_eq!(e.paths, 35);
        let b = Adaptive {
            rel_error: 0.5,
            ..a
        };
        let e = b.run(|| [1.0; 3]);
        assert_eq!(e.paths, 10);
    }
}
