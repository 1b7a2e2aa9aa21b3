//! The Perez all-weather sky (R. Perez, R. Seals, J. Michalsky, "All-weather model for sky
//! luminance distribution — preliminary configuration and validation", Solar Energy 50(3),
//! 235–245, 1993), as Radiance's `gendaylit` evaluates it.
//!
//! The relative luminance of the sky element at zenith angle θ and angle γ from the sun is the
//! paper's eq. (1):
//!
//! ```text
//! lv(θ, γ) = (1 + a·exp(b / cos θ)) · (1 + c·exp(d·γ) + e·cos² γ)
//! ```
//!
//! with a…e from the sky clearness ε, the sky brightness Δ and the solar zenith angle Z (radians)
//! through the paper's Table 1: eight ε bins, and in each x = x₁ + x₂·Z + Δ·(x₃ + x₄·Z) for every
//! coefficient x — except in the first (overcast) bin, where the paper gives c = exp((Δ·(c₁ +
//! c₂·Z))^c₃) − c₄ and d = −exp(Δ·(d₁ + d₂·Z)) + d₃ + Δ·d₄. As in `gendaylit`, Δ is raised to 0.2
//! in the bins 1.065 ≤ ε < 2.8 (its correction of the model), ε is kept in [1, 12.01) and Δ in
//! [0.01, 0.6], and cos θ is taken as at least 0.01 (`perezlum.cal`'s floor at the horizon).
//!
//! The parameters (Perez et al. 1990, "Modeling daylight availability and irradiance components
//! from direct and global irradiance", Solar Energy 44(5), 271–289):
//!
//! ```text
//! ε = ((E_dh + E_dn)/E_dh + κ·Z³) / (1 + κ·Z³),   κ = 1.041
//! Δ = m · E_dh / E₀
//! ```
//!
//! with E_dn the direct normal and E_dh the diffuse horizontal **irradiance** (W/m²), m the
//! relative optical air mass (Kasten & Young 1989) and E₀ = 1367 W/m² the extraterrestrial
//! irradiance at the mean Earth–Sun distance (no date: no eccentricity correction).
//! [`parameters_from_illuminance`] takes illuminances (lux), as `gendaylit -L` does: starting from
//! the solar constants' ratio 127 500 lx / 1367 W/m², it converts each with the Perez et al. (1990)
//! luminous efficacy models — diffuse horizontal and direct normal, per ε bin — at the ε and
//! Δ found so far, with 2 cm of precipitable water (`gendaylit`'s default dew point), until they
//! settle.

/// The paper's Table 1: for each ε bin, the rows a, b, c, d, e, each (x₁, x₂, x₃, x₄).
const TABLE: [[[f64; 4]; 5]; 8] = [
    [
        [1.3525, -0.2576, -0.2690, -1.4366],
        [-0.7670, 0.0007, 1.2734, -0.1233],
        [2.8000, 0.6004, 1.2375, 1.0000],
        [1.8734, 0.6297, 0.9738, 0.2809],
        [0.0356, -0.1246, -0.5718, 0.9938],
    ],
    [
        [-1.2219, -0.7730, 1.4148, 1.1016],
        [-0.2054, 0.0367, -3.9128, 0.9156],
        [6.9750, 0.1774, 6.4477, -0.1239],
        [-1.5798, -0.5081, -1.7812, 0.1080],
        [0.2624, 0.0672, -0.2190, -0.4285],
    ],
    [
        [-1.1000, -0.2515, 0.8952, 0.0156],
        [0.2782, -0.1812, -4.5000, 1.1766],
        [24.7219, -13.0812, -37.7000, 34.8438],
        [-5.0000, 1.5218, 3.9229, -2.6204],
        [-0.0156, 0.1597, 0.4199, -0.5562],
    ],
    [
        [-0.5484, -0.6654, -0.2672, 0.7117],
        [0.7234, -0.6219, -5.6812, 2.6297],
        [33.3389, -18.3000, -62.2500, 52.0781],
        [-3.5000, 0.0016, 1.1477, 0.1062],
        [0.4659, -0.3296, -0.0876, -0.0329],
    ],
    [
        [-0.6000, -0.3566, -2.5000, 2.3250],
        [0.2937, 0.0496, -5.6812, 1.8415],
        [21.0000, -4.7656, -21.5906, 7.2492],
        [-3.5000, -0.1554, 1.4062, 0.3988],
        [0.0032, 0.0766, -0.0656, -0.1294],
    ],
    [
        [-1.0156, -0.3670, 1.0078, 1.4051],
        [0.2875, -0.5328, -3.8500, 3.3750],
        [14.0000, -0.9999, -7.1406, 7.5469],
        [-3.4000, -0.1078, -1.0750, 1.5702],
        [-0.0672, 0.4016, 0.3017, -0.4844],
    ],
    [
        [-1.0000, 0.0211, 0.5025, -0.5119],
        [-0.3000, 0.1922, 0.7023, -1.6317],
        [19.0000, -5.0000, 1.2438, -1.9094],
        [-4.0000, 0.0250, 0.3844, 0.2656],
        [1.0468, -0.3788, -2.4517, 1.4656],
    ],
    [
        [-1.0500, 0.0289, 0.4260, 0.3590],
        [-0.3250, 0.1156, 0.7781, 0.0025],
        [31.0625, -14.5000, -46.1148, 55.3750],
        [-7.2312, 0.4050, 13.3500, 0.6234],
        [1.5000, -0.6426, 1.8564, 0.5636],
    ],
];

/// The upper ε bounds of the first seven bins (the eighth is open).
const BINS: [f64; 7] = [1.065, 1.23, 1.5, 1.95, 2.8, 4.5, 6.2];

/// The range `gendaylit` keeps ε in (lower bound, and just under its upper bound 12.01).
const EPSILON_RANGE: (f64, f64) = (1.0, 12.009);
/// The range `gendaylit` keeps Δ in.
const DELTA_RANGE: (f64, f64) = (0.01, 0.6);

/// κ of the clearness ε (Perez et al. 1990; Z in radians).
const KAPPA: f64 = 1.041;
/// Extraterrestrial normal irradiance at the mean Earth–Sun distance, W/m².
const SOLAR_CONSTANT: f64 = 1367.0;
/// Extraterrestrial normal illuminance, lux (`gendaylit`'s first guess of the efficacy).
const SOLAR_CONSTANT_LUX: f64 = 127_500.0;
/// Atmospheric precipitable water, cm (`gendaylit`'s default dew point gives 2 cm).
const WATER: f64 = 2.0;

/// The ε bin (0–7) of a clearness.
fn bin(epsilon: f64) -> usize {
    BINS.iter().take_while(|&&b| epsilon >= b).count()
}

/// ε and Δ kept in the ranges `gendaylit` keeps them in (module docs).
pub fn clamp(epsilon: f64, delta: f64) -> (f64, f64) {
    (
        epsilon.clamp(EPSILON_RANGE.0, EPSILON_RANGE.1),
        delta.clamp(DELTA_RANGE.0, DELTA_RANGE.1),
    )
}

/// The coefficients a, b, c, d, e of eq. (1) for clearness `epsilon`, brightness `delta` and the
/// solar zenith angle `zenith` (radians): Table 1 and the first bin's special forms (module docs).
pub fn coefficients(epsilon: f64, delta: f64, zenith: f64) -> [f64; 5] {
    let (epsilon, mut delta) = clamp(epsilon, delta);
    let k = bin(epsilon);
    if (1..=4).contains(&k) {
        // gendaylit's correction: 1.065 < ε < 2.8 with Δ under 0.2
        delta = delta.max(0.2);
    }
    let z = zenith;
    let linear = |x: &[f64; 4]| x[0] + x[1] * z + delta * (x[2] + x[3] * z);
    let mut out = TABLE[k].map(|x| linear(&x));
    if k == 0 {
        let [c, d] = [TABLE[0][2], TABLE[0][3]];
        out[2] = (delta * (c[0] + c[1] * z)).powf(c[2]).exp() - c[3];
        out[3] = -(delta * (d[0] + d[1] * z)).exp() + d[2] + delta * d[3];
    }
    out
}

/// The relative luminance lv(θ, γ) of eq. (1) for the coefficients `c` (from [`coefficients`]),
/// the cosine of the zenith angle (at least 0.01: module docs) and the angle `gamma` (radians)
/// from the sun.
pub fn relative_luminance(c: &[f64; 5], cos_theta: f64, gamma: f64) -> f64 {
    let gradation = 1.0 + c[0] * (c[1] / cos_theta.max(0.01)).exp();
    let indicatrix = 1.0 + c[2] * (c[3] * gamma).exp() + c[4] * gamma.cos().powi(2);
    gradation * indicatrix
}

/// The relative optical air mass at solar zenith angle `zenith` (radians), Kasten & Young (1989):
/// m = 1/(cos Z + 0.50572·(96.07995° − Z)^−1.6364).
pub fn air_mass(zenith: f64) -> f64 {
    let z = zenith.to_degrees().clamp(0.0, 90.0);
    1.0 / (z.to_radians().cos() + 0.50572 * (96.07995 - z).powf(-1.6364))
}

/// The clearness ε from the direct normal and diffuse horizontal irradiances (or illuminances)
/// and the solar zenith angle (radians); the largest ε when there is no diffuse light.
pub fn clearness(direct_normal: f64, diffuse_horizontal: f64, zenith: f64) -> f64 {
    if diffuse_horizontal <= 0.0 {
        return EPSILON_RANGE.1;
    }
    let kz3 = KAPPA * zenith.powi(3);
    ((diffuse_horizontal + direct_normal) / diffuse_horizontal + kz3) / (1.0 + kz3)
}

/// The brightness Δ from the diffuse horizontal irradiance (W/m²) and the solar zenith angle.
pub fn brightness(diffuse_horizontal: f64, zenith: f64) -> f64 {
    diffuse_horizontal * air_mass(zenith) / SOLAR_CONSTANT
}

/// The Perez et al. (1990) diffuse luminous efficacy (lm/W; the table gendaylit uses): per ε bin
/// (a, b, c, d) of a + b·W + c·cos Z + d·ln Δ.
const DIFFUSE_EFFICACY: [[f64; 4]; 8] = [
    [97.24, -0.46, 12.00, -8.91],
    [107.22, 1.15, 0.59, -3.95],
    [104.97, 2.96, -5.53, -8.77],
    [102.39, 5.59, -13.95, -13.90],
    [100.71, 5.94, -22.75, -23.74],
    [106.42, 3.83, -36.15, -28.83],
    [141.88, 1.90, -53.24, -14.03],
    [152.23, 0.35, -45.27, -7.98],
];

/// The Perez et al. (1990) direct normal luminous efficacy (lm/W; the table gendaylit uses): per ε bin
/// (a, b, c, d) of a + b·W + c·exp(5.73·Z − 5) + d·Δ, at least 0.
const DIRECT_EFFICACY: [[f64; 4]; 8] = [
    [57.20, -4.55, -2.98, 117.12],
    [98.99, -3.46, -1.21, 12.38],
    [109.83, -4.90, -1.71, -8.81],
    [110.34, -5.84, -1.99, -4.56],
    [106.36, -3.97, -1.75, -6.16],
    [107.19, -1.25, -1.51, -26.73],
    [105.75, 0.77, -1.26, -34.44],
    [101.18, 1.58, -1.10, -8.29],
];

/// The diffuse and direct normal luminous efficacies (lm/W) of a sky (ε, Δ) at solar zenith Z.
fn efficacies(epsilon: f64, delta: f64, zenith: f64) -> (f64, f64) {
    let k = bin(epsilon);
    let [a, b, c, d] = DIFFUSE_EFFICACY[k];
    let diffuse = a + b * WATER + c * zenith.cos() + d * delta.ln();
    let [a, b, c, d] = DIRECT_EFFICACY[k];
    let direct = (a + b * WATER + c * (5.73 * zenith - 5.0).exp() + d * delta).max(0.0);
    (diffuse, direct)
}

/// The Perez parameters (ε, Δ), kept in range, of a sky with direct normal illuminance
/// `direct_normal` and diffuse horizontal illuminance `diffuse_horizontal` (lux) at solar zenith
/// angle `zenith` (radians), as `gendaylit -L` finds them (module docs): the illuminances are
/// turned into irradiances by the efficacies of the (ε, Δ) they give, until those settle.
pub fn parameters_from_illuminance(
    direct_normal: f64,
    diffuse_horizontal: f64,
    zenith: f64,
) -> (f64, f64) {
    let to_watts = SOLAR_CONSTANT / SOLAR_CONSTANT_LUX;
    let (mut dn, mut dh) = (direct_normal * to_watts, diffuse_horizontal * to_watts);
    let mut params = clamp(clearness(dn, dh, zenith), brightness(dh, zenith));
    // a fixed point; gendaylit takes nine steps, which is as settled as this gets (1e-9 W/m²)
    for _ in 0..50 {
        let (diffuse, direct) = efficacies(params.0, params.1, zenith);
        let next_dh = diffuse_horizontal / diffuse;
        let next_dn = if direct < 0.1 {
            0.0
        } else {
            direct_normal / direct
        };
        let settled = (next_dh - dh).abs() < 1e-9 && (next_dn - dn).abs() < 1e-9;
        (dn, dh) = (next_dn, next_dh);
        params = clamp(clearness(dn, dh, zenith), brightness(dh, zenith));
        if settled {
            break;
        }
    }
    params
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The bins' bounds, the overcast bin's special forms and the linear ones, against values
    /// worked by hand from Table 1.
    #[test]
    fn coefficients_follow_table_1() {
        assert_eq!(bin(1.0), 0);
        assert_eq!(bin(1.065), 1);
        assert_eq!(bin(6.19), 6);
        assert_eq!(bin(6.2), 7);
        // clear bin 8 at Z = 0.5, Δ = 0.1: a = −1.05 + 0.0289·0.5 + 0.1·(0.426 + 0.359·0.5)
        let c = coefficients(7.0, 0.1, 0.5);
        assert!((c[0] - (-1.05 + 0.01445 + 0.1 * (0.426 + 0.1795))).abs() < 1e-12);
        // overcast bin 1 at Z = 0.5, Δ = 0.2: c = exp((0.2·(2.8 + 0.6004·0.5))^1.2375) − 1
        let c = coefficients(1.02, 0.2, 0.5);
        let c_hand = (0.2f64 * (2.8 + 0.3002)).powf(1.2375).exp() - 1.0;
        let d_hand = -(0.2f64 * (1.8734 + 0.31485)).exp() + 0.9738 + 0.2 * 0.2809;
        assert!((c[2] - c_hand).abs() < 1e-12 && (c[3] - d_hand).abs() < 1e-12);
        // the correction: Δ = 0.1 in bin 3 is taken as 0.2
        assert_eq!(coefficients(1.3, 0.1, 0.7), coefficients(1.3, 0.2, 0.7));
    }

    /// ε and Δ with Kasten & Young's air mass (m = 1/cos Z within 0.1 % up high,
    /// 2.356 at Z = 65°, about 38 at the horizon).
    #[test]
    fn clearness_brightness_and_air_mass() {
        let z = 0.3f64;
        let kz3 = 1.041 * z.powi(3);
        assert!((clearness(500.0, 100.0, z) - (6.0 + kz3) / (1.0 + kz3)).abs() < 1e-12);
        assert_eq!(clearness(500.0, 0.0, z), EPSILON_RANGE.1);
        assert!((air_mass(0.2) * 0.2f64.cos() - 1.0).abs() < 1e-3);
        assert!((air_mass(65f64.to_radians()) - 2.356).abs() < 2e-3);
        assert!((air_mass(std::f64::consts::FRAC_PI_2) - 37.9).abs() < 0.2);
        assert!((brightness(137.0, 0.0) - 137.0 * air_mass(0.0) / 1367.0).abs() < 1e-12);
    }
}
