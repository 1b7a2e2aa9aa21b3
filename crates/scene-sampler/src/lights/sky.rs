//! The sky: radiance from every direction above the horizon, and the ground's below it, at
//! infinity. Models (Radiance's `gensky` names them the same way):
//!
//! * **uniform**: constant radiance L; horizontal irradiance E_h = π L;
//! * **CIE overcast** (Moon & Spencer): L(θ) = L_z (1 + 2 cos θ)/3 from the zenith angle θ;
//!   E_h = 7π L_z/9;
//! * **CIE clear** (CIE 1973/ISO 15469 type 12, as `gensky +s`): L(θ, γ) = L_z ·
//!   f(γ) φ(θ)/(f(Z₀) φ(0)), φ(θ) = 1 − exp(−0.32/cos θ), f(γ) = 0.91 + 10 exp(−3γ) +
//!   0.45 cos² γ, with γ the angle to the sun and Z₀ the sun's zenith angle; E_h by quadrature;
//! * **Perez all-weather** (Perez, Seals & Michalsky 1993, as `gendaylit`): L(θ, γ) ∝
//!   (1 + a·exp(b/cos θ))·(1 + c·exp(d·γ) + e·cos² γ), a…e from the sky clearness ε, brightness
//!   Δ and Z₀ ([`super::perez`]); E_h by quadrature.
//!
//! Every model is given by its horizontal irradiance E_h (diffuse horizontal illuminance, in lux
//! for photometric scenes). The **ground** is the lower hemisphere at constant radiance
//! L_g = ρ_g·E_g/π — Radiance's ground glow, with E_g the horizontal irradiance of the sky and
//! the sun together and ρ_g the ground reflectance (0.2 by default in `gensky`); ρ_g = 0 makes it
//! black.
//!
//! With portals ([`Sky::with_portals`]: the openings an interior sees the sky through), three
//! quarters of the shadow rays go through them (`portal.rs`), the rest as follows.
//!
//! Sampled by a mixture of cosine-weighted hemispheres about the zenith and the nadir, chosen in
//! proportion to the power each sends to the receiver's side (E_h·(1 + cos β) against
//! π L_g·(1 − cos β) for a receiver tilted by β); MIS with the receivers' cosine rays keeps the
//! weights bounded near the horizon, where the zenith density goes to 0.

use super::{Light, LightSample, Portals, Receiver, ShadowTarget};
use crate::{BANDS, Bands, cosine_hemisphere};
use glam::DVec3;
use std::f64::consts::PI;

/// The sky's luminance distribution (module docs).
#[derive(Clone, Debug, PartialEq)]
pub enum SkyModel {
    /// Constant radiance.
    Uniform,
    /// The CIE overcast sky.
    CieOvercast,
    /// The CIE clear sky for the sun in the unit direction given (toward the sun).
    CieClear {
        /// Unit direction toward the sun (above the horizon).
        sun: DVec3,
    },
    /// The Perez all-weather sky ([`super::perez`]) for the sun in the unit direction given, of
    /// clearness ε and brightness Δ (kept in [1, 12.01) and [0.01, 0.6]).
    Perez {
        /// Unit direction toward the sun (above the horizon).
        sun: DVec3,
        /// Sky clearness ε (1: overcast, above 6: clear).
        epsilon: f64,
        /// Sky brightness Δ.
        delta: f64,
    },
}

impl SkyModel {
    /// The direction toward the sun, for the models that have one.
    fn sun(&self) -> Option<DVec3> {
        match self {
            SkyModel::CieClear { sun } | SkyModel::Perez { sun, .. } => Some(*sun),
            _ => None,
        }
    }
}

/// The sky and its ground (module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct Sky {
    model: SkyModel,
    /// Unit zenith direction.
    up: DVec3,
    /// Zenith radiance L_z per band (for the uniform sky: its radiance).
    zenith: Bands,
    /// The ground's radiance per band.
    ground: Bands,
    /// The horizontal irradiance the sky gives (per band).
    horizontal: Bands,
    /// The upper and lower hemispheres' powers for sampling (E_h and π·L_g, band means).
    powers: (f64, f64),
    /// Openings through which interiors see the sky ([`Sky::with_portals`]).
    portals: Portals,
    /// The Perez sky's coefficients a…e (zeros for the other models).
    perez: [f64; 5],
}

/// Zenith angles and azimuths of the quadrature that normalises the clear sky.
const QUAD: usize = 256;

impl Sky {
    /// A sky of `model` about the zenith `up` with horizontal irradiance `horizontal` and ground
    /// radiance `ground` (module docs: ρ_g·E_g/π). `None` when `up` is zero, a value is negative
    /// or not finite, a clear or Perez sky's sun is below the horizon, or a Perez sky's ε or Δ is
    /// not finite or gives a gradation that grows toward the horizon (b > 0, which `gendaylit`
    /// refuses too).
    pub fn new(model: SkyModel, up: DVec3, horizontal: Bands, ground: Bands) -> Option<Self> {
        let up = up.try_normalize()?;
        let ok = |b: &Bands| b.iter().all(|v| v.is_finite() && *v >= 0.0);
        if !ok(&horizontal) || !ok(&ground) {
            return None;
        }
        if let Some(sun) = model.sun() {
            if sun.try_normalize()?.dot(up) <= 0.0 {
                return None;
            }
        }
        let mut perez = [0.0; 5];
        let model = match model {
            SkyModel::CieClear { sun } => SkyModel::CieClear {
                sun: sun.normalize(),
            },
            SkyModel::Perez {
                sun,
                epsilon,
                delta,
            } => {
                if !(epsilon.is_finite() && delta.is_finite()) {
                    return None;
                }
                let sun = sun.normalize();
                let zenith = sun.dot(up).clamp(-1.0, 1.0).acos();
                perez = super::perez::coefficients(epsilon, delta, zenith);
                if perez[1] > 0.0 {
                    return None;
                }
                let (epsilon, delta) = super::perez::clamp(epsilon, delta);
                SkyModel::Perez {
                    sun,
                    epsilon,
                    delta,
                }
            }
            m => m,
        };
        let mut sky = Self {
            model,
            up,
            zenith: [1.0; BANDS],
            ground,
            horizontal,
            powers: (mean(&horizontal), PI * mean(&ground)),
            portals: Portals::default(),
            perez,
        };
        // E_h of the model at L_z = 1, then L_z from the given E_h
        let unit = sky.unit_horizontal();
        sky.zenith = horizontal.map(|e| e / unit);
        Some(sky)
    }

    /// The horizontal irradiance the sky gives at L_z = 1: π, 7π/9, or by quadrature (clear,
    /// Perez).
    fn unit_horizontal(&self) -> f64 {
        match self.model {
            SkyModel::Uniform => PI,
            SkyModel::CieOvercast => 7.0 * PI / 9.0,
            SkyModel::CieClear { .. } | SkyModel::Perez { .. } => {
                crate::hemisphere_quadrature(self.up, QUAD, |w| self.shape(w) * w.dot(self.up))
            }
        }
    }

    /// The model's radiance relative to the zenith's, for a direction above the horizon.
    fn shape(&self, w: DVec3) -> f64 {
        let c = w.dot(self.up).clamp(0.0, 1.0);
        match self.model {
            SkyModel::Uniform => 1.0,
            SkyModel::CieOvercast => (1.0 + 2.0 * c) / 3.0,
            SkyModel::CieClear { sun } => {
                let phi = |cos_theta: f64| 1.0 - (-0.32 / cos_theta.max(1e-6)).exp();
                let f =
                    |gamma: f64| 0.91 + 10.0 * (-3.0 * gamma).exp() + 0.45 * gamma.cos().powi(2);
                let gamma = w.dot(sun).clamp(-1.0, 1.0).acos();
                let z0 = sun.dot(self.up).clamp(-1.0, 1.0).acos();
                f(gamma) * phi(c) / (f(z0) * phi(1.0))
            }
            SkyModel::Perez { sun, .. } => {
                let lv = |cos_theta: f64, cos_gamma: f64| {
                    super::perez::relative_luminance(
                        &self.perez,
                        cos_theta,
                        cos_gamma.clamp(-1.0, 1.0).acos(),
                    )
                };
                let cos_z0 = sun.dot(self.up);
                lv(c, w.dot(sun)) / lv(1.0, cos_z0)
            }
        }
    }

    /// The sky seen through `portals` (module docs of `lights/portal.rs`): most shadow rays go
    /// through them.
    pub fn with_portals(self, portals: Portals) -> Self {
        Self { portals, ..self }
    }

    /// The horizontal irradiance the sky gives (the value it was made with).
    pub fn horizontal(&self) -> Bands {
        self.horizontal
    }

    /// Radiance π·L toward the unit direction `dir` (sky above the horizon, ground below).
    fn emission(&self, dir: DVec3) -> Bands {
        if dir.dot(self.up) > 0.0 {
            let s = self.shape(dir);
            self.zenith.map(|l| PI * l * s)
        } else {
            self.ground.map(|l| PI * l)
        }
    }

    /// The probability of sampling the upper hemisphere for a receiver with normal `n`: each
    /// hemisphere's power times the share of it a plane tilted like the receiver sees —
    /// (1 ± cos β)/2, exact for uniform hemispheres — so that a floor draws no ground samples
    /// and a ceiling no sky samples.
    fn p_up(&self, n: DVec3) -> f64 {
        let c = n.dot(self.up).clamp(-1.0, 1.0);
        let (up, down) = (self.powers.0 * (1.0 + c), self.powers.1 * (1.0 - c));
        if up + down > 0.0 {
            up / (up + down)
        } else {
            0.5
        }
    }

    /// The hemispheres' density of `dir` for a receiver with normal `n`.
    fn hemisphere_pdf(&self, n: DVec3, dir: DVec3) -> f64 {
        let (c, p_up) = (dir.dot(self.up), self.p_up(n));
        if c > 0.0 {
            p_up * c / PI
        } else {
            (1.0 - p_up) * (-c) / PI
        }
    }

    /// The sampling density of `dir` at the receiver: the hemispheres', mixed with the portals'
    /// when there are portals that the receiver has in view.
    fn pdf(&self, at: &Receiver, dir: DVec3) -> f64 {
        self.portals
            .mix_pdf(at.p, dir, self.hemisphere_pdf(at.n, dir))
    }
}

fn mean(b: &Bands) -> f64 {
    b.iter().sum::<f64>() / BANDS as f64
}

impl Light for Sky {
    fn sample(&self, at: &Receiver, u: [f64; 2]) -> Option<LightSample> {
        // through a portal, or a hemisphere chosen by u[0] remapped to [0, 1) within the rest
        let w = self.portals.mix_sample(at.p, u, |[u0, u1]| {
            let p_up = self.p_up(at.n);
            let (axis, v) = if u0 < p_up {
                (self.up, u0 / p_up)
            } else {
                (-self.up, (u0 - p_up) / (1.0 - p_up))
            };
            cosine_hemisphere(axis, [v.min(1.0 - f64::EPSILON), u1])
        })?;
        let (cy, pdf) = (at.n.dot(w), self.pdf(at, w));
        (cy > 0.0 && pdf > 0.0).then(|| LightSample {
            target: ShadowTarget::Direction(w),
            emission: self.emission(w),
            g: cy / PI,
            pdf,
        })
    }

    fn escaped(&self, dir: DVec3) -> Bands {
        self.emission(dir)
    }

    fn escaped_pdf(&self, at: &Receiver, dir: DVec3) -> f64 {
        self.pdf(at, dir)
    }

    fn is_delta(&self) -> bool {
        false
    }

    fn is_background(&self) -> bool {
        true
    }

    fn power(&self, radius: f64) -> f64 {
        // with portals, the flux that can come through them (at most E_h per unit area, each
        // side), not through the scene's whole bounding disc
        self.portals.collecting_area(radius) * (mean(&self.horizontal) + PI * mean(&self.ground))
    }

    fn is_grey(&self) -> bool {
        super::grey(&self.horizontal) && super::grey(&self.ground)
    }

    fn describe(&self) -> String {
        let model = match self.model {
            SkyModel::Uniform => "uniform".to_string(),
            SkyModel::CieOvercast => "CIE overcast".to_string(),
            SkyModel::CieClear { .. } => "CIE clear".to_string(),
            SkyModel::Perez { epsilon, delta, .. } => {
                format!("Perez (ε = {epsilon:.3}, Δ = {delta:.3})")
            }
        };
        format!(
            "{model} sky, {} horizontal irradiance, ground radiance {}",
            self.horizontal[0], self.ground[0]
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The horizontal irradiance ∫ L cos θ dω of each model, by a fine quadrature of the sky's own
    /// radiance, is the E_h it was made with (the overcast and uniform normalisations are closed
    /// forms; the clear sky's is the constructor's coarser quadrature). And E·g/p averaged over the
    /// sky's samples is the same irradiance (the density and the radiance agree).
    #[test]
    fn each_model_gives_its_horizontal_irradiance() {
        let up = DVec3::new(0.0, 0.0, 1.0);
        let sun = DVec3::new(0.5, 0.2, 0.6).normalize();
        for model in [
            SkyModel::Uniform,
            SkyModel::CieOvercast,
            SkyModel::CieClear { sun },
            SkyModel::Perez {
                sun,
                epsilon: 6.3,
                delta: 0.12,
            },
            SkyModel::Perez {
                sun,
                epsilon: 1.02,
                delta: 0.2,
            },
            SkyModel::Perez {
                sun,
                epsilon: 3.0,
                delta: 0.3,
            },
        ] {
            let sky = Sky::new(model.clone(), up, [10_000.0; BANDS], [0.0; BANDS]).unwrap();
            let quad =
                crate::hemisphere_quadrature(up, 1000, |w| sky.escaped(w)[0] / PI * w.dot(up));
            assert!((quad / 10_000.0 - 1.0).abs() < 2e-3, "{model:?}: {quad}");
            let at = Receiver {
                p: DVec3::ZERO,
                n: up,
            };
            let m = 400;
            let mut est = 0.0;
            for i in 0..m {
                for j in 0..m {
                    let u = [(i as f64 + 0.5) / m as f64, (j as f64 + 0.5) / m as f64];
                    if let Some(s) = sky.sample(&at, u) {
                        est += s.emission[0] * s.g / s.pdf;
                    }
                }
            }
            est /= (m * m) as f64;
            assert!((est / 10_000.0 - 1.0).abs() < 2e-3, "{model:?}: {est}");
        }
    }

    /// The Perez sky's radiance relative to the zenith's, with the sun 30° from the zenith, against
    /// values worked independently from the paper's eq. (1), Table 1 and the first bin's forms (a
    /// short Python evaluation): a clear sky (ε = 6.3, Δ = 0.12: `gendaylit`'s CIE-clear-like example) is
    /// brightest about the sun and brighter at the horizon under the sun than opposite it; an
    /// overcast one (ε = 1.02, Δ = 0.2) falls from the zenith toward the horizon, loosely as the
    /// CIE overcast sky does, and hardly depends on the sun's azimuth.
    #[test]
    fn perez_shape_matches_the_paper() {
        let up = DVec3::Z;
        let z0 = 30f64.to_radians();
        let sun = DVec3::new(z0.sin(), 0.0, z0.cos());
        // (zenith angle, azimuth from the sun's, degrees)
        let dir = |theta: f64, az: f64| {
            let (t, a) = (theta.to_radians(), az.to_radians());
            DVec3::new(t.sin() * a.cos(), t.sin() * a.sin(), t.cos())
        };
        let points = [(20.0, 0.0), (85.0, 0.0), (85.0, 180.0), (60.0, 90.0)];
        let cases = [
            (6.3, 0.12, [3.362184, 2.163881, 1.706690, 0.657445]),
            (1.02, 0.2, [1.054946, 0.586387, 0.511253, 0.775229]),
        ];
        for (epsilon, delta, want) in cases {
            let model = SkyModel::Perez {
                sun,
                epsilon,
                delta,
            };
            let sky = Sky::new(model, up, [1.0; BANDS], [0.0; BANDS]).unwrap();
            let zenith = sky.escaped(up)[0];
            for ((theta, az), want) in points.into_iter().zip(want) {
                let r = sky.escaped(dir(theta, az))[0] / zenith;
                assert!(
                    (r / want - 1.0).abs() < 1e-5,
                    "ε {epsilon} at {theta},{az}: {r}"
                );
            }
        }
        let overcast = Sky::new(
            SkyModel::Perez {
                sun,
                epsilon: 1.02,
                delta: 0.2,
            },
            up,
            [1.0; BANDS],
            [0.0; BANDS],
        )
        .unwrap();
        let cie = Sky::new(SkyModel::CieOvercast, up, [1.0; BANDS], [0.0; BANDS]).unwrap();
        for theta in [30.0, 60.0, 80.0] {
            let rel = |s: &Sky| s.escaped(dir(theta, 90.0))[0] / s.escaped(up)[0];
            let (p, c) = (rel(&overcast), rel(&cie));
            assert!((p - c).abs() < 0.2, "θ {theta}: Perez {p}, CIE {c}");
        }
    }

    /// A sun below the horizon, a non-finite ε and a gradation that grows toward the horizon
    /// (b > 0: ε = 7, Δ = 0.6, the sun low) are refused.
    #[test]
    fn perez_refuses_what_gendaylit_refuses() {
        let up = DVec3::Z;
        let perez = |sun: DVec3, epsilon: f64, delta: f64| {
            Sky::new(
                SkyModel::Perez {
                    sun,
                    epsilon,
                    delta,
                },
                up,
                [1.0; BANDS],
                [0.0; BANDS],
            )
        };
        assert!(perez(-DVec3::Z, 6.0, 0.1).is_none());
        assert!(perez(DVec3::Z, f64::NAN, 0.1).is_none());
        let low = DVec3::new(1.0, 0.0, 0.05).normalize();
        assert!(perez(low, 7.0, 0.6).is_none());
        assert!(perez(low, 7.0, 0.1).is_some());
    }

    /// The overcast sky is three times brighter at the zenith than at the horizon; the ground
    /// takes its share of the samples in proportion to its power.
    #[test]
    fn overcast_gradation_and_ground() {
        let up = DVec3::Y;
        let sky = Sky::new(SkyModel::CieOvercast, up, [1.0; BANDS], [0.1; BANDS]).unwrap();
        let horizon = DVec3::new(1.0, 1e-9, 0.0).normalize();
        let r = sky.escaped(up)[0] / sky.escaped(horizon)[0];
        assert!((r - 3.0).abs() < 1e-6, "{r}");
        assert!((sky.escaped(-up)[0] - PI * 0.1).abs() < 1e-12);
        let side = DVec3::X;
        assert!((sky.p_up(side) - 1.0 / (1.0 + PI * 0.1)).abs() < 1e-12);
        assert_eq!(sky.p_up(up), 1.0, "a floor draws no ground samples");
        assert_eq!(sky.p_up(-up), 0.0, "a ceiling draws no sky samples");
        assert!(Sky::new(SkyModel::Uniform, DVec3::ZERO, [1.0; BANDS], [0.0; BANDS]).is_none());
        let below = SkyModel::CieClear { sun: -DVec3::Y };
        assert!(Sky::new(below, up, [1.0; BANDS], [0.0; BANDS]).is_none());
    }
}
