//! A reference approximator to measure the network against (issue 2): a Gaussian radial basis
//! function network with k-means centres and least-squares output weights.

use crate::data::{RegressorError, check_data};
pub use crate::kmeans::kmeans;
use crate::network::IsgcsError;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Ψ(x) = Σ_j v_j exp(−|x − c_j|² / d_j²) with centres c_j from k-means (Lloyd) on the training
/// inputs, widths d_j = `width_multiplier` × the mean distance from c_j to its n + 1 nearest
/// other centres, and output weights v_j by regularised least squares.
#[derive(Clone, Debug)]
pub struct GaussianRbf {
    n: usize,
    m: usize,
    centres: Vec<f64>,
    widths: Vec<f64>,
    weights: Vec<f64>,
}

fn dist2(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(p, q)| (p - q) * (p - q)).sum()
}

/// k-means centres (`centres` × n, row-major) of the N × n `inputs`: `centres` distinct random
/// inputs (partial Fisher–Yates, seeded by `seed`), then at most `iterations` Lloyd rounds
/// (each input to its nearest centre, each centre to the mean of its inputs) until no input
/// changes centre.
fn lloyd_centres(
    inputs: &[f64],
    n: usize,
    centres: usize,
    iterations: usize,
    seed: u64,
) -> Vec<f64> {
    let count = inputs.len() / n;
    // k-means initialisation: distinct random samples (partial Fisher–Yates).
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut order: Vec<usize> = (0..count).collect();
    for i in 0..centres {
        let j = rng.random_range(i..count);
        order.swap(i, j);
    }
    let mut c: Vec<f64> = order[..centres]
        .iter()
        .flat_map(|&s| inputs[s * n..(s + 1) * n].iter().copied())
        .collect();
    let mut assign = vec![usize::MAX; count];
    for _ in 0..iterations {
        let mut changed = false;
        for (s, x) in inputs.chunks_exact(n).enumerate() {
            let best = (0..centres)
                .map(|j| (j, dist2(x, &c[j * n..(j + 1) * n])))
                .min_by(|a, b| a.1.total_cmp(&b.1))
                .map_or(0, |(j, _)| j);
            changed |= assign[s] != best;
            assign[s] = best;
        }
        if !changed {
            break;
        }
        let mut sum = vec![0.0; centres * n];
        let mut cnt = vec![0usize; centres];
        for (s, x) in inputs.chunks_exact(n).enumerate() {
            cnt[assign[s]] += 1;
            for a in 0..n {
                sum[assign[s] * n + a] += x[a];
            }
        }
        for j in 0..centres {
            if cnt[j] > 0 {
                for a in 0..n {
                    c[j * n + a] = sum[j * n + a] / cnt[j] as f64;
                }
            }
        }
    }
    c
}

/// The width of each of the `centres` centres `c` (× n): `multiplier` × the mean distance to
/// its n + 1 nearest other centres (all others when there are fewer).
fn centre_widths(c: &[f64], n: usize, centres: usize, multiplier: f64) -> Vec<f64> {
    let q = (n + 1).min(centres - 1);
    (0..centres)
        .map(|j| {
            let mut d: Vec<f64> = (0..centres)
                .filter(|&i| i != j)
                .map(|i| dist2(&c[i * n..(i + 1) * n], &c[j * n..(j + 1) * n]).sqrt())
                .collect();
            d.select_nth_unstable_by(q - 1, |a, b| a.total_cmp(b));
            multiplier * d[..q].iter().sum::<f64>() / q as f64
        })
        .collect()
}

impl GaussianRbf {
    /// Fits `centres` Gaussians to N points `inputs` (N × n, row-major) with values `targets`
    /// (N × m): `kmeans_iterations` Lloyd iterations from `centres` distinct random inputs
    /// (seeded by `seed`), then least squares with relative ridge `ridge` (as in
    /// [`crate::Isgcs::fit_outputs`]).
    #[allow(clippy::too_many_arguments)]
    pub fn fit(
        inputs: &[f64],
        targets: &[f64],
        n: usize,
        m: usize,
        centres: usize,
        width_multiplier: f64,
        kmeans_iterations: usize,
        ridge: f64,
        seed: u64,
    ) -> Result<Self, IsgcsError> {
        let bad = |s: String| Err(IsgcsError::Invalid(s));
        if n == 0 || m == 0 || inputs.len() % n != 0 || targets.len() != inputs.len() / n * m {
            return bad(format!(
                "rbf: {} input and {} target numbers do not fit n = {n}, m = {m}",
                inputs.len(),
                targets.len()
            ));
        }
        let count = inputs.len() / n;
        if centres < 2 || centres > count {
            return bad(format!(
                "rbf: {centres} centres need 2 to {count} (the number of samples)"
            ));
        }
        let knobs_ok = width_multiplier.is_finite()
            && width_multiplier > 0.0
            && ridge.is_finite()
            && ridge >= 0.0;
        if !knobs_ok || inputs.iter().chain(targets).any(|v| !v.is_finite()) {
            return bad("rbf: non-finite data, width multiplier <= 0 or ridge < 0".into());
        }
        // ⟨k-means centres, their widths, the output weights by least squares⟩
        let c = lloyd_centres(inputs, n, centres, kmeans_iterations, seed);
        let widths = centre_widths(&c, n, centres, width_multiplier);
        let mut net = Self {
            n,
            m,
            centres: c,
            widths,
            weights: vec![0.0; centres * m],
        };
        net.weights = net.least_squares_weights(inputs, targets, ridge)?;
        Ok(net)
    }

    /// The output weights (centres × m) by least squares on the rows `inputs` (N × n) and
    /// `targets` (N × m), with relative ridge `ridge` ([`crate::linalg::ridge_solve`]); the
    /// centres and widths are the network's.
    fn least_squares_weights(
        &self,
        inputs: &[f64],
        targets: &[f64],
        ridge: f64,
    ) -> Result<Vec<f64>, IsgcsError> {
        let (n, m, centres) = (self.n, self.m, self.widths.len());
        let mut gram = vec![0.0; centres * centres];
        let mut rhs = vec![0.0; centres * m];
        let mut act = Vec::new();
        for (x, y) in inputs.chunks_exact(n).zip(targets.chunks_exact(m)) {
            self.activations(x, &mut act);
            for &(i, a) in &act {
                for &(j, b) in &act {
                    if j <= i {
                        gram[i * centres + j] += a * b;
                    }
                }
                for k in 0..m {
                    rhs[i * m + k] += a * y[k];
                }
            }
        }
        crate::linalg::ridge_solve(&gram, centres, &mut rhs, m, ridge)
            .ok_or_else(|| IsgcsError::Invalid("rbf: no sample activates any centre".into()))?;
        Ok(rhs)
    }

    /// Number of centres.
    pub fn len(&self) -> usize {
        self.widths.len()
    }

    /// Always false (a fit has at least two centres).
    pub fn is_empty(&self) -> bool {
        self.widths.is_empty()
    }

    /// The Gaussians reaching x (|x − c_j| < 4 d_j, relative cut-off e⁻¹⁶) with their values.
    fn activations(&self, x: &[f64], out: &mut Vec<(usize, f64)>) {
        out.clear();
        for (j, &d) in self.widths.iter().enumerate() {
            let r2 = dist2(x, &self.centres[j * self.n..(j + 1) * self.n]);
            if d > 0.0 && r2 < 16.0 * d * d {
                out.push((j, (-r2 / (d * d)).exp()));
            }
        }
    }

    /// Ψ(x) into `out` (length m).
    pub fn predict(&self, x: &[f64], out: &mut [f64]) {
        let mut act = Vec::new();
        self.activations(x, &mut act);
        out.iter_mut().for_each(|o| *o = 0.0);
        for &(j, a) in &act {
            for (o, v) in out
                .iter_mut()
                .zip(&self.weights[j * self.m..(j + 1) * self.m])
            {
                *o += a * v;
            }
        }
    }
}

/// The reference of issue 19: a plain Gaussian RBF network on standardized inputs and outputs
/// with k-means centres (30 Lloyd iterations at most), widths μ × the mean distance to the
/// n + 1 nearest other centres, and ridge least-squares weights; μ ∈ {0.5, 0.7, 1, 1.4, 2, 2.8,
/// 4} and the relative ridge ∈ {10⁻¹², 10⁻¹⁰, …, 10⁰} chosen by the error on a random 20 %
/// holdout, then refitted on every row. It uses the same design-matrix and Gram code (and
/// threads) as [`crate::regressor::Regressor`], so fit times compare the methods, not their
/// code; its seven ridges per width are solved by blocked Cholesky factorisations (cheaper
/// than the regressor's one eigendecomposition per width for so few ridges).
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct KMeansRbf {
    readout: crate::readout::Readout,
}

impl KMeansRbf {
    /// Fits `centres` Gaussians to N rows (`inputs` N × n, `targets` N × m, row-major).
    pub fn fit(
        inputs: &[f64],
        targets: &[f64],
        n: usize,
        m: usize,
        centres: usize,
        seed: u64,
    ) -> Result<Self, RegressorError> {
        use crate::readout::{Basis, Readout, Standardizer, fit_holdout, nearest_widths};
        let rows = check_data(inputs, targets, n, m)?;
        if centres < 2 || centres > rows {
            return Err(RegressorError::InvalidParams(format!(
                "{centres} centres need 2 to {rows} (the number of rows)"
            )));
        }
        let xstd = Standardizer::of(inputs, n);
        let ystd = Standardizer::of(targets, m);
        let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x9e37_79b9);
        let mut order: Vec<usize> = (0..rows).collect();
        for i in (1..rows).rev() {
            let j = rng.random_range(0..=i);
            order.swap(i, j);
        }
        let permute = |data: &[f64], d: usize| -> Vec<f64> {
            order
                .iter()
                .flat_map(|&r| data[r * d..(r + 1) * d].iter().copied())
                .collect()
        };
        let xs = xstd.apply(&permute(inputs, n));
        let ys = ystd.apply(&permute(targets, m));
        let c = kmeans(&xs, n, centres, 30, seed);
        let basis = Basis {
            n,
            base: nearest_widths(&c, n, n + 1),
            centres: c,
            normalized: false,
            affine: false,
        };
        let yv = ndarray::ArrayView2::from_shape((rows, m), &ys).expect("shape checked");
        let mults = [0.5, 0.7, 1.0, 1.4, 2.0, 2.8, 4.0];
        let ridges: Vec<f64> = (0..7).map(|i| 10f64.powi(-12 + 2 * i)).collect();
        let (weights, chosen) = fit_holdout(&basis, &xs, yv, &mults, &ridges, 0.2)
            .ok_or_else(|| RegressorError::Solve("no row activates any centre".into()))?;
        Ok(Self {
            readout: Readout {
                basis,
                mult: chosen.mult,
                weights,
                m,
                x: xstd,
                y: ystd,
                ridge: chosen.ridge,
                transform: None,
            },
        })
    }

    /// Predictions for N inputs (N × n) into `out` (N × m), in parallel.
    pub fn predict(&self, inputs: &[f64], out: &mut [f64]) -> Result<(), RegressorError> {
        let (n, m) = (self.readout.basis.n, self.readout.m);
        if inputs.len() % n != 0 || out.len() != inputs.len() / n * m {
            return Err(RegressorError::Shape(format!(
                "predict: {} input numbers are not N × {n}, or {} outputs not N × {m}",
                inputs.len(),
                out.len()
            )));
        }
        self.readout.predict(inputs, out);
        Ok(())
    }

    /// The width multiplier and relative ridge the holdout chose.
    pub fn chosen(&self) -> (f64, f64) {
        (self.readout.mult, self.readout.ridge)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fits_a_smooth_function_and_rejects_bad_input() {
        let f = |x: f64, y: f64| (3.0 * x).sin() + y * y;
        let mut inputs = Vec::new();
        let mut targets = Vec::new();
        for i in 0..2000u64 {
            let (x, y) = (
                ((i as f64) * 0.754_877_666).fract(),
                ((i as f64) * 0.569_840_291).fract(),
            );
            inputs.extend([x, y]);
            targets.push(f(x, y));
        }
        let rbf = GaussianRbf::fit(&inputs, &targets, 2, 1, 60, 2.5, 20, 1e-9, 3).unwrap();
        let mut out = [0.0];
        let mut worst: f64 = 0.0;
        for i in 0..200 {
            let (x, y) = (
                0.1 + 0.8 * ((i as f64) * 0.31).fract(),
                0.1 + 0.8 * ((i as f64) * 0.77).fract(),
            );
            rbf.predict(&[x, y], &mut out);
            worst = worst.max((out[0] - f(x, y)).abs());
        }
        assert!(worst < 0.02, "max error {worst}");
        assert!(GaussianRbf::fit(&inputs, &targets, 2, 1, 1, 1.0, 20, 1e-9, 3).is_err());
        assert!(GaussianRbf::fit(&inputs, &targets[1..], 2, 1, 60, 1.0, 20, 1e-9, 3).is_err());
        assert!(GaussianRbf::fit(&inputs, &targets, 2, 1, 60, -1.0, 20, 1e-9, 3).is_err());
    }
}
