//! The dissertation's error estimates for the flat closed forms (sec. 3.9.4, eq. 3.62–3.73) and
//! the decision of fig. 3.6 as thresholds on fuzzy roughness and depth.

use std::f64::consts::PI;

fn erf_int(x: f64) -> f64 {
    // ∫_0^x exp(−t²) dt = √π/2 · erf(x)
    0.5 * PI.sqrt() * libm::erf(x)
}

/// E_FI(α), eq. 3.64: inner product on a patch rotated by α (radians).
pub fn e_fi(alpha: f64) -> f64 {
    let a = (1.0 + alpha.tan().powi(2)).sqrt();
    let approx = PI * erf_int(2.0);
    let exact = PI * erf_int(2.0 * a);
    ((approx - exact) / exact).powi(2)
}

/// E_FT(α), eq. 3.67: transfer coefficient on patches rotated by α.
pub fn e_ft(alpha: f64) -> f64 {
    let a = (1.0 + alpha.tan().powi(2)).sqrt();
    let approx = 2.0 * PI * PI * erf_int(2f64.sqrt()).powi(2);
    let exact = 2.0 * PI * PI * erf_int((2.0 * a).sqrt()).powi(2);
    ((approx - exact) / exact).powi(2)
}

/// E_DI(δ), eq. 3.70: inner product of a Gaussian δ widths from a straight network boundary.
pub fn e_di(delta: f64) -> f64 {
    let i_di = PI / 2.0;
    let i_ri = PI / 4.0 * (1.0 - 2.0 / PI.sqrt() * erf_int(delta * 2f64.sqrt()));
    (i_ri / i_di).powi(2)
}

/// E_DT(δ), eq. 3.73: transfer coefficient of two Gaussians δ widths from the boundary.
pub fn e_dt(delta: f64) -> f64 {
    let i_dt = PI * PI;
    let i_rt = PI * PI / 4.0 * (2.0 / PI.sqrt() * erf_int(delta) - 1.0).powi(2);
    (i_rt / i_dt).powi(2)
}

/// How an integral is computed (fig. 3.6).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Integration {
    /// Set to zero (separate sub-networks, opposed normals, or normals not facing).
    Zero,
    /// The flat closed form.
    ClosedForm,
    /// The exact sum over the network's elements.
    ElementSum,
}

/// The decision of fig. 3.6 for one Gaussian: closed form when its fuzzy roughness is below
/// `roughness_threshold` and its depth flag at least `depth_threshold` (sec. 4.4.1: 0.4 and 1).
pub fn decide(
    fuzzy_roughness: f64,
    depth: u32,
    roughness_threshold: f64,
    depth_threshold: u32,
) -> Integration {
    if fuzzy_roughness < roughness_threshold && depth >= depth_threshold {
        Integration::ClosedForm
    } else {
        Integration::ElementSum
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn errors_vanish_for_flat_deep_networks_and_grow_monotonically() {
        assert!(e_fi(0.0) < 1e-30 && e_ft(0.0) < 1e-30);
        assert!(e_fi(0.4) > e_fi(0.2) && e_ft(0.4) > e_ft(0.2));
        assert!(e_di(3.0) < e_di(1.0) && e_dt(3.0) < e_dt(1.0));
        assert!(e_di(0.0) > 0.0);
        assert_eq!(decide(0.1, 2, 0.4, 1), Integration::ClosedForm);
        assert_eq!(decide(0.5, 2, 0.4, 1), Integration::ElementSum);
        assert_eq!(decide(0.1, 0, 0.4, 1), Integration::ElementSum);
    }
}
