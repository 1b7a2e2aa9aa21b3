//! The right-triangle integral behind the exact triangle formula, tabulated.
//!
//! With `a = 1`, a right triangle with its acute vertex at the Gaussian's centre, leg `ε` along the
//! perpendicular to an edge and leg `u` along the edge, integrates to
//!
//! `R(ε, u) = ½ ∫_0^{atan(u/ε)} (1 − exp(−ε² sec²φ)) dφ = (½) ε ∫_0^u φ₁(ε² + s²) ds`,
//! `φ₁(z) = (1 − e^{−z})/z`,
//!
//! i.e. `R = ½ atan(u/ε) − π T(√2 ε, u/ε)` with Owen's T (MATH.md §2). The second form shows that
//! `R` is an entire function of `(ε, u)`, bounded by π/4, with no cancellation near `ε = 0`: it is
//! tabulated once as piecewise tensor-Chebyshev polynomials (converted to monomials) on
//! `[0, L)²`, so that one evaluation costs ~`(D+1)²` multiply-adds and no transcendental call.
//! Outside the table the Gaussian factor `exp(−(ε² + u²))` is below `e^{−L²} < 1e−18` and `R` is
//! `½ atan(u/ε)` plus a constant (see [`r`]).

use std::f64::consts::PI;
use std::sync::OnceLock;

/// Patch edge length in units of the Gaussian width `d = 1/√a`.
const H: f64 = 0.125;
/// Polynomial degree per variable in each patch.
const D: usize = 8;
const _: () = assert!(D % 2 == 0, "the centre must be a Chebyshev point");
const NC: usize = D + 1;
/// Number of patches per axis; the table covers `[0, L)²`, `L = N·H`.
const N: usize = 52;
/// Table extent: beyond it `exp(−L²) ≈ 5e−19`.
pub(crate) const L: f64 = N as f64 * H;

struct Table {
    /// `N·N` patches of `NC·NC` monomial coefficients, `c[m_u][m_ε]` (ε contiguous, so that the
    /// Horner steps in u run over all ε powers at once), local variables in [−1, 1].
    coef: Vec<[[f64; NC]; NC]>,
}

fn table() -> &'static Table {
    static T: OnceLock<Table> = OnceLock::new();
    T.get_or_init(build)
}

/// Gauss–Legendre nodes and weights on [−1, 1] (Newton on the Legendre recurrence).
pub(crate) fn gauss_legendre(n: usize) -> (Vec<f64>, Vec<f64>) {
    let mut x = vec![0.0; n];
    let mut w = vec![0.0; n];
    let legendre = |z: f64| {
        // (P_n(z), P_n'(z))
        let (mut p0, mut p1) = (1.0, z);
        for k in 2..=n {
            let p2 = ((2 * k - 1) as f64 * z * p1 - (k - 1) as f64 * p0) / k as f64;
            p0 = p1;
            p1 = p2;
        }
        (p1, n as f64 * (z * p1 - p0) / (z * z - 1.0))
    };
    for i in 0..n {
        let mut z = (PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
        for _ in 0..100 {
            let (p, dp) = legendre(z);
            let dz = p / dp;
            z -= dz;
            if dz.abs() < 1e-15 {
                break;
            }
        }
        let (_, dp) = legendre(z);
        x[i] = z;
        w[i] = 2.0 / ((1.0 - z * z) * dp * dp);
    }
    (x, w)
}

/// Compensated (Neumaier) summation.
#[derive(Default, Clone, Copy)]
pub(crate) struct Neumaier {
    sum: f64,
    comp: f64,
}

impl Neumaier {
    pub(crate) fn add(&mut self, x: f64) {
        let t = self.sum + x;
        if self.sum.abs() >= x.abs() {
            self.comp += (self.sum - t) + x;
        } else {
            self.comp += (x - t) + self.sum;
        }
        self.sum = t;
    }
    pub(crate) fn value(&self) -> f64 {
        self.sum + self.comp
    }
}

/// `φ₁(z) = (1 − e^{−z})/z`, accurate for small z.
fn phi1(z: f64) -> f64 {
    if z == 0.0 { 1.0 } else { -(-z).exp_m1() / z }
}

/// Reference value of `R(ε, u)` by composite Gauss–Legendre on the entire integrand
/// `½ ε φ₁(ε² + s²)` (panels of length ≤ 1/8, 12 nodes each: far below 1e−17 relative).
pub fn r_reference(eps: f64, u: f64) -> f64 {
    let (gx, gw) = gauss_legendre(12);
    let (sign, u) = if u < 0.0 { (-1.0, -u) } else { (1.0, u) };
    let eps = eps.abs();
    let um = u.min(L);
    let panels = ((um * 8.0).ceil() as usize).max(1);
    let mut s = Neumaier::default();
    for p in 0..panels {
        let lo = um * p as f64 / panels as f64;
        let hi = um * (p + 1) as f64 / panels as f64;
        let (m, h) = (0.5 * (lo + hi), 0.5 * (hi - lo));
        for i in 0..12 {
            let t = m + h * gx[i];
            s.add(gw[i] * h * phi1(eps * eps + t * t));
        }
    }
    let mut r = 0.5 * eps * s.value();
    if u > L {
        r += 0.5 * ((u - L) * eps).atan2(eps * eps + u * L);
    }
    sign * r
}

fn build() -> Table {
    // Chebyshev points of the first kind in each patch.
    let cheb: Vec<f64> = (0..NC)
        .map(|j| (PI * (j as f64 + 0.5) / NC as f64).cos())
        .collect();
    // Sorted u-nodes over the whole axis, with patch index and node index.
    let mut unodes: Vec<(f64, usize, usize)> = Vec::with_capacity(N * NC);
    for p in 0..N {
        for (j, c) in cheb.iter().enumerate() {
            unodes.push((H * (p as f64 + 0.5 + 0.5 * c), p, j));
        }
    }
    unodes.sort_by(|a, b| a.0.total_cmp(&b.0));
    let (gx, gw) = gauss_legendre(8);
    // values[pe][pu][ie][iu]
    let mut values = vec![0.0; N * N * NC * NC];
    for pe in 0..N {
        for (ie, ce) in cheb.iter().enumerate() {
            let eps = H * (pe as f64 + 0.5 + 0.5 * ce);
            // Cumulative integration of ½ ε φ₁(ε² + s²) along u through the sorted nodes.
            let (mut prev, mut acc) = (0.0, Neumaier::default());
            for &(u, pu, iu) in &unodes {
                let (m, h) = (0.5 * (prev + u), 0.5 * (u - prev));
                let mut s = 0.0;
                for i in 0..8 {
                    let t = m + h * gx[i];
                    s += gw[i] * phi1(eps * eps + t * t);
                }
                acc.add(h * s);
                prev = u;
                values[((pe * N + pu) * NC + ie) * NC + iu] = 0.5 * eps * acc.value();
            }
        }
    }
    // Chebyshev coefficients by the discrete cosine transform, then monomials.
    // T-to-monomial matrix: mono[k][m] = coefficient of t^m in T_k(t).
    let mut mono = vec![[0.0f64; NC]; NC];
    mono[0][0] = 1.0;
    if NC > 1 {
        mono[1][1] = 1.0;
    }
    for k in 2..NC {
        for m in 0..NC {
            let up = if m > 0 { 2.0 * mono[k - 1][m - 1] } else { 0.0 };
            mono[k][m] = up - mono[k - 2][m];
        }
    }
    let tk: Vec<f64> = (0..NC * NC)
        .map(|kj| (PI * (kj / NC) as f64 * ((kj % NC) as f64 + 0.5) / NC as f64).cos())
        .collect();
    let mut coef = vec![[[0.0; NC]; NC]; N * N];
    let mut cc = vec![0.0; NC * NC];
    let mut tmp = vec![0.0; NC * NC];
    for pe in 0..N {
        for pu in 0..N {
            let v = &values[(pe * N + pu) * NC * NC..(pe * N + pu + 1) * NC * NC];
            // Fit the deviation from the value at the patch centre (NC is odd: the middle
            // Chebyshev point is 0), so that the transform's rounding scales with the
            // variation over the patch, not with R itself.
            let mid = v[(NC / 2) * NC + NC / 2];
            // Separable discrete cosine transform: along u into tmp[ie][ku], then along ε.
            for ie in 0..NC {
                for ku in 0..NC {
                    let s: f64 = (0..NC)
                        .map(|iu| (v[ie * NC + iu] - mid) * tk[ku * NC + iu])
                        .sum();
                    let f = if ku == 0 { 1.0 } else { 2.0 };
                    tmp[ie * NC + ku] = s * f / NC as f64;
                }
            }
            for ke in 0..NC {
                for ku in 0..NC {
                    let s: f64 = (0..NC).map(|ie| tmp[ie * NC + ku] * tk[ke * NC + ie]).sum();
                    let f = if ke == 0 { 1.0 } else { 2.0 };
                    cc[ke * NC + ku] = s * f / NC as f64;
                }
            }
            // To monomials: first along u, then along ε.
            for ke in 0..NC {
                for m in 0..NC {
                    tmp[ke * NC + m] = (0..NC).map(|ku| cc[ke * NC + ku] * mono[ku][m]).sum();
                }
            }
            let out = &mut coef[pe * N + pu];
            for me in 0..NC {
                for mu in 0..NC {
                    out[mu][me] = (0..NC).map(|ke| tmp[ke * NC + mu] * mono[ke][me]).sum();
                }
            }
            out[0][0] += mid;
        }
    }
    Table { coef }
}

/// Forces the one-time construction of the table (~10⁶ exponentials); optional, the first
/// call to [`r`] does it otherwise.
pub fn init() {
    let _ = table();
}

/// `R(ε, u)` for `ε ≥ 0` and any `u` (odd in `u`), absolute error below ~2e−16.
#[inline]
pub fn r(eps: f64, u: f64) -> f64 {
    let (sign, u) = if u < 0.0 { (-1.0, -u) } else { (1.0, u) };
    if eps >= L {
        // exp(−ε²) < 5e−19: only the atan part is left.
        return sign * 0.5 * u.atan2(eps);
    }
    if eps.is_nan() || eps < 0.0 || !u.is_finite() {
        // NaN inputs or u = ∞: the limit ½·atan(∞) − π T(√2ε, ∞) = (π/4)·erf(ε).
        if u == f64::INFINITY && eps >= 0.0 {
            return sign * 0.25 * PI * libm::erf(eps);
        }
        return f64::NAN;
    }
    if eps == 0.0 || u == 0.0 {
        return 0.0;
    }
    let (uu, extra) = if u >= L {
        // Beyond the table the integrand is ε/(ε² + s²) to e^{−L²}: add its exact integral.
        (
            L * (1.0 - f64::EPSILON),
            0.5 * ((u - L) * eps).atan2(eps * eps + u * L),
        )
    } else {
        (u, 0.0)
    };
    let pe = ((eps * (1.0 / H)) as usize).min(N - 1);
    let pu = ((uu * (1.0 / H)) as usize).min(N - 1);
    let te = (eps - H * (pe as f64 + 0.5)) * (2.0 / H);
    let tu = (uu - H * (pu as f64 + 0.5)) * (2.0 / H);
    let c = &table().coef[pe * N + pu];
    // Horner in u for all powers of ε at once (vectorizes), then Horner in ε.
    let mut rows = c[NC - 1];
    for mu in (0..NC - 1).rev() {
        let row = &c[mu];
        for me in 0..NC {
            rows[me] = rows[me] * tu + row[me];
        }
    }
    let mut s = rows[NC - 1];
    for me in (0..NC - 1).rev() {
        s = s * te + rows[me];
    }
    sign * (s + extra)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn table_matches_reference_and_owens_t() {
        // A deterministic scatter over the table and a little beyond it.
        let mut worst: f64 = 0.0;
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        for _ in 0..4000 {
            let eps = 7.0 * next();
            let u = 8.0 * next() - 1.0;
            let (t, r0) = (r(eps, u), r_reference(eps, u));
            worst = worst.max((t - r0).abs());
        }
        assert!(worst < 5e-16, "table error {worst:e}");
        // Against Owen's T (absolute error ~1e−16 itself).
        for &(eps, u) in &[
            (0.3f64, 0.7f64),
            (1.0, 2.5),
            (2.0, 0.1),
            (0.05, 3.0),
            (4.0, 6.0),
        ] {
            let owen = 0.5 * (u / eps).atan() - PI * owens_t::owens_t(2f64.sqrt() * eps, u / eps);
            assert!((r(eps, u) - owen).abs() < 1e-15, "{eps} {u}");
        }
        assert_eq!(r(0.0, 3.0), 0.0);
        assert_eq!(r(2.0, 0.0), 0.0);
        assert!((r(1.5, f64::INFINITY) - 0.25 * PI * libm::erf(1.5)).abs() < 1e-16);
    }
}
