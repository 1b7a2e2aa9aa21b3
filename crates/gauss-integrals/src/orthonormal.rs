//! Orthonormalization of a Gaussian base (sec. 3.8.1, docs/design/math.md §5).
//!
//! Gram–Schmidt on functions with Gram matrix G equals, in exact arithmetic, the Cholesky
//! factorization `G = L Lᵀ` with `A = L⁻¹` (so `A G Aᵀ = I`). We factor G directly, in the
//! dissertation's order, and reject a component whose squared residual norm (the Cholesky pivot)
//! falls below `threshold × G_kk` — the "nearly linear dependent" test of sec. 3.8.1. The
//! classical Gram–Schmidt printed in fig. B.3 is kept for comparison: it loses orthogonality.

use nalgebra::DMatrix;

/// The Cholesky factor of a Gram matrix with nearly dependent components rejected.
#[derive(Clone, Debug)]
pub struct Orthonormal {
    /// Lower-triangular factor over the kept components (rows/columns of rejected ones are 0).
    l: DMatrix<f64>,
    kept: Vec<bool>,
}

impl Orthonormal {
    /// Factors the symmetric positive semi-definite `gram`.
    ///
    /// Left-looking Cholesky in the dissertation's order; the factor is built in a row-major
    /// buffer (each update is a dot product of two contiguous rows) and the rows below the pivot
    /// are updated in parallel for large matrices. Every entry is computed by the same operations
    /// in the same order as the plain triple loop, so the result does not depend on the layout or
    /// the thread count.
    pub fn new(gram: &DMatrix<f64>, threshold: f64) -> Self {
        use rayon::prelude::*;
        let n = gram.nrows();
        let mut lr = vec![0.0f64; n * n];
        let mut kept = vec![false; n];
        for k in 0..n {
            let (head, tail) = lr.split_at_mut((k + 1) * n);
            let row_k = &mut head[k * n..];
            let mut d = gram[(k, k)];
            for j in 0..k {
                d -= row_k[j] * row_k[j];
            }
            if d.is_nan()
                || d <= threshold * gram[(k, k)].abs()
                || !d.is_finite()
                || gram[(k, k)] <= 0.0
            {
                continue;
            }
            kept[k] = true;
            let lkk = d.sqrt();
            row_k[k] = lkk;
            let row_k = &row_k[..k];
            let update = |(r, row_i): (usize, &mut [f64])| {
                let i = k + 1 + r;
                let mut s = gram[(i, k)];
                for j in 0..k {
                    s -= row_i[j] * row_k[j];
                }
                row_i[k] = s / lkk;
            };
            if (n - k) * k > 1 << 16 {
                tail.par_chunks_mut(n).enumerate().for_each(update);
            } else {
                tail.chunks_mut(n).enumerate().for_each(update);
            }
        }
        Self {
            l: DMatrix::from_row_slice(n, n, &lr),
            kept,
        }
    }

    /// Number of rejected components.
    pub fn rejected(&self) -> usize {
        self.kept.iter().filter(|k| !**k).count()
    }

    /// Which components were kept.
    pub fn kept(&self) -> &[bool] {
        &self.kept
    }

    /// `r = A u` (coefficients in the orthonormal base of the projections u_k = ⟨Λ_k|f⟩).
    pub fn apply_a(&self, u: &[f64]) -> Vec<f64> {
        let n = u.len();
        let mut r = vec![0.0; n];
        for i in 0..n {
            if !self.kept[i] {
                continue;
            }
            let mut s = u[i];
            for j in 0..i {
                s -= self.l[(i, j)] * r[j];
            }
            r[i] = s / self.l[(i, i)];
        }
        r
    }

    /// `γ = Aᵀ r`: coefficients in the original Gaussians.
    pub fn apply_at(&self, r: &[f64]) -> Vec<f64> {
        let n = r.len();
        let mut g = vec![0.0; n];
        for i in (0..n).rev() {
            if !self.kept[i] {
                continue;
            }
            let mut s = r[i];
            for j in i + 1..n {
                s -= self.l[(j, i)] * g[j];
            }
            g[i] = s / self.l[(i, i)];
        }
        g
    }

    /// `γ = G⁻¹ u` over the kept components (the least-squares projection onto their span).
    pub fn solve(&self, u: &[f64]) -> Vec<f64> {
        self.apply_at(&self.apply_a(u))
    }

    /// The coefficient matrix A (rows: orthonormal N_k, columns: Gaussians), rejected rows zero.
    pub fn matrix_a(&self) -> DMatrix<f64> {
        let n = self.l.nrows();
        let mut a = DMatrix::zeros(n, n);
        for c in 0..n {
            let mut e = vec![0.0; n];
            e[c] = 1.0;
            let col = self.apply_a(&e);
            for r in 0..n {
                a[(r, c)] = col[r];
            }
        }
        a
    }
}

/// Classical Gram–Schmidt as printed in fig. B.3 (for comparison only): returns A with rows the
/// coefficients of N_k, normalized, using projections on the non-updated A_k.
pub fn classical_gram_schmidt(gram: &DMatrix<f64>) -> DMatrix<f64> {
    let n = gram.nrows();
    let mut a = DMatrix::<f64>::zeros(n, n);
    let ip = |x: &[f64], y: &[f64]| -> f64 {
        let mut s = 0.0;
        for i in 0..n {
            if x[i] == 0.0 {
                continue;
            }
            for j in 0..n {
                s += x[i] * gram[(i, j)] * y[j];
            }
        }
        s
    };
    for k in 0..n {
        let mut row = vec![0.0; n];
        row[k] = 1.0;
        let ak = row.clone();
        for i in 0..k {
            let ni: Vec<f64> = (0..n).map(|j| a[(i, j)]).collect();
            let c = ip(&ak, &ni); // ⟨A_k|N_i⟩ with N_i already normalized
            for j in 0..n {
                row[j] -= c * ni[j];
            }
        }
        let norm = ip(&row, &row).max(0.0).sqrt();
        for j in 0..n {
            a[(k, j)] = if norm > 0.0 { row[j] / norm } else { 0.0 };
        }
    }
    a
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Gram matrix of 1-D Gaussians exp(−(x−c)²/d²) on the whole line (closed form).
    fn line_gram(centres: &[f64], d: f64) -> DMatrix<f64> {
        let n = centres.len();
        DMatrix::from_fn(n, n, |i, j| {
            let a = 1.0 / (d * d);
            (std::f64::consts::PI / (2.0 * a)).sqrt()
                * (-(a / 2.0) * (centres[i] - centres[j]).powi(2)).exp()
        })
    }

    /// The plain column-major triple loop the factor was first written as.
    fn plain_cholesky(gram: &DMatrix<f64>, threshold: f64) -> DMatrix<f64> {
        let n = gram.nrows();
        let mut l = DMatrix::<f64>::zeros(n, n);
        for k in 0..n {
            let mut d = gram[(k, k)];
            for j in 0..k {
                d -= l[(k, j)] * l[(k, j)];
            }
            if d.is_nan() || d <= threshold * gram[(k, k)].abs() || gram[(k, k)] <= 0.0 {
                continue;
            }
            let lkk = d.sqrt();
            l[(k, k)] = lkk;
            for i in k + 1..n {
                let mut s = gram[(i, k)];
                for j in 0..k {
                    s -= l[(i, j)] * l[(k, j)];
                }
                l[(i, k)] = s / lkk;
            }
        }
        l
    }

    #[test]
    fn row_major_parallel_factor_is_bit_identical_to_the_plain_loop() {
        // Large enough for the parallel branch; with near-duplicates for rejections.
        let mut c: Vec<f64> = (0..600).map(|i| (i as f64 * 0.37).sin() * 90.0).collect();
        c[17] = c[3] + 1e-9;
        let g = line_gram(&c, 1.0);
        let o = Orthonormal::new(&g, 1e-10);
        assert!(o.rejected() > 0);
        assert_eq!(o.l, plain_cholesky(&g, 1e-10));
    }

    #[test]
    fn a_g_at_is_identity_and_solve_inverts() {
        let c: Vec<f64> = (0..30).map(|i| i as f64 * 0.8).collect();
        let g = line_gram(&c, 1.0);
        let o = Orthonormal::new(&g, 1e-12);
        assert_eq!(o.rejected(), 0);
        let a = o.matrix_a();
        let id = &a * &g * a.transpose();
        assert!((id - DMatrix::identity(30, 30)).amax() < 1e-10);
        let u: Vec<f64> = (0..30).map(|i| (i as f64).sin()).collect();
        let gamma = o.solve(&u);
        let back = &g * nalgebra::DVector::from_vec(gamma);
        for i in 0..30 {
            assert!((back[i] - u[i]).abs() < 1e-9);
        }
    }

    #[test]
    fn near_duplicates_are_rejected_and_classical_gs_loses_orthogonality() {
        let mut c: Vec<f64> = (0..20).map(|i| i as f64 * 0.3).collect();
        c.push(c[5] + 1e-9);
        let g = line_gram(&c, 1.0);
        let o = Orthonormal::new(&g, 1e-10);
        assert_eq!(
            o.rejected(),
            1 + o.kept()[..20].iter().filter(|k| !**k).count()
        );
        assert!(!o.kept()[20]);
        // Dense spacing makes G ill-conditioned: classical GS drifts from orthonormality.
        let c: Vec<f64> = (0..25).map(|i| i as f64 * 0.35).collect();
        let g = line_gram(&c, 1.0);
        let cgs = classical_gram_schmidt(&g);
        let err_cgs = (&cgs * &g * cgs.transpose() - DMatrix::identity(25, 25)).amax();
        let a = Orthonormal::new(&g, 1e-14).matrix_a();
        let err_chol = (&a * &g * a.transpose() - DMatrix::identity(25, 25)).amax();
        assert!(
            err_cgs > 1e3 * err_chol,
            "classical {err_cgs:e} vs Cholesky {err_chol:e}"
        );
    }
}
