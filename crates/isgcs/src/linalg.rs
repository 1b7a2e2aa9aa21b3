//! Dense symmetric positive-definite solves for the least-squares output fits.

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

#[cfg(test)]
mod tests {
    use super::*;

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
}
