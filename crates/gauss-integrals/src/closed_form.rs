//! Exact integrals of `exp(−a|x − c|²)` (docs/design/math.md §2).

use std::f64::consts::PI;

type V = [f64; 3];

fn sub(a: V, b: V) -> V {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn dot(a: V, b: V) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn cross(a: V, b: V) -> V {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
fn scale(a: V, s: f64) -> V {
    [a[0] * s, a[1] * s, a[2] * s]
}
fn add(a: V, b: V) -> V {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

/// Product rule: `exp(−a|x−p|²)·exp(−b|x−q|²) = s·exp(−(a+b)|x−c|²)`; returns `(a+b, c, s)` with
/// `c = (a p + b q)/(a + b)` and `s = exp(−ab/(a+b)·|p−q|²)`.
pub fn product(a: f64, p: V, b: f64, q: V) -> (f64, V, f64) {
    let ab = a + b;
    let c = scale(add(scale(p, a), scale(q, b)), 1.0 / ab);
    let d = sub(p, q);
    (ab, c, (-(a * b / ab) * dot(d, d)).exp())
}

/// Whole plane in 3-D at distance `h` from the centre: `(π/a)·exp(−a h²)`.
pub fn plane(a: f64, h: f64) -> f64 {
    PI / a * (-a * h * h).exp()
}

/// Whole line in 2-D at distance `h`: `√(π/a)·exp(−a h²)`.
pub fn line(a: f64, h: f64) -> f64 {
    (PI / a).sqrt() * (-a * h * h).exp()
}

/// ∫ over the segment p–q of `exp(−a|x − c|²)` ds (any dimension; erf form of docs/design/math.md §2).
/// Zero-length segments give 0.
pub fn segment(c: V, a: f64, p: V, q: V) -> f64 {
    let d = sub(q, p);
    let len = dot(d, d).sqrt();
    if len == 0.0 || a <= 0.0 || !len.is_finite() {
        return 0.0;
    }
    let u = scale(d, 1.0 / len);
    let tc = dot(sub(c, p), u);
    let foot = add(p, scale(u, tc));
    let hv = sub(c, foot);
    let h2 = dot(hv, hv);
    let sa = a.sqrt();
    let (x0, x1) = (sa * (0.0 - tc), sa * (len - tc));
    // erf(x1) − erf(x0) without cancellation when both are far on the same side.
    let diff = if x0 > 0.0 {
        libm::erfc(x0) - libm::erfc(x1)
    } else if x1 < 0.0 {
        libm::erfc(-x1) - libm::erfc(-x0)
    } else {
        libm::erf(x1) - libm::erf(x0)
    };
    0.5 * (PI / a).sqrt() * diff * (-a * h2).exp()
}

/// ∫ over the triangle (p, q, r) of `exp(−a|x − c|²)` dA, to the crate's accuracy contract:
/// relative error ≤ 1e−12 wherever the integral is ≥ 1e−12·π/a, absolute error ≤ 1e−15·π/a
/// everywhere.
///
/// The exact signed edge decomposition of docs/design/math.md §2 is evaluated by [`triangle_fast`] (absolute
/// error ~1e−15·π/a·e^{−ah²}). Where that is not enough for the relative bound (the integral is
/// below ~2e−3·π/a because the triangle is tiny against the width, a sliver, or far from the
/// centre), the integral is computed by the adaptive cubature to a relative tolerance, after an
/// area × maximum bound has ruled out values below 1e−15·π/a. Degenerate triangles give 0.
pub fn triangle(c: V, a: f64, p: V, q: V, r: V) -> f64 {
    let Some(geo) = Plane::new(c, a, p, q, r) else {
        return 0.0;
    };
    let verts = [p, q, r];
    let dmin2 = in_plane_distance2(geo.foot, verts);
    let area = 0.5 * geo.nn;
    let bound = area * (-a * dmin2).exp() * geo.damp;
    if bound <= 1e-15 * PI / a {
        return 0.0;
    }
    let fast = geo.signed_sum(a) / a;
    // The fast sum's absolute error is below 2e−15/a (six table values and the sum's rounding);
    // it meets the relative bound once it is above 2e−3/a.
    if fast >= 2e-3 / a {
        return fast * geo.damp;
    }
    let f = |x: V| {
        let d = sub(x, c);
        (-a * dot(d, d)).exp()
    };
    // Relative tolerance against a safe lower estimate of the value; never asks for less than
    // the absolute contract.
    let scale = (fast.max(0.0) * geo.damp).max(1e-15 * PI / a);
    let tol = (1e-14 * scale)
        .max(0.25e-15 * PI / a)
        .min(1e-13 * bound.max(scale));
    crate::cubature::triangle_cubature(f, verts, tol).value
}

/// ∫ over the planar convex quadrilateral (p, q, r, s) (corners in order) of `exp(−a|x − c|²)` dA,
/// to the accuracy contract of [`triangle`]: the signed edge decomposition of docs/design/math.md §2 over its
/// four edges (8 table values instead of the 12 of two triangles: a scene's rectangles, split in two
/// triangles on load, cost a third less), and where that sum is too small for the relative bound,
/// [`triangle`] on (p, q, r) plus (p, r, s). The caller guarantees planarity and convexity; a
/// degenerate (p, q, r) falls back to the two triangles.
pub fn quad(c: V, a: f64, [p, q, r, s]: [V; 4]) -> f64 {
    if let Some(geo) = Plane::new(c, a, p, q, r) {
        let geo = geo.with_fourth(s);
        let fast = geo.signed_sum(a) / a;
        // Eight table values: absolute error below ~2.7e−15/a, relative 1e−12 from 3e−3/a on.
        if fast >= 3e-3 / a {
            return fast * geo.damp;
        }
    }
    triangle(c, a, p, q, r) + triangle(c, a, p, r, s)
}

/// [`quad`] without the relative-accuracy fallback, as [`triangle_fast`] is to [`triangle`]:
/// absolute error ≲ 3e−15/a (times `exp(−a h²)`), what a FEM sum over near elements needs.
/// Many Gaussians on one quadrilateral: [`ConvexPolygon`] prepares its geometry once.
pub fn quad_fast(c: V, a: f64, q: [V; 4]) -> f64 {
    ConvexPolygon::quad(q).map_or(0.0, |g| g.gaussian_integral(c, a))
}

/// The exact triangle integral of docs/design/math.md §2 (signed edge decomposition around the centre's foot
/// c' on the plane) with each right triangle read from the tabulated function `R(ε, u)` of
/// [`crate::wedge`] instead of two Owen's T calls: 6 × 45 multiply–adds (in two-lane SIMD), one
/// `exp`, four square roots and divisions (the frame, see [`ConvexPolygon`]), no other transcendental call.
/// Many Gaussians on one triangle: [`ConvexPolygon`] prepares its geometry once.
///
/// Absolute error ≲ 2e−15/a (times `exp(−a h²)`); no relative guarantee where the signed parts
/// cancel or the value is tiny (use [`triangle`] there). What a FEM step needs: its sums are
/// dominated by the near elements. Degenerate triangles give 0.
pub fn triangle_fast(c: V, a: f64, p: V, q: V, r: V) -> f64 {
    if a.is_nan() || a <= 0.0 || !a.is_finite() {
        return 0.0;
    }
    match ConvexPolygon::triangle(p, q, r) {
        Some(t) => t.integral(c, a, a.sqrt()),
        None => 0.0,
    }
}

/// A planar convex polygon (a triangle or a quadrilateral) prepared for many Gaussian integrals:
/// the geometry that does not depend on the Gaussian, computed once per element (a FEM sum
/// integrates each element against thousands of Gaussians): its corners, unit normal, and per
/// edge the unit direction, the in-plane unit normal and the length.
///
/// Everything the per-Gaussian sum needs is then a dot product with the centre's offset from a
/// corner: with `ê_i` the direction of edge `i` (corner `i` to `i + 1`) and `ŵ_i = ê_i × n̂` (in
/// the plane, pointing to the inside for counter-clockwise corners), the centre's foot `c'` lies
/// at the signed distance `(v_i − c)·ŵ_i` from the edge line (positive inside), and the edge's
/// ends lie at `(v_i − c)·ê_i` and that plus its length along it, counted from the foot's
/// projection. Both hold for the 3-D centre `c` as well as for its foot, since `ŵ_i, ê_i ⊥ n̂`:
/// no foot and no in-plane frame per call.
///
/// ```
/// use gauss_integrals::{ConvexPolygon, quad_fast};
/// let q = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]];
/// let prepared = ConvexPolygon::quad(q).expect("a unit square");
/// let (c, a) = ([0.3, 0.4, 0.1], 20.0);
/// assert!((prepared.gaussian_integral(c, a) - quad_fast(c, a, q)).abs() < 1e-15);
/// ```
#[derive(Clone, Copy, Debug)]
pub struct ConvexPolygon {
    /// Corners (the first `corners`).
    v: [V; 4],
    /// Unit normal (the corners are counter-clockwise about it).
    n: V,
    /// Unit edge directions, corner `i` to `i + 1` (zero for a zero-length edge).
    e: [V; 4],
    /// In-plane unit normals of the edges, `ŵ_i = ê_i × n̂` (inward).
    w: [V; 4],
    /// Edge lengths.
    len: [f64; 4],
    /// 3 or 4.
    corners: usize,
}

impl ConvexPolygon {
    /// The triangle (p, q, r); `None` when degenerate (zero-area or non-finite), its integral 0.
    ///
    /// Four square roots and four divisions, all independent of each other (the normal's and the
    /// three edges'). A non-degenerate triangle has no zero-length edge: a repeated corner makes
    /// the cross product exactly 0.
    #[inline(always)]
    pub fn triangle(p: V, q: V, r: V) -> Option<Self> {
        Self::new([p, q, r, p], cross(sub(q, p), sub(r, p)), 3)
    }

    /// The planar convex quadrilateral (p, q, r, s), corners in order; `None` when degenerate.
    /// The normal is that of the diagonals, `(r − p) × (s − q)`, so three collinear corners (a
    /// triangle stored as a quadrilateral) are fine; a zero-length edge contributes nothing.
    /// The caller guarantees planarity and convexity.
    pub fn quad([p, q, r, s]: [V; 4]) -> Option<Self> {
        Self::new([p, q, r, s], cross(sub(r, p), sub(s, q)), 4)
    }

    #[inline(always)]
    fn new(v: [V; 4], n: V, corners: usize) -> Option<Self> {
        let n2 = dot(n, n);
        if !(n2 > 0.0 && n2.is_finite()) {
            return None;
        }
        let n = scale(n, 1.0 / n2.sqrt());
        let (mut e, mut w, mut len) = ([[0.0; 3]; 4], [[0.0; 3]; 4], [0.0; 4]);
        for i in 0..corners {
            let ed = sub(v[(i + 1) % corners], v[i]);
            let l2 = dot(ed, ed);
            if !l2.is_finite() {
                return None;
            }
            if l2 > 0.0 {
                len[i] = l2.sqrt();
                e[i] = scale(ed, 1.0 / len[i]);
                w[i] = cross(e[i], n);
            }
        }
        Some(Self {
            v,
            n,
            e,
            w,
            len,
            corners,
        })
    }

    /// `∫ exp(−a|x − c|²) dA` over the polygon, as [`triangle_fast`] and [`quad_fast`]: absolute
    /// error ≲ 3e−15/a (times `exp(−a h²)`), 0 for a non-positive or non-finite `a`.
    pub fn gaussian_integral(&self, c: V, a: f64) -> f64 {
        if a.is_nan() || a <= 0.0 || !a.is_finite() {
            return 0.0;
        }
        self.integral(c, a, a.sqrt())
    }

    /// The integral for `a` finite and > 0, `sa = √a`: the signed edge decomposition around the
    /// centre's foot (docs/design/math.md §2), one [`crate::wedge::r_diff`] (two right triangles sharing ε)
    /// per edge:
    /// `∫ = (1/a)·exp(−a h²)·Σ_i sign(ε_i)·[R(|ε_i|, u_i + ℓ_i) − R(|ε_i|, u_i)]` with
    /// `ε_i = √a·(v_i − c)·ŵ_i`, `u_i = √a·(v_i − c)·ê_i`, `ℓ_i = √a·len_i` and `h` the centre's
    /// distance from the plane.
    #[inline(always)]
    pub(crate) fn integral(&self, c: V, a: f64, sa: f64) -> f64 {
        let h = dot(sub(c, self.v[0]), self.n);
        let damp = (-a * h * h).exp();
        if damp.is_nan() || damp <= 0.0 {
            return 0.0;
        }
        let tab = crate::wedge::table();
        let edge = |i| self.edge(tab, c, sa, i);
        let mut sum = (edge(0) + edge(1)) + edge(2);
        if self.corners == 4 {
            sum += edge(3);
        }
        (sum * (damp / a)).max(0.0)
    }

    /// Edge `i`'s signed pair of right triangles, `sign(ε_i)·[R(|ε_i|, u_i + ℓ_i) − R(|ε_i|, u_i)]`.
    #[inline(always)]
    fn edge(&self, tab: &crate::wedge::Table, c: V, sa: f64, i: usize) -> f64 {
        let d = sub(self.v[i], c);
        // Signed distance of the foot from the edge line (positive: foot on the inner side),
        // and the corner's position along the edge, from the foot's projection.
        let cr = dot(d, self.w[i]);
        let t0 = dot(d, self.e[i]);
        let w = crate::wedge::r_diff_with(tab, cr.abs() * sa, t0 * sa, (t0 + self.len[i]) * sa);
        if cr >= 0.0 { w } else { -w }
    }
}

/// The previous implementation, kept as an independent reference: the signed decomposition with
/// two `owens_t::owens_t` calls and two `atan` per edge,
/// `∫ = Σ ± [(φ1 − φ0)/(2a) − (π/a)·(T(√(2a e²), t1/e) − T(√(2a e²), t0/e))]·exp(−a h²)`.
/// Absolute error ~1e−16·π/a, but it cancels both far outside the triangle and for edges passing
/// close to the foot (relative error ~1e−16/(a e²)).
pub fn triangle_reference(c: V, a: f64, p: V, q: V, r: V) -> f64 {
    let n = cross(sub(q, p), sub(r, p));
    let n2 = dot(n, n);
    if n2 == 0.0 || a <= 0.0 || !n2.is_finite() {
        return 0.0;
    }
    let unit = scale(n, 1.0 / n2.sqrt());
    let h = dot(sub(c, p), unit);
    let foot = sub(c, scale(unit, h));
    let damp = (-a * h * h).exp();
    if damp == 0.0 {
        return 0.0;
    }
    let verts = [p, q, r];
    let mut sum = 0.0;
    for i in 0..3 {
        sum += signed_wedge(foot, verts[i], verts[(i + 1) % 3], unit, a);
    }
    (sum * damp).max(0.0)
}

/// A triangle projected into its own plane around the Gaussian's foot.
struct Plane {
    /// |(q − p) × (r − p)| (twice the area).
    nn: f64,
    /// The centre's foot on the plane.
    foot: V,
    /// exp(−a h²), h the centre's distance from the plane.
    damp: f64,
    /// Vertices relative to the foot in an orthonormal in-plane basis, counter-clockwise (the
    /// first `corners` are used: 3 for a triangle, 4 for a quadrilateral).
    xy: [[f64; 2]; 4],
    /// Number of corners.
    corners: usize,
    /// In-plane basis (for further corners).
    basis: [V; 2],
}

impl Plane {
    fn new(c: V, a: f64, p: V, q: V, r: V) -> Option<Self> {
        let e1 = sub(q, p);
        let n = cross(e1, sub(r, p));
        let n2 = dot(n, n);
        if n2 == 0.0 || a.is_nan() || a <= 0.0 || !n2.is_finite() || !a.is_finite() {
            return None;
        }
        let nn = n2.sqrt();
        let unit = scale(n, 1.0 / nn);
        let h = dot(sub(c, p), unit);
        let damp = (-a * h * h).exp();
        if damp.is_nan() || damp <= 0.0 {
            return None;
        }
        let foot = sub(c, scale(unit, h));
        let b1 = scale(e1, 1.0 / dot(e1, e1).sqrt());
        let b2 = cross(unit, b1);
        let to2 = |v: V| {
            let d = sub(v, foot);
            [dot(d, b1), dot(d, b2)]
        };
        Some(Self {
            nn,
            foot,
            damp,
            xy: [to2(p), to2(q), to2(r), [0.0; 2]],
            corners: 3,
            basis: [b1, b2],
        })
    }

    /// Adds a fourth corner `s` (in the plane, after r: the polygon p, q, r, s).
    fn with_fourth(mut self, s: V) -> Self {
        let d = sub(s, self.foot);
        self.xy[3] = [dot(d, self.basis[0]), dot(d, self.basis[1])];
        self.corners = 4;
        self
    }

    /// Σ over the edges of the signed right-triangle pairs, for a = 1 after scaling lengths by √a
    /// (so the integral is this / a).
    fn signed_sum(&self, a: f64) -> f64 {
        let sa = a.sqrt();
        let mut sum = 0.0;
        for i in 0..self.corners {
            let [x0, y0] = self.xy[i];
            let [x1, y1] = self.xy[(i + 1) % self.corners];
            let (dx, dy) = (x1 - x0, y1 - y0);
            let len = (dx * dx + dy * dy).sqrt();
            if len == 0.0 {
                continue;
            }
            // Signed distance of the foot from the edge line (positive: foot on the inner side).
            let cr = x0 * y1 - x1 * y0;
            let k = sa / len;
            let eps = cr.abs() * k;
            let t0 = (x0 * dx + y0 * dy) * k;
            let t1 = (x1 * dx + y1 * dy) * k;
            let w = crate::wedge::r_diff(eps, t0, t1);
            sum += if cr >= 0.0 { w } else { -w };
        }
        sum
    }
}

/// Squared distance from `o` (in the triangle's plane) to the triangle; 0 inside.
fn in_plane_distance2(o: V, t: [V; 3]) -> f64 {
    let n = cross(sub(t[1], t[0]), sub(t[2], t[0]));
    let inside = (0..3).all(|i| dot(cross(sub(t[(i + 1) % 3], t[i]), sub(o, t[i])), n) >= 0.0);
    if inside {
        return 0.0;
    }
    (0..3)
        .map(|i| {
            let (a, b) = (t[i], t[(i + 1) % 3]);
            let e = sub(b, a);
            let s = (dot(sub(o, a), e) / dot(e, e)).clamp(0.0, 1.0);
            let d = sub(o, add(a, scale(e, s)));
            dot(d, d)
        })
        .fold(f64::INFINITY, f64::min)
}

/// Signed integral over the triangle (o, p, q) in the plane with unit normal `n`, of exp(−a|x−o|²).
fn signed_wedge(o: V, p: V, q: V, n: V, a: f64) -> f64 {
    let e_vec = sub(q, p);
    let len = dot(e_vec, e_vec).sqrt();
    if len == 0.0 {
        return 0.0;
    }
    let u = scale(e_vec, 1.0 / len);
    let t0 = dot(sub(p, o), u);
    let t1 = t0 + len;
    let perp = sub(sub(p, o), scale(u, t0));
    let e = dot(perp, perp).sqrt();
    if e == 0.0 {
        return 0.0;
    }
    // Orientation of (o, p, q) against the plane normal.
    let sign = dot(cross(sub(p, o), sub(q, o)), n).signum();
    let (phi0, phi1) = ((t0 / e).atan(), (t1 / e).atan());
    let hh = (2.0 * a * e * e).sqrt();
    let tt = owens_t::owens_t(hh, t1 / e) - owens_t::owens_t(hh, t0 / e);
    sign * ((phi1 - phi0) / (2.0 * a) - PI / a * tt)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cubature::triangle_cubature;
    use proptest::prelude::*;

    #[test]
    fn whole_plane_line_and_segment_limits() {
        let big = [[-50.0, -50.0, 0.0], [50.0, -50.0, 0.0], [0.0, 80.0, 0.0]];
        let i = triangle([0.3, 0.2, 0.7], 1.5, big[0], big[1], big[2]);
        assert!((i - plane(1.5, 0.7)).abs() < 1e-13);
        let s = segment([0.0, 0.4, 0.0], 2.0, [-40.0, 0.0, 0.0], [40.0, 0.0, 0.0]);
        assert!((s - line(2.0, 0.4)).abs() < 1e-14);
        assert_eq!(segment([0.0; 3], 1.0, [1.0; 3], [1.0; 3]), 0.0);
        assert_eq!(
            triangle([0.0; 3], 1.0, [0.0; 3], [1.0, 0.0, 0.0], [2.0, 0.0, 0.0]),
            0.0
        );
    }

    /// The quadrilateral's four-edge sum against its two triangles (each to the crate's contract):
    /// relative 1e−12 where the value is ≥ 1e−12·π/a, absolute 1e−15·π/a everywhere, for centres
    /// on, near and far from a skewed convex quad, widths from 1e−2 to 1e2 of its size.
    #[test]
    fn quad_equals_its_two_triangles() {
        let (o, u, w) = ([0.3, -0.2, 0.1], [1.3, 0.2, -0.4], [-0.1, 0.9, 0.5]);
        let at = |x: f64, y: f64| [0, 1, 2].map(|k| o[k] + x * u[k] + y * w[k]);
        let q = [at(0.0, 0.0), at(1.0, 0.0), at(1.3, 0.8), at(-0.2, 1.1)];
        let mut state = 0x9E37_79B9_7F4A_7C15u64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut checked = 0;
        for _ in 0..600 {
            let c = at(4.0 * next() - 1.5, 4.0 * next() - 1.5);
            let lift = 2.0 * next() - 1.0;
            let c = [c[0] + 0.3 * lift, c[1] - 0.2 * lift, c[2] + 0.5 * lift];
            let a = 10f64.powf(4.0 * next() - 2.0);
            let got = quad(c, a, q);
            let want = triangle(c, a, q[0], q[1], q[2]) + triangle(c, a, q[0], q[2], q[3]);
            let floor = 1e-15 * PI / a;
            let tol = if want >= 1e-12 * PI / a {
                2e-12 * want
            } else {
                floor
            };
            assert!(
                (got - want).abs() <= tol.max(floor),
                "{c:?} a={a}: {got} vs {want}"
            );
            checked += usize::from(want >= 1e-12 * PI / a);
        }
        assert!(checked > 200, "{checked} values above the relative floor");
        // A degenerate first corner triple falls back to the triangles.
        let flat = [q[0], q[0], q[2], q[3]];
        let c = at(0.4, 0.5);
        assert_eq!(quad(c, 1.0, flat), triangle(c, 1.0, q[0], q[2], q[3]));
        // The fast form: absolute agreement with the two fast triangles.
        for i in 0..400 {
            let t = i as f64 / 400.0;
            let c = at(3.0 * t - 1.0, 2.5 * (7.0 * t).fract() - 0.7);
            let a = 10f64.powf(3.0 * (13.0 * t).fract() - 1.0);
            let got = quad_fast(c, a, q);
            let want =
                triangle_fast(c, a, q[0], q[1], q[2]) + triangle_fast(c, a, q[0], q[2], q[3]);
            assert!(
                (got - want).abs() <= 5e-15 / a,
                "{c:?} a={a}: {got} vs {want}"
            );
        }
        // A repeated corner (a triangle stored as a quadrilateral): the zero-length edge adds 0.
        let c = at(0.4, 0.5);
        let (got, want) = (
            quad_fast(c, 1.0, flat),
            triangle_fast(c, 1.0, q[0], q[2], q[3]),
        );
        assert!((got - want).abs() <= 5e-15, "{got} vs {want}");
        assert_eq!(quad_fast(c, 1.0, [q[0]; 4]), 0.0, "a point has no area");
    }

    /// `triangle_fast` (precomputed frame, one table pair per edge) against `triangle` (the
    /// foot-centred frame, and adaptive cubature where the value is small) on random triangles of
    /// sizes 1e−2 to 1e2 widths, centres on, near and far from them, slivers and degenerate
    /// triangles: absolute agreement to 1e−14·π/a, never negative or NaN.
    #[test]
    fn fast_triangle_matches_the_accurate_one_on_random_inputs() {
        let mut state = 0x5DEE_CE66_D1A4_F87Du64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut worst: f64 = 0.0;
        for k in 0..3000 {
            let size = 10f64.powf(4.0 * next() - 2.0);
            let mut v = [[0.0; 3]; 3];
            for p in v.iter_mut() {
                for x in p.iter_mut() {
                    *x = (2.0 * next() - 1.0) * size;
                }
            }
            if k % 10 == 0 {
                // A sliver, down to a degenerate (collinear) triangle.
                let w = if k % 50 == 0 {
                    0.0
                } else {
                    10f64.powf(-12.0 * next())
                };
                v[2] = [0, 1, 2].map(|i| 0.5 * (v[0][i] + v[1][i]) + w * size * (next() - 0.5));
            }
            let far = 10f64.powf(2.0 * next() - 1.0);
            let c = [0, 1, 2].map(|_| (2.0 * next() - 1.0) * size * far);
            let a = 10f64.powf(4.0 * next() - 2.0);
            let fast = triangle_fast(c, a, v[0], v[1], v[2]);
            let accurate = triangle(c, a, v[0], v[1], v[2]);
            assert!(fast >= 0.0 && fast.is_finite(), "{c:?} {v:?} {a}: {fast}");
            worst = worst.max((fast - accurate).abs() / (PI / a));
        }
        assert!(worst <= 1e-14, "worst |fast − accurate| = {worst:e}·π/a");
    }

    #[test]
    fn far_outside_centres_keep_relative_accuracy() {
        let t = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        let c = [3.0, 0.4, 0.2];
        let a = 2.0;
        let exact = triangle(c, a, t[0], t[1], t[2]);
        let f = |x: V| {
            let d = sub(x, c);
            (-a * dot(d, d)).exp()
        };
        let reference = triangle_cubature(f, t, 1e-16 * exact);
        assert!(exact > 1e-12 * PI / a);
        assert!(
            (exact - reference.value).abs() <= 1e-10 * exact,
            "{exact} vs {reference:?}"
        );
    }

    #[test]
    fn far_centres_underflow_to_zero_never_nan() {
        let t = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        for c in [[1e3, 1e3, 0.0], [0.0, 0.0, 1e6], [1e300, 0.0, 0.0]] {
            let v = triangle(c, 1.0, t[0], t[1], t[2]);
            assert!((0.0..1e-300).contains(&v));
        }
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]
        #[test]
        fn triangle_matches_adaptive_cubature(
            v in prop::array::uniform9(-2.0f64..2.0),
            c in prop::array::uniform3(-2.5f64..2.5),
            a in 0.2f64..20.0,
        ) {
            let (p, q, r) = ([v[0], v[1], v[2]], [v[3], v[4], v[5]], [v[6], v[7], v[8]]);
            let n = cross(sub(q, p), sub(r, p));
            prop_assume!(dot(n, n).sqrt() > 1e-2);
            let exact = triangle(c, a, p, q, r);
            let reference = triangle_cubature(|x| (-a * dot(sub(x, c), sub(x, c))).exp(), [p, q, r], 1e-12);
            let tol = 1e-9 * (PI / a) + 1e-8 * reference.value;
            prop_assert!((exact - reference.value).abs() <= tol, "{} vs {} ± {}", exact, reference.value, reference.error);
        }

        #[test]
        fn triangle_split_in_four_sums_to_the_whole(
            v in prop::array::uniform9(-2.0f64..2.0),
            c in prop::array::uniform3(-2.0f64..2.0),
            a in 0.2f64..10.0,
        ) {
            let (p, q, r) = ([v[0], v[1], v[2]], [v[3], v[4], v[5]], [v[6], v[7], v[8]]);
            let m = |x: V, y: V| scale(add(x, y), 0.5);
            let (pq, qr, rp) = (m(p, q), m(q, r), m(r, p));
            let whole = triangle(c, a, p, q, r);
            let parts = triangle(c, a, p, pq, rp) + triangle(c, a, pq, q, qr) + triangle(c, a, rp, qr, r) + triangle(c, a, pq, qr, rp);
            prop_assert!((whole - parts).abs() <= 1e-12 * (PI / a));
        }

        #[test]
        fn segment_matches_cubature_and_scales(
            p in prop::array::uniform3(-2.0f64..2.0),
            q in prop::array::uniform3(-2.0f64..2.0),
            c in prop::array::uniform3(-2.0f64..2.0),
            a in 0.1f64..30.0,
            k in 0.01f64..100.0,
        ) {
            let exact = segment(c, a, p, q);
            // 2000-point Gauss-free midpoint reference with Richardson would be slow; use the
            // scaling law instead: lengths ×k, a ÷k² ⇒ integral ×k.
            let scaled = segment(scale(c, k), a / (k * k), scale(p, k), scale(q, k));
            prop_assert!((scaled - k * exact).abs() <= 1e-12 * k * (PI / a).sqrt());
            let len = dot(sub(q, p), sub(q, p)).sqrt();
            let nmid = 20000;
            let mid: f64 = (0..nmid).map(|i| {
                let t = (i as f64 + 0.5) / nmid as f64;
                let x = add(p, scale(sub(q, p), t));
                (-a * dot(sub(x, c), sub(x, c))).exp()
            }).sum::<f64>() * len / nmid as f64;
            prop_assert!((exact - mid).abs() <= 1e-6 * (PI / a).sqrt());
        }
    }
}
