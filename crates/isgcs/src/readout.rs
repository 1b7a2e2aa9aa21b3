//! The least-squares output layer of a Gaussian network with fixed centres, chosen by
//! exact leave-one-out (the default regressor) or on a holdout (the k-means RBF
//! reference), on standardized inputs and outputs.

use crate::linalg::{
    RidgePath, Scratch, gcv, gram, gram_add, mul_few, rademacher, ridge_fit, ridge_weights,
};
use ndarray::{Array2, ArrayView2, Axis, Slice};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::borrow::Cow;

/// Rows per block when the design matrix is accumulated into the Gram matrix.
const ROW_BLOCK: usize = 2048;

/// Per-feature affine map to zero mean and unit standard deviation (features without spread
/// keep scale 1).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub(crate) struct Standardizer {
    pub mean: Vec<f64>,
    pub scale: Vec<f64>,
}

impl Standardizer {
    /// From N rows of width `d` (row-major).
    pub fn of(data: &[f64], d: usize) -> Self {
        let rows = (data.len() / d).max(1) as f64;
        let mut mean = vec![0.0; d];
        for r in data.chunks_exact(d) {
            for (m, v) in mean.iter_mut().zip(r) {
                *m += v;
            }
        }
        mean.iter_mut().for_each(|m| *m /= rows);
        let mut var = vec![0.0; d];
        for r in data.chunks_exact(d) {
            for ((s, v), m) in var.iter_mut().zip(r).zip(&mean) {
                *s += (v - m) * (v - m);
            }
        }
        let scale = var
            .into_iter()
            .map(|s| {
                let sd = (s / rows).sqrt();
                if sd > 1e-300 && sd.is_finite() {
                    sd
                } else {
                    1.0
                }
            })
            .collect();
        Self { mean, scale }
    }

    /// The standardized copy of N rows.
    pub fn apply(&self, data: &[f64]) -> Vec<f64> {
        let d = self.mean.len();
        let mut out = data.to_vec();
        for r in out.chunks_exact_mut(d) {
            for ((v, m), s) in r.iter_mut().zip(&self.mean).zip(&self.scale) {
                *v = (*v - m) / s;
            }
        }
        out
    }
}

/// Basis values exp(−t) with t beyond this are 0 (see [`Basis::row`]).
const FLUSH: f64 = 300.0;

/// exp(−r²/w²), 0 when w = 0 or r²/w² > [`FLUSH`].
fn gaussian(r2: f64, w2: f64) -> f64 {
    if w2 > 0.0 && r2 <= FLUSH * w2 {
        (-r2 / w2).exp()
    } else {
        0.0
    }
}

/// Gaussians Ω_i(x) = exp(−|x − c_i|²/(μ d_i)²) on fixed centres with base widths d_i and a
/// width multiplier μ (not cut off); normalized (divided
/// by their sum) or plain, optionally followed by the affine columns 1, x₁ … xₙ.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub(crate) struct Basis {
    pub n: usize,
    /// z × n, standardized coordinates.
    pub centres: Vec<f64>,
    /// d_i, before the multiplier.
    pub base: Vec<f64>,
    pub normalized: bool,
    pub affine: bool,
}

impl Basis {
    pub fn cells(&self) -> usize {
        self.base.len()
    }

    pub fn cols(&self) -> usize {
        self.cells() + if self.affine { self.n + 1 } else { 0 }
    }

    /// The basis values at x (standardized) into `out` (length `cols`).
    pub fn row(&self, mult: f64, x: &[f64], out: &mut [f64]) {
        let z = self.cells();
        let mut sum = 0.0;
        let (mut nearest, mut nearest_d2) = (0, f64::INFINITY);
        for i in 0..z {
            let c = &self.centres[i * self.n..(i + 1) * self.n];
            let r2: f64 = c.iter().zip(x).map(|(a, b)| (a - b) * (a - b)).sum();
            if r2 < nearest_d2 {
                (nearest, nearest_d2) = (i, r2);
            }
            let w = mult * self.base[i];
            let w2 = w * w;
            // No visible cut-off: with small ridges the weights can be large, and a cut-off's
            // jump (e⁻¹⁶ × weight) would show. Values below e^−FLUSH (~10⁻¹³⁰) are set to 0:
            // exp's subnormal results (beyond ~26.6 widths) and products of tiny values
            // landing in the subnormal range made the design and Gram matrices several times
            // slower in 2-D, where most cells are far from most rows.
            out[i] = gaussian(r2, w2);
            sum += out[i];
        }
        self.finish(out, x, nearest, sum);
    }

    /// Completes a row of raw Gaussians (the first `cells` entries of `row`, length `cols`)
    /// at the input x into the basis values of [`Basis::row`]: normalized by their sum (a row
    /// without any positive value gets its `nearest` cell) and the affine columns.
    pub fn finish_row(&self, row: &mut [f64], x: &[f64], nearest: usize) {
        let z = self.cells();
        let sum = if self.normalized {
            row[..z].iter().sum()
        } else {
            0.0
        };
        self.finish(row, x, nearest, sum);
    }

    /// The end of [`Basis::row`] and [`Basis::finish_row`]: the raw Gaussians (summing to `sum`)
    /// normalized, or the `nearest` cell where none is positive, and the affine columns.
    fn finish(&self, row: &mut [f64], x: &[f64], nearest: usize, sum: f64) {
        let z = self.cells();
        if self.normalized {
            if sum > 0.0 {
                row[..z].iter_mut().for_each(|v| *v /= sum);
            } else if z > 0 {
                row[nearest] = 1.0;
            }
        }
        if self.affine {
            row[z] = 1.0;
            row[z + 1..z + 1 + self.n].copy_from_slice(x);
        }
    }

    /// The raw Gaussians exp(−|x − c_i|²/(μ d_i)²) of `rows` standardized inputs (rows ×
    /// cells, flushed to 0 below e^−FLUSH as in [`Basis::row`]; neither normalized nor with
    /// the affine columns), rows in parallel. [`Basis::design_of_raw`] makes the design matrix.
    pub fn raw(&self, mult: f64, xs: &[f64]) -> Array2<f64> {
        let (n, z) = (self.n, self.cells());
        let rows = xs.len() / n;
        let w2: Vec<f64> = self.base.iter().map(|b| (mult * b) * (mult * b)).collect();
        let mut a = Array2::zeros((rows, z));
        a.as_slice_mut()
            .expect("fresh arrays are contiguous")
            .par_chunks_mut(z.max(1))
            .zip(xs.par_chunks(n))
            .with_min_len(16)
            .for_each(|(o, x)| {
                for (i, (o, &w2)) in o.iter_mut().zip(&w2).enumerate() {
                    let c = &self.centres[i * n..(i + 1) * n];
                    let r2: f64 = c.iter().zip(x).map(|(a, b)| (a - b) * (a - b)).sum();
                    *o = gaussian(r2, w2);
                }
            });
        a
    }

    /// The design matrix of the rows `xs` from their raw values ([`Basis::raw`]): the same
    /// numbers as [`Basis::design`] for raw values at the same multiplier (normalized by the
    /// row sum in the same order; a row without any positive value gets its nearest cell).
    /// Borrowed when there is nothing to do (plain Gaussians without affine columns).
    pub fn design_of_raw<'a>(&self, raw: &'a Array2<f64>, xs: &[f64]) -> Cow<'a, Array2<f64>> {
        if !self.normalized && !self.affine {
            return Cow::Borrowed(raw);
        }
        let mut a = Array2::zeros((raw.nrows(), self.cols()));
        self.design_of_raw_into(raw, xs, &mut a);
        Cow::Owned(a)
    }

    /// [`Basis::design_of_raw`] into `a` (rows × cols, every entry overwritten), a design
    /// matrix kept from an earlier width or candidate ([`Scratch`]).
    pub fn design_of_raw_into(&self, raw: &Array2<f64>, xs: &[f64], a: &mut Array2<f64>) {
        let (n, z, cols) = (self.n, self.cells(), self.cols());
        a.as_slice_mut()
            .expect("fresh arrays are contiguous")
            .par_chunks_mut(cols)
            .zip(
                raw.as_slice()
                    .expect("raw values are contiguous")
                    .par_chunks(z.max(1)),
            )
            .zip(xs.par_chunks(n))
            .with_min_len(16)
            .for_each(|((o, r), x)| {
                let out = &mut o[..z];
                out.iter_mut().zip(r.iter()).for_each(|(o, v)| *o = *v);
                if self.normalized {
                    let sum: f64 = out.iter().sum();
                    if sum > 0.0 {
                        out.iter_mut().for_each(|v| *v /= sum);
                    } else if z > 0 {
                        out[self.nearest(x)] = 1.0;
                    }
                }
                if self.affine {
                    o[z] = 1.0;
                    o[z + 1..z + 1 + n].copy_from_slice(x);
                }
            });
    }

    /// The index of the centre nearest to x (the first of equally near ones; 0 without
    /// centres).
    pub fn nearest(&self, x: &[f64]) -> usize {
        let (mut nearest, mut nearest_d2) = (0, f64::INFINITY);
        for (i, c) in self.centres.chunks_exact(self.n).enumerate() {
            let r2: f64 = c.iter().zip(x).map(|(a, b)| (a - b) * (a - b)).sum();
            if r2 < nearest_d2 {
                (nearest, nearest_d2) = (i, r2);
            }
        }
        nearest
    }

    /// The design matrix of `rows` standardized inputs (rows × cols), rows in parallel.
    pub fn design(&self, mult: f64, xs: &[f64]) -> Array2<f64> {
        let cols = self.cols();
        let rows = xs.len() / self.n;
        let mut a = Array2::zeros((rows, cols));
        a.as_slice_mut()
            .expect("fresh arrays are contiguous")
            .par_chunks_mut(cols)
            .zip(xs.par_chunks(self.n))
            .with_min_len(16)
            .for_each(|(o, x)| self.row(mult, x, o));
        a
    }

    /// G = AᵀA, B = AᵀY and Σ y² over the rows (xs N × n, ys N × m), and the blocks of the
    /// design matrix A when `keep` (for exact residuals).
    pub fn normal_equations(
        &self,
        mult: f64,
        xs: &[f64],
        ys: ArrayView2<'_, f64>,
        keep: bool,
    ) -> (Array2<f64>, Array2<f64>, f64, Vec<Array2<f64>>) {
        let cols = self.cols();
        let m = ys.ncols();
        // The first block's Gram is written, not added, into fresh memory (adding reads the
        // zeroed pages first, and the write then faults again to copy them).
        let mut g: Option<Array2<f64>> = None;
        let mut b = Array2::zeros((cols, m));
        let rows = ys.nrows();
        let mut blocks = Vec::new();
        let mut start = 0;
        while start < rows {
            let end = (start + ROW_BLOCK).min(rows);
            let a = self.design(mult, &xs[start * self.n..end * self.n]);
            match g.as_mut() {
                Some(g) => gram_add(a.view(), g),
                None => g = Some(gram(a.view())),
            }
            ndarray::linalg::general_mat_mul(
                1.0,
                &a.t(),
                &ys.slice_axis(Axis(0), Slice::from(start..end)),
                1.0,
                &mut b,
            );
            if keep {
                blocks.push(a);
            }
            start = end;
        }
        let yy = ys.iter().map(|v| v * v).sum();
        let g = g.unwrap_or_else(|| Array2::zeros((cols, cols)));
        (g, b, yy, blocks)
    }
}

/// Σ |y − A W|² over the row blocks of A.
fn residual(blocks: &[ArrayView2<'_, f64>], w: &Array2<f64>, ys: ArrayView2<'_, f64>) -> f64 {
    let mut start = 0;
    let mut sum = 0.0;
    for a in blocks {
        let end = start + a.nrows();
        let pred = mul_few(a.view(), w.view());
        let y = ys.slice_axis(Axis(0), Slice::from(start..end));
        sum += pred
            .iter()
            .zip(y.iter())
            .map(|(p, t)| (p - t) * (p - t))
            .sum::<f64>();
        start = end;
    }
    sum
}

/// A fitted output layer: basis, multiplier, weights, and the standardization of inputs and
/// outputs.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub(crate) struct Readout {
    pub basis: Basis,
    pub mult: f64,
    /// cols × m, in standardized output units.
    pub weights: Vec<f64>,
    pub m: usize,
    pub x: Standardizer,
    pub y: Standardizer,
    /// The relative ridge used.
    pub ridge: f64,
    /// The learned input metric T (n × n row-major): the basis sees T·x of the standardized
    /// input x. `None`: the identity.
    #[serde(default)]
    pub transform: Option<Vec<f64>>,
}

impl Readout {
    /// The basis's view of raw input `x` in `xs` (standardized, then through the learned metric;
    /// `ts` scratch of the same length n); false when `x` is not finite (its prediction is NaN).
    fn basis_input(&self, x: &[f64], xs: &mut [f64], ts: &mut [f64]) -> bool {
        if x.iter().any(|v| !v.is_finite()) {
            return false;
        }
        let n = xs.len();
        for a in 0..n {
            xs[a] = (x[a] - self.x.mean[a]) / self.x.scale[a];
        }
        if let Some(t) = &self.transform {
            for (a, ta) in ts.iter_mut().enumerate() {
                *ta = (0..n).map(|b| t[a * n + b] * xs[b]).sum();
            }
            xs.copy_from_slice(ts);
        }
        true
    }

    /// Predictions for N raw inputs (N × n) into `out` (N × m), rows in parallel.
    pub fn predict(&self, inputs: &[f64], out: &mut [f64]) {
        let (n, m, cols) = (self.basis.n, self.m, self.basis.cols());
        out.par_chunks_mut(m)
            .zip(inputs.par_chunks(n))
            .with_min_len(32)
            .for_each_init(
                || (vec![0.0; n], vec![0.0; n], vec![0.0; cols]),
                |(xs, ts, row), (o, x)| {
                    if !self.basis_input(x, xs, ts) {
                        o.fill(f64::NAN);
                        return;
                    }
                    self.basis.row(self.mult, xs, row);
                    for c in 0..m {
                        let mut s = 0.0;
                        for (j, r) in row.iter().enumerate() {
                            if *r != 0.0 {
                                s += r * self.weights[j * m + c];
                            }
                        }
                        o[c] = self.y.mean[c] + self.y.scale[c] * s;
                    }
                },
            );
    }
}

impl Readout {
    /// The blend (1 − `share`)·self + `share`·other of two layers' predictions for N raw
    /// inputs into `out` (N × m). When both layers have the same centres, base widths and
    /// metric and their multipliers differ by a power of √2 (the walks' grid; at most four
    /// steps), each row's distances are computed once and the wider layer's Gaussians are the
    /// narrower one's moved up by square roots, as along the width walk ([`move_raw`]: an
    /// entry flushed at the narrower width is computed afresh); otherwise the two layers
    /// predict separately.
    pub fn predict_blend(&self, other: &Readout, share: f64, inputs: &[f64], out: &mut [f64]) {
        let steps = 2.0 * (other.mult / self.mult).log2();
        let k = steps.round();
        let shared = self.basis.centres == other.basis.centres
            && self.basis.base == other.basis.base
            && self.transform == other.transform
            && self.basis.n == other.basis.n
            && self.m == other.m
            && (steps - k).abs() < 1e-9
            && k.abs() <= 4.0;
        if !shared {
            self.predict(inputs, out);
            let mut second = vec![0.0; out.len()];
            other.predict(inputs, &mut second);
            for (o, s) in out.iter_mut().zip(&second) {
                *o = (1.0 - share) * *o + share * s;
            }
            return;
        }
        // The narrower layer first: its values are moved up to the wider one's.
        let (lo, hi, lo_share) = if k >= 0.0 {
            (self, other, 1.0 - share)
        } else {
            (other, self, share)
        };
        let k = k.abs() as usize;
        let (n, m, z) = (self.basis.n, self.m, self.basis.cells());
        let w2 = |r: &Readout| -> Vec<f64> {
            r.basis
                .base
                .iter()
                .map(|b| (r.mult * b) * (r.mult * b))
                .collect()
        };
        let (w2_lo, w2_hi) = (w2(lo), w2(hi));
        out.par_chunks_mut(m)
            .zip(inputs.par_chunks(n))
            .with_min_len(32)
            .for_each_init(
                || {
                    let cols = self.basis.cols();
                    (vec![0.0; n], vec![0.0; n], vec![0.0; cols], vec![0.0; cols])
                },
                |(xs, ts, r_lo, r_hi), (o, x)| {
                    if !self.basis_input(x, xs, ts) {
                        o.fill(f64::NAN);
                        return;
                    }
                    let (mut nearest, mut nearest_d2) = (0, f64::INFINITY);
                    for i in 0..z {
                        let c = &self.basis.centres[i * n..(i + 1) * n];
                        let r2: f64 = c
                            .iter()
                            .zip(xs.iter())
                            .map(|(a, b)| (a - b) * (a - b))
                            .sum();
                        if r2 < nearest_d2 {
                            (nearest, nearest_d2) = (i, r2);
                        }
                        let v = gaussian(r2, w2_lo[i]);
                        r_lo[i] = v;
                        r_hi[i] = if v > 0.0 {
                            (0..k).fold(v, |v, _| v.sqrt())
                        } else {
                            gaussian(r2, w2_hi[i])
                        };
                    }
                    lo.basis.finish_row(r_lo, xs, nearest);
                    hi.basis.finish_row(r_hi, xs, nearest);
                    let value = |r: &Readout, row: &[f64], c: usize| -> f64 {
                        let mut s = 0.0;
                        for (j, v) in row.iter().enumerate() {
                            if *v != 0.0 {
                                s += v * r.weights[j * m + c];
                            }
                        }
                        s
                    };
                    for c in 0..m {
                        let f_lo = self.y.mean[c] + self.y.scale[c] * value(lo, r_lo, c);
                        let f_hi = self.y.mean[c] + self.y.scale[c] * value(hi, r_hi, c);
                        o[c] = lo_share * f_lo + (1.0 - lo_share) * f_hi;
                    }
                },
            );
    }
}

/// What a selection measured.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Selected {
    pub mult: f64,
    pub ridge: f64,
    /// Effective degrees of freedom tr H of the final fit.
    pub dof: f64,
    /// The selection score (holdout or leave-one-out estimate of the mean squared error per
    /// row, in standardized units) of the chosen multiplier and ridge.
    pub score: f64,
}

/// One multiplier's output layer on the given rows: the weights, the relative ridge, tr H and
/// the selection score. Without a given ridge, the ridge minimises the exact leave-one-out
/// error of the first `loo_rows` rows (a random sample: the rows are shuffled) on the full
/// fit, all ridges from one eigendecomposition ([`RidgePath`]); the score is that error.
/// With a given ridge, one Cholesky solve, scored by GCV.
fn gcv_at(
    basis: &Basis,
    mult: f64,
    ridge: Option<f64>,
    xs: &[f64],
    ys: ArrayView2<'_, f64>,
    loo_rows: usize,
) -> Option<(f64, Array2<f64>, f64, f64)> {
    let (g, b, yy, blocks) = basis.normal_equations(mult, xs, ys, true);
    let views: Vec<_> = blocks.iter().map(|a| a.view()).collect();
    gcv_of(&g, &b, yy, &views, ys, ridge, loo_rows)
}

/// [`gcv_at`] from the normal equations G, B, Σ y² and the row blocks of the design matrix.
fn gcv_of(
    g: &Array2<f64>,
    b: &Array2<f64>,
    yy: f64,
    blocks: &[ArrayView2<'_, f64>],
    ys: ArrayView2<'_, f64>,
    ridge: Option<f64>,
    loo_rows: usize,
) -> Option<(f64, Array2<f64>, f64, f64)> {
    let rows = ys.nrows();
    if let Some(r) = ridge {
        let probes = rademacher(g.nrows(), 24, 0x5eed);
        let mut fit = ridge_fit(g, b, yy, r, &probes)?;
        // The closed form yy − 2⟨W, B⟩ + ⟨W, GW⟩ cancels badly for small ridges.
        fit.rss = residual(blocks, &fit.weights, ys);
        return Some((gcv(rows, &fit), fit.weights, fit.relative, fit.dof));
    }
    let loo_rows = loo_rows.clamp(1, rows);
    let path = if blocks.first().is_some_and(|a| a.nrows() >= loo_rows) {
        // The leave-one-out rows are all in the first block: no copy.
        RidgePath::new(
            g,
            b,
            blocks[0].slice_axis(Axis(0), Slice::from(..loo_rows)),
            ys.slice_axis(Axis(0), Slice::from(..loo_rows)),
        )?
    } else {
        let mut parts = Vec::new();
        let mut left = loo_rows;
        for a in blocks {
            if left == 0 {
                break;
            }
            let take = left.min(a.nrows());
            parts.push(a.slice_axis(Axis(0), Slice::from(..take)));
            left -= take;
        }
        let a_loo = ndarray::concatenate(Axis(0), &parts).ok()?;
        RidgePath::new(
            g,
            b,
            a_loo.view(),
            ys.slice_axis(Axis(0), Slice::from(..loo_rows)),
        )?
    };
    let (relative, score, dof) = path.best_ridge()?;
    Some((score, path.weights(relative), relative, dof))
}

/// [`gcv_at`] on all rows `xs` from their raw Gaussians at `mult` ([`Basis::raw`]).
fn gcv_of_raw(
    basis: &Basis,
    raw: &Array2<f64>,
    xs: &[f64],
    ys: ArrayView2<'_, f64>,
    ridge: Option<f64>,
    loo_rows: usize,
) -> Option<(f64, Array2<f64>, f64, f64)> {
    let a = basis.design_of_raw(raw, xs);
    let (g, b, yy) = normal_from(a.view(), ys);
    gcv_of(&g, &b, yy, &[a.view()], ys, ridge, loo_rows)
}

/// The output layer at a fixed multiplier and relative ridge on the rows `xs` (N × n,
/// standardized) with targets `ys`: the weights (cols × m) and the fitted values (N × m) from
/// the same design matrix (one Cholesky solve; `None` when it fails). The growth rounds'
/// residuals: predicting the rows again would compute every basis value twice.
pub(crate) fn fit_fixed(
    basis: &Basis,
    mult: f64,
    ridge: f64,
    xs: &[f64],
    ys: ArrayView2<'_, f64>,
) -> Option<(Array2<f64>, Array2<f64>)> {
    let (g, b, yy, blocks) = basis.normal_equations(mult, xs, ys, true);
    let zero = Array2::zeros((basis.cols(), 0));
    let fit = ridge_fit(&g, &b, yy, ridge, &zero)?;
    let parts: Vec<Array2<f64>> = blocks
        .iter()
        .map(|a| mul_few(a.view(), fit.weights.view()))
        .collect();
    let views: Vec<_> = parts.iter().map(|p| p.view()).collect();
    let fitted = ndarray::concatenate(Axis(0), &views).ok()?;
    Some((fit.weights, fitted))
}

/// Chooses the width multiplier (unless given: a geometric walk by √2 from `start`, on at
/// most `select_rows` rows) and the relative ridge (unless given) by leave-one-out, then
/// refits on every row. `xs`/`ys` are standardized and in random row order; returns the
/// weights (cols × m) and what was chosen.
pub(crate) fn fit_gcv(
    basis: &Basis,
    xs: &[f64],
    ys: ArrayView2<'_, f64>,
    mult: Option<f64>,
    ridge: Option<f64>,
    select_rows: usize,
    start: f64,
) -> Option<(Vec<f64>, Selected)> {
    fit_best(&[(basis, xs)], ys, mult, ridge, select_rows, start).map(|(_, w, s, _)| (w, s))
}

/// [`fit_gcv`] for several candidate bases, each with its own copy of the rows (`xs` in
/// that basis' coordinates; the targets are shared), on the first `select_rows` rows: every
/// candidate is scored at `start` (in parallel), the [`RACE_KEEP`] best walk their
/// multiplier from there (in parallel), and the one with the lowest score (the lowest index
/// on ties) is refitted on every row. The score is the error on the rows after the selection
/// rows ([`fit_best_holdout`]) when there are enough of them, else the leave-one-out error on
/// the selection rows (`gcv_at`: [`lone_walk`], [`loo_race`], [`loo_refit`]). Returns the
/// winner's index in `candidates`, weights and choice, and with the holdout score the second
/// walked candidate and its share α when the blend (1 − α)·winner + α·second
/// ([`blend_share`]) has the lower holdout error (its score is then the blend's).
pub(crate) fn fit_best(
    candidates: &[(&Basis, &[f64])],
    ys: ArrayView2<'_, f64>,
    mult: Option<f64>,
    ridge: Option<f64>,
    select_rows: usize,
    start: f64,
) -> Option<Choice> {
    let rows = ys.nrows();
    let sel = select_rows.min(rows).max(1);
    let sy = ys.slice_axis(Axis(0), Slice::from(..sel));
    // With enough rows beyond the selection rows, the score is the error on (up to
    // 2 × `sel` of) them instead of the leave-one-out error on the selection rows.
    let hold = (rows - sel).min(2 * sel);
    // (A fifth of the rows or more also counts: `selection_rows` holds that out when rows are
    // few per column.)
    let use_holdout =
        ridge.is_none() && (2 * hold >= sel || 5 * hold >= rows) && hold >= HOLDOUT_MIN;
    if use_holdout {
        return fit_best_holdout(candidates, ys, mult, sel, hold, start);
    }
    // ⟨The leave-one-out selection on the first `sel` rows: the walks, the best of them
    // refitted on every row⟩
    let first = mult.unwrap_or_else(|| start.clamp(MULT_RANGE.0, MULT_RANGE.1));
    let walks: Vec<(usize, (f64, Scored))> = if candidates.len() == 1 && mult.is_none() {
        let (basis, xs) = candidates[0];
        vec![(0, lone_walk(basis, &xs[..sel * basis.n], sy, ridge, first)?)]
    } else {
        loo_race(candidates, sy, mult, ridge, first)
    };
    let (index, (mult, fit)) = walks
        .into_iter()
        .min_by(|a, b| a.1.1.0.total_cmp(&b.1.1.0).then(a.0.cmp(&b.0)))?;
    let (basis, xs) = candidates[index];
    let (score, weights, relative, dof) = loo_refit(basis, mult, xs, ys, ridge, sel, fit)?;
    let (index, weights, chosen) = picked(index, weights, mult, relative, dof, score);
    Some((index, weights, chosen, None))
}

/// The width walk of a lone candidate scored by leave-one-out ([`fit_best`]: the metric
/// pilots; no ridge hint, every score depends on its multiplier only), `basis` on the
/// selection rows `xs` with targets `sy`, from the multiplier `first`: speculative, the next
/// two multipliers at once on the two threads (at the start up and down), the results taken
/// in the order of the walk, so the choice is the one-by-one walk's. Its raw Gaussians are
/// computed once, at the first multiplier, and moved along the walk ([`move_raw`]) as in the
/// holdout walk. Returns the multiplier and fit where the walk stops; `None` without a fit at
/// `first`.
fn lone_walk(
    basis: &Basis,
    xs: &[f64],
    sy: ArrayView2<'_, f64>,
    ridge: Option<f64>,
    first: f64,
) -> Option<(f64, Scored)> {
    let sel = sy.nrows();
    let step = std::f64::consts::SQRT_2;
    let in_range = |m: f64| (MULT_RANGE.0..=MULT_RANGE.1).contains(&m);
    type At = (f64, Scored, Array2<f64>);
    // The fit at `at`'s multiplier · √2^steps, from `at`'s raw values.
    let try_at = |at: &At, steps: i32| -> Option<At> {
        let m = at.0 * step.powi(steps);
        if !in_range(m) {
            return None;
        }
        let mut raw = at.2.clone();
        move_raw(&mut raw, steps, basis, m, xs);
        let fit = gcv_of_raw(basis, &raw, xs, sy, ridge, sel)?;
        Some((m, fit, raw))
    };
    let better = |f: &Option<At>, at: &At| f.as_ref().is_some_and(|f| f.1.0 < at.1.0);
    let raw = basis.raw(first, xs);
    let mut at = match gcv_of_raw(basis, &raw, xs, sy, ridge, sel) {
        Some(fit) => (first, fit, raw),
        None => return None,
    };
    let (up, down) = rayon::join(|| try_at(&at, 1), || try_at(&at, -1));
    let dir = if better(&up, &at) {
        at = up.expect("better implies some");
        Some(1)
    } else if better(&down, &at) {
        at = down.expect("better implies some");
        Some(-1)
    } else {
        None
    };
    if let Some(dir) = dir {
        loop {
            let (fa, fb) = rayon::join(|| try_at(&at, dir), || try_at(&at, 2 * dir));
            if !better(&fa, &at) {
                break;
            }
            at = fa.expect("better implies some");
            if !better(&fb, &at) {
                break;
            }
            at = fb.expect("better implies some");
        }
    }
    Some((at.0, at.1))
}

/// The leave-one-out race of [`fit_best`] on the selection rows (targets `sy`): every
/// candidate scored at the multiplier `first` (in parallel), then the walk (module docs of
/// `regressor`; none with a given `mult`) only from the [`RACE_KEEP`] best of them (one with
/// a given `mult`), in parallel: a candidate that starts behind the leaders rarely overtakes
/// both of them. Each walked candidate's index, multiplier and fit.
fn loo_race(
    candidates: &[(&Basis, &[f64])],
    sy: ArrayView2<'_, f64>,
    mult: Option<f64>,
    ridge: Option<f64>,
    first: f64,
) -> Vec<(usize, (f64, Scored))> {
    let sel = sy.nrows();
    let eval = |&(basis, xs): &(&Basis, &[f64]), mult: f64| {
        gcv_at(basis, mult, ridge, &xs[..sel * basis.n], sy, sel).map(|fit| (mult, fit))
    };
    // Every candidate at the first multiplier (in parallel) …
    let mut starts: Vec<Option<(f64, Scored)>> =
        candidates.par_iter().map(|c| eval(c, first)).collect();
    // … then the walk only from the RACE_KEEP best of them.
    let keep = if mult.is_some() { 1 } else { RACE_KEEP };
    let order = leaders(
        candidates.len(),
        |i| starts[i].as_ref().map(|s| s.1.0),
        keep,
    );
    let seeds: Vec<(usize, (f64, Scored))> = order
        .iter()
        .filter_map(|&i| starts[i].take().map(|s| (i, s)))
        .collect();
    let walk = |(i, at): (usize, (f64, Scored))| -> (usize, (f64, Scored)) {
        if mult.is_some() {
            return (i, at);
        }
        let c = &candidates[i];
        let at = walk_width(
            at,
            |f: &Scored| f.0,
            |m, _: &Scored| eval(c, m).map(|(_, fit)| fit),
        );
        (i, at)
    };
    seeds.into_par_iter().map(walk).collect()
}

/// The leave-one-out selection's winner, `basis` at the multiplier `mult` with its `fit` on
/// the first `sel` rows, refitted on every row `xs` (targets `ys`) unless the selection rows
/// were all rows. Without a given `ridge`: the same absolute ridge ρ on every row (the
/// relative ridge is ρ over the mean diagonal of G, which grows with the rows; floored at
/// [`RIDGE_FLOOR`] as in the selection), one Cholesky solve, the ridge raised while it fails
/// ([`refit_all`]); the eigendecomposition's ridge path only if no relative ridge up to 1
/// factorises. The score stays the selection's.
fn loo_refit(
    basis: &Basis,
    mult: f64,
    xs: &[f64],
    ys: ArrayView2<'_, f64>,
    ridge: Option<f64>,
    sel: usize,
    fit: Scored,
) -> Option<Scored> {
    let rows = ys.nrows();
    if sel == rows {
        return Some(fit);
    }
    if ridge.is_some() {
        return gcv_at(basis, mult, ridge, xs, ys, sel);
    }
    let r = (fit.2 * sel as f64 / rows as f64).max(RIDGE_FLOOR);
    match refit_all(basis, mult, xs, ys, r, 1.0) {
        Some((w, relative, dof)) => Some((fit.0, w, relative, dof)),
        None => gcv_at(basis, mult, ridge, xs, ys, sel),
    }
}

/// A refitted candidate's [`Picked`] from its weights (cols × m) and choice.
fn picked(
    index: usize,
    weights: Array2<f64>,
    mult: f64,
    ridge: f64,
    dof: f64,
    score: f64,
) -> Picked {
    let weights = weights.into_raw_vec_and_offset().0;
    let chosen = Selected {
        mult,
        ridge,
        dof,
        score,
    };
    (index, weights, chosen)
}

/// The refit of [`fit_best`] on every row: the relative ridge `start`, raised by half
/// decades while the Cholesky factorisation fails (a ridge below the rounding level of G),
/// up to `max`. Returns the weights, the relative ridge used and tr H (estimated).
fn refit_all(
    basis: &Basis,
    mult: f64,
    xs: &[f64],
    ys: ArrayView2<'_, f64>,
    start: f64,
    max: f64,
) -> Option<(Array2<f64>, f64, f64)> {
    let (g, b, yy, _) = basis.normal_equations(mult, xs, ys, false);
    refit_solve(&g, &b, yy, start, max)
}

/// [`refit_all`] on given normal equations G W = B (Σ y² = `yy`).
fn refit_solve(
    g: &Array2<f64>,
    b: &Array2<f64>,
    yy: f64,
    start: f64,
    max: f64,
) -> Option<(Array2<f64>, f64, f64)> {
    let probes = rademacher(g.nrows(), 24, 0x5eed);
    let mut r = start;
    loop {
        if let Some(fit) = ridge_fit(g, b, yy, r, &probes) {
            return Some((fit.weights, fit.relative, fit.dof));
        }
        if r >= max {
            return None;
        }
        r = (r.max(f64::EPSILON) * 10f64.powf(0.25)).min(max);
    }
}

/// Fewest rows beyond the selection rows for the holdout score of [`fit_best`].
const HOLDOUT_MIN: usize = 200;

/// The selection rows S of the regressor's output layer (module docs of `regressor`, step
/// 4) for N = `rows` rows and `cols` columns: S = max(3·cols, 1500) when at least a fifth of
/// the rows is left over for the holdout, else S = N − ⌈N/5⌉ (a fifth of the rows held out,
/// as the k-means RBF does). [`fit_best`] scores on a holdout whenever it has at least
/// [`HOLDOUT_MIN`] rows; with fewer (N < 1000) it falls back to the exact leave-one-out
/// error, whose eigendecomposition per width costs O(cols³) (measured: docs/design/isgcs.md,
/// "Tried and not kept").
pub(crate) fn selection_rows(rows: usize, cols: usize) -> usize {
    let wanted = (3 * cols).max(1500);
    if 4 * rows >= 5 * wanted {
        wanted
    } else {
        rows - rows.div_ceil(5)
    }
}

/// [`holdout_solve`] on the rows `fit` and `hold` (inputs, targets) at the multiplier `mult`,
/// from their design matrices: the tests' reference (the selection scores the holdout rows
/// from their raw values, [`HoldoutRows::score`]).
#[cfg(test)]
fn holdout_at(
    basis: &Basis,
    mult: f64,
    fit: (&[f64], ArrayView2<'_, f64>),
    hold: (&[f64], ArrayView2<'_, f64>),
    hint: Option<f64>,
) -> Option<(f64, Array2<f64>, f64, f64)> {
    let a_fit = basis.design(mult, fit.0);
    let a_hold = basis.design(mult, hold.0);
    holdout_solve(
        a_fit.view(),
        fit.1,
        Holdout::Design(a_hold.view()),
        hold.1,
        hint,
        &Scratch::default(),
    )
    .map(|(f, _)| f)
}

/// A refitted candidate: its index, weights (cols × m) and what was chosen.
pub(crate) type Picked = (usize, Vec<f64>, Selected);
/// [`fit_best`]'s choice: the winner and, when blended, the second candidate with its share.
pub(crate) type Choice = (usize, Vec<f64>, Selected, Option<(Picked, f64)>);

/// G = AᵀA and B = AᵀY of the fitted rows.
type Normal = (Array2<f64>, Array2<f64>);
/// A selection's score, weights (cols × m), relative ridge and tr H.
type Scored = (f64, Array2<f64>, f64, f64);

/// One multiplier's output layer fitted on the rows of the design matrix `a_fit` (targets
/// `y_fit`) and scored by the mean squared error per row on the holdout rows `a` (targets
/// `y_hold`): the weights, the relative ridge (ε…1, [`holdout_floor`], the one with the lowest
/// holdout error) and tr H (NaN: not computed); also the fitted rows' G and B (the refit adds
/// the other rows to them). Each ridge is one Cholesky solve (skipped when the factorisation
/// fails). Without a `hint`, the ridges 1, 10⁻², … down to ε, then the best one's neighbours
/// at ±1 decade; with a `hint` (the ridge chosen at a neighbouring multiplier), the hint and
/// ±2 decades (upwards by half decades while every factorisation failed); then half decades
/// around the best until both its neighbours are tried.
fn holdout_solve(
    a_fit: ArrayView2<'_, f64>,
    y_fit: ArrayView2<'_, f64>,
    a: Holdout<'_>,
    y_hold: ArrayView2<'_, f64>,
    hint: Option<f64>,
    scratch: &Scratch,
) -> Option<(Scored, Normal)> {
    let (g, b, _) = normal_from(a_fit, y_fit);
    let hold = ((), y_hold);
    let rows = hold.1.nrows().max(1) as f64;
    // (log10 ridge, error, weights) of the best ridge so far.
    let mut best: Option<(f64, f64, Array2<f64>)> = None;
    let mut tried: Vec<f64> = Vec::new();
    let lo = holdout_floor().log10();
    type Best = Option<(f64, f64, Array2<f64>)>;
    // The ridges `es` not tried yet, factorised in parallel (independent solves), then taken
    // in the order given: the same choice as trying them one after the other.
    let try_all = |es: &[f64], best: &mut Best, tried: &mut Vec<f64>| {
        let mut todo: Vec<f64> = Vec::with_capacity(es.len());
        for &e in es {
            let e = e.clamp(lo, 0.0);
            if !tried.iter().chain(&todo).any(|t| (t - e).abs() < 1e-9) {
                todo.push(e);
            }
        }
        tried.extend(&todo);
        let solved: Vec<Option<Array2<f64>>> = todo
            .par_iter()
            .map(|&e| ridge_weights(&g, &b, 10f64.powf(e), scratch))
            .collect();
        // The holdout errors of all of them in one pass over the holdout rows.
        let ws: Vec<&Array2<f64>> = solved.iter().flatten().collect();
        let mut errs = a.squared_errors(&ws, hold.1).into_iter();
        let fits: Vec<Option<(f64, Array2<f64>)>> = solved
            .into_iter()
            .map(|w| w.map(|w| (errs.next().expect("one error per solution") / rows, w)))
            .collect();
        for (&e, fit) in todo.iter().zip(fits) {
            if let Some((err, w)) = fit
                && err.is_finite()
                && best.as_ref().is_none_or(|(_, s, _)| err < *s)
            {
                *best = Some((e, err, w));
            }
        }
    };
    match hint {
        None => {
            let decades = (-lo / 2.0).ceil() as usize;
            let sweep: Vec<f64> = (0..=decades).map(|i| -2.0 * i as f64).collect();
            try_all(&sweep, &mut best, &mut tried);
            let centre = best.as_ref()?.0;
            try_all(&[centre - 1.0, centre + 1.0], &mut best, &mut tried);
        }
        Some(h) => {
            // The hint and probes two decades to either side (then the refinement below):
            // the holdout error is not convex in the ridge, and a walk by half decades from
            // the hint stopped in a shallow local minimum (Franke, 300 cells, seed 3: 7·10⁻⁷
            // at 10⁻⁵, rms/σ 4.8 × the k-means RBF's, against a deeper minimum near 10⁻⁹;
            // 0.91 with the probes; probes at ±4 decades as well changed no result).
            let e0 = h.log10().clamp(lo, 0.0);
            try_all(&[e0, e0 - 2.0, e0 + 2.0], &mut best, &mut tried);
            // Every factorisation failed (ridges below G's rounding): upwards from the top.
            let mut e = tried.iter().fold(lo, |a, &t| a.max(t));
            while best.is_none() && e < 0.0 {
                e = (e + 0.5).min(0.0);
                try_all(&[e], &mut best, &mut tried);
            }
        }
    }
    // Refine by half decades around the best until both neighbours are tried.
    loop {
        let e = best.as_ref()?.0;
        let before = tried.len();
        try_all(&[e - 0.5, e + 0.5], &mut best, &mut tried);
        if tried.len() == before {
            break;
        }
    }
    let (e, err, w) = best?;
    Some(((err, w, 10f64.powf(e), f64::NAN), (g, b)))
}

/// The holdout rows of a selection, as their design matrix or as their raw Gaussians
/// ([`Basis::raw`]) completed row by row ([`Basis::design_of_raw`]'s numbers up to the
/// rounding of the row sum) while they are read.
#[derive(Clone, Copy)]
enum Holdout<'a> {
    /// The design matrix: the tests' reference ([`holdout_at`]; the selection scores from raw
    /// values).
    #[cfg(test)]
    Design(ArrayView2<'a, f64>),
    Raw {
        raw: ArrayView2<'a, f64>,
        basis: &'a Basis,
        xs: &'a [f64],
    },
}

impl Holdout<'_> {
    /// Σ |y − A W|² over the holdout rows for each of the weights `ws` (cols × m), in one
    /// pass over the rows (rows in parallel): each row is read once for all of them.
    fn squared_errors(&self, ws: &[&Array2<f64>], y: ArrayView2<'_, f64>) -> Vec<f64> {
        let m = y.ncols();
        let k = ws.len();
        if k == 0 {
            return Vec::new();
        }
        // The weights as k·m contiguous columns.
        let cols: Vec<Vec<f64>> = ws
            .iter()
            .flat_map(|w| (0..m).map(move |c| w.column(c).to_vec()))
            .collect();
        let rows = y.nrows();
        let row_err = |r: usize, acc: &mut [f64], pred: &mut [f64]| {
            match *self {
                #[cfg(test)]
                Holdout::Design(a) => {
                    let row = a.row(r);
                    let row = row.as_slice().expect("design rows are contiguous");
                    for (p, c) in pred.iter_mut().zip(&cols) {
                        *p = dot(row, c);
                    }
                }
                Holdout::Raw { raw, basis, xs } => {
                    let z = basis.cells();
                    let row = raw.row(r);
                    let row = row.as_slice().expect("raw rows are contiguous");
                    let x = &xs[r * basis.n..(r + 1) * basis.n];
                    let sum = if basis.normalized {
                        ndarray::ArrayView1::from(row).sum()
                    } else {
                        1.0
                    };
                    if sum > 0.0 {
                        for (p, c) in pred.iter_mut().zip(&cols) {
                            *p = dot(row, &c[..z]) / sum;
                        }
                    } else {
                        // Normalized, no positive value: the nearest cell's indicator
                        // (`finish`).
                        let nearest = basis.nearest(x);
                        for (p, c) in pred.iter_mut().zip(&cols) {
                            *p = c[nearest];
                        }
                    }
                    if basis.affine {
                        for (p, c) in pred.iter_mut().zip(&cols) {
                            *p += c[z] + dot(x, &c[z + 1..z + 1 + basis.n]);
                        }
                    }
                }
            }
            for (j, p) in pred.iter().enumerate() {
                let e = p - y[[r, j % m]];
                acc[j / m] += e * e;
            }
        };
        (0..rows)
            .into_par_iter()
            .with_min_len(64)
            .fold(
                || (vec![0.0; k], vec![0.0; k * m]),
                |(mut acc, mut pred), r| {
                    row_err(r, &mut acc, &mut pred);
                    (acc, pred)
                },
            )
            .map(|(acc, _)| acc)
            .reduce(
                || vec![0.0; k],
                |mut a, b| {
                    a.iter_mut().zip(b).for_each(|(a, b)| *a += b);
                    a
                },
            )
    }
}

/// Σ aᵢbᵢ (ndarray's unrolled dot product).
fn dot(a: &[f64], b: &[f64]) -> f64 {
    ndarray::ArrayView1::from(a).dot(&ndarray::ArrayView1::from(b))
}

/// G = AᵀA, B = AᵀY and Σ y² of a design matrix A (rows × cols) and targets Y.
fn normal_from(a: ArrayView2<'_, f64>, ys: ArrayView2<'_, f64>) -> (Array2<f64>, Array2<f64>, f64) {
    let g = gram(a);
    let mut b = Array2::zeros((a.ncols(), ys.ncols()));
    ndarray::linalg::general_mat_mul(1.0, &a.t(), &ys, 1.0, &mut b);
    let yy = ys.iter().map(|v| v * v).sum();
    (g, b, yy)
}

/// The raw Gaussians ([`Basis::raw`]) of the selection rows and of the holdout rows of one
/// candidate geometry at the multiplier `mult`, kept along a width walk.
#[derive(Clone)]
struct RawRows {
    mult: f64,
    fit: Array2<f64>,
    hold: Array2<f64>,
}

impl RawRows {
    /// Moves the raw values to the multiplier `to`. Plain Gaussians at μ·√2 are the square
    /// roots of those at μ (exp(−t/2μ²) = exp(−t/μ²)^½), at μ/√2 their squares (flushed below
    /// e^−FLUSH like [`gaussian`]): a step of the walk costs one square root or product per
    /// entry instead of a distance and an exponential. Other ratios are computed afresh.
    fn move_to(&mut self, to: f64, basis: &Basis, xs_fit: &[f64], xs_hold: &[f64]) {
        let k = 2.0 * (to / self.mult).log2();
        let steps = k.round();
        if (k - steps).abs() > 1e-9 || steps.abs() > 4.0 {
            self.fit = basis.raw(to, xs_fit);
            self.hold = basis.raw(to, xs_hold);
        } else {
            move_raw(&mut self.fit, steps as i32, basis, to, xs_fit);
            move_raw(&mut self.hold, steps as i32, basis, to, xs_hold);
        }
        self.mult = to;
    }
}

/// Raw Gaussians ([`Basis::raw`]) of the rows `xs` moved to the multiplier `to` = μ·√2^`steps`:
/// a square root per entry and step up, a square (flushed below e^−FLUSH like [`gaussian`])
/// per step down. An entry flushed to 0 at μ is computed afresh when moving up: it stood for
/// any exponent beyond FLUSH, and after k steps up its value exp(−t/2ᵏ) can matter again
/// (relative to the row's largest value, in a normalized row: a pilot walking from μ = 1 to
/// 5.7 lost entries of 10⁻⁵ relative size).
fn move_raw(a: &mut Array2<f64>, steps: i32, basis: &Basis, to: f64, xs: &[f64]) {
    let (n, z) = (basis.n, basis.cells());
    let floor = (-FLUSH).exp();
    let w2: Vec<f64> = basis.base.iter().map(|b| (to * b) * (to * b)).collect();
    a.as_slice_mut()
        .expect("raw values are contiguous")
        .par_chunks_mut(z.max(1))
        .zip(xs.par_chunks(n))
        .with_min_len(16)
        .for_each(|(row, x)| {
            for (i, v) in row.iter_mut().enumerate() {
                if steps > 0 && *v == 0.0 {
                    let c = &basis.centres[i * n..(i + 1) * n];
                    let r2: f64 = c.iter().zip(x).map(|(a, b)| (a - b) * (a - b)).sum();
                    *v = gaussian(r2, w2[i]);
                    continue;
                }
                for _ in 0..steps.max(0) {
                    *v = v.sqrt();
                }
                for _ in 0..(-steps).max(0) {
                    let sq = *v * *v;
                    *v = if sq < floor { 0.0 } else { sq };
                }
            }
        });
}

/// A holdout selection's score, weights, relative ridge and tr H, with the fitted rows' G and B.
type HoldoutFit = (Scored, Normal);
/// A candidate of the holdout selection along its walk: its index, multiplier and fit there,
/// and its raw values.
type Walked = (usize, (f64, HoldoutFit), RawRows);

/// The rows of a holdout selection ([`fit_best_holdout`]): the first `sel` rows fitted, the
/// next `hold` rows scored, the rest only refitted; with a pool of spare matrices.
struct HoldoutRows<'a> {
    /// The targets of every row.
    ys: ArrayView2<'a, f64>,
    /// The targets of the fitted rows.
    sy: ArrayView2<'a, f64>,
    /// The targets of the holdout rows.
    hy: ArrayView2<'a, f64>,
    sel: usize,
    hold: usize,
    scratch: Scratch,
}

impl<'a> HoldoutRows<'a> {
    /// The rows of `ys`: `sel` fitted, the next `hold` scored.
    fn new(ys: ArrayView2<'a, f64>, sel: usize, hold: usize) -> Self {
        Self {
            ys,
            sy: ys.slice_axis_move(Axis(0), Slice::from(..sel)),
            hy: ys.slice_axis_move(Axis(0), Slice::from(sel..sel + hold)),
            sel,
            hold,
            scratch: Scratch::default(),
        }
    }

    /// A candidate's inputs of the fitted rows and of the holdout rows.
    fn split<'b>(&self, c: &(&Basis, &'b [f64])) -> (&'b [f64], &'b [f64]) {
        let (sel, hold) = (self.sel, self.hold);
        let n = c.0.n;
        (&c.1[..sel * n], &c.1[sel * n..(sel + hold) * n])
    }

    /// Candidate `c` fitted on the fitted rows and scored on the holdout rows
    /// ([`holdout_solve`]) from its raw values `raw` at their multiplier, the ridge search
    /// from `hint` when given.
    fn score(&self, c: &(&Basis, &[f64]), raw: &RawRows, hint: Option<f64>) -> Option<HoldoutFit> {
        let (sy, hy, scratch) = (self.sy, self.hy, &self.scratch);
        let (xf, xh) = self.split(c);
        let basis = c.0;
        // The holdout rows are scored from their raw values (normalized and completed row
        // by row as they are read), the selection rows' design matrix made in a spare matrix
        // of the selection (no fresh pages per width).
        let holdout = Holdout::Raw {
            raw: raw.hold.view(),
            basis,
            xs: xh,
        };
        if !basis.normalized && !basis.affine {
            return holdout_solve(raw.fit.view(), sy, holdout, hy, hint, scratch);
        }
        let mut a_fit = scratch.take(self.sel, basis.cols());
        basis.design_of_raw_into(&raw.fit, xf, &mut a_fit);
        let fit = holdout_solve(a_fit.view(), sy, holdout, hy, hint, scratch);
        scratch.give(a_fit);
        fit
    }

    /// Every candidate at the first multiplier (its raw values there in `raws`): the first
    /// one with the full ridge search, the others (in parallel) from its ridge as the hint
    /// (the ridge is the noise-to-signal ratio of the data, relative to the Gram's mean
    /// diagonal, so it carries over between bases; the hint's probes two decades to either
    /// side and the refinement still walk to a different optimum).
    fn starts(
        &self,
        candidates: &[(&Basis, &[f64])],
        raws: &SharedRaws,
    ) -> Vec<Option<HoldoutFit>> {
        let lead = self.score(&candidates[0], raws.of(0), None);
        let hint = lead.as_ref().map(|f| f.0.2);
        std::iter::once(lead)
            .chain(
                (1..candidates.len())
                    .into_par_iter()
                    .map(|i| self.score(&candidates[i], raws.of(i), hint))
                    .collect::<Vec<_>>(),
            )
            .collect()
    }

    /// The width walk ([`walk_width`]) of a started candidate, its raw values moved along
    /// ([`RawRows::move_to`]), each multiplier's ridge search from the previous one's ridge;
    /// none with a given multiplier (`fixed`).
    fn walk(&self, candidates: &[(&Basis, &[f64])], start: Walked, fixed: bool) -> Walked {
        let (i, at, mut raw) = start;
        if fixed {
            return (i, at, raw);
        }
        let c = &candidates[i];
        let (xf, xh) = self.split(c);
        let at = walk_width(
            at,
            |f: &HoldoutFit| f.0.0,
            |m, f: &HoldoutFit| {
                raw.move_to(m, c.0, xf, xh);
                self.score(c, &raw, Some(f.0.2))
            },
        );
        (i, at, raw)
    }

    /// The holdout predictions of every walked candidate at its chosen multiplier. From here
    /// on only the holdout rows' design matrix is needed (the refit adds its Gram matrix): it
    /// replaces their raw values in `raw.hold` (and the fitted rows' raw values are dropped).
    fn predictions(
        &self,
        candidates: &[(&Basis, &[f64])],
        walks: &mut [Walked],
    ) -> Vec<Array2<f64>> {
        walks
            .par_iter_mut()
            .map(|(i, (mult, fit), raw)| {
                let c = &candidates[*i];
                let (_, xh) = self.split(c);
                raw.fit = Array2::zeros((0, c.0.cells()));
                raw.move_to(*mult, c.0, &[], xh);
                if c.0.normalized || c.0.affine {
                    raw.hold = c.0.design_of_raw(&raw.hold, xh).into_owned();
                }
                mul_few(raw.hold.view(), fit.0.1.view())
            })
            .collect()
    }

    /// The refit of a walked candidate on every row with the same absolute ridge (module docs
    /// of `regressor`): G and B of the selection rows as scored at the chosen multiplier,
    /// plus those of the holdout rows (their design matrix, made for [`Self::predictions`],
    /// in `raw.hold`) and of the remaining rows; the ridge raised while the factorisation
    /// fails ([`refit_solve`]). `yy` is Σ y² over every row; `score` the selection's.
    fn refit(
        &self,
        candidates: &[(&Basis, &[f64])],
        walked: Walked,
        yy: f64,
        score: f64,
    ) -> Option<Picked> {
        let (ys, hy, sel, hold) = (self.ys, self.hy, self.sel, self.hold);
        let rows = ys.nrows();
        let (index, (mult, fit), raw) = walked;
        let (fit, (mut g, mut b)) = fit;
        let (basis, xs) = candidates[index];
        let n = basis.n;
        let rest = basis.design(mult, &xs[(sel + hold) * n..rows * n]);
        // (`raw.hold` holds the holdout rows' design matrix since the predictions.)
        let pieces = [
            (raw.hold, hy),
            (rest, ys.slice_axis_move(Axis(0), Slice::from(sel + hold..))),
        ];
        for (a, y) in &pieces {
            gram_add(a.view(), &mut g);
            ndarray::linalg::general_mat_mul(1.0, &a.t(), y, 1.0, &mut b);
        }
        drop(pieces);
        let r = (fit.2 * sel as f64 / rows as f64).max(holdout_floor());
        let (weights, relative, dof) = refit_solve(&g, &b, yy, r, 1.0)?;
        Some(picked(index, weights, mult, relative, dof, score))
    }
}

/// The raw Gaussians ([`RawRows`]) of the holdout selection's candidates at the first
/// multiplier, computed once per geometry: candidates with the same centres, widths and rows
/// (normalized and plain ones on the same centres) share them.
struct SharedRaws {
    /// Per candidate: the first candidate of its geometry.
    geometry: Vec<usize>,
    /// The first candidate of each geometry, in order.
    owners: Vec<usize>,
    /// Per owner: the raw values.
    raws: Vec<RawRows>,
}

impl SharedRaws {
    /// The raw values of the `candidates`' geometries on the rows of `h` at the multiplier
    /// `first` (in parallel).
    fn at(candidates: &[(&Basis, &[f64])], h: &HoldoutRows, first: f64) -> Self {
        let same = |a: &(&Basis, &[f64]), b: &(&Basis, &[f64])| {
            std::ptr::eq(a.1, b.1) && a.0.centres == b.0.centres && a.0.base == b.0.base
        };
        let geometry: Vec<usize> = (0..candidates.len())
            .map(|i| {
                (0..i)
                    .find(|&j| same(&candidates[i], &candidates[j]))
                    .unwrap_or(i)
            })
            .collect();
        let owners: Vec<usize> = (0..candidates.len())
            .filter(|&i| geometry[i] == i)
            .collect();
        let raws: Vec<RawRows> = owners
            .par_iter()
            .map(|&i| {
                let (xf, xh) = h.split(&candidates[i]);
                let basis = candidates[i].0;
                RawRows {
                    mult: first,
                    fit: basis.raw(first, xf),
                    hold: basis.raw(first, xh),
                }
            })
            .collect();
        Self {
            geometry,
            owners,
            raws,
        }
    }

    /// The raw values of candidate `i`.
    fn of(&self, i: usize) -> &RawRows {
        &self.raws[self
            .owners
            .iter()
            .position(|&o| o == self.geometry[i])
            .expect("owner")]
    }
}

/// [`fit_best`] scored on a holdout: `sel` fitted rows, the next `hold` rows scored. The raw
/// Gaussians of the rows are computed once per candidate geometry (normalized and plain
/// candidates on the same centres and rows share them: [`SharedRaws`]) and moved along the
/// width walk by [`RawRows::move_to`]; the refit on every row reuses the winner's raw values of
/// the selection and holdout rows and computes only the remaining rows afresh.
fn fit_best_holdout(
    candidates: &[(&Basis, &[f64])],
    ys: ArrayView2<'_, f64>,
    mult: Option<f64>,
    sel: usize,
    hold: usize,
    start: f64,
) -> Option<Choice> {
    let h = HoldoutRows::new(ys, sel, hold);
    let first = mult.unwrap_or_else(|| start.clamp(MULT_RANGE.0, MULT_RANGE.1));
    // ⟨Every candidate at the first multiplier …⟩
    let raws = SharedRaws::at(candidates, &h, first);
    let mut starts = h.starts(candidates, &raws);
    // ⟨… then the walk (module docs of `regressor`) only from the RACE_KEEP best of them⟩
    let keep = if mult.is_some() { 1 } else { RACE_KEEP };
    let order = leaders(
        candidates.len(),
        |i| starts[i].as_ref().map(|s| s.0.0),
        keep,
    );
    let seeds: Vec<Walked> = order
        .iter()
        .filter_map(|&i| {
            starts[i]
                .take()
                .map(|s| (i, (first, s), raws.of(i).clone()))
        })
        .collect();
    drop(raws);
    let walk = |seed: Walked| h.walk(candidates, seed, mult.is_some());
    let mut walks: Vec<Walked> = seeds.into_par_iter().map(walk).collect();
    walks.sort_by(|a, b| a.1.1.0.0.total_cmp(&b.1.1.0.0).then(a.0.cmp(&b.0)));
    // ⟨The blend of the two best on the holdout rows⟩
    let preds = h.predictions(candidates, &mut walks);
    let share = if BLEND && walks.len() > 1 {
        blend_share(preds[0].view(), preds[1].view(), h.hy)
    } else {
        None
    };
    let used = if share.is_some() { 2 } else { 1 };
    walks.truncate(used);
    let score = match share {
        Some((_, err)) => err,
        None => walks[0].1.1.0.0,
    };
    // ⟨The refit on every row⟩
    let yy: f64 = ys.iter().map(|v| v * v).sum();
    let refit = |walked: Walked| h.refit(candidates, walked, yy, score);
    let mut fits: Vec<Option<Picked>> = walks.into_par_iter().map(refit).collect();
    let (index, weights, chosen) = fits[0].take()?;
    let partner = match (share, fits.get_mut(1).and_then(Option::take)) {
        (Some((alpha, _)), Some(p)) => Some((p, alpha)),
        _ => None,
    };
    Some((index, weights, chosen, partner))
}

/// The share α ∈ (0, 1] of the second prediction in the blend (1 − α)·p₁ + α·p₂ that
/// minimises the squared error against `y` (holdout rows), with that blend's mean squared
/// error per row; `None` when the best share is 0 (the first prediction alone) or not finite.
fn blend_share(
    p1: ArrayView2<'_, f64>,
    p2: ArrayView2<'_, f64>,
    y: ArrayView2<'_, f64>,
) -> Option<(f64, f64)> {
    let (mut dd, mut dr) = (0.0, 0.0);
    for ((a, b), t) in p1.iter().zip(p2.iter()).zip(y.iter()) {
        let (d, r) = (b - a, t - a);
        dd += d * d;
        dr += d * r;
    }
    let alpha = (dr / dd).clamp(0.0, 1.0);
    if !(alpha > 0.0 && alpha.is_finite()) {
        return None;
    }
    let err: f64 = p1
        .iter()
        .zip(p2.iter())
        .zip(y.iter())
        .map(|((a, b), t)| {
            let e = (1.0 - alpha) * a + alpha * b - t;
            e * e
        })
        .sum();
    Some((alpha, err / y.nrows().max(1) as f64))
}

/// Blend the two best candidates of the holdout selection (`fit_best`).
const BLEND: bool = true;

/// The width walk of [`fit_best`] (module docs of `regressor`) from `at` (multiplier, fit):
/// by √2 upwards while the `score` falls, else downwards, within [`MULT_RANGE`]; `eval`
/// fits at a multiplier given the current best fit (whose ridge is the hint).
fn walk_width<F>(
    at: (f64, F),
    score: impl Fn(&F) -> f64,
    mut eval: impl FnMut(f64, &F) -> Option<F>,
) -> (f64, F) {
    let step = std::f64::consts::SQRT_2;
    let mut at = at;
    for dir in [step, 1.0 / step] {
        let mut next = at.0 * dir;
        let mut improved = false;
        while (MULT_RANGE.0..=MULT_RANGE.1).contains(&next) {
            match eval(next, &at.1) {
                Some(fit) if score(&fit) < score(&at.1) => {
                    at = (next, fit);
                    improved = true;
                    next *= dir;
                }
                _ => break,
            }
        }
        if improved {
            break;
        }
    }
    at
}

/// Candidates of [`fit_best`] whose multiplier is walked: the best ones at the first
/// multiplier.
const RACE_KEEP: usize = 2;

/// The smallest relative ridge of the selection ([`crate::linalg::RidgePath::best_ridge`]).
const RIDGE_FLOOR: f64 = 1e-12;

/// The smallest relative ridge of the holdout selection (and of its refit): machine epsilon,
/// the smallest ridge that changes G's diagonal at all. The holdout score (thousands of rows,
/// independent of the fit) decides whether a ridge this small generalizes; where the
/// factorisation fails the ridge is skipped (selection) or raised (refit, [`refit_all`]).
/// (The leave-one-out selection keeps [`RIDGE_FLOOR`]: its near-null eigenvectors were
/// rounding noise.) At 1000 cells the floor 10⁻¹² held Franke at 2 × the k-means RBF's rms.
fn holdout_floor() -> f64 {
    f64::EPSILON
}

/// The range of the width multiplier walk.
const MULT_RANGE: (f64, f64) = (0.2, 12.0);

/// Chooses multiplier and relative ridge from the grids by the mean squared error on the last
/// `holdout` share of the rows (fitted on the others), then refits on every row.
pub(crate) fn fit_holdout(
    basis: &Basis,
    xs: &[f64],
    ys: ArrayView2<'_, f64>,
    mults: &[f64],
    ridges: &[f64],
    holdout: f64,
) -> Option<(Vec<f64>, Selected)> {
    let n = basis.n;
    let rows = ys.nrows();
    let train = ((rows as f64 * (1.0 - holdout)).round() as usize).clamp(1, rows);
    let (tx, hx) = xs.split_at(train * n);
    let (ty, hy) = ys.split_at(Axis(0), train);
    let zero = Array2::zeros((basis.cols(), 0));
    let mut best: Option<(f64, f64, f64)> = None;
    for &mult in mults {
        let (g, b, yy, _) = basis.normal_equations(mult, tx, ty, false);
        let a = basis.design(mult, hx);
        for &r in ridges {
            let Some(fit) = ridge_fit(&g, &b, yy, r, &zero) else {
                continue;
            };
            let err = if hy.nrows() == 0 {
                fit.rss
            } else {
                (&mul_few(a.view(), fit.weights.view()) - &hy)
                    .mapv(|e| e * e)
                    .sum()
            };
            if err.is_finite() && best.is_none_or(|(e, _, _)| err < e) {
                best = Some((err, mult, r));
            }
        }
    }
    let (_, mult, ridge) = best?;
    let best = best.map(|(e, m, r)| (e / hy.nrows().max(1) as f64, m, r));
    let (g, b, yy, _) = basis.normal_equations(mult, xs, ys, false);
    let fit = ridge_fit(&g, &b, yy, ridge, &zero)?;
    Some((
        fit.weights.into_raw_vec_and_offset().0,
        Selected {
            mult,
            ridge,
            dof: fit.dof,
            score: best.map_or(f64::NAN, |b| b.0),
        },
    ))
}

/// The expected gradient outer product E = (1/N) Σ_rows Σ_c ∇f_c ∇f_cᵀ (n × n row-major) of
/// the fitted layer f (weights cols × m) over the rows `xs` (N × n, the basis' coordinates),
/// from the analytic gradients of the Gaussians.
pub(crate) fn egop(basis: &Basis, mult: f64, weights: &[f64], m: usize, xs: &[f64]) -> Vec<f64> {
    let (n, z) = (basis.n, basis.cells());
    let rows = (xs.len() / n).max(1);
    // Fixed chunks of rows summed in order, so the result does not depend on the threads.
    let chunks: Vec<Vec<f64>> = xs
        .par_chunks(n * 64)
        .map(|chunk| {
            let (mut e, mut grad) = (vec![0.0; n * n], vec![0.0; n]);
            let (mut raw, mut phi) = (vec![0.0; z], vec![0.0; z]);
            for x in chunk.chunks_exact(n) {
                // Un-normalized values and their sum, and the basis values φ from them (the
                // same numbers as `Basis::row`; its affine columns are not needed: f below
                // is the Gaussians' part, and a row without any positive value adds nothing).
                let mut sum = 0.0;
                for i in 0..z {
                    let c = &basis.centres[i * n..(i + 1) * n];
                    let w = mult * basis.base[i];
                    let r2: f64 = c.iter().zip(x).map(|(a, b)| (a - b) * (a - b)).sum();
                    raw[i] = gaussian(r2, w * w);
                    sum += raw[i];
                }
                for (p, &r) in phi.iter_mut().zip(&raw) {
                    *p = if basis.normalized && sum > 0.0 {
                        r / sum
                    } else {
                        r
                    };
                }
                for out in 0..m {
                    let f: f64 = (0..z).map(|i| phi[i] * weights[i * m + out]).sum();
                    grad.fill(0.0);
                    for i in 0..z {
                        if raw[i] == 0.0 {
                            continue;
                        }
                        let w = mult * basis.base[i];
                        // ∂φ_i/∂x = −2 (x − c_i)/w² φ_i; normalized: ∂f = Σ (v_i − f) ∂φ_i / S.
                        let coef = if basis.normalized {
                            if sum <= 0.0 {
                                continue;
                            }
                            (weights[i * m + out] - f) * raw[i] / sum
                        } else {
                            weights[i * m + out] * raw[i]
                        } * (-2.0 / (w * w));
                        let c = &basis.centres[i * n..(i + 1) * n];
                        for a in 0..n {
                            grad[a] += coef * (x[a] - c[a]);
                        }
                    }
                    if basis.affine {
                        for a in 0..n {
                            grad[a] += weights[(z + 1 + a) * m + out];
                        }
                    }
                    for a in 0..n {
                        for b in 0..n {
                            e[a * n + b] += grad[a] * grad[b];
                        }
                    }
                }
            }
            e
        })
        .collect();
    let mut partial = vec![0.0; n * n];
    for c in &chunks {
        partial.iter_mut().zip(c).for_each(|(p, q)| *p += q);
    }
    partial.into_iter().map(|v| v / rows as f64).collect()
}

/// Mean distance from every centre to its `q` nearest other centres (q clamped to z − 1),
/// rows of `centres` z × n.
pub(crate) fn nearest_widths(centres: &[f64], n: usize, q: usize) -> Vec<f64> {
    let z = centres.len() / n;
    let q = q.min(z.saturating_sub(1)).max(1);
    (0..z)
        .into_par_iter()
        .map(|j| {
            let cj = &centres[j * n..(j + 1) * n];
            let mut d: Vec<f64> = (0..z)
                .filter(|&i| i != j)
                .map(|i| {
                    let ci = &centres[i * n..(i + 1) * n];
                    ci.iter()
                        .zip(cj)
                        .map(|(a, b)| (a - b) * (a - b))
                        .sum::<f64>()
                        .sqrt()
                })
                .collect();
            if d.is_empty() {
                return 1.0;
            }
            let q = q.min(d.len());
            d.select_nth_unstable_by(q - 1, |a, b| a.total_cmp(b));
            let w = d[..q].iter().sum::<f64>() / q as f64;
            if w > 0.0 { w } else { 1e-6 }
        })
        .collect()
}

/// The first `keep` of the `n` candidates that have a score (lower is better), best first; ties
/// go to the lower index.
fn leaders(n: usize, score: impl Fn(usize) -> Option<f64>, keep: usize) -> Vec<usize> {
    let mut order: Vec<usize> = (0..n).filter(|&i| score(i).is_some()).collect();
    let score_of = |i: usize| score(i).unwrap_or(f64::INFINITY);
    order.sort_by(|&a, &b| score_of(a).total_cmp(&score_of(b)).then(a.cmp(&b)));
    order.truncate(keep);
    order
}

#[cfg(test)]
mod tests {
    use super::*;

    /// y = sin 3x at `rows` points spread over [−1, 1] (golden-ratio steps).
    fn sine_rows(rows: usize) -> (Vec<f64>, Vec<f64>) {
        let xs: Vec<f64> = (0..rows)
            .map(|i| -1.0 + 2.0 * ((i as f64 * 0.618_034) % 1.0))
            .collect();
        let ys = xs.iter().map(|x| (3.0 * x).sin()).collect();
        (xs, ys)
    }

    /// `count` Gaussians evenly spaced over [−1, 1] (1-D), widths from their nearest neighbours.
    fn line_basis(count: usize, normalized: bool) -> Basis {
        let centres: Vec<f64> = (0..count)
            .map(|i| -1.0 + 2.0 * i as f64 / (count - 1) as f64)
            .collect();
        Basis {
            n: 1,
            base: nearest_widths(&centres, 1, 2),
            centres,
            normalized,
            affine: false,
        }
    }

    #[test]
    fn lone_leave_one_out_walk_ends_at_a_local_minimum_of_the_fresh_scores() {
        // One candidate on all its rows (the metric pilots' case): the walk moves the raw
        // values by square roots and squares instead of recomputing them. Its choice must be
        // a local minimum of the scores computed from scratch on the √2 grid, and its score
        // the fresh one at that multiplier to 10⁻³ (rounding: the chosen fits interpolate to
        // a score near 6·10⁻¹² at the 10⁻¹² ridge floor; 1.7·10⁻⁴ apart). From μ = 0.25 most entries start
        // flushed: before they were computed afresh on the way up, the walk stopped at
        // μ = 1.41 with a score 0.3 % off the fresh one, where the fresh scores still fell.
        let rows = 400;
        let (xs, ys) = sine_rows(rows);
        let yv = ArrayView2::from_shape((rows, 1), &ys).unwrap();
        for normalized in [true, false] {
            let basis = line_basis(20, normalized);
            let start = 0.25;
            let (_, _, chosen, _) =
                fit_best(&[(&basis, &xs[..])], yv, None, None, rows, start).expect("a fit");
            let steps = (2.0 * (chosen.mult / start).log2()).round();
            assert!(steps >= 2.0, "walked {steps} steps from {start}");
            let fresh = |m: f64| gcv_at(&basis, m, None, &xs, yv, rows).expect("a fit").0;
            let at = fresh(chosen.mult);
            assert!(
                (at - chosen.score).abs() <= 1e-3 * at,
                "normalized {normalized}: moved {} fresh {at}",
                chosen.score
            );
            let step = std::f64::consts::SQRT_2;
            for m in [chosen.mult * step, chosen.mult / step] {
                assert!(
                    at <= fresh(m),
                    "normalized {normalized}: {} not a minimum",
                    chosen.mult
                );
            }
        }
    }

    #[test]
    fn fit_best_keeps_the_candidate_with_the_lower_leave_one_out_score() {
        // y = sin 3x on 400 rows in [-1, 1], 20 centres spread over the rows. Candidate 0 sees
        // the rows stretched by 5 (most rows far from every centre), candidate 1 the rows
        // themselves: candidate 1 must win, and its weights must reproduce the function.
        let rows = 400;
        let (xs, ys) = sine_rows(rows);
        let stretched: Vec<f64> = xs.iter().map(|x| 5.0 * x).collect();
        let basis = line_basis(20, false);
        let yv = ArrayView2::from_shape((rows, 1), &ys).unwrap();
        let candidates = [(&basis, &stretched[..]), (&basis, &xs[..])];
        let (index, weights, chosen, _) = fit_best(&candidates, yv, None, None, 200, 1.0).unwrap();
        assert_eq!(index, 1, "chose the stretched rows ({chosen:?})");
        let mut row = vec![0.0; basis.cols()];
        for x in [-0.9, -0.3, 0.2, 0.7] {
            basis.row(chosen.mult, &[x], &mut row);
            let f: f64 = row.iter().zip(&weights).map(|(a, w)| a * w).sum();
            assert!((f - (3.0 * x).sin()).abs() < 1e-3, "f({x}) = {f}");
        }
        // Equal candidates: the first one.
        let same = [(&basis, &xs[..]), (&basis, &xs[..])];
        assert_eq!(fit_best(&same, yv, None, None, 200, 1.0).unwrap().0, 0);
    }

    #[test]
    fn holdout_ridge_grows_with_noise_and_the_walk_hint_finds_it_again() {
        // y = sin 3x (+ noise) on 800 rows in [-1, 1], 40 centres; fit on the first 400 rows,
        // score on the other 400. Noise must give a larger ridge than clean targets; started
        // from a hint two decades off, the half-decade walk must reach a ridge at least as
        // good as the full search's.
        let rows = 800;
        let xs: Vec<f64> = (0..rows)
            .map(|i| -1.0 + 2.0 * ((i as f64 * 0.618_034) % 1.0))
            .collect();
        let clean: Vec<f64> = xs.iter().map(|x| (3.0 * x).sin()).collect();
        let noisy: Vec<f64> = clean
            .iter()
            .enumerate()
            .map(|(i, y)| y + 0.5 * (((i * 7919) % 1000) as f64 / 500.0 - 1.0))
            .collect();
        let basis = line_basis(40, false);
        let ridge = |ys: &[f64], hint: Option<f64>| {
            let yv = ArrayView2::from_shape((rows, 1), ys).unwrap();
            let (fy, hy) = yv.split_at(Axis(0), 400);
            holdout_at(&basis, 2.0, (&xs[..400], fy), (&xs[400..], hy), hint).unwrap()
        };
        let (e_clean, _, r_clean, _) = ridge(&clean, None);
        let (e_noisy, _, r_noisy, _) = ridge(&noisy, None);
        assert!(r_noisy > 100.0 * r_clean, "{r_noisy} vs {r_clean}");
        assert!(e_clean < 1e-4 && e_noisy < 0.15, "{e_clean} {e_noisy}");
        for off in [1e-4, 100.0, 1e4] {
            let (e_hint, _, _, _) = ridge(&noisy, Some(r_noisy * off));
            assert!(
                e_hint <= e_noisy * 1.01,
                "hint × {off}: {e_hint} vs {e_noisy}"
            );
        }
        // Clean targets: the holdout may go below the leave-one-out floor 10⁻¹², never below ε.
        assert!(r_clean >= f64::EPSILON * 0.999, "{r_clean}");
    }

    /// `count` 2-D rows spread over [−2, 2]² (golden-ratio steps) and one row far from
    /// every centre of [`plane_centres`] (all of its Gaussians flushed).
    fn plane_rows(count: usize) -> Vec<f64> {
        let mut xs: Vec<f64> = (0..count)
            .flat_map(|i| {
                let t = i as f64;
                [
                    (t * 0.618_034) % 1.0 * 4.0 - 2.0,
                    (t * 0.414_214) % 1.0 * 4.0 - 2.0,
                ]
            })
            .collect();
        xs.extend([400.0, -300.0]);
        xs
    }

    /// 30 centres in [−2, 2]², irregularly placed (so their nearest-centre widths differ).
    fn plane_centres() -> Vec<f64> {
        (0..60)
            .map(|i| ((i * 37) % 61) as f64 / 15.0 - 2.0)
            .collect()
    }

    /// Gaussians on [`plane_centres`] (nearest-centre widths), plain and normalized, with and
    /// without the affine columns.
    fn plane_bases() -> Vec<Basis> {
        let centres = plane_centres();
        let base = nearest_widths(&centres, 2, 3);
        [(false, false), (true, false), (true, true), (false, true)]
            .into_iter()
            .map(|(normalized, affine)| Basis {
                n: 2,
                centres: centres.clone(),
                base: base.clone(),
                normalized,
                affine,
            })
            .collect()
    }

    #[test]
    fn raw_values_make_the_design_and_move_along_the_walk() {
        // 2-D rows and 30 centres with unequal widths; one row far from every centre (all of
        // its values flushed, so the normalized row falls back to its nearest centre).
        let n = 2;
        let xs = plane_rows(200);
        for basis in plane_bases() {
            let raw = basis.raw(1.7, &xs);
            // The design from the raw values is the design, bit for bit.
            assert_eq!(*basis.design_of_raw(&raw, &xs), basis.design(1.7, &xs));
        }
        // Plain Gaussians without the affine columns.
        let basis = plane_bases().swap_remove(0);
        let step = std::f64::consts::SQRT_2;
        let (fit, hold) = xs.split_at(120 * n);
        let mut moved = RawRows {
            mult: 1.7,
            fit: basis.raw(1.7, fit),
            hold: basis.raw(1.7, hold),
        };
        // Up one and two steps (square roots), down four (squares, flushed), and a ratio
        // that is no power of √2 (computed afresh).
        for to in [1.7 * step, 1.7 * 2.0 * step, 1.7 / step, 0.9] {
            moved.move_to(to, &basis, fit, hold);
            for (got, rows) in [(&moved.fit, fit), (&moved.hold, hold)] {
                let direct = basis.raw(to, rows);
                for (g, d) in got.iter().zip(direct.iter()) {
                    // Rounding of the exponent t = r²/w² (relative ε) scales the value's
                    // relative error with t = −ln d; values below e^−150 may be 0 after a
                    // square root of a flushed value.
                    let tol = 1e-14 * (1.0 - d.ln().max(-FLUSH)) * d;
                    let tiny = (-150.0f64).exp();
                    assert!(
                        (g - d).abs() <= tol || (*g == 0.0 && *d < tiny),
                        "at {to}: {g} vs {d}"
                    );
                }
            }
        }
    }

    #[test]
    fn holdout_errors_from_raw_values_are_those_of_the_design() {
        // 2-D rows, one far from every centre (its normalized row is its nearest centre's
        // indicator); two targets; three weight matrices scored in one pass.
        let n = 2;
        let xs = plane_rows(150);
        let rows = xs.len() / n;
        let ys = Array2::from_shape_fn((rows, 2), |(r, c)| (r as f64 * 0.37 + c as f64).sin());
        for basis in plane_bases() {
            let ws: Vec<Array2<f64>> = (0..3)
                .map(|k| {
                    Array2::from_shape_fn((basis.cols(), 2), |(j, c)| {
                        ((j * 7 + c * 3 + k * 11) % 13) as f64 / 6.0 - 1.0
                    })
                })
                .collect();
            let refs: Vec<&Array2<f64>> = ws.iter().collect();
            let design = basis.design(1.7, &xs);
            let raw = basis.raw(1.7, &xs);
            let from_design = Holdout::Design(design.view()).squared_errors(&refs, ys.view());
            let from_raw = Holdout::Raw {
                raw: raw.view(),
                basis: &basis,
                xs: &xs,
            }
            .squared_errors(&refs, ys.view());
            for (k, w) in ws.iter().enumerate() {
                let direct = (&design.dot(w) - &ys).mapv(|e| e * e).sum();
                for got in [from_design[k], from_raw[k]] {
                    assert!(
                        (got - direct).abs() <= 1e-12 * direct,
                        "normalized {} affine {} weights {k}: {got} vs {direct}",
                        basis.normalized,
                        basis.affine
                    );
                }
            }
        }
    }

    #[test]
    fn fit_fixed_equals_the_fixed_selection_and_its_fitted_values_the_predictions() {
        // y = sin 3x on 300 rows, 25 normalized Gaussians: the weights of `fit_fixed` are the
        // fixed-multiplier, fixed-ridge selection's (`fit_gcv`), and its fitted values are the
        // layer's predictions at the rows.
        let rows = 300;
        let (xs, ys) = sine_rows(rows);
        let basis = line_basis(25, true);
        let yv = ArrayView2::from_shape((rows, 1), &ys).unwrap();
        let (w, fitted) = fit_fixed(&basis, 1.5, 1e-6, &xs, yv).unwrap();
        let (w_sel, _) = fit_gcv(&basis, &xs, yv, Some(1.5), Some(1e-6), rows, 1.5).unwrap();
        assert_eq!(w.into_raw_vec_and_offset().0, w_sel);
        let mut row = vec![0.0; basis.cols()];
        for (r, x) in xs.iter().enumerate() {
            basis.row(1.5, &[*x], &mut row);
            let f: f64 = row.iter().zip(&w_sel).map(|(a, w)| a * w).sum();
            assert!(
                (f - fitted[[r, 0]]).abs() < 1e-12,
                "row {r}: {f} vs {}",
                fitted[[r, 0]]
            );
        }
        assert!(fitted.iter().zip(&ys).all(|(f, y)| (f - y).abs() < 0.01));
    }

    #[test]
    fn a_blend_on_one_geometry_predicts_as_its_two_layers_do() {
        // Two layers on the same centres and widths (normalized at μ = 0.5, plain at 2 and at
        // 0.7): the shared pass (square roots of the narrower layer's values; fresh values
        // where those are flushed) must give the separate predictions' blend to rounding, in
        // either order; a ratio off the √2 grid takes the separate path.
        let basis = line_basis(30, true);
        let weights: Vec<f64> = (0..30).map(|i| ((i * 7) % 11) as f64 - 5.0).collect();
        let layer = |normalized: bool, mult: f64| Readout {
            basis: Basis {
                normalized,
                ..basis.clone()
            },
            mult,
            weights: weights.clone(),
            m: 1,
            x: Standardizer {
                mean: vec![0.1],
                scale: vec![2.0],
            },
            y: Standardizer {
                mean: vec![3.0],
                scale: vec![0.5],
            },
            ridge: 0.0,
            transform: None,
        };
        // Inputs inside and far outside the centres (every value flushed at μ = 0.5).
        let xs: Vec<f64> = (0..400)
            .map(|i| -3.0 + 0.02 * i as f64)
            .chain([90.0])
            .collect();
        let separate = |a: &Readout, b: &Readout, share: f64| -> Vec<f64> {
            let (mut pa, mut pb) = (vec![0.0; xs.len()], vec![0.0; xs.len()]);
            a.predict(&xs, &mut pa);
            b.predict(&xs, &mut pb);
            pa.iter()
                .zip(&pb)
                .map(|(u, v)| (1.0 - share) * u + share * v)
                .collect()
        };
        for (a, b) in [
            (layer(true, 0.5), layer(false, 2.0)),
            (layer(false, 2.0), layer(true, 0.5)),
            (layer(true, 0.5), layer(false, 0.7)),
        ] {
            let mut got = vec![0.0; xs.len()];
            a.predict_blend(&b, 0.3, &xs, &mut got);
            let want = separate(&a, &b, 0.3);
            for (g, w) in got.iter().zip(&want) {
                assert!((g - w).abs() <= 1e-9 * w.abs().max(1.0), "{g} vs {w}");
            }
        }
    }

    #[test]
    fn few_rows_per_cell_still_leave_a_fifth_for_the_holdout() {
        // Ten rows per cell (the benchmark's shapes): S = 3 z, the holdout 2 S or the rest.
        assert_eq!(selection_rows(3000, 300), 1500);
        assert_eq!(selection_rows(10_000, 1000), 3000);
        for (rows, cols) in [
            (3000, 1000),
            (2000, 300),
            (1200, 300),
            (1000, 100),
            (4001, 1000),
        ] {
            let sel = selection_rows(rows, cols);
            let hold = (rows - sel).min(2 * sel);
            assert!(
                5 * hold >= rows && sel + hold <= rows,
                "{rows} × {cols}: {sel}"
            );
            assert!(hold >= HOLDOUT_MIN, "{rows} × {cols}: holdout {hold}");
        }
        // Below 1000 rows the holdout would be under HOLDOUT_MIN: leave-one-out instead.
        let sel = selection_rows(900, 100);
        assert!(900 - sel < HOLDOUT_MIN);
    }

    #[test]
    fn blend_share_is_the_least_squares_share_in_0_1() {
        let y = ndarray::array![[1.0], [2.0], [-1.0], [0.5]];
        let e = ndarray::array![[0.1], [-0.3], [0.2], [0.05]];
        // Errors of opposite sign and equal size: half of each, no error left.
        let (p1, p2) = (&y + &e, &y - &e);
        let (a, err) = blend_share(p1.view(), p2.view(), y.view()).unwrap();
        assert!((a - 0.5).abs() < 1e-12 && err < 1e-24, "{a} {err}");
        // Errors in a 2 : 1 ratio, opposite sign: α = 2/3 (1/3·2e − 2/3·e = 0).
        let p2 = &y - &(&e * 0.5);
        let p1 = &y + &e;
        let (a, _) = blend_share(p1.view(), p2.view(), y.view()).unwrap();
        assert!((a - 2.0 / 3.0).abs() < 1e-12, "{a}");
        // The first exact, or the second worse in the same direction: the first alone.
        assert!(blend_share(y.view(), p1.view(), y.view()).is_none());
        let worse = &y + &(&e * 2.0);
        assert!(blend_share(p1.view(), worse.view(), y.view()).is_none());
        // The second exact: all of it (clamped at 1, not beyond).
        let (a, err) = blend_share(p1.view(), y.view(), y.view()).unwrap();
        assert!(a == 1.0 && err < 1e-24, "{a} {err}");
    }

    #[test]
    fn refit_raises_the_ridge_until_the_factorisation_succeeds() {
        // Every centre twice: G is singular, and with relative ridge 0 the factorisation meets
        // a zero (or rounding-negative) pivot. The refit must still return finite weights
        // with a ridge in [start, max]; a ridge that factorises is used as it is.
        let rows = 300;
        let (xs, ys) = sine_rows(rows);
        let centres: Vec<f64> = (0..20)
            .flat_map(|i| {
                let c = -1.0 + 2.0 * i as f64 / 19.0;
                [c, c]
            })
            .collect();
        let basis = Basis {
            n: 1,
            base: vec![0.1; 40],
            centres,
            normalized: false,
            affine: false,
        };
        let yv = ArrayView2::from_shape((rows, 1), &ys).unwrap();
        let (w, r, _) = refit_all(&basis, 1.0, &xs, yv, 0.0, 1e-3).unwrap();
        assert!(w.iter().all(|v| v.is_finite()));
        assert!((0.0..=1e-3).contains(&r), "{r}");
        let (_, r, _) = refit_all(&basis, 1.0, &xs, yv, 1e-6, 1e-3).unwrap();
        assert_eq!(r, 1e-6);
    }
}
