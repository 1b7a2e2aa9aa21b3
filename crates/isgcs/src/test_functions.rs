//! Test functions for measuring approximation error (the examples and the benchmarks).

/// Franke's 2-D test function on [0, 1]² (Franke 1979), the usual scattered-data benchmark.
pub fn franke(x: f64, y: f64) -> f64 {
    0.75 * (-((9.0 * x - 2.0).powi(2) + (9.0 * y - 2.0).powi(2)) / 4.0).exp()
        + 0.75 * (-(9.0 * x + 1.0).powi(2) / 49.0 - (9.0 * y + 1.0) / 10.0).exp()
        + 0.5 * (-((9.0 * x - 7.0).powi(2) + (9.0 * y - 3.0).powi(2)) / 4.0).exp()
        - 0.2 * (-(9.0 * x - 4.0).powi(2) - (9.0 * y - 7.0).powi(2)).exp()
}

/// A smooth function on [0, 1]⁶: a broad bump modulated by a plane wave, plus a product term
/// and a cosine. Reads the first six coordinates of `x` (shorter inputs count as zero-padded).
pub fn smooth6(x: &[f64]) -> f64 {
    let c = |i: usize| x.get(i).copied().unwrap_or(0.0);
    let r2: f64 = (0..6).map(|i| (c(i) - 0.5) * (c(i) - 0.5)).sum();
    (-r2).exp() * (1.0 + 0.5 * (2.0 * c(0) + c(1) - c(2)).sin()) + 0.3 * c(3) * c(4)
        - 0.2 * (2.0 * c(5)).cos()
}

/// Friedman #1 on [0, 1]¹⁰ (Friedman 1991): 10 sin(π x₁x₂) + 20 (x₃ − ½)² + 10 x₄ + 5 x₅; the
/// other five inputs are irrelevant.
pub fn friedman1(x: &[f64]) -> f64 {
    10.0 * (std::f64::consts::PI * x[0] * x[1]).sin()
        + 20.0 * (x[2] - 0.5).powi(2)
        + 10.0 * x[3]
        + 5.0 * x[4]
}

/// Friedman #2 on [0, 100] × [40π, 560π] × [0, 1] × [1, 11]: √(x₁² + (x₂x₃ − 1/(x₂x₄))²).
pub fn friedman2(x: &[f64]) -> f64 {
    (x[0] * x[0] + (x[1] * x[2] - 1.0 / (x[1] * x[3])).powi(2)).sqrt()
}

/// Friedman #3 on Friedman #2's domain: atan((x₂x₃ − 1/(x₂x₄)) / x₁).
pub fn friedman3(x: &[f64]) -> f64 {
    ((x[1] * x[2] - 1.0 / (x[1] * x[3])) / x[0]).atan()
}

/// The Ishigami function on [−π, π]³ (a = 7, b = 0.1): sin x₁ + 7 sin² x₂ + 0.1 x₃⁴ sin x₁.
pub fn ishigami(x: &[f64]) -> f64 {
    x[0].sin() + 7.0 * x[1].sin().powi(2) + 0.1 * x[2].powi(4) * x[0].sin()
}

/// A 2-D function with a jump on [0, 1]²: a smooth part plus 1 above the curve
/// y = 0.3 + 0.4 x + 0.1 sin(6x).
pub fn jump2(x: &[f64]) -> f64 {
    let step = if x[1] > 0.3 + 0.4 * x[0] + 0.1 * (6.0 * x[0]).sin() {
        1.0
    } else {
        0.0
    };
    0.5 * (x[0] * x[0] + x[1]) + step
}

/// Genz's oscillatory function on [0, 1]⁴: cos(2π · 0.3 + Σ aᵢxᵢ) with a = (3, 2.5, 2, 1.5).
pub fn oscillatory4(x: &[f64]) -> f64 {
    let a = [3.0, 2.5, 2.0, 1.5];
    (2.0 * std::f64::consts::PI * 0.3 + a.iter().zip(x).map(|(a, x)| a * x).sum::<f64>()).cos()
}

/// One benchmark problem: a function on a box, sampled uniformly, with Gaussian noise of this
/// standard deviation on the training targets (the test targets are noise-free).
#[derive(Clone, Copy, Debug)]
pub struct Problem {
    /// Short name.
    pub name: &'static str,
    /// Lower corner of the box.
    pub lo: &'static [f64],
    /// Upper corner of the box.
    pub hi: &'static [f64],
    /// The function.
    pub f: fn(&[f64]) -> f64,
    /// Noise standard deviation on the training targets.
    pub noise: f64,
}

const PI: f64 = std::f64::consts::PI;
const F2_LO: &[f64] = &[0.0, 40.0 * PI, 0.0, 1.0];
const F2_HI: &[f64] = &[100.0, 560.0 * PI, 1.0, 11.0];

fn franke2(x: &[f64]) -> f64 {
    franke(x[0], x[1])
}

/// The benchmark suite of docs/design/isgcs.md: published test functions (Franke, Friedman #1–#3,
/// Ishigami, Genz oscillatory), a discontinuous 2-D function, the smooth 6-D function, and
/// noisy variants (noise about a quarter to a half of the function's standard deviation).
pub fn suite() -> Vec<Problem> {
    vec![
        Problem {
            name: "franke",
            lo: &[0.0; 2],
            hi: &[1.0; 2],
            f: franke2,
            noise: 0.0,
        },
        Problem {
            name: "franke-noisy",
            lo: &[0.0; 2],
            hi: &[1.0; 2],
            f: franke2,
            noise: 0.1,
        },
        Problem {
            name: "jump2",
            lo: &[0.0; 2],
            hi: &[1.0; 2],
            f: jump2,
            noise: 0.0,
        },
        Problem {
            name: "ishigami",
            lo: &[-PI; 3],
            hi: &[PI; 3],
            f: ishigami,
            noise: 0.0,
        },
        Problem {
            name: "oscillatory4",
            lo: &[0.0; 4],
            hi: &[1.0; 4],
            f: oscillatory4,
            noise: 0.0,
        },
        Problem {
            name: "friedman1",
            lo: &[0.0; 10],
            hi: &[1.0; 10],
            f: friedman1,
            noise: 0.0,
        },
        Problem {
            name: "friedman1-noisy",
            lo: &[0.0; 10],
            hi: &[1.0; 10],
            f: friedman1,
            noise: 1.0,
        },
        Problem {
            name: "friedman2",
            lo: F2_LO,
            hi: F2_HI,
            f: friedman2,
            noise: 0.0,
        },
        Problem {
            name: "friedman3",
            lo: F2_LO,
            hi: F2_HI,
            f: friedman3,
            noise: 0.0,
        },
        Problem {
            name: "smooth6",
            lo: &[0.0; 6],
            hi: &[1.0; 6],
            f: smooth6,
            noise: 0.0,
        },
    ]
}

impl Problem {
    /// Input dimension.
    pub fn dim(&self) -> usize {
        self.lo.len()
    }

    /// `rows` uniform inputs (row-major) and their targets, with noise when `noisy`.
    pub fn sample(&self, rows: usize, noisy: bool, seed: u64) -> (Vec<f64>, Vec<f64>) {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let n = self.dim();
        let mut x = Vec::with_capacity(rows * n);
        let mut y = Vec::with_capacity(rows);
        for _ in 0..rows {
            let start = x.len();
            for a in 0..n {
                x.push(self.lo[a] + (self.hi[a] - self.lo[a]) * rng.random::<f64>());
            }
            let mut v = (self.f)(&x[start..]);
            if noisy && self.noise > 0.0 {
                // Box–Muller.
                let (u1, u2): (f64, f64) = (rng.random::<f64>().max(1e-300), rng.random());
                v += self.noise * (-2.0 * u1.ln()).sqrt() * (2.0 * PI * u2).cos();
            }
            y.push(v);
        }
        (x, y)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn known_values() {
        // Franke's function peaks near (0.2, 0.2); reference value computed from the formula.
        let f = franke(2.0 / 9.0, 2.0 / 9.0);
        let expect = 0.75
            + 0.75 * (-(3.0f64).powi(2) / 49.0 - 0.3).exp()
            + 0.5 * (-(25.0 + 1.0) / 4.0f64).exp()
            - 0.2 * (-4.0 - 25.0f64).exp();
        assert!((f - expect).abs() < 1e-14, "{f} vs {expect}");
        let centre = smooth6(&[0.5; 6]);
        let expect = 1.0 + 0.5 * (1.0f64).sin() + 0.3 * 0.25 - 0.2 * (1.0f64).cos();
        assert!((centre - expect).abs() < 1e-14);
    }
}
