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
/// Total polynomial degree in each patch (`ε^i u^j`, `i + j ≤ D`).
const D: usize = 9;
/// Number of coefficients per patch.
const NT: usize = (D + 1) * (D + 2) / 2;
/// Chebyshev points per axis of the tensor fit that is truncated to total degree `D` (odd, so
/// that the patch centre is a node).
const NF: usize = 13;
const _: () = assert!(NF % 2 == 1 && NF > D);
/// Number of patches per axis; the table covers `[0, L)²`, `L = N·H`.
const N: usize = 52;
/// Table extent: beyond it `exp(−L²) ≈ 5e−19`.
pub(crate) const L: f64 = N as f64 * H;

/// Offset of the row of `u^j` in a patch's coefficients: rows `j = 0..=D` of `D + 1 − j`
/// coefficients of `ε^0 … ε^{D−j}`.
const fn row_start(j: usize) -> usize {
    j * (D + 1) - j * (j.saturating_sub(1)) / 2
}
const _: () = assert!(row_start(D + 1) == NT);

struct Table {
    /// `N·N` patches (ε-major) of `NT` monomial coefficients in the local variables in [−1, 1]
    /// (see [`row_start`]).
    coef: Vec<[f64; NT]>,
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
    let cheb: Vec<f64> = (0..NF)
        .map(|j| (PI * (j as f64 + 0.5) / NF as f64).cos())
        .collect();
    // Sorted u-nodes over the whole axis, with patch index and node index.
    let mut unodes: Vec<(f64, usize, usize)> = Vec::with_capacity(N * NF);
    for p in 0..N {
        for (j, c) in cheb.iter().enumerate() {
            unodes.push((H * (p as f64 + 0.5 + 0.5 * c), p, j));
        }
    }
    unodes.sort_by(|a, b| a.0.total_cmp(&b.0));
    let (gx, gw) = gauss_legendre(8);
    // values[pe][pu][ie][iu]
    let mut values = vec![0.0; N * N * NF * NF];
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
                values[((pe * N + pu) * NF + ie) * NF + iu] = 0.5 * eps * acc.value();
            }
        }
    }
    // Chebyshev coefficients by the discrete cosine transform, truncated to total degree D,
    // then monomials. T-to-monomial matrix: mono[k][m] = coefficient of t^m in T_k(t).
    let mut mono = vec![[0.0f64; D + 1]; D + 1];
    mono[0][0] = 1.0;
    mono[1][1] = 1.0;
    for k in 2..=D {
        for m in 0..=D {
            let up = if m > 0 { 2.0 * mono[k - 1][m - 1] } else { 0.0 };
            mono[k][m] = up - mono[k - 2][m];
        }
    }
    let tk: Vec<f64> = (0..NF * NF)
        .map(|kj| (PI * (kj / NF) as f64 * ((kj % NF) as f64 + 0.5) / NF as f64).cos())
        .collect();
    let mut coef = vec![[0.0; NT]; N * N];
    let mut cc = vec![0.0; NF * NF];
    let mut tmp = vec![0.0; NF * NF];
    for pe in 0..N {
        for pu in 0..N {
            let v = &values[(pe * N + pu) * NF * NF..(pe * N + pu + 1) * NF * NF];
            // Fit the deviation from the value at the patch centre (the middle Chebyshev point
            // is 0), so that the transform's rounding scales with the variation over the patch,
            // not with R itself.
            let mid = v[(NF / 2) * NF + NF / 2];
            // Separable discrete cosine transform: along u into tmp[ie][ku], then along ε.
            for ie in 0..NF {
                for ku in 0..=D {
                    let s: f64 = (0..NF)
                        .map(|iu| (v[ie * NF + iu] - mid) * tk[ku * NF + iu])
                        .sum();
                    let f = if ku == 0 { 1.0 } else { 2.0 };
                    tmp[ie * NF + ku] = s * f / NF as f64;
                }
            }
            for ke in 0..=D {
                for ku in 0..=D - ke {
                    let s: f64 = (0..NF).map(|ie| tmp[ie * NF + ku] * tk[ke * NF + ie]).sum();
                    let f = if ke == 0 { 1.0 } else { 2.0 };
                    cc[ke * NF + ku] = s * f / NF as f64;
                }
            }
            // To monomials: first along u (degree ≤ D − ke), then along ε.
            for ke in 0..=D {
                for m in 0..=D - ke {
                    tmp[ke * NF + m] = (m..=D - ke).map(|ku| cc[ke * NF + ku] * mono[ku][m]).sum();
                }
            }
            let out = &mut coef[pe * N + pu];
            for mu in 0..=D {
                for me in 0..=D - mu {
                    out[row_start(mu) + me] = (me..=D - mu)
                        .map(|ke| tmp[ke * NF + mu] * mono[ke][me])
                        .sum();
                }
            }
            out[0] += mid;
        }
    }
    Table { coef }
}

/// Forces the one-time construction of the table (~10⁶ exponentials); optional, the first
/// call to [`r`] does it otherwise.
pub fn init() {
    let _ = table();
}

/// Powers `1, t, …, t^D` of the local ε variable of patch `pe`.
#[inline(always)]
fn eps_powers(eps: f64) -> (usize, [f64; D + 1]) {
    let pe = ((eps * (1.0 / H)) as usize).min(N - 1);
    let te = (eps - H * (pe as f64 + 0.5)) * (2.0 / H);
    let mut pw = [1.0; D + 1];
    for k in 1..=D {
        pw[k] = pw[k - 1] * te;
    }
    (pe, pw)
}

const _: () = assert!(D == 9, "table_r2's unrolled rows are written for D = 9");

/// `Σ_{k<M} c_l[S + k]·pw[k]` for both lanes `l`, smallest terms first.
#[inline(always)]
fn row2<const S: usize, const M: usize>(c: [&[f64; NT]; 2], pw: &[f64; D + 1]) -> [f64; 2] {
    let mut q = [0.0; 2];
    let mut k = M;
    while k > 0 {
        k -= 1;
        q[0] += c[0][S + k] * pw[k];
        q[1] += c[1][S + k] * pw[k];
    }
    q
}

/// `q·t + r` lane-wise.
#[inline(always)]
fn horner2(q: [f64; 2], t: [f64; 2], r: [f64; 2]) -> [f64; 2] {
    [q[0] * t[0] + r[0], q[1] * t[1] + r[1]]
}

/// `R(ε, u_l)` for `0 < ε < L` and two finite `u_l`, from the patch row `pe` with the ε powers
/// `pw`: the two evaluations run in lock-step (two independent chains, SIMD lanes).
#[inline(always)]
fn table_r2(tab: &Table, pe: usize, pw: &[f64; D + 1], eps: f64, u: [f64; 2]) -> [f64; 2] {
    let prep = |u: f64| {
        let (sign, u) = if u < 0.0 { (-1.0, -u) } else { (1.0, u) };
        let (uu, extra) = if u >= L {
            // Beyond the table the integrand is ε/(ε² + s²) to e^{−L²}: add its exact integral.
            (
                L * (1.0 - f64::EPSILON),
                0.5 * ((u - L) * eps).atan2(eps * eps + u * L),
            )
        } else {
            (u, 0.0)
        };
        let pu = ((uu * (1.0 / H)) as usize).min(N - 1);
        let tu = (uu - H * (pu as f64 + 0.5)) * (2.0 / H);
        // R(ε, 0) = 0 exactly (the table is ~1e−17 off there).
        let sign = if u == 0.0 { 0.0 } else { sign };
        (sign, extra, &tab.coef[pe * N + pu], tu)
    };
    let (s0, x0, c0, t0) = prep(u[0]);
    let (s1, x1, c1, t1) = prep(u[1]);
    let (c, t) = ([c0, c1], [t0, t1]);
    // Each power of u: a dot product with the ε powers (independent, so they overlap); then
    // Horner in u. The patch constant c[0] (the large term) is added last, alone.
    let s = row2::<{ row_start(9) }, 1>(c, pw);
    let s = horner2(s, t, row2::<{ row_start(8) }, 2>(c, pw));
    let s = horner2(s, t, row2::<{ row_start(7) }, 3>(c, pw));
    let s = horner2(s, t, row2::<{ row_start(6) }, 4>(c, pw));
    let s = horner2(s, t, row2::<{ row_start(5) }, 5>(c, pw));
    let s = horner2(s, t, row2::<{ row_start(4) }, 6>(c, pw));
    let s = horner2(s, t, row2::<{ row_start(3) }, 7>(c, pw));
    let s = horner2(s, t, row2::<{ row_start(2) }, 8>(c, pw));
    let s = horner2(s, t, row2::<{ row_start(1) }, 9>(c, pw));
    let r0 = row2::<1, 9>(
        c,
        &[
            pw[1], pw[2], pw[3], pw[4], pw[5], pw[6], pw[7], pw[8], pw[9], 0.0,
        ],
    );
    let s = horner2(s, t, r0);
    [s0 * ((c0[0] + s[0]) + x0), s1 * ((c1[0] + s[1]) + x1)]
}

/// `R(ε, u)` outside the table's domain: `ε ≥ L`, NaN, negative ε or infinite u.
#[cold]
fn r_outside(eps: f64, u: f64) -> f64 {
    let (sign, u) = if u < 0.0 { (-1.0, -u) } else { (1.0, u) };
    if eps >= L {
        // exp(−ε²) < 5e−19: only the atan part is left.
        return sign * 0.5 * u.atan2(eps);
    }
    // NaN inputs or u = ∞: the limit ½·atan(∞) − π T(√2ε, ∞) = (π/4)·erf(ε).
    if u == f64::INFINITY && eps >= 0.0 {
        return sign * 0.25 * PI * libm::erf(eps);
    }
    f64::NAN
}

/// `R(ε, u)` for `ε ≥ 0` and any `u` (odd in `u`), absolute error below ~3e−16.
#[inline]
pub fn r(eps: f64, u: f64) -> f64 {
    if !((0.0..L).contains(&eps) && u.is_finite()) {
        return r_outside(eps, u);
    }
    if eps == 0.0 {
        return 0.0;
    }
    let (pe, pw) = eps_powers(eps);
    table_r2(table(), pe, &pw, eps, [u, 0.0])[0]
}

/// `R(ε, u1) − R(ε, u0)`: the signed pair of right triangles of one edge (same ε), sharing the
/// patch row and the ε powers.
#[inline(always)]
pub fn r_diff(eps: f64, u0: f64, u1: f64) -> f64 {
    if !((0.0..L).contains(&eps) && u0.is_finite() && u1.is_finite()) {
        return r(eps, u1) - r(eps, u0);
    }
    if eps == 0.0 {
        return 0.0;
    }
    let (pe, pw) = eps_powers(eps);
    let [r0, r1] = table_r2(table(), pe, &pw, eps, [u0, u1]);
    r1 - r0
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
