//! Dense symmetric positive-definite solves for the least-squares output fits.

use ndarray::linalg::general_mat_mul;
use ndarray::{Array2, ArrayView2, Axis, Slice};

/// Solves (G + ρ·I) X = B in place for a symmetric positive semi-definite z×z matrix `g`
/// (row-major, only the lower triangle is read) and `b` (z×m row-major, overwritten with X),
/// by a Cholesky factorisation. The ridge ρ = `ridge` × mean diagonal of G is retried ten times
/// larger while the factorisation meets a non-positive pivot; returns the ridge used, or `None`
/// if G has no positive diagonal or the factorisation never succeeded.
pub(crate) fn ridge_solve(g: &[f64], z: usize, b: &mut [f64], m: usize, ridge: f64) -> Option<f64> {
    debug_assert_eq!(g.len(), z * z);
    debug_assert_eq!(b.len(), z * m);
    let mean_diag = (0..z).map(|i| g[i * z + i]).sum::<f64>() / z.max(1) as f64;
    if !(mean_diag > 0.0 && mean_diag.is_finite()) {
        return None;
    }
    let mut rho = ridge.max(f64::EPSILON) * mean_diag;
    for _ in 0..12 {
        if let Some(l) = cholesky(g, z, rho) {
            // Forward then backward substitution, every right-hand side at once.
            for i in 0..z {
                for c in 0..m {
                    let mut s = b[i * m + c];
                    for k in 0..i {
                        s -= l[i * z + k] * b[k * m + c];
                    }
                    b[i * m + c] = s / l[i * z + i];
                }
            }
            for i in (0..z).rev() {
                for c in 0..m {
                    let mut s = b[i * m + c];
                    for k in i + 1..z {
                        s -= l[k * z + i] * b[k * m + c];
                    }
                    b[i * m + c] = s / l[i * z + i];
                }
            }
            return Some(rho / mean_diag);
        }
        rho *= 10.0;
    }
    None
}

/// Lower Cholesky factor of G + ρ·I (row-major), or `None` at a non-positive pivot.
fn cholesky(g: &[f64], z: usize, rho: f64) -> Option<Vec<f64>> {
    let mut l = vec![0.0; z * z];
    for i in 0..z {
        for j in 0..=i {
            let (ri, rj) = (&l[i * z..i * z + j], &l[j * z..j * z + j]);
            let dot: f64 = ri.iter().zip(rj).map(|(a, b)| a * b).sum();
            let mut s = g[i * z + j] - dot;
            if i == j {
                s += rho;
                if s.is_nan() || s <= 0.0 {
                    return None;
                }
                l[i * z + i] = s.sqrt();
            } else {
                l[i * z + j] = s / l[j * z + j];
            }
        }
    }
    Some(l)
}

/// A W for a matrix A and a W with few columns: one matrix-vector product per column of W
/// (ndarray's unrolled row dot products) instead of a general matrix product, which packs
/// all of A and pads W's columns to the kernel's width (most of the product's time for one
/// column: the holdout predictions and G W of every candidate ridge).
pub(crate) fn mul_few(a: ArrayView2<'_, f64>, w: ArrayView2<'_, f64>) -> Array2<f64> {
    if w.ncols() > FEW {
        return a.dot(&w);
    }
    let mut out = Array2::zeros((a.nrows(), w.ncols()));
    for (mut o, c) in out.columns_mut().into_iter().zip(w.columns()) {
        o.assign(&a.dot(&c));
    }
    out
}

/// Right-hand sides up to which [`mul_few`] and the triangular solves work column by column.
const FEW: usize = 4;

/// Block size of the blocked Cholesky factorisation.
const BLOCK: usize = 64;

/// Column block of [`gram_add`]'s lower-triangle products.
const GRAM_BLOCK: usize = 128;

/// G += AᵀA for a dense block A (rows × z). Only the blocks on and below the diagonal are
/// multiplied (blocks of [`GRAM_BLOCK`] columns, spread over the rayon threads; about half
/// the multiply-adds of the full product for large z) and mirrored into the upper triangle.
pub(crate) fn gram_add(a: ArrayView2<'_, f64>, g: &mut Array2<f64>) {
    gram_into(a, g, true);
}

/// AᵀA for a dense block A (rows × z), as [`gram_add`] but written into fresh memory: the
/// zeroed pages of a new matrix are not read first (reading them maps the shared zero page,
/// and the write after it faults again to copy it, flushing the other threads' address
/// translations: a tenth of a 1000-cell selection's time went to that).
pub(crate) fn gram(a: ArrayView2<'_, f64>) -> Array2<f64> {
    let mut g = Array2::zeros((a.ncols(), a.ncols()));
    gram_into(a, &mut g, false);
    g
}

/// G += AᵀA (`add`) or G = AᵀA, blocked as [`gram_add`] describes.
fn gram_into(a: ArrayView2<'_, f64>, g: &mut Array2<f64>, add: bool) {
    use rayon::prelude::*;
    let z = a.ncols();
    let blocks = z.div_ceil(GRAM_BLOCK);
    if blocks <= 1 {
        general_mat_mul(1.0, &a.t(), &a, if add { 1.0 } else { 0.0 }, g);
        return;
    }
    let pairs: Vec<(usize, usize)> = (0..blocks)
        .flat_map(|i| (0..=i).map(move |j| (i, j)))
        .collect();
    let cols = |b: usize| Slice::from(b * GRAM_BLOCK..((b + 1) * GRAM_BLOCK).min(z));
    let products: Vec<Array2<f64>> = pairs
        .par_iter()
        .map(|&(i, j)| {
            let ai = a.slice_axis(Axis(1), cols(i));
            let aj = a.slice_axis(Axis(1), cols(j));
            ai.t().dot(&aj)
        })
        .collect();
    for (&(i, j), p) in pairs.iter().zip(&products) {
        let mut lower = g.slice_axis_mut(Axis(0), cols(i));
        let mut lower = lower.slice_axis_mut(Axis(1), cols(j));
        if add {
            lower += p;
        } else {
            lower.assign(p);
        }
        if i != j {
            let mut upper = g.slice_axis_mut(Axis(0), cols(j));
            let mut upper = upper.slice_axis_mut(Axis(1), cols(i));
            if add {
                upper += &p.t();
            } else {
                upper.assign(&p.t());
            }
        }
    }
}

/// The diagonal block `rows` of a blocked Cholesky factorization of the z × z row-major `data`
/// (its columns `rows` already updated by the blocks before), unblocked. Rows as slices: the same
/// operations in the same order as indexing, without the bounds checks. `false` at a
/// non-positive or NaN pivot.
fn factor_diagonal_block(data: &mut [f64], z: usize, rows: std::ops::Range<usize>) -> bool {
    let k0 = rows.start;
    for i in rows {
        let (head, tail) = data.split_at_mut(i * z);
        let ri = &mut tail[..z];
        for j in k0..=i {
            let rj: &[f64] = if j == i {
                &[]
            } else {
                &head[j * z..(j + 1) * z]
            };
            let mut s = ri[j];
            for p in k0..j {
                s -= ri[p] * if j == i { ri[p] } else { rj[p] };
            }
            if i == j {
                if s.is_nan() || s <= 0.0 {
                    return false;
                }
                ri[i] = s.sqrt();
            } else {
                ri[j] = s / rj[j];
            }
        }
    }
    true
}

/// In-place lower Cholesky factor of the symmetric matrix `a` plus `rho`·I (the lower triangle
/// is read; the strict upper triangle is left unspecified). Blocked right-looking: the
/// diagonal block by substitution, the panel below it by substitution in groups of rows that
/// share the vector lanes ([`PanelRows`]; groups in parallel), the trailing update of the
/// lower triangle only by matrix products on column blocks (in parallel). `false` at a
/// non-positive or NaN pivot.
pub(crate) fn cholesky_in_place(a: &mut Array2<f64>, rho: f64) -> bool {
    use rayon::prelude::*;
    let z = a.nrows();
    if a.as_slice().is_none() {
        *a = a.as_standard_layout().into_owned();
    }
    for i in 0..z {
        a[[i, i]] += rho;
    }
    let mut lt = vec![0.0; BLOCK * BLOCK];
    let mut k0 = 0;
    while k0 < z {
        let k1 = (k0 + BLOCK).min(z);
        let bw = k1 - k0;
        if !factor_diagonal_block(a.as_slice_mut().expect("standard layout"), z, k0..k1) {
            return false;
        }
        if k1 == z {
            break;
        }
        // Panel L21 = A21 L11⁻ᵀ by substitution, groups of rows side by side ([`PanelRows`]);
        // L11ᵀ into `lt` first (its rows contiguous).
        {
            let data = a.as_slice_mut().expect("standard layout");
            for p in 0..bw {
                for j in 0..bw {
                    lt[p * BLOCK + j] = if j > p {
                        data[(k0 + j) * z + k0 + p]
                    } else {
                        0.0
                    };
                }
            }
        }
        let diag: Vec<f64> = (k0..k1).map(|j| a[[j, j]]).collect();
        {
            let data = a.as_slice_mut().expect("standard layout");
            let (_, bottom) = data.split_at_mut(k1 * z);
            let (lt, diag) = (&lt[..], &diag[..]);
            bottom
                .par_chunks_mut(PANEL_ROWS * z)
                .with_min_len(4)
                .for_each(|group| {
                    pulp::Arch::new().dispatch(PanelRows {
                        group,
                        z,
                        cols: k0..k1,
                        lt,
                        diag,
                    })
                });
        }
        // Trailing update A22 −= L21 L21ᵀ, lower triangle only: column block c gets the rows
        // from its own first row down.
        let l21 = a
            .slice_axis(Axis(0), Slice::from(k1..))
            .slice_axis(Axis(1), Slice::from(k0..k1))
            .to_owned();
        let mut a22 = a.slice_axis_mut(Axis(0), Slice::from(k1..));
        let mut a22 = a22.slice_axis_mut(Axis(1), Slice::from(k1..));
        let mut cols: Vec<(usize, ndarray::ArrayViewMut2<'_, f64>)> = a22
            .axis_chunks_iter_mut(Axis(1), TRAIL_BLOCK)
            .enumerate()
            .map(|(c, v)| (c * TRAIL_BLOCK, v))
            .collect();
        cols.par_iter_mut().for_each(|(c0, v)| {
            let w = v.ncols();
            let mut below = v.slice_axis_mut(Axis(0), Slice::from(*c0..));
            let lrows = l21.slice_axis(Axis(0), Slice::from(*c0..));
            let lcols = l21.slice_axis(Axis(0), Slice::from(*c0..*c0 + w));
            general_mat_mul(-1.0, &lrows, &lcols.t(), 1.0, &mut below);
        });
        k0 = k1;
    }
    true
}

/// Rows of a [`PanelRows`] group: the lanes of its vector operations.
const PANEL_ROWS: usize = 8;

/// Up to [`PANEL_ROWS`] consecutive rows of a Cholesky panel (`group`, row-major with `z`
/// columns) solved against the diagonal block's factor on the columns `cols`: entry j of a
/// row becomes (a_j − Σ_{p<j} l_p L11[j][p]) / L11[j][j], p ascending, computed as l_p final
/// and then subtracted from every later entry (`lt` holds L11ᵀ, rows of BLOCK; `diag` the
/// diagonal). The rows sit side by side in the vector lanes (one division and one update per
/// lane for all of them), so each entry gets the same operations in the same order as row by
/// row, without waiting on its own row's division chain; `pulp` compiles it for the
/// processor's vector unit.
struct PanelRows<'a> {
    group: &'a mut [f64],
    z: usize,
    cols: std::ops::Range<usize>,
    lt: &'a [f64],
    diag: &'a [f64],
}

impl pulp::WithSimd for PanelRows<'_> {
    type Output = ();

    #[inline(always)]
    fn with_simd<S: pulp::Simd>(self, _: S) {
        let Self {
            group,
            z,
            cols,
            lt,
            diag,
        } = self;
        let (k0, bw) = (cols.start, cols.len());
        let rows = group.len() / z;
        // r[j][q]: column j of the block, row q of the group.
        let mut r = [[0.0f64; PANEL_ROWS]; BLOCK];
        for q in 0..rows {
            for (j, rj) in r.iter_mut().enumerate().take(bw) {
                rj[q] = group[q * z + k0 + j];
            }
        }
        for p in 0..bw {
            let d = diag[p];
            let mut l = r[p];
            for v in l.iter_mut() {
                *v /= d;
            }
            r[p] = l;
            for (j, rj) in r.iter_mut().enumerate().take(bw).skip(p + 1) {
                let t = lt[p * BLOCK + j];
                for (v, l) in rj.iter_mut().zip(&l) {
                    *v -= l * t;
                }
            }
        }
        for q in 0..rows {
            for (j, rj) in r.iter().enumerate().take(bw) {
                group[q * z + k0 + j] = rj[q];
            }
        }
    }
}

/// Column block of [`cholesky_in_place`]'s trailing update.
const TRAIL_BLOCK: usize = 128;

/// Solves L X = B in place (L lower triangular from [`cholesky_in_place`], B z × c), blocked:
/// the off-diagonal blocks by matrix products, the diagonal blocks by substitution.
pub(crate) fn forward(l: &Array2<f64>, b: &mut Array2<f64>) {
    let z = l.nrows();
    let c = b.ncols();
    if let (true, Some(ld)) = (c <= FEW, l.as_slice()) {
        // Column by column: row i of L against the solved head (unrolled dot products),
        // instead of packing L's blocks for a one-column product.
        for mut col in b.columns_mut() {
            let mut x = col.to_vec();
            for i in 0..z {
                let row = ndarray::ArrayView1::from(&ld[i * z..i * z + i]);
                let s = x[i] - row.dot(&ndarray::ArrayView1::from(&x[..i]));
                x[i] = s / l[[i, i]];
            }
            col.assign(&ndarray::ArrayView1::from(&x[..]));
        }
        return;
    }
    if b.as_slice().is_none() {
        *b = b.as_standard_layout().into_owned();
    }
    let mut k0 = 0;
    while k0 < z {
        let k1 = (k0 + BLOCK).min(z);
        if k0 > 0 {
            let whole = b.view_mut();
            let (done, mut rest) = whole.split_at(Axis(0), k0);
            let mut blk = rest.slice_axis_mut(Axis(0), Slice::from(..k1 - k0));
            let lrows = l.slice_axis(Axis(0), Slice::from(k0..k1));
            let lblk = lrows.slice_axis(Axis(1), Slice::from(..k0));
            general_mat_mul(-1.0, &lblk, &done, 1.0, &mut blk);
        }
        let bs = b.as_slice_mut().expect("standard layout");
        for i in k0..k1 {
            let (head, tail) = bs.split_at_mut(i * c);
            let row = &mut tail[..c];
            for p in k0..i {
                let lip = l[[i, p]];
                if lip != 0.0 {
                    for (r, d) in row.iter_mut().zip(&head[p * c..(p + 1) * c]) {
                        *r -= lip * d;
                    }
                }
            }
            let inv = 1.0 / l[[i, i]];
            row.iter_mut().for_each(|r| *r *= inv);
        }
        k0 = k1;
    }
}

/// Solves Lᵀ X = B in place, blocked like [`forward`].
pub(crate) fn backward(l: &Array2<f64>, b: &mut Array2<f64>) {
    let z = l.nrows();
    let c = b.ncols();
    if let (true, Some(ld)) = (c <= FEW, l.as_slice()) {
        // Column by column, from the bottom: x_i from the updated b_i, then b_p −= L_ip x_i
        // for p < i (row i of L, contiguous).
        for mut col in b.columns_mut() {
            let mut x = col.to_vec();
            for i in (0..z).rev() {
                let xi = x[i] / l[[i, i]];
                x[i] = xi;
                let row = &ld[i * z..i * z + i];
                for (v, lip) in x[..i].iter_mut().zip(row) {
                    *v -= lip * xi;
                }
            }
            col.assign(&ndarray::ArrayView1::from(&x[..]));
        }
        return;
    }
    if b.as_slice().is_none() {
        *b = b.as_standard_layout().into_owned();
    }
    let mut k1 = z;
    while k1 > 0 {
        let k0 = k1.saturating_sub(BLOCK);
        if k1 < z {
            let whole = b.view_mut();
            let (mut head, rest) = whole.split_at(Axis(0), k1);
            let mut blk = head.slice_axis_mut(Axis(0), Slice::from(k0..));
            let lrows = l.slice_axis(Axis(0), Slice::from(k1..));
            let lblk = lrows.slice_axis(Axis(1), Slice::from(k0..k1));
            general_mat_mul(-1.0, &lblk.t(), &rest, 1.0, &mut blk);
        }
        let bs = b.as_slice_mut().expect("standard layout");
        for i in (k0..k1).rev() {
            let (head, tail) = bs.split_at_mut((i + 1) * c);
            let row = &mut head[i * c..];
            for p in i + 1..k1 {
                let lpi = l[[p, i]];
                if lpi != 0.0 {
                    let q = (p - i - 1) * c;
                    for (r, d) in row.iter_mut().zip(&tail[q..q + c]) {
                        *r -= lpi * d;
                    }
                }
            }
            let inv = 1.0 / l[[i, i]];
            row.iter_mut().for_each(|r| *r *= inv);
        }
        k1 = k0;
    }
}

/// The ridge solution of one regularisation strength: weights, residual sum of squares and the
/// effective degrees of freedom tr H.
pub(crate) struct RidgeFit {
    /// ρ relative to the mean diagonal of G.
    pub relative: f64,
    /// The solution W (z × m).
    pub weights: Array2<f64>,
    /// Σ |y − A w|² over the rows.
    pub rss: f64,
    /// tr(A (G + ρI)⁻¹ Aᵀ) (estimated by Rademacher probes).
    pub dof: f64,
}

/// Solves (G + ρI) W = B for ρ = `relative` × mean diagonal of G, with the residual sum of
/// squares from `yy` = Σ y² (RSS = yy − 2⟨W, B⟩ + ⟨W, G W⟩) and tr H = z − ρ tr((G + ρI)⁻¹),
/// the trace by `probes` (z × p Rademacher vectors: E‖L⁻¹u‖² = tr (G + ρI)⁻¹). `None` when
/// the factorisation fails.
pub(crate) fn ridge_fit(
    g: &Array2<f64>,
    b: &Array2<f64>,
    yy: f64,
    relative: f64,
    probes: &Array2<f64>,
) -> Option<RidgeFit> {
    let (w, u, rho) = ridge_solve_with(g, b, relative, probes, None)?;
    let z = g.nrows();
    let gw = mul_few(g.view(), w.view());
    let rss = (yy - 2.0 * (&w * b).sum() + (&w * &gw).sum()).max(0.0);
    let trace_inv = u.iter().map(|v| v * v).sum::<f64>() / probes.ncols().max(1) as f64;
    let dof = (z as f64 - rho * trace_inv).clamp(0.0, z as f64);
    Some(RidgeFit {
        relative,
        weights: w,
        rss,
        dof,
    })
}

/// The weights W of (G + ρI) W = B alone ([`ridge_fit`] without the residual and tr H, which
/// the holdout selection does not use: ⟨W, G W⟩ reads all of G once more per ridge), the
/// factor made in a spare matrix of `scratch`. `None` when the factorisation fails.
pub(crate) fn ridge_weights(
    g: &Array2<f64>,
    b: &Array2<f64>,
    relative: f64,
    scratch: &Scratch,
) -> Option<Array2<f64>> {
    let none = Array2::zeros((g.nrows(), 0));
    ridge_solve_with(g, b, relative, &none, Some(scratch)).map(|(w, _, _)| w)
}

/// The Cholesky solve of [`ridge_fit`]: W = (G + ρI)⁻¹ B, L⁻¹ `probes` and the absolute ρ.
fn ridge_solve_with(
    g: &Array2<f64>,
    b: &Array2<f64>,
    relative: f64,
    probes: &Array2<f64>,
    scratch: Option<&Scratch>,
) -> Option<(Array2<f64>, Array2<f64>, f64)> {
    let z = g.nrows();
    let mean_diag = g.diag().sum() / z.max(1) as f64;
    if !(mean_diag > 0.0 && mean_diag.is_finite()) {
        return None;
    }
    let rho = relative * mean_diag;
    let mut l = match scratch {
        Some(s) => {
            let mut l = s.take(z, z);
            l.assign(g);
            l
        }
        None => g.clone(),
    };
    let solved = cholesky_in_place(&mut l, rho).then(|| {
        let mut w = b.clone();
        forward(&l, &mut w);
        backward(&l, &mut w);
        let mut u = probes.clone();
        forward(&l, &mut u);
        (w, u, rho)
    });
    if let Some(s) = scratch {
        s.give(l);
    }
    solved
}

/// Spare matrices for [`ridge_weights`]' Cholesky factors and the selection's design matrices,
/// shared by the solves and candidates of one selection (a fresh 8 MB factor per solve and
/// 24–48 MB design matrices per width at z = 1000 cost page faults, ~8 % of a fit's CPU).
/// Dropped with the selection, so nothing stays allocated after a fit.
#[derive(Default)]
pub(crate) struct Scratch(std::sync::Mutex<Vec<Array2<f64>>>);

impl Scratch {
    /// A spare rows × cols matrix (contents unspecified), or a new one.
    pub fn take(&self, rows: usize, cols: usize) -> Array2<f64> {
        let mut spare = self.0.lock().unwrap_or_else(|e| e.into_inner());
        match spare.iter().position(|a| a.dim() == (rows, cols)) {
            Some(i) => spare.swap_remove(i),
            None => Array2::zeros((rows, cols)),
        }
    }

    /// Returns a matrix from [`Scratch::take`].
    pub fn give(&self, a: Array2<f64>) {
        self.0.lock().unwrap_or_else(|e| e.into_inner()).push(a);
    }
}

/// z × p Rademacher probe vectors (±1), deterministic in `seed`.
pub(crate) fn rademacher(z: usize, p: usize, seed: u64) -> Array2<f64> {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    Array2::from_shape_fn((z, p), |_| if rng.random::<bool>() { 1.0 } else { -1.0 })
}

/// Generalized cross-validation score N·RSS / (N − tr H)² (∞ when tr H ≥ N).
pub(crate) fn gcv(rows: usize, fit: &RidgeFit) -> f64 {
    let free = rows as f64 - fit.dof;
    if free <= 0.5 {
        f64::INFINITY
    } else {
        rows as f64 * fit.rss / (free * free)
    }
}

/// Every ridge solution of one least-squares problem at once, from one symmetric
/// eigendecomposition G = AᵀA = V Λ Vᵀ: for ρ the weights are W(ρ) = V (Λ + ρI)⁻¹ VᵀB, the
/// effective degrees of freedom tr H = Σ λ_k/(λ_k + ρ), and for the rows kept for
/// leave-one-out (their design rows a_i, Q = A_S V) the fitted values a_iᵀW(ρ) =
/// Σ_k q_ik c_k/(λ_k + ρ) (c = VᵀB) and the leverages h_ii = Σ_k q_ik²/(λ_k + ρ). One
/// candidate ρ then costs O(S z (m + 1)) instead of an O(z³) factorisation.
pub(crate) struct RidgePath {
    /// λ_k (clamped at 0: rounding can make them slightly negative).
    values: Vec<f64>,
    /// V, z × z.
    vectors: Array2<f64>,
    /// VᵀB, z × m.
    c: Array2<f64>,
    /// Q = A_S V, S × z.
    q: Array2<f64>,
    /// Q ∘ Q (elementwise square).
    q2: Array2<f64>,
    /// The targets of the S rows, S × m.
    y: Array2<f64>,
    /// tr G / z (the unit of the relative ridge).
    mean_diag: f64,
}

impl RidgePath {
    /// From G (z × z, symmetric), B = AᵀY (z × m), and the design rows `a_loo` (S × z) and
    /// targets `y_loo` (S × m) of the rows whose leave-one-out residuals are scored. `None`
    /// when G has no positive diagonal.
    pub fn new(
        g: &Array2<f64>,
        b: &Array2<f64>,
        a_loo: ArrayView2<'_, f64>,
        y_loo: ArrayView2<'_, f64>,
    ) -> Option<Self> {
        let z = g.nrows();
        let mean_diag = g.diag().sum() / z.max(1) as f64;
        if !(mean_diag > 0.0 && mean_diag.is_finite()) {
            return None;
        }
        let gm = nalgebra::DMatrix::from_fn(z, z, |i, j| g[[i, j]]);
        let eig = nalgebra::SymmetricEigen::new(gm);
        let values: Vec<f64> = eig.eigenvalues.iter().map(|&l| l.max(0.0)).collect();
        if values.iter().any(|l| !l.is_finite()) {
            return None;
        }
        let vectors = Array2::from_shape_fn((z, z), |(i, k)| eig.eigenvectors[(i, k)]);
        let c = vectors.t().dot(b);
        let q = a_loo.dot(&vectors);
        let q2 = q.mapv(|v| v * v);
        Some(Self {
            values,
            vectors,
            c,
            q,
            q2,
            y: y_loo.to_owned(),
            mean_diag,
        })
    }

    /// 1/(λ_k + ρ) for ρ = `relative` × mean diagonal of G.
    fn inverse(&self, relative: f64) -> Vec<f64> {
        let rho = relative * self.mean_diag;
        self.values.iter().map(|&l| 1.0 / (l + rho)).collect()
    }

    /// The mean squared exact leave-one-out residual e_i/(1 − h_ii) over the S rows (∞ when a
    /// leverage reaches 1) and tr H, at the relative ridge `relative`.
    pub fn loo(&self, relative: f64) -> (f64, f64) {
        let d = self.inverse(relative);
        let rho = relative * self.mean_diag;
        let dof = self.values.iter().map(|&l| l / (l + rho)).sum::<f64>();
        let (s, m) = (self.q.nrows(), self.c.ncols());
        if s == 0 {
            return (f64::INFINITY, dof);
        }
        // Fitted values Q (c ∘ d) and leverages (Q ∘ Q) d by matrix-vector products (a
        // matrix product would repack Q for every candidate).
        let d = ndarray::Array1::from(d);
        let h = self.q2.dot(&d);
        let pred: Vec<ndarray::Array1<f64>> = (0..m)
            .map(|j| self.q.dot(&(&self.c.column(j) * &d)))
            .collect();
        let mut press = 0.0;
        for i in 0..s {
            let hi = h[i];
            if hi.is_nan() || hi >= 1.0 - 1e-9 {
                return (f64::INFINITY, dof);
            }
            for j in 0..m {
                let e = (self.y[[i, j]] - pred[j][i]) / (1.0 - hi);
                press += e * e;
            }
        }
        (press / s as f64, dof)
    }

    /// W(ρ) = V (Λ + ρI)⁻¹ VᵀB (z × m) at the relative ridge `relative`.
    pub fn weights(&self, relative: f64) -> Array2<f64> {
        let d = self.inverse(relative);
        let mut cd = self.c.clone();
        for (mut row, dk) in cd.rows_mut().into_iter().zip(&d) {
            row.iter_mut().for_each(|v| *v *= dk);
        }
        self.vectors.dot(&cd)
    }

    /// The relative ridge in 10⁻¹²…10⁰ with the lowest leave-one-out score (decades, then
    /// refined by half and quarter decades around the best), with that score and tr H.
    pub fn best_ridge(&self) -> Option<(f64, f64, f64)> {
        let mut best: Option<(f64, f64, f64)> = None;
        let try_one = |e: f64, best: &mut Option<(f64, f64, f64)>| {
            if !(-12.0..=0.0).contains(&e) {
                return;
            }
            let r = 10f64.powf(e);
            let (score, dof) = self.loo(r);
            if score.is_finite() && best.is_none_or(|(s, _, _)| score < s) {
                *best = Some((score, r, dof));
            }
        };
        for e in -12..=0 {
            try_one(e as f64, &mut best);
        }
        for step in [0.5, 0.25] {
            let centre = best?.1.log10();
            try_one(centre - step, &mut best);
            try_one(centre + step, &mut best);
        }
        best.map(|(s, r, d)| (r, s, d))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The blocked Cholesky of round eight (row-by-row panel, full trailing update): the
    /// reference of `cholesky_is_bit_identical_to_the_row_panel_reference`.
    fn reference_cholesky(a: &mut Array2<f64>, rho: f64) -> bool {
        let z = a.nrows();
        if a.as_slice().is_none() {
            *a = a.as_standard_layout().into_owned();
        }
        for i in 0..z {
            a[[i, i]] += rho;
        }
        let mut k0 = 0;
        while k0 < z {
            let k1 = (k0 + BLOCK).min(z);
            if !factor_diagonal_block(a.as_slice_mut().expect("standard layout"), z, k0..k1) {
                return false;
            }
            if k1 == z {
                break;
            }
            // Panel L21 = A21 L11⁻ᵀ (the rows of L11 are above every panel row).
            {
                let data = a.as_slice_mut().expect("standard layout");
                let (top, bottom) = data.split_at_mut(k1 * z);
                let l11 = &top[k0 * z..];
                // Column by column of the panel, every row within a column: each element gets the
                // same operations in the same order as row by row, but consecutive ones (other
                // rows) do not wait for each other's dependent sums and divisions.
                for j in k0..k1 {
                    let rj = &l11[(j - k0) * z..(j - k0 + 1) * z];
                    for ri in bottom.chunks_exact_mut(z) {
                        let mut s = ri[j];
                        for p in k0..j {
                            s -= ri[p] * rj[p];
                        }
                        ri[j] = s / rj[j];
                    }
                }
            }
            // Trailing update A22 −= L21 L21ᵀ.
            let l21 = a
                .slice_axis(Axis(0), Slice::from(k1..))
                .slice_axis(Axis(1), Slice::from(k0..k1))
                .to_owned();
            let mut a22 = a.slice_axis_mut(Axis(0), Slice::from(k1..));
            let mut a22 = a22.slice_axis_mut(Axis(1), Slice::from(k1..));
            let rows = z - k1;
            if rows >= 2 * BLOCK {
                let h = rows / 2;
                let (l_top, l_bottom) = l21.view().split_at(Axis(0), h);
                let (mut top, mut bottom) = a22.view_mut().split_at(Axis(0), h);
                rayon::join(
                    || general_mat_mul(-1.0, &l_top, &l21.t(), 1.0, &mut top),
                    || general_mat_mul(-1.0, &l_bottom, &l21.t(), 1.0, &mut bottom),
                );
            } else {
                general_mat_mul(-1.0, &l21, &l21.t(), 1.0, &mut a22);
            }
            k0 = k1;
        }
        true
    }

    #[test]
    fn cholesky_is_bit_identical_to_the_row_panel_reference() {
        // The vectorized panel and the lower-only trailing update perform the same
        // operations in the same order as the row-by-row panel and full trailing update of
        // round eight (the regressor's fits must not change): equal bits, z not a multiple of
        // the blocks, for a well- and an ill-conditioned ridge.
        let z = 3 * TRAIL_BLOCK + 45;
        let a = rademacher(z, z + 7, 5);
        let g = a.dot(&a.t());
        for rho in [1e-3, 1e-12] {
            let (mut l, mut reference) = (g.clone(), g.clone());
            assert!(cholesky_in_place(&mut l, rho) && reference_cholesky(&mut reference, rho));
            for i in 0..z {
                for j in 0..=i {
                    assert_eq!(
                        l[[i, j]].to_bits(),
                        reference[[i, j]].to_bits(),
                        "({i}, {j})"
                    );
                }
            }
        }
        // A matrix that is not positive definite fails in both.
        let mut bad = g.clone();
        bad[[z - 1, z - 1]] = -1.0;
        assert!(!cholesky_in_place(&mut bad.clone(), 0.0));
        assert!(!reference_cholesky(&mut bad, 0.0));
    }

    #[test]
    fn solves_a_small_spd_system() {
        // G = [[4, 2], [2, 3]], x = [1, -2] → b = [0, -4].
        let g = [4.0, 2.0, 2.0, 3.0];
        let mut b = [0.0, -4.0];
        let used = ridge_solve(&g, 2, &mut b, 1, 1e-14).unwrap();
        assert!(used < 1e-12);
        assert!(
            (b[0] - 1.0).abs() < 1e-9 && (b[1] + 2.0).abs() < 1e-9,
            "{b:?}"
        );
    }

    #[test]
    fn lower_block_gram_equals_the_full_product() {
        // z not a multiple of the block, added onto a non-zero G.
        for z in [5, GRAM_BLOCK + 1, 2 * GRAM_BLOCK + 37] {
            let a =
                Array2::from_shape_fn((300, z), |(i, j)| ((i * 31 + j * 17) % 23) as f64 - 11.0);
            let mut g = Array2::from_shape_fn((z, z), |(i, j)| (i + j) as f64);
            let mut expect = g.clone();
            general_mat_mul(1.0, &a.t(), &a, 1.0, &mut expect);
            gram_add(a.view(), &mut g);
            let worst = (&g - &expect).iter().fold(0.0f64, |w, v| w.max(v.abs()));
            assert!(worst < 1e-9, "z = {z}: {worst}");
        }
    }

    #[test]
    fn blocked_triangular_solves_match_the_matrix() {
        // A random SPD matrix larger than two blocks; solve L Lᵀ X = B and check G X = B, with
        // few right-hand sides (solved column by column) and many (blocked products).
        let z = 2 * BLOCK + 17;
        let a = rademacher(z, z + 5, 3);
        let g = a.dot(&a.t());
        let mut l = g.clone();
        assert!(cholesky_in_place(&mut l, 1e-3));
        for i in 0..z {
            for j in i + 1..z {
                l[[i, j]] = 0.0;
            }
        }
        let mut gi = g.clone();
        for i in 0..z {
            gi[[i, i]] += 1e-3;
        }
        for cols in [1, FEW, FEW + 5] {
            let b = rademacher(z, cols, 4);
            let mut x = b.clone();
            forward(&l, &mut x);
            backward(&l, &mut x);
            let err = (&gi.dot(&x) - &b)
                .mapv(f64::abs)
                .fold(0.0f64, |m, &v| m.max(v));
            assert!(err < 1e-8, "{cols} columns: {err}");
            // The product for few columns equals the general one.
            let diff = (&mul_few(gi.view(), x.view()) - &gi.dot(&x))
                .mapv(f64::abs)
                .fold(0.0f64, |m, &v| m.max(v));
            assert!(diff < 1e-9, "{cols} columns: {diff}");
        }
    }

    #[test]
    fn singular_matrix_gets_the_ridge_solution() {
        // G = [[1, 1], [1, 1]] is singular; with ρ = 1e-6 the answer is the minimum-norm one.
        let g = [1.0, 1.0, 1.0, 1.0];
        let mut b = [2.0, 2.0];
        let used = ridge_solve(&g, 2, &mut b, 1, 1e-6).unwrap();
        assert!((used - 1e-6).abs() < 1e-12);
        assert!(
            (b[0] - 1.0).abs() < 1e-5 && (b[1] - 1.0).abs() < 1e-5,
            "{b:?}"
        );
        assert!(ridge_solve(&[0.0; 4], 2, &mut b, 1, 1e-9).is_none());
    }

    #[test]
    fn ridge_path_matches_cholesky_and_brute_force_leave_one_out() {
        // A random 40 × 12 design, two outputs: the path's weights equal the Cholesky
        // solution, its tr H the exact trace, its leave-one-out residuals those of refits
        // without each row.
        let (rows, z) = (40, 12);
        let a =
            rademacher(rows, z, 7).mapv(|v| v * 0.5) + &rademacher(rows, z, 8).mapv(|v| v * 0.3);
        let y = rademacher(rows, 2, 9);
        let g = a.t().dot(&a);
        let b = a.t().dot(&y);
        let path = RidgePath::new(&g, &b, a.view(), y.view()).unwrap();
        let mean_diag = g.diag().sum() / z as f64;
        for relative in [1e-6, 1e-2, 1.0] {
            let fit = ridge_fit(&g, &b, 0.0, relative, &Array2::zeros((z, 0))).unwrap();
            let w = path.weights(relative);
            let err = (&w - &fit.weights)
                .mapv(f64::abs)
                .fold(0.0f64, |m, &v| m.max(v));
            assert!(err < 1e-8, "weights differ by {err}");
            let rho = relative * mean_diag;
            let mut gi = g.clone();
            for i in 0..z {
                gi[[i, i]] += rho;
            }
            // tr H = tr(G (G + ρI)⁻¹) = Σ_i (G (G + ρI)⁻¹)_ii, by solving with G's columns.
            let mut x = g.clone();
            let mut l = gi.clone();
            assert!(cholesky_in_place(&mut l, 0.0));
            forward(&l, &mut x);
            backward(&l, &mut x);
            let trace: f64 = (0..z).map(|i| x[[i, i]]).sum();
            let (press, dof) = path.loo(relative);
            assert!((dof - trace).abs() < 1e-8, "{dof} vs {trace}");
            let mut brute = 0.0;
            for out in 0..rows {
                let keep: Vec<usize> = (0..rows).filter(|&r| r != out).collect();
                let ak = a.select(Axis(0), &keep);
                let yk = y.select(Axis(0), &keep);
                let mut gk = ak.t().dot(&ak);
                for i in 0..z {
                    gk[[i, i]] += rho;
                }
                let mut wk = ak.t().dot(&yk);
                assert!(cholesky_in_place(&mut gk, 0.0));
                forward(&gk, &mut wk);
                backward(&gk, &mut wk);
                let pred = a.row(out).dot(&wk);
                brute += (&y.row(out) - &pred).mapv(|e| e * e).sum();
            }
            brute /= rows as f64;
            assert!(
                (press - brute).abs() < 1e-8 * brute.max(1.0),
                "{press} vs {brute}"
            );
        }
    }
}
