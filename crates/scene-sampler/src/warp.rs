//! Named warps of the unit square onto directions (pbrt-v4's `util/sampling.h`): each maps
//! `u ∈ [0, 1)²` to a direction with a known density, so that an estimator can divide by it and
//! weigh it against another technique. The surface warps (a point uniform on a triangle, on all
//! faces) are in [`crate::distribution`] and [`crate::sample`].

use glam::{DVec2, DVec3};

/// An orthonormal basis `(t, b)` completing the unit vector `n` (Duff et al. 2017, branchless).
pub fn orthonormal_basis(n: DVec3) -> (DVec3, DVec3) {
    let sign = 1.0f64.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (
        DVec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
        DVec3::new(b, sign + n.y * n.y * a, -n.y),
    )
}

/// Cosine-weighted direction on the hemisphere around unit `n`: density `cos θ / π` per steradian
/// (Malley's method: uniform disk, lifted). With it the pointwise estimator of docs/design/math.md §8,
/// `B(y) = E(y) + ρ(y)·B(hit(y, ω))`, needs no cosine or π factor.
pub fn cosine_hemisphere(n: DVec3, u: [f64; 2]) -> DVec3 {
    let r = u[0].clamp(0.0, 1.0).sqrt();
    let phi = 2.0 * std::f64::consts::PI * u[1];
    let (x, y) = (r * phi.cos(), r * phi.sin());
    let z = (1.0 - u[0].clamp(0.0, 1.0)).max(0.0).sqrt();
    let (t, b) = orthonormal_basis(n);
    (t * x + b * y + n * z).normalize()
}

/// A direction uniform in the cone of half-angle α about the unit `axis`, given by
/// `one_minus_cos` = 1 − cos α (pass it as 2 sin²(α/2) so that a sun's 0.27° keeps its digits):
/// density 1/(2π (1 − cos α)) per steradian ([`uniform_cone_pdf`]; pbrt-v4's `SampleUniformCone`).
pub fn uniform_cone(axis: DVec3, one_minus_cos: f64, u: [f64; 2]) -> DVec3 {
    uniform_cone_about((axis, orthonormal_basis(axis)), one_minus_cos, u)
}

/// [`uniform_cone`] about a frame (the unit `axis` and two unit tangents orthogonal to it and to
/// each other, as [`orthonormal_basis`] gives) computed once: a sun's cone is sampled at every
/// path vertex. The direction is unit by construction (sin²θ + cos²θ = 1 up to rounding).
pub fn uniform_cone_about(
    (axis, (t, b)): (DVec3, (DVec3, DVec3)),
    one_minus_cos: f64,
    u: [f64; 2],
) -> DVec3 {
    // 1 − cos θ uniform on [0, 1 − cos α]; sin θ from it without cancellation
    let omc = u[0].clamp(0.0, 1.0) * one_minus_cos;
    let sin = (omc * (2.0 - omc)).max(0.0).sqrt();
    let (s, c) = (2.0 * std::f64::consts::PI * u[1]).sin_cos();
    t * (sin * c) + b * (sin * s) + axis * (1.0 - omc)
}

/// The solid-angle density of [`uniform_cone`]: 1/(2π (1 − cos α)).
pub fn uniform_cone_pdf(one_minus_cos: f64) -> f64 {
    1.0 / (2.0 * std::f64::consts::PI * one_minus_cos)
}

/// Flatland analogue of [`cosine_hemisphere`]: a direction in the half-plane around unit `n` with density
/// `cos θ / 2` per radian (θ from the normal), i.e. `sin θ = 2u − 1`. The Flatland kernel
/// `cos θx cos θy / (2r)` integrates to 1 over the half-plane with exactly this measure.
pub fn cosine_halfplane(n: DVec2, u: f64) -> DVec2 {
    let s = (2.0 * u.clamp(0.0, 1.0) - 1.0).clamp(-1.0, 1.0);
    let c = (1.0 - s * s).max(0.0).sqrt();
    let t = DVec2::new(-n.y, n.x);
    (n * c + t * s).normalize()
}

/// ∫ f(ω) dω over the hemisphere about the unit `axis`, by the midpoint rule on an n × n grid in
/// (cos θ, φ) (cos θ uniform is area-uniform on the hemisphere): the reference quadrature of a
/// sky's normalisation and of the lights' tests.
pub fn hemisphere_quadrature(axis: DVec3, n: usize, mut f: impl FnMut(DVec3) -> f64) -> f64 {
    let (t, b) = orthonormal_basis(axis);
    let mut sum = 0.0;
    for i in 0..n {
        let c = (i as f64 + 0.5) / n as f64;
        let s = (1.0 - c * c).sqrt();
        for j in 0..n {
            let phi = 2.0 * std::f64::consts::PI * (j as f64 + 0.5) / n as f64;
            sum += f(t * (s * phi.cos()) + b * (s * phi.sin()) + axis * c);
        }
    }
    sum * 2.0 * std::f64::consts::PI / (n * n) as f64
}
