//! The right-triangle integral behind the exact triangle formula, tabulated.
//!
//! With `a = 1`, a right triangle with its acute vertex at the Gaussian's centre, leg `ε` along the
//! perpendicular to an edge and leg `u` along the edge, integrates to
//!
//! `R(ε, u) = ½ ∫_0^{atan(u/ε)} (1 − exp(−ε² sec²φ)) dφ = (½) ε ∫_0^u φ₁(ε² + s²) ds`,
//! `φ₁(z) = (1 − e^{−z})/z`,
//!
//! i.e. `R = ½ atan(u/ε) − π T(√2 ε, u/ε)` with Owen's T (docs/design/math.md §2). The second form shows that
//! `R` is an entire function of `(ε, u)`, bounded by π/4, with no cancellation near `ε = 0`: it is
//! tabulated once as piecewise tensor-Chebyshev polynomials (converted to monomials) on
//! `[0, L)²`, so that one evaluation costs `(D+1)(D+2)/2 = 45` multiply-adds (two-lane SIMD
//! over coefficient pairs, see `patch_value`) and no transcendental call.
//! Outside the table the Gaussian factor `exp(−(ε² + u²))` is below `e^{−L²} < 1e−18` and `R` is
//! `½ atan(u/ε)` plus a constant (see [`r`]).

use std::f64::consts::PI;
use std::sync::OnceLock;

/// Patch edge length in units of the Gaussian width `d = 1/√a`.
const H: f64 = 0.1;
/// Total polynomial degree in each patch (`ε^i u^j`, `i + j ≤ D`). Degree 8 on patches of 0.1 has
/// the same error as degree 9 on patches of 0.125 (4.4e−16 worst on 10⁵ points, rounding of the
/// value itself) with 45 instead of 55 coefficients; degree 8 on 0.125 reaches 2.2e−15, degree 7
/// on 0.08 3.0e−15.
const D: usize = 8;
/// Number of coefficients per patch.
const NT: usize = (D + 1) * (D + 2) / 2;
/// Chebyshev points per axis of the tensor fit that is truncated to total degree `D` (odd, so
/// that the patch centre is a node).
const NF: usize = 13;
const _: () = assert!(NF % 2 == 1 && NF > D);
/// Number of patches per axis; the table covers `[0, L)²`, `L = N·H`.
const N: usize = 65;
/// Table extent: beyond it `exp(−L²) ≈ 5e−19`.
pub(crate) const L: f64 = N as f64 * H;

/// Offset of the row of `u^j` in a patch's coefficients: rows `j = 0..=D` of `D + 1 − j`
/// coefficients of `ε^0 … ε^{D−j}`.
const fn row_start(j: usize) -> usize {
    j * (D + 1) - j * (j.saturating_sub(1)) / 2
}
const _: () = assert!(row_start(D + 1) == NT);

/// Stored coefficients per patch: the rows `j = 0..D−1` padded to an even length (so that each is
/// a run of aligned pairs), then `c_{0,D}` and the patch constant `c_{00}` (whose slot in row 0
/// holds 0). 50 for `D = 8`: 400 bytes, the whole table 1.69 MB.
const NP: usize = row_pad(D) + 2;

/// Number of coefficient pairs of the padded row `j < D`: `⌈(D + 1 − j)/2⌉`.
const fn row_pairs(j: usize) -> usize {
    (D + 2 - j) / 2
}

/// Offset of the padded row `j ≤ D` in a patch's stored coefficients ([`NP`]).
const fn row_pad(j: usize) -> usize {
    let mut o = 0;
    let mut k = 0;
    while k < j {
        o += 2 * row_pairs(k);
        k += 1;
    }
    o
}

/// Index of `c_{0,D}` and of the patch constant `c_{00}` in the stored coefficients.
const C0D: usize = NP - 2;
const C00: usize = NP - 1;

/// The pairs of all padded rows must fit the ε powers `1 … t^{2·row_pairs(0)−1}`.
const _: () = assert!(2 * row_pairs(0) > D && row_pairs(0) == 5);

/// One patch's stored coefficients: the row pairs as lane pairs (16-byte aligned, so each is one
/// aligned load, folded into the multiplication), then `[c_{0,D}, c_{00}]`.
#[derive(Clone, Copy)]
#[repr(C)]
struct Patch {
    pairs: [F2; C0D / 2],
    tail: [f64; 2],
}
const _: () = assert!(NP % 2 == 0 && C0D % 2 == 0);

/// The tabulated `R` (see [`table`]).
pub(crate) struct Table {
    /// `N·N` patches (ε-major) of monomial coefficients `c_ij` of `t_ε^i t_u^j` in the local
    /// variables in [−1, 1], in the padded layout of [`NP`].
    coef: Box<[Patch; N * N]>,
}

/// The table, built on first use.
#[inline]
pub(crate) fn table() -> &'static Table {
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
    let mut coef = vec![
        Patch {
            pairs: [splat(0.0); C0D / 2],
            tail: [0.0; 2],
        };
        N * N
    ];
    let mut stored = [0.0; NP];
    let mut out = [0.0; NT];
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
            for mu in 0..=D {
                for me in 0..=D - mu {
                    out[row_start(mu) + me] = (me..=D - mu)
                        .map(|ke| tmp[ke * NF + mu] * mono[ke][me])
                        .sum();
                }
            }
            out[0] += mid;
            // To the padded layout.
            for mu in 0..D {
                for me in 0..=D - mu {
                    stored[row_pad(mu) + me] = out[row_start(mu) + me];
                }
            }
            stored[0] = 0.0;
            stored[C0D] = out[row_start(D)];
            stored[C00] = out[0];
            let patch = &mut coef[pe * N + pu];
            for (k, p) in patch.pairs.iter_mut().enumerate() {
                *p = pair(stored[2 * k], stored[2 * k + 1]);
            }
            patch.tail = [stored[C0D], stored[C00]];
        }
    }
    Table {
        coef: coef
            .into_boxed_slice()
            .try_into()
            .unwrap_or_else(|_| unreachable!("N·N patches")),
    }
}

/// Forces the one-time construction of the table (~10⁶ exponentials); optional, the first
/// call to [`r`] does it otherwise.
pub fn init() {
    let _ = table();
}

/// Lane pairs: two `f64` operated on together, one SSE2 register on x86-64 (NEON on aarch64, a
/// plain pair elsewhere: [`wide`] picks at compile time; each lane is one IEEE multiplication or
/// addition on every target, so all give the same bits).
type F2 = wide::f64x2;

#[inline(always)]
fn pair(lo: f64, hi: f64) -> F2 {
    F2::from([lo, hi])
}
#[inline(always)]
fn splat(x: f64) -> F2 {
    F2::splat(x)
}
#[inline(always)]
fn add2(a: F2, b: F2) -> F2 {
    a + b
}
#[inline(always)]
fn mul2(a: F2, b: F2) -> F2 {
    a * b
}
/// `lo + hi`.
#[inline(always)]
fn hsum(a: F2) -> f64 {
    let [lo, hi] = a.to_array();
    lo + hi
}
/// Lane-wise `a + b·c` (two roundings, as the scalar expression).
#[inline(always)]
fn mad2(a: F2, b: F2, c: F2) -> F2 {
    add2(a, mul2(b, c))
}

/// 1.5·2⁵²: `x + ROUND` leaves `round(x)` in the low mantissa bits for `|x| < 2⁵¹`.
const ROUND: f64 = 6_755_399_441_055_744.0;

/// The patch of `v ∈ [0, L)` along one axis and its local variable `(v − H(k + ½))·2/H ∈ [−1, 1]`.
///
/// `k` is `round(v/H − ½)` by the 1.5·2⁵² trick (adding it leaves the rounded integer in the low
/// mantissa bits): no float-to-int saturation checks, no int-to-float conversion; at a patch
/// boundary either neighbour may be chosen, with the local variable exactly ±1.
#[inline(always)]
fn cell(v: f64) -> (usize, f64) {
    let x = v * (1.0 / H) - 0.5;
    let r = x + ROUND;
    let k = r - ROUND;
    ((r.to_bits() as usize & 0xff).min(N - 1), (x - k) * 2.0)
}

/// Powers `t^0 … t^9` in pairs `(t^{2k}, t^{2k+1})`, by squaring (four multiplications deep).
#[inline(always)]
fn power_pairs(t: f64) -> [F2; 5] {
    let t2 = t * t;
    let t4 = t2 * t2;
    let t8 = t4 * t4;
    let p = pair(1.0, t);
    [
        p,
        mul2(p, splat(t2)),
        mul2(p, splat(t4)),
        mul2(p, splat(t4 * t2)),
        mul2(p, splat(t8)),
    ]
}

const _: () = assert!(D == 8 || D == 9, "power_pairs covers t^0 … t^9");

/// Row `J` of a patch against the ε powers: `Σ_i c_iJ t_ε^i` as two partial sums (even and odd
/// `i`), highest powers first. A row past the table's degree is 0.
#[inline(always)]
fn row<const J: usize>(c: &Patch, pw: &[F2; 5]) -> F2 {
    if J >= D {
        return splat(0.0);
    }
    let o = row_pad(J) / 2;
    let n = row_pairs(J);
    let mut s = mul2(c.pairs[o + n - 1], pw[n - 1]);
    for k in (0..n - 1).rev() {
        s = add2(s, mul2(c.pairs[o + k], pw[k]));
    }
    s
}

/// The patch polynomial `Σ_{i+j≤D} c_ij t_ε^i t_u^j` at `t_u` (ε powers `pw`).
///
/// Evaluated as `c_00 + Σ_j q_j t_u^j` with the rows `q_j = Σ_i c_ij t_ε^i` as dot products over
/// contiguous coefficient pairs (one aligned load, one multiply and one add per two terms, no
/// shuffles; the ε powers are shared by both ends of an edge) and Horner's rule in `t_u` on the
/// lane pairs, starting from the single coefficient `c_{0D}`. The patch constant `c_00` (the large
/// term; its slot in row 0 holds 0) is added last, alone, so the rounding of the rest scales with
/// the variation over the patch (|t| ≤ 1, coefficients decaying with the degree).
#[inline(always)]
fn patch_value(c: &Patch, pw: &[F2; 5], tu: f64) -> f64 {
    c.tail[1] + hsum(patch_sum(c, pw, tu))
}

/// The lane pair of [`patch_value`] before its last two additions.
#[inline(always)]
fn patch_sum(c: &Patch, pw: &[F2; 5], tu: f64) -> F2 {
    let u = splat(tu);
    let s = pair(c.tail[0], 0.0);
    let s = if D > 8 {
        mad2(row::<8>(c, pw), s, u)
    } else {
        s
    };
    let s = mad2(row::<7>(c, pw), s, u);
    let s = mad2(row::<6>(c, pw), s, u);
    let s = mad2(row::<5>(c, pw), s, u);
    let s = mad2(row::<4>(c, pw), s, u);
    let s = mad2(row::<3>(c, pw), s, u);
    let s = mad2(row::<2>(c, pw), s, u);
    let s = mad2(row::<1>(c, pw), s, u);
    mad2(row::<0>(c, pw), s, u)
}

/// [`patch_value`] for the two ends of an edge at once: the same operations in the same order
/// (the same bits), with the lane-pair steps before and after the two Horner sums, the patch
/// cells, the two constants and the signs, done once on `[u1, u0]` instead of twice.
#[inline(always)]
fn edge_values(tab: &Table, pe: usize, pw: &[F2; 5], u: F2) -> F2 {
    let x = u.abs() * splat(1.0 / H) - splat(0.5);
    let r = x + splat(ROUND);
    let t = (x - (r - splat(ROUND))) * splat(2.0);
    let ([r1, r0], [t1, t0]) = (r.to_array(), t.to_array());
    let idx = |r: f64| pe * N + (r.to_bits() as usize & 0xff).min(N - 1);
    let (c1, c0) = (&tab.coef[idx(r1)], &tab.coef[idx(r0)]);
    let (s1, s0) = (patch_sum(c1, pw, t1), patch_sum(c0, pw, t0));
    let ([a1, b1], [a0, b0]) = (s1.to_array(), s0.to_array());
    let v = pair(c1.tail[1], c0.tail[1]) + (pair(a1, a0) + pair(b1, b0));
    // R is odd in u, and R(ε, 0) = 0 exactly (the table is ~1e−17 off there).
    v.copysign(u) & wide::CmpNe::cmp_ne(u, splat(0.0))
}

/// Where `|u| ≥ L`: the clamped argument and the exact integral of the integrand ε/(ε² + s²)
/// from `L` to `|u|` (the Gaussian factor is below `e^{−L²}` there).
#[cold]
#[inline(never)]
fn beyond(eps: f64, u: f64) -> (f64, f64) {
    (
        L * (1.0 - f64::EPSILON),
        0.5 * ((u - L) * eps).atan2(eps * eps + u * L),
    )
}

/// `R(ε, u)` for `0 < ε < L` and finite `u`, from the patch row `pe` with the ε powers `pw`.
#[inline(always)]
fn table_r(tab: &Table, pe: usize, pw: &[F2; 5], eps: f64, u: f64) -> f64 {
    let au = u.abs();
    let (uu, extra) = if au >= L { beyond(eps, au) } else { (au, 0.0) };
    let (pu, tu) = cell(uu);
    let v = patch_value(&tab.coef[pe * N + pu], pw, tu) + extra;
    // R is odd in u, and R(ε, 0) = 0 exactly (the table is ~1e−17 off there).
    if u == 0.0 { 0.0 } else { v.copysign(u) }
}

/// `R(ε, u1) − R(ε, u0)` for `0 < ε < L` and finite `u0`, `u1`.
#[inline(always)]
fn table_diff(tab: &Table, eps: f64, u0: f64, u1: f64) -> f64 {
    let (pe, te) = cell(eps);
    let pw = power_pairs(te);
    if !(u0.abs() < L && u1.abs() < L) {
        // Rare (an end ≥ L widths from the foot's projection) or NaN: one end at a time.
        return table_r(tab, pe, &pw, eps, u1) - table_r(tab, pe, &pw, eps, u0);
    }
    let [v1, v0] = edge_values(tab, pe, &pw, pair(u1, u0)).to_array();
    v1 - v0
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
    let (pe, te) = cell(eps);
    table_r(table(), pe, &power_pairs(te), eps, u)
}

/// `R(ε, u1) − R(ε, u0)`: the signed pair of right triangles of one edge (same ε), sharing the
/// patch row and the ε powers.
#[inline]
pub fn r_diff(eps: f64, u0: f64, u1: f64) -> f64 {
    r_diff_with(table(), eps, u0, u1)
}

/// [`r_diff`] with the table at hand (callers that evaluate several edges fetch it once).
#[inline(always)]
pub(crate) fn r_diff_with(tab: &Table, eps: f64, u0: f64, u1: f64) -> f64 {
    if !((0.0..L).contains(&eps) && u0.is_finite() && u1.is_finite()) {
        return r_diff_outside(eps, u0, u1);
    }
    if eps == 0.0 {
        return 0.0;
    }
    table_diff(tab, eps, u0, u1)
}

/// [`r_diff`] where `ε` or `u` leave the table (rare: the foot ≥ `L` widths from the edge line).
#[cold]
#[inline(never)]
fn r_diff_outside(eps: f64, u0: f64, u1: f64) -> f64 {
    r(eps, u1) - r(eps, u0)
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
