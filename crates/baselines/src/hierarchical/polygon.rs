//! Point-to-polygon form factors in 3-D (Lambert 1760; the contour-integral form used by Baum, Rushmeier and
//! Winget 1989) and random points on triangles.
//!
//! For a differential area at `x` with unit normal `n` and a planar polygon `P` that faces `x`, the
//! unoccluded form factor is
//!
//! `F(x → P) = (1/π) ∫_P cos θx cos θy / r² dA = (1/2π) Σ_i γ_i · n · û_i`,
//!
//! where `a_i = p_i − x`, `γ_i` is the angle between `a_i` and `a_{i+1}`, and `û_i` the unit vector along
//! `a_i × a_{i+1}` (the sum's sign follows the winding; its absolute value is taken). The formula needs `P` in
//! front of `x` (`cos θx ≥ 0`), so `P` is first clipped to the half-space `n · (y − x) ≥ 0`; and only the
//! front side of `P` emits, so `F = 0` when `x` is not strictly in front of `P`'s plane.

use glam::DVec3;

/// Clips a convex polygon to the closed half-space `n · (p − o) ≥ 0` (Sutherland–Hodgman).
pub fn clip_to_half_space(poly: &[DVec3], o: DVec3, n: DVec3) -> Vec<DVec3> {
    let mut out = Vec::with_capacity(poly.len() + 1);
    for i in 0..poly.len() {
        let (p, q) = (poly[i], poly[(i + 1) % poly.len()]);
        let (dp, dq) = (n.dot(p - o), n.dot(q - o));
        if dp >= 0.0 {
            out.push(p);
        }
        if (dp >= 0.0) != (dq >= 0.0) {
            let t = dp / (dp - dq);
            out.push(p + (q - p) * t);
        }
    }
    out
}

/// `F(x → P)` for a differential area at `x` with unit normal `n` and a convex polygon `poly` with unit
/// front normal `poly_normal` (module docs). 0 if `x` is not in front of the polygon's plane or the polygon is
/// entirely behind `x`.
pub fn point_to_polygon(x: DVec3, n: DVec3, poly: &[DVec3], poly_normal: DVec3) -> f64 {
    if poly.len() < 3 {
        return 0.0;
    }
    // scale for the "strictly in front" test: the polygon's extent
    let scale = poly
        .iter()
        .map(|p| (*p - poly[0]).length())
        .fold(0.0, f64::max);
    if poly_normal.dot(x - poly[0]) <= 1e-12 * scale {
        return 0.0;
    }
    let clipped = clip_to_half_space(poly, x, n);
    if clipped.len() < 3 {
        return 0.0;
    }
    let mut sum = 0.0;
    for i in 0..clipped.len() {
        let a = clipped[i] - x;
        let b = clipped[(i + 1) % clipped.len()] - x;
        let c = a.cross(b);
        let cl = c.length();
        if cl == 0.0 {
            continue;
        }
        let gamma = cl.atan2(a.dot(b));
        sum += gamma * n.dot(c) / cl;
    }
    (sum.abs() / (2.0 * std::f64::consts::PI)).min(1.0)
}

/// The point of triangle `v` for a uniform `u ∈ [0,1)²` (area-uniform: `b = (1 − √u0, √u0 (1 − u1), √u0 u1)`).
pub fn triangle_point(v: &[DVec3; 3], u: [f64; 2]) -> DVec3 {
    let s = u[0].sqrt();
    v[0] * (1.0 - s) + v[1] * (s * (1.0 - u[1])) + v[2] * (s * u[1])
}

/// The three points of the degree-2 Strang–Fix rule on triangle `v` (barycentric `(2/3, 1/6, 1/6)` and
/// permutations, equal weights 1/3): the receiver points at which a link's form factor is averaged.
pub fn quadrature_points(v: &[DVec3; 3]) -> [DVec3; 3] {
    let (a, b) = (2.0 / 3.0, 1.0 / 6.0);
    [
        v[0] * a + v[1] * b + v[2] * b,
        v[0] * b + v[1] * a + v[2] * b,
        v[0] * b + v[1] * b + v[2] * a,
    ]
}

/// `(1/A_r) ∫_r F(x → P) dx` for the triangle `r` (unit normal `nr`) and the convex polygon `P`: `r` is
/// clipped to the front half-space of `P`'s plane (only that part can receive), fan-triangulated, and
/// [`point_to_polygon`] is averaged with [`quadrature_points`] on each piece, weighted by its area. Exact up
/// to the quadrature (the integrand is smooth away from shared edges); positive whenever some part of `r`
/// sees the front of `P`. For an enclosure the factors of each quadrature point sum to one, so the average
/// does too.
pub fn triangle_to_polygon(r: &[DVec3; 3], nr: DVec3, poly: &[DVec3], poly_normal: DVec3) -> f64 {
    let area = 0.5 * (r[1] - r[0]).cross(r[2] - r[0]).length();
    if area <= 0.0 || poly.len() < 3 {
        return 0.0;
    }
    let front = clip_to_half_space(r, poly[0], poly_normal);
    if front.len() < 3 {
        return 0.0;
    }
    let mut sum = 0.0;
    for k in 1..front.len() - 1 {
        let t = [front[0], front[k], front[k + 1]];
        let a = 0.5 * (t[1] - t[0]).cross(t[2] - t[0]).length();
        if a <= 0.0 {
            continue;
        }
        let f: f64 = quadrature_points(&t)
            .iter()
            .map(|&x| point_to_polygon(x, nr, poly, poly_normal))
            .sum();
        sum += a * f / 3.0;
    }
    sum / area
}
