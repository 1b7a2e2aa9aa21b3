//! ISGCS as an off-the-shelf regressor on scattered data (issue 19): defaults that choose
//! everything from the data, on plain slices (the `linfa` feature wraps it).
//!
//! [`Regressor::fit`] runs:
//!
//! 1. **Standardization** of inputs and outputs (zero mean, unit standard deviation per
//!    column), so no input's units dominate the distances.
//!
//! **Input metric** (`metric`, step 1b, default on): recursive expected gradient outer product
//! of pilot networks (100 k-means centres, ≤ 2000 rows): T = E^½ of the pilot's mean gradient
//! outer product, directions floored at 10 %, up to three rounds, the metric with the lowest
//! pilot leave-one-out score kept (identity if none beats it, or if the identity pilot's score
//! is above half the targets' variance: a pilot that misses most of the function has no
//! gradients to learn from); everything below runs on T·x.
//!
//! 2. **Topology and start**: k (when not given) is the number of principal components of the
//!    standardized inputs that carry at least 10 % of the largest component's variance, at most
//!    3 and at most n; the initial k-simplex sits at the mean, vertex i moved by one standard
//!    deviation along principal axis i.
//! 3. **Growth** in rounds, each: λ online ISGCS steps per cell (the unsupervised adaption
//!    of the centres only, [`Isgcs::fit`], rows in shuffled epochs; λ = 10 by default) and two batch USL steps
//!    ([`Isgcs::relax`]: every cell to the mean of the rows it wins) on a sample of 4z + 200 rows;
//!    a least-squares output fit on that sample; each cell's resource τ^SL becomes the summed
//!    squared residual of the rows it wins ([`Isgcs::set_resources`]); then 0.3 z insertions
//!    ([`Isgcs::insert`]: the longest edge of the highest-resource cell is split), in
//!    decreasing order of the measured resource and each cell split at most once per round
//!    (the resources are measured once per round). This is the supervised resource of
//!    sec. 2.4 measured on the least-squares network instead of the slowly converging delta
//!    rule. After growth, ⅓ as many settling steps and five batch USL steps on all rows.
//! 4. **Output layer**: the network's centres with per-cell widths d_i = mean distance to the
//!    n + 1 nearest other centres, times a multiplier μ; the weights by ridge least squares on
//!    every row. Candidates (with `choose_basis`, the default): normalized and plain Gaussians,
//!    each in the learned metric and, when a metric was learned, in the standardized metric at
//!    the same centres mapped back (x = T⁻¹c; the pilots that chose T had fewer centres).
//!    The weights are fitted on the first S = max(3z, 1500) rows (the rows are shuffled, rows
//!    of one input kept together: `group_repeats`) and
//!    scored by their mean squared error on the next min(N − S, 2S) rows (a holdout). With
//!    fewer rows per cell (N < 1.25 S) the last fifth of the rows is held out (S = N − ⌈N/5⌉,
//!    `readout::selection_rows`); below 1000 rows, where that fifth is under 200 rows, the
//!    score is the exact closed-form leave-one-out error mean(e_i/(1 − h_ii))² over all rows
//!    instead, every ridge from one symmetric eigendecomposition of AᵀA
//!    (`linalg::RidgePath`; O(z³) per width, which is why it is not used on more rows). For
//!    each μ the relative ridge in ε…1 (ε = machine epsilon) is the one with the lowest score (one Cholesky solve per
//!    ridge: every second decade, then the best one's neighbours at ±1 decade; at the next μ
//!    of a walk, the previous ridge and ±2 decades; then half decades around the best until
//!    both neighbours are tried). Every candidate is scored at the pilot's multiplier (the
//!    first with the full ridge search, the others in parallel from its ridge as the hint);
//!    the two best then walk μ by √2 (in parallel) while the score falls. The raw Gaussians
//!    of the selection and holdout rows are computed once per geometry and moved along the
//!    walk (μ → √2 μ is an elementwise square root, μ → μ/√2 a square). The
//!    two walked candidates are then **blended**: the prediction (1 − α)·f₁ + α·f₂ of the
//!    best (f₁) and the second (f₂), with the share α ∈ [0, 1] that minimises the squared
//!    error on the holdout rows (one least-squares parameter; stacked regression). Two
//!    output layers of different bases (normalized and plain Gaussians, or two metrics)
//!    err in partly different places, so their blend is more accurate than either when
//!    both are about equally good (measured: `docs/design/isgcs.md`, "The regressor"), and α = 0
//!    leaves the best one alone. Each
//!    layer used is refitted on all rows with its own absolute ridge
//!    (relative ridge × S/N, floored at ε, raised by quarter decades while the
//!    factorisation fails), its Gram matrix that of the selection rows as scored at the
//!    chosen multiplier plus those of the holdout rows (moved raw values) and the remaining
//!    rows. The leave-one-out selection (too few rows for a holdout) does not blend.
//!
//! Cost: growth O(steps · z · n); the output layer O(S · z²) per candidate multiplier (S
//! selection rows; dense matrix products on two threads) plus O(z³/3 + H · z) per candidate
//! ridge (H holdout rows).

pub use crate::data::RegressorError;
use crate::data::check_data;
use crate::kmeans::kmeans;
use crate::readout::{
    Basis, Choice, Readout, Selected, Standardizer, egop, fit_best, fit_fixed, fit_gcv,
    nearest_widths, selection_rows,
};
use crate::{GoalFunction, Isgcs, IsgcsError, Params, Termination};
use ndarray::ArrayView2;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::ops::ControlFlow;

/// Hyperparameters of [`Regressor::fit`]; `None` means chosen from the data.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RegressorParams {
    /// Number of cells (Gaussians) to grow; at least k + 1 and at most the number of rows.
    pub max_cells: usize,
    /// Seed of the row order; equal seeds give equal models.
    pub seed: u64,
    /// Topology dimension k (module docs for the automatic choice).
    pub topology_dim: Option<usize>,
    /// λ: online training steps per cell in each growth round (default 10).
    pub lambda: Option<usize>,
    /// Settling steps after growth, as a multiple of the growth steps (default ⅓).
    pub settle: f64,
    /// Relative ridge (× mean diagonal of AᵀA); `None`: chosen from the data (module docs).
    pub ridge: Option<f64>,
    /// Width multiplier μ on the nearest-centre widths; `None`: chosen from the data (module
    /// docs).
    pub width_multiplier: Option<f64>,
    /// Normalized Gaussians (a partition of unity; bounded extrapolation). Default true.
    pub normalized: bool,
    /// Append the affine columns 1, x₁ … xₙ to the output layer. Default false.
    pub affine: bool,
    /// Fit the output layer with normalized and with plain Gaussians and keep the one with the
    /// lower selection score, module docs step 4 (`normalized` then only applies to the growth
    /// rounds). Default true.
    #[serde(default = "yes")]
    pub choose_basis: bool,
    /// Learn an input metric from the data (module docs, step 1b); the output layer is then
    /// also tried in the standardized metric at the same centres (step 4). Default true.
    #[serde(default = "yes")]
    pub metric: bool,
}

fn yes() -> bool {
    true
}

impl Default for RegressorParams {
    fn default() -> Self {
        Self {
            max_cells: 100,
            seed: 0,
            topology_dim: None,
            lambda: None,
            settle: 1.0 / 3.0,
            ridge: None,
            width_multiplier: None,
            normalized: true,
            affine: false,
            metric: true,
            choose_basis: true,
        }
    }
}

/// How a fit went and what it chose.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct RegressorReport {
    /// The topology dimension used.
    pub topology_dim: usize,
    /// λ used.
    pub lambda: usize,
    /// Training steps of the growth phase.
    pub growth_steps: u64,
    /// Training steps of the settling phase.
    pub settle_steps: u64,
    /// Width multiplier of the output layer.
    pub width_multiplier: f64,
    /// Relative ridge of the output layer.
    pub ridge: f64,
    /// Effective degrees of freedom tr H of the output layer (estimated).
    pub dof: f64,
    /// Share α of the second output layer in a blended fit (module docs, step 4): the
    /// predictions are (1 − α)·first + α·second; 0 when the first layer alone is used.
    #[serde(default)]
    pub blend_share: f64,
}

/// A fitted regressor: the grown network (in standardized input coordinates) and its
/// least-squares output layer. Serde-serializable.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Regressor {
    net: Isgcs,
    readout: Readout,
    report: RegressorReport,
    /// The second output layer of a blend (module docs, step 4).
    #[serde(default)]
    blend: Option<Blend>,
}

/// The second output layer of a blended fit and its share α: predictions are
/// (1 − α)·first + α·second.
#[derive(Clone, Debug, Serialize, Deserialize)]
struct Blend {
    share: f64,
    readout: Readout,
}

/// Training rows in shuffled epochs.
struct Epochs<'a> {
    xs: &'a [f64],
    ys: &'a [f64],
    n: usize,
    m: usize,
    order: Vec<usize>,
    next: usize,
    rng: ChaCha8Rng,
    last: usize,
}

impl GoalFunction for Epochs<'_> {
    fn sample(&mut self, x: &mut [f64]) {
        if self.next == self.order.len() {
            shuffle(&mut self.order, &mut self.rng);
            self.next = 0;
        }
        self.last = self.order[self.next];
        self.next += 1;
        x.copy_from_slice(&self.xs[self.last * self.n..(self.last + 1) * self.n]);
    }

    fn evaluate(&mut self, _x: &[f64], y: &mut [f64]) {
        y.copy_from_slice(&self.ys[self.last * self.m..(self.last + 1) * self.m]);
    }
}

fn shuffle(v: &mut [usize], rng: &mut ChaCha8Rng) {
    for i in (1..v.len()).rev() {
        let j = rng.random_range(0..=i);
        v.swap(i, j);
    }
}

/// The shuffled row `order` with rows of identical inputs moved next to the first of them
/// (otherwise in the same order). The output layer is fitted on a prefix of the rows and
/// scored on the next ones (module docs, step 4): a repeated input on both sides would score
/// the interpolation of its noise as accuracy (docs/design/isgcs.md, "Tried and not kept"). Inputs compare
/// bit for bit (−0 as +0).
fn group_repeats(order: &[usize], inputs: &[f64], n: usize) -> Vec<usize> {
    // ⟨each row's group: the rank of its input's first occurrence in `order`⟩
    let mut first: std::collections::HashMap<Vec<u64>, usize> =
        std::collections::HashMap::with_capacity(order.len());
    let mut rows: Vec<(usize, usize)> = order
        .iter()
        .map(|&r| {
            let key = inputs[r * n..(r + 1) * n]
                .iter()
                .map(|v| (v + 0.0).to_bits())
                .collect();
            let next = first.len();
            (*first.entry(key).or_insert(next), r)
        })
        .collect();
    // A stable sort: the rows of a group keep their shuffled order.
    rows.sort_by_key(|&(group, _)| group);
    rows.into_iter().map(|(_, r)| r).collect()
}

/// Eigenvalues (descending) and eigenvectors (columns of the returned row-major d × d matrix)
/// of a symmetric d × d matrix, by cyclic Jacobi rotations.
fn symmetric_eigen(mut a: Vec<f64>, d: usize) -> (Vec<f64>, Vec<f64>) {
    let mut v = vec![0.0; d * d];
    for i in 0..d {
        v[i * d + i] = 1.0;
    }
    for _sweep in 0..60 {
        let off: f64 = (0..d)
            .flat_map(|i| (0..d).filter(move |&j| j != i).map(move |j| (i, j)))
            .map(|(i, j)| a[i * d + j] * a[i * d + j])
            .sum();
        if off < 1e-22 {
            break;
        }
        for p in 0..d {
            for q in p + 1..d {
                let apq = a[p * d + q];
                if apq.abs() < 1e-300 {
                    continue;
                }
                let theta = (a[q * d + q] - a[p * d + p]) / (2.0 * apq);
                let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
                let t = if theta == 0.0 { 1.0 } else { t };
                let c = 1.0 / (t * t + 1.0).sqrt();
                let s = t * c;
                for k in 0..d {
                    let (akp, akq) = (a[k * d + p], a[k * d + q]);
                    a[k * d + p] = c * akp - s * akq;
                    a[k * d + q] = s * akp + c * akq;
                }
                for k in 0..d {
                    let (apk, aqk) = (a[p * d + k], a[q * d + k]);
                    a[p * d + k] = c * apk - s * aqk;
                    a[q * d + k] = s * apk + c * aqk;
                }
                for k in 0..d {
                    let (vkp, vkq) = (v[k * d + p], v[k * d + q]);
                    v[k * d + p] = c * vkp - s * vkq;
                    v[k * d + q] = s * vkp + c * vkq;
                }
            }
        }
    }
    let mut idx: Vec<usize> = (0..d).collect();
    idx.sort_by(|&i, &j| a[j * d + j].total_cmp(&a[i * d + i]));
    let values = idx.iter().map(|&i| a[i * d + i]).collect();
    let mut vectors = vec![0.0; d * d];
    for (c, &i) in idx.iter().enumerate() {
        for r in 0..d {
            vectors[r * d + c] = v[r * d + i];
        }
    }
    (values, vectors)
}

/// k (module docs) and the initial simplex for standardized inputs (N × n).
pub(crate) fn topology_from_data(xs: &[f64], n: usize, k: Option<usize>) -> (usize, Vec<Vec<f64>>) {
    let rows = (xs.len() / n).max(1) as f64;
    let mut cov = vec![0.0; n * n];
    for r in xs.chunks_exact(n) {
        for i in 0..n {
            for j in 0..n {
                cov[i * n + j] += r[i] * r[j];
            }
        }
    }
    cov.iter_mut().for_each(|c| *c /= rows);
    let (values, vectors) = symmetric_eigen(cov, n);
    let top = values[0].max(1e-12);
    let k = k.unwrap_or_else(|| {
        values
            .iter()
            .filter(|&&l| l >= 0.1 * top)
            .count()
            .clamp(1, 3.min(n))
    });
    let mut simplex = vec![vec![0.0; n]];
    for c in 0..k {
        let sd = values[c].max(0.01 * top).sqrt();
        simplex.push((0..n).map(|r| sd * vectors[r * n + c]).collect());
    }
    (k, simplex)
}

/// x' = T x for every row of `xs` (N × n), T n × n row-major.
fn apply_transform(t: &[f64], xs: &[f64], n: usize) -> Vec<f64> {
    let mut out = vec![0.0; xs.len()];
    for (o, x) in out.chunks_exact_mut(n).zip(xs.chunks_exact(n)) {
        for a in 0..n {
            o[a] = (0..n).map(|b| t[a * n + b] * x[b]).sum();
        }
    }
    out
}

/// The symmetric square root of a positive semi-definite n × n matrix, eigenvalues floored at
/// `floor` × the largest, scaled so that the rows `xs` map to a mean squared norm of n.
fn metric_root(e: &[f64], n: usize, floor: f64, xs: &[f64]) -> Option<Vec<f64>> {
    let (values, vectors) = symmetric_eigen(e.to_vec(), n);
    let top = values[0];
    if !(top > 0.0 && top.is_finite()) {
        return None;
    }
    let roots: Vec<f64> = values
        .iter()
        .map(|&l| l.max(floor * floor * top).sqrt())
        .collect();
    let mut t = vec![0.0; n * n];
    for a in 0..n {
        for b in 0..n {
            t[a * n + b] = (0..n)
                .map(|j| vectors[a * n + j] * roots[j] * vectors[b * n + j])
                .sum();
        }
    }
    let tx = apply_transform(&t, xs, n);
    let rows = (xs.len() / n).max(1) as f64;
    let ms = tx.iter().map(|v| v * v).sum::<f64>() / rows;
    if !(ms > 0.0 && ms.is_finite()) {
        return None;
    }
    let scale = (n as f64 / ms).sqrt();
    t.iter_mut().for_each(|v| *v *= scale);
    Some(t)
}

/// One growth round's insertions (module docs, step 3): up to `add` ISGCS insertions in
/// decreasing order of the measured resources `tau` (one per cell), each cell split at most
/// once. The resources were measured before the round's first split, so a second split of the
/// same cell would act on an error it may no longer have; repeated splits of one cell gave
/// clusters of cells 30× narrower than their neighbours, whose few rows have leverages near 1
/// and spoil the leave-one-out choice of the output layer. When no cell saw any residual, one
/// insertion by the plain ISGCS rule. Returns the split cells in order; `tau` ends with one
/// (zero) entry per new cell.
fn insert_by_resource(
    net: &mut Isgcs,
    tau: &mut Vec<f64>,
    add: usize,
) -> Result<Vec<usize>, IsgcsError> {
    let mut split = Vec::with_capacity(add);
    for _ in 0..add {
        let q = (0..tau.len())
            .max_by(|&a, &b| tau[a].total_cmp(&tau[b]).then(b.cmp(&a)))
            .unwrap_or(0);
        if tau.get(q).is_none_or(|&t| t <= 0.0) {
            break;
        }
        // `insert` splits the highest-resource cell: q.
        net.set_resources(tau)?;
        net.insert();
        split.push(q);
        tau[q] = 0.0;
        tau.push(0.0);
    }
    if split.is_empty() {
        net.set_resources(tau)?;
        net.insert();
        tau.push(0.0);
    }
    Ok(split)
}

/// The inverse of an invertible n × n row-major matrix (`None` when singular).
fn inverse(t: &[f64], n: usize) -> Option<Vec<f64>> {
    let inv = nalgebra::DMatrix::from_row_slice(n, n, t).try_inverse()?;
    Some((0..n * n).map(|i| inv[(i / n, i % n)]).collect())
}

/// Rows of the metric search.
const METRIC_ROWS: usize = 2000;
/// Centres of the metric search's pilot networks.
const METRIC_CELLS: usize = 100;
/// Pilots of the metric search (the first in the identity metric).
const METRIC_ROUNDS: usize = 3;

/// The input metric (module docs, step 2): pilot Gaussian networks (k-means centres, output
/// layer chosen by leave-one-out) in the identity metric and then, recursively, in the metric
/// of the previous pilot's expected gradient outer product; the metric whose pilot has the
/// lowest leave-one-out score wins (`None`: the identity), returned with its pilot's width
/// multiplier (1 when no pilot ran).
fn learn_metric(
    xs: &[f64],
    ys: &[f64],
    n: usize,
    m: usize,
    params: &RegressorParams,
) -> (Option<Vec<f64>>, f64) {
    let rows = xs.len() / n;
    let sample = rows.min(METRIC_ROWS);
    let z0 = params.max_cells.min(METRIC_CELLS).min(sample / 4);
    if z0 < 4 || n < 2 {
        return (None, 1.0);
    }
    let (sx, sy) = (&xs[..sample * n], &ys[..sample * m]);
    let yv = ArrayView2::from_shape((sample, m), sy).expect("shape");
    let mut best: (f64, Option<Vec<f64>>, f64) = (f64::INFINITY, None, 1.0);
    let mut t: Option<Vec<f64>> = None;
    let mut start = 1.0;
    for round in 0..METRIC_ROUNDS {
        let tx = t
            .as_ref()
            .map_or_else(|| sx.to_vec(), |t| apply_transform(t, sx, n));
        let centres = kmeans(&tx, n, z0, 10, params.seed ^ 0x3e7a);
        let basis = Basis {
            n,
            base: nearest_widths(&centres, n, n + 1),
            centres,
            normalized: params.normalized,
            affine: params.affine,
        };
        let Some((weights, sel)) = fit_gcv(&basis, &tx, yv, None, None, sample, start) else {
            break;
        };
        if sel.score.is_nan() || sel.score >= best.0 {
            break;
        }
        start = sel.mult;
        best = (sel.score, t.clone(), sel.mult);
        if round == 0 && sel.score > METRIC_UNRESOLVED {
            // The identity pilot misses most of the function (its leave-one-out error is
            // above half the targets' variance): its gradients are mostly noise, and a metric
            // learned from them distorts the network (a 2-D sine of 5 × 4 periods: 0.95 ×
            // the k-means RBF's rms with the metric, 0.58 without).
            break;
        }
        if round + 1 == METRIC_ROUNDS {
            // No pilot would try the next metric.
            break;
        }
        // E in the original coordinates: ∇ₓf = Tᵀ ∇f(Tx), so E = Tᵀ E' T.
        let e1 = egop(&basis, sel.mult, &weights, m, &tx);
        let e = match &t {
            None => e1,
            Some(t) => {
                let mut e = vec![0.0; n * n];
                for a in 0..n {
                    for b in 0..n {
                        let mut v = 0.0;
                        for p in 0..n {
                            for q in 0..n {
                                v += t[p * n + a] * e1[p * n + q] * t[q * n + b];
                            }
                        }
                        e[a * n + b] = v;
                    }
                }
                e
            }
        };
        let Some(next) = metric_root(&e, n, METRIC_FLOOR, sx) else {
            break;
        };
        t = Some(next);
    }
    (best.1, best.2)
}

/// Width multiplier of the growth rounds' least-squares fits.
const GROWTH_MULT: f64 = 1.5;
/// Relative ridge of the growth rounds' least-squares fits.
const GROWTH_RIDGE: f64 = 1e-6;

/// Smallest scale of a direction in the learned metric, relative to the largest.
const METRIC_FLOOR: f64 = 0.1;

/// The identity pilot's leave-one-out score (mean squared error of the standardized targets,
/// a share of their variance) above which no metric is learned from it.
const METRIC_UNRESOLVED: f64 = 0.5;

/// Refuses parameters out of range for `n` inputs: the topology dimension, λ, the settling
/// share, a given ridge or width multiplier.
fn check_params(params: &RegressorParams, n: usize) -> Result<(), RegressorError> {
    let invalid = |s: String| Err(RegressorError::InvalidParams(s));
    if params.topology_dim == Some(0) || params.topology_dim.is_some_and(|k| k > n) {
        return invalid(format!(
            "topology_dim {:?} must be 1 ≤ k ≤ n = {n}",
            params.topology_dim
        ));
    }
    if params.lambda == Some(0) {
        return invalid("lambda must be at least 1".into());
    }
    if !(params.settle.is_finite() && params.settle >= 0.0) {
        return invalid(format!("settle {} must be finite and >= 0", params.settle));
    }
    if params.ridge.is_some_and(|r| !(r.is_finite() && r >= 0.0)) {
        return invalid(format!("ridge {:?} must be finite and >= 0", params.ridge));
    }
    if params
        .width_multiplier
        .is_some_and(|w| !(w.is_finite() && w > 0.0))
    {
        return invalid(format!(
            "width_multiplier {:?} must be finite and > 0",
            params.width_multiplier
        ));
    }
    Ok(())
}

/// The training rows (module docs, step 1): inputs and targets standardized and in one
/// shuffled order (rows of one input kept together: [`group_repeats`]), with their
/// standardizers and the random stream, which goes on to shuffle the growth's epochs.
struct Rows {
    xstd: Standardizer,
    ystd: Standardizer,
    /// Standardized inputs, N × n, shuffled.
    xs: Vec<f64>,
    /// Standardized targets, N × m, in the same order.
    ys: Vec<f64>,
    rng: ChaCha8Rng,
}

impl Rows {
    /// Standardizes `inputs` (N × n) and `targets` (N × m) and shuffles their `rows` rows once
    /// with `seed` (the output layer's selection uses a prefix of them).
    fn shuffled(
        inputs: &[f64],
        targets: &[f64],
        n: usize,
        m: usize,
        rows: usize,
        seed: u64,
    ) -> Self {
        let xstd = Standardizer::of(inputs, n);
        let ystd = Standardizer::of(targets, m);
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut order: Vec<usize> = (0..rows).collect();
        shuffle(&mut order, &mut rng);
        let order = group_repeats(&order, inputs, n);
        let permute = |data: &[f64], d: usize| -> Vec<f64> {
            order
                .iter()
                .flat_map(|&r| data[r * d..(r + 1) * d].iter().copied())
                .collect()
        };
        let xs = xstd.apply(&permute(inputs, n));
        let ys = ystd.apply(&permute(targets, m));
        Self {
            xstd,
            ystd,
            xs,
            ys,
            rng,
        }
    }
}

/// The standardized inputs in the learned metric (module docs, step 1b).
struct InMetric {
    /// The rows T·x (the standardized rows when no metric was learned).
    xs: Vec<f64>,
    /// The standardized rows, for the output layer's candidates in the standardized metric
    /// (empty when no metric was learned).
    xs_plain: Vec<f64>,
    /// T (n × n row-major), `None`: the identity.
    transform: Option<Vec<f64>>,
    /// The metric pilot's width multiplier, where the output layer's walks start.
    pilot_mult: f64,
}

impl InMetric {
    /// Learns the metric from the standardized rows `xs` and targets `ys` ([`learn_metric`],
    /// when `params.metric`) and maps the rows into it.
    fn learn(xs: Vec<f64>, ys: &[f64], n: usize, m: usize, params: &RegressorParams) -> Self {
        let (transform, pilot_mult) = if params.metric {
            learn_metric(&xs, ys, n, m, params)
        } else {
            (None, 1.0)
        };
        // The standardized rows are kept for the identity-metric readout candidate.
        let (xs, xs_plain) = match &transform {
            Some(t) => (apply_transform(t, &xs, n), xs),
            None => (xs, Vec::new()),
        };
        Self {
            xs,
            xs_plain,
            transform,
            pilot_mult,
        }
    }
}

impl Epochs<'_> {
    /// `steps` online ISGCS steps of `net` on the rows (none when 0).
    fn train(&mut self, net: &mut Isgcs, steps: u64) -> Result<(), IsgcsError> {
        let go_on = |_: &Isgcs, _: &crate::Event| ControlFlow::Continue(());
        if steps > 0 {
            net.fit(
                self,
                &Termination {
                    max_steps: Some(steps),
                    ..Termination::default()
                },
                go_on,
            )?;
        }
        Ok(())
    }
}

/// The Gaussians at the cells of `net` (n inputs): widths from the n + 1 nearest other
/// centres, normalized and affine as `params` say.
fn cell_basis(net: &Isgcs, n: usize, params: &RegressorParams) -> Basis {
    let z = net.len();
    let centres: Vec<f64> = (0..z).flat_map(|i| net.centre(i).to_vec()).collect();
    Basis {
        n,
        base: nearest_widths(&centres, n, n + 1),
        centres,
        normalized: params.normalized,
        affine: params.affine,
    }
}

/// The grown network and how it grew (module docs, steps 2 and 3).
struct Grown {
    net: Isgcs,
    /// The topology dimension k.
    k: usize,
    lambda: usize,
    growth_steps: u64,
    settle_steps: u64,
}

/// Batch USL steps of each growth round, and after the settling steps.
const RELAX_ROUNDS: (usize, usize) = (2, 5);

/// Module docs, steps 2 and 3, on the rows `xs` (in the metric) and targets `ys`: the topology
/// and initial simplex, growth rounds ([`growth_round`]) up to `params.max_cells` cells, then
/// the settling steps and five batch steps on all rows. `rng` shuffles the epochs.
fn grow(
    params: &RegressorParams,
    xs: &[f64],
    ys: &[f64],
    n: usize,
    m: usize,
    rng: ChaCha8Rng,
) -> Result<Grown, RegressorError> {
    let rows = xs.len() / n;
    let (k, simplex) = topology_from_data(xs, n, params.topology_dim);
    if params.max_cells < k + 1 || params.max_cells > rows {
        return Err(RegressorError::CellBudget {
            cells: params.max_cells,
            min: k + 1,
            max: rows,
        });
    }
    let lambda = params.lambda.unwrap_or(10);
    let net_params = Params {
        lambda,
        ..Params::accurate()
    };
    let mut net = Isgcs::new(net_params, n, m, k, simplex)?;
    net.set_growing(false);
    // Only the centres are trained: the output layer is fitted by least squares and the
    // resources are set from its residuals (the delta rule's outputs were never used).
    net.set_unsupervised_only(true);
    let mut epochs = Epochs {
        xs,
        ys,
        n,
        m,
        order: (0..rows).collect(),
        next: rows,
        rng,
        last: 0,
    };
    let mut tau = vec![0.0; 0];
    while net.len() < params.max_cells {
        growth_round(&mut net, &mut epochs, &mut tau, params, lambda)?;
    }
    let growth_steps = net.steps();
    let settle_steps = (growth_steps as f64 * params.settle).round() as u64;
    epochs.train(&mut net, settle_steps)?;
    net.relax(xs, RELAX_ROUNDS.1)?;
    Ok(Grown {
        net,
        k,
        lambda,
        growth_steps,
        settle_steps,
    })
}

/// One growth round (module docs, step 3): adapt (λ online steps per cell, then two batch
/// steps), fit the output layer by least squares on a sample of rows, make each cell's
/// resource `tau` the squared residuals of its rows ([`residual_resources`]), and insert 30 %
/// more cells (at most up to `params.max_cells`) where that resource is largest
/// ([`insert_by_resource`]).
fn growth_round(
    net: &mut Isgcs,
    epochs: &mut Epochs,
    tau: &mut Vec<f64>,
    params: &RegressorParams,
    lambda: usize,
) -> Result<(), IsgcsError> {
    let (xs, n) = (epochs.xs, epochs.n);
    let rows = xs.len() / n;
    let z = net.len();
    epochs.train(net, (lambda * z) as u64)?;
    let sample = rows.min(4 * z + 200);
    net.relax(&xs[..sample * n], RELAX_ROUNDS.0)?;
    residual_resources(net, epochs, params, sample, tau);
    let add = (z * 3 / 10).max(1).min(params.max_cells - z);
    insert_by_resource(net, tau, add)?;
    Ok(())
}

/// Each cell's resource τ^SL into `tau` (one entry per cell of `net`): the summed squared
/// residuals of the rows it wins among the first `sample` rows of `epochs`, under a least-squares
/// output layer fitted on those rows ([`GROWTH_MULT`], [`GROWTH_RIDGE`]); all 0 when that fit
/// fails.
fn residual_resources(
    net: &Isgcs,
    epochs: &Epochs,
    params: &RegressorParams,
    sample: usize,
    tau: &mut Vec<f64>,
) {
    let (xs, ys, n, m) = (epochs.xs, epochs.ys, epochs.n, epochs.m);
    let z = net.len();
    let basis = cell_basis(net, n, params);
    let yv = ArrayView2::from_shape((sample, m), &ys[..sample * m]).expect("shape");
    let fitted = fit_fixed(&basis, GROWTH_MULT, GROWTH_RIDGE, &xs[..sample * n], yv);
    tau.clear();
    tau.resize(z, 0.0);
    if let Some((_, pred)) = fitted {
        let bmus: Vec<usize> = xs[..sample * n]
            .par_chunks(n)
            .with_min_len(64)
            .map(|x| net.bmu(x, None))
            .collect();
        for (r, &bmu) in bmus.iter().enumerate() {
            let e: f64 = (0..m).map(|c| (pred[[r, c]] - ys[r * m + c]).powi(2)).sum();
            tau[bmu] += e;
        }
    }
}

/// The output layer's candidate bases (module docs, step 4), each with whether it is in the
/// learned metric: normalized and plain Gaussians (unless `params.choose_basis` is off: only
/// `params.normalized`) at the network's cells `basis`, and, when a metric T was learned (and
/// inverts), the same kinds at the same centres mapped back (x = T⁻¹c) in the standardized
/// metric.
fn output_bases(
    basis: Basis,
    params: &RegressorParams,
    transform: Option<&[f64]>,
    n: usize,
) -> Vec<(Basis, bool)> {
    let kinds: &[bool] = if params.choose_basis {
        &[true, false]
    } else {
        std::slice::from_ref(&params.normalized)
    };
    // The metric was chosen by small pilots; at the model's size the standardized metric
    // can be better (more cells resolve the weak directions too): the same centres, mapped
    // back (x = T⁻¹ c), are candidates in the standardized metric as well.
    let t_inv = transform.and_then(|t| inverse(t, n));
    let back = t_inv.as_ref().map(|t_inv| {
        let centres = apply_transform(t_inv, &basis.centres, n);
        Basis {
            base: nearest_widths(&centres, n, n + 1),
            centres,
            ..basis.clone()
        }
    });
    let mut bases: Vec<(Basis, bool)> = Vec::new();
    for (geometry, in_metric) in [(Some(&basis), true), (back.as_ref(), false)] {
        if let Some(g) = geometry {
            for &normalized in kinds {
                let b = Basis {
                    normalized,
                    ..g.clone()
                };
                bases.push((b, in_metric));
            }
        }
    }
    bases
}

/// The output layer among the candidate `bases` ([`fit_best`]; module docs, step 4) on the
/// rows of `metric` (each candidate's in its metric) and the standardized targets `ys` (× m),
/// selected on the first `select_rows` rows; an error says why none could be fitted.
fn select_output_layer(
    bases: &[(Basis, bool)],
    metric: &InMetric,
    ys: &[f64],
    m: usize,
    select_rows: usize,
    params: &RegressorParams,
) -> Result<Choice, RegressorError> {
    let rows = ys.len() / m;
    let yv = ArrayView2::from_shape((rows, m), ys).expect("shape checked");
    // Normalized and plain Gaussians (unless fixed), in the learned and the standardized
    // metric: the lowest score (holdout, or leave-one-out below 1000 rows; module docs,
    // step 4) wins; the walks start at the metric pilot's multiplier.
    let (xs, xs_plain) = (&metric.xs, &metric.xs_plain);
    let candidates: Vec<(&Basis, &[f64])> = bases
        .iter()
        .map(|(b, in_metric)| (b, if *in_metric { &xs[..] } else { &xs_plain[..] }))
        .collect();
    fit_best(
        &candidates,
        yv,
        params.width_multiplier,
        params.ridge,
        select_rows,
        metric.pilot_mult,
    )
    .ok_or_else(|| {
        RegressorError::Solve(match params.ridge {
            // A fixed ridge is used as given: below the rounding level of AᵀA the
            // Cholesky factorisation meets a non-positive pivot.
            Some(r) => format!(
                "the normal equations AᵀA + ρI are not positive definite at the fixed \
                 relative ridge {r:e} (the Cholesky factorisation failed); use a larger \
                 ridge, or leave it unset to choose it from the data"
            ),
            None => "no ridge factorised the normal equations, or no row activates any \
                     cell"
                .into(),
        })
    })
}

impl Regressor {
    /// Fits N rows: `inputs` N × n and `targets` N × m, row-major (module docs).
    pub fn fit(
        params: &RegressorParams,
        inputs: &[f64],
        targets: &[f64],
        n: usize,
        m: usize,
    ) -> Result<Self, RegressorError> {
        let rows = check_data(inputs, targets, n, m)?;
        check_params(params, n)?;
        // ⟨1. Standardize, and shuffle the rows once (the output layer's selection uses a
        // prefix)⟩
        let data = Rows::shuffled(inputs, targets, n, m, rows, params.seed);
        // ⟨1b. The input metric⟩
        let metric = InMetric::learn(data.xs, &data.ys, n, m, params);
        // ⟨2, 3. Topology and start, growth, settling⟩
        let grown = grow(params, &metric.xs, &data.ys, n, m, data.rng)?;
        // ⟨4. The output layer: its candidates, the selection, the readouts⟩
        let basis = cell_basis(&grown.net, n, params);
        let select_rows = selection_rows(rows, basis.cols());
        let bases = output_bases(basis, params, metric.transform.as_deref(), n);
        let (index, weights, chosen, partner) =
            select_output_layer(&bases, &metric, &data.ys, m, select_rows, params)?;
        let readout_of = |index: usize, weights: Vec<f64>, chosen: &Selected| {
            let (basis, in_metric) = bases[index].clone();
            Readout {
                basis,
                mult: chosen.mult,
                weights,
                m,
                x: data.xstd.clone(),
                y: data.ystd.clone(),
                ridge: chosen.ridge,
                transform: if in_metric {
                    metric.transform.clone()
                } else {
                    None
                },
            }
        };
        let readout = readout_of(index, weights, &chosen);
        let blend = partner.map(|((i, w, c), share)| Blend {
            share,
            readout: readout_of(i, w, &c),
        });
        let blend_share = blend.as_ref().map_or(0.0, |b| b.share);
        Ok(Self {
            net: grown.net,
            readout,
            blend,
            report: RegressorReport {
                topology_dim: grown.k,
                lambda: grown.lambda,
                growth_steps: grown.growth_steps,
                settle_steps: grown.settle_steps,
                width_multiplier: chosen.mult,
                ridge: chosen.ridge,
                dof: chosen.dof,
                blend_share,
            },
        })
    }

    /// Predictions for N inputs (N × n row-major) into `out` (N × m), in parallel. Errors on
    /// lengths that do not fit; rows with a non-finite input get NaN.
    pub fn predict(&self, inputs: &[f64], out: &mut [f64]) -> Result<(), RegressorError> {
        let (n, m) = (self.input_dim(), self.output_dim());
        if inputs.len() % n != 0 || out.len() != inputs.len() / n * m {
            return Err(RegressorError::Shape(format!(
                "predict: {} input numbers are not N × {n}, or {} outputs not N × {m}",
                inputs.len(),
                out.len()
            )));
        }
        match &self.blend {
            Some(b) => self.readout.predict_blend(&b.readout, b.share, inputs, out),
            None => self.readout.predict(inputs, out),
        }
        Ok(())
    }

    /// Input dimension n.
    pub fn input_dim(&self) -> usize {
        self.readout.basis.n
    }

    /// Output dimension m.
    pub fn output_dim(&self) -> usize {
        self.readout.m
    }

    /// Number of cells (Gaussians).
    pub fn len(&self) -> usize {
        self.readout.basis.cells()
    }

    /// Always false (a fit has at least k + 1 cells).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The grown network, in standardized input coordinates (only its centres and topology
    /// are trained: its own outputs stay at 0 and its resources are the last growth round's;
    /// predictions use the least-squares layer).
    pub fn network(&self) -> &Isgcs {
        &self.net
    }

    /// What the fit chose.
    pub fn report(&self) -> &RegressorReport {
        &self.report
    }

    /// Per-cell widths of the output layer, in standardized input units.
    pub fn widths(&self) -> Vec<f64> {
        self.readout
            .basis
            .base
            .iter()
            .map(|b| b * self.readout.mult)
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A k = 2 network in the plane with `cells` cells (grown by plain ISGCS insertions).
    fn sheet(cells: usize) -> Isgcs {
        let simplex = vec![vec![0.0, 0.0], vec![1.0, 0.0], vec![0.0, 1.0]];
        let mut net = Isgcs::new(Params::accurate(), 2, 1, 2, simplex).unwrap();
        while net.len() < cells {
            let tau: Vec<f64> = (0..net.len()).map(|i| 1.0 + i as f64).collect();
            net.set_resources(&tau).unwrap();
            net.insert();
        }
        net
    }

    #[test]
    fn a_round_splits_each_cell_at_most_once_in_resource_order() {
        // One cell with a resource far above the others: the plain ISGCS rule (resource shared
        // 2/3 : 1/3 per split) would split it several times in one round; a round splits it
        // once, then the next cells by resource.
        let mut net = sheet(8);
        let z = net.len();
        let mut tau = vec![1.0; z];
        tau[3] = 1000.0;
        tau[5] = 2.0;
        tau[6] = 3.0;
        let split = insert_by_resource(&mut net, &mut tau, 3).unwrap();
        assert_eq!(split, vec![3, 6, 5]);
        assert_eq!(net.len(), z + 3);
        assert_eq!(tau.len(), z + 3);
        // Each new cell is a neighbour of the cell that was split for it.
        for (new, &q) in (z..z + 3).zip(&split) {
            assert!(
                net.neighbours(new).contains(&(q as u32)),
                "{new} not next to {q}"
            );
        }
        // The reference: the plain rule on the same resources splits cell 3 again.
        let mut plain = sheet(8);
        let mut tau = vec![1.0; z];
        tau[3] = 1000.0;
        plain.set_resources(&tau).unwrap();
        for _ in 0..3 {
            plain.insert();
        }
        let again = (z..z + 3)
            .filter(|&c| plain.neighbours(c).contains(&3))
            .count();
        assert!(again >= 2, "the plain rule split cell 3 only {again} times");
    }

    #[test]
    fn a_round_without_residuals_still_grows() {
        let mut net = sheet(5);
        let mut tau = vec![0.0; 5];
        assert!(
            insert_by_resource(&mut net, &mut tau, 2)
                .unwrap()
                .is_empty()
        );
        assert_eq!((net.len(), tau.len()), (6, 6));
    }

    #[test]
    fn repeated_inputs_are_grouped_and_the_rest_keep_their_order() {
        // Rows 0 and 3 share an input (as do 1 and 4, written with −0); 2 and 5 are unique.
        let inputs = [1.0, 2.0, 0.0, 5.0, 3.0, 3.0, 1.0, 2.0, -0.0, 5.0, 4.0, 4.0];
        let order = [5, 3, 2, 1, 0, 4];
        assert_eq!(group_repeats(&order, &inputs, 2), vec![5, 3, 0, 2, 1, 4]);
        let distinct = [0.0, 1.0, 2.0, 3.0];
        assert_eq!(group_repeats(&[2, 0, 3, 1], &distinct, 1), vec![2, 0, 3, 1]);
    }

    #[test]
    fn no_metric_is_learned_from_a_pilot_that_misses_the_function() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let xs: Vec<f64> = (0..2 * 2000).map(|_| rng.random::<f64>()).collect();
        let tau = std::f64::consts::TAU;
        let metric_of = |f: &dyn Fn(&[f64]) -> f64| {
            let ys: Vec<f64> = xs.chunks(2).map(f).collect();
            let xs = Standardizer::of(&xs, 2).apply(&xs);
            let ys = Standardizer::of(&ys, 1).apply(&ys);
            let params = RegressorParams {
                max_cells: 300,
                ..RegressorParams::default()
            };
            learn_metric(&xs, &ys, 2, 1, &params).0
        };
        // 5 × 4 periods: the 100-cell identity pilot leaves most of the variance.
        assert!(metric_of(&|x| (tau * 5.0 * x[0]).sin() * (tau * 4.0 * x[1]).sin()).is_none());
        // Resolved and anisotropic (x₁ barely matters): a metric is learned.
        assert!(metric_of(&|x| (3.0 * x[0]).sin() + 0.01 * x[1]).is_some());
    }

    #[test]
    fn inverse_inverts() {
        let t = [2.0, 1.0, 0.0, 1.0, 3.0, 0.5, 0.0, 0.5, 1.0];
        let inv = inverse(&t, 3).unwrap();
        for a in 0..3 {
            for b in 0..3 {
                let v: f64 = (0..3).map(|j| t[a * 3 + j] * inv[j * 3 + b]).sum();
                assert!((v - f64::from(u8::from(a == b))).abs() < 1e-12);
            }
        }
        assert!(inverse(&[1.0, 2.0, 2.0, 4.0], 2).is_none());
    }
}
