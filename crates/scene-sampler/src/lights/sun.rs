//! The sun: a distant disc of directions of angular diameter 2α (0.53° by default) with normal
//! irradiance E_n — the illuminance of glTF's directional light, Radiance's `gensky`/`gendaylit`
//! solar source. Its radiance is uniform over the disc, L = E_n/(π sin²α) (∫_disc cos γ dω =
//! π sin²α about its centre), so a receiver facing it gets E = E_n cos θ and a shadow edge gets a
//! penumbra of width ≈ 2α·(distance to the occluder). Sampled uniformly over the disc's cone
//! ([`crate::uniform_cone`]); a diameter of 0 makes it a delta direction.

use super::{Light, LightSample, Receiver, ShadowTarget};
use crate::{BANDS, Bands, uniform_cone_about, uniform_cone_pdf};
use glam::DVec3;
use std::f64::consts::PI;

/// The sun (module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct Sun {
    /// Unit direction toward the sun's centre.
    dir: DVec3,
    /// Irradiance on a plane normal to `dir` (illuminance in lux for photometric scenes).
    normal_irradiance: Bands,
    /// Half of the angular diameter, radians.
    half_angle: f64,
    /// 1 − cos α, as 2 sin²(α/2).
    one_minus_cos: f64,
    /// Two unit tangents orthogonal to `dir` (the cone's frame, computed once).
    tangents: (DVec3, DVec3),
    /// The disc's emission π·L = E_n/sin²α (0 for a delta direction).
    disc_emission: Bands,
}

impl Sun {
    /// The mean solar angular diameter, degrees.
    pub const DIAMETER_DEG: f64 = 0.53;

    /// A sun toward the (not necessarily unit) direction `dir` with normal irradiance
    /// `normal_irradiance` and angular diameter `diameter_deg` (0: a delta direction; at most
    /// 20°). `None` for a zero or non-finite direction, a negative or non-finite irradiance, or a
    /// diameter out of range.
    pub fn new(dir: DVec3, normal_irradiance: Bands, diameter_deg: f64) -> Option<Self> {
        let dir = dir.try_normalize()?;
        if !normal_irradiance.iter().all(|e| e.is_finite() && *e >= 0.0)
            || !(0.0..=20.0).contains(&diameter_deg)
        {
            return None;
        }
        let half_angle = (diameter_deg / 2.0).to_radians();
        let s2 = half_angle.sin().powi(2);
        Some(Self {
            dir,
            normal_irradiance,
            half_angle,
            one_minus_cos: 2.0 * (half_angle / 2.0).sin().powi(2),
            tangents: crate::orthonormal_basis(dir),
            disc_emission: normal_irradiance.map(|e| if s2 > 0.0 { e / s2 } else { 0.0 }),
        })
    }

    /// Unit direction toward the sun.
    pub fn direction(&self) -> DVec3 {
        self.dir
    }

    fn in_disc(&self, dir: DVec3) -> bool {
        self.half_angle > 0.0 && 1.0 - dir.dot(self.dir) <= self.one_minus_cos
    }
}

impl Light for Sun {
    fn sample(&self, at: &Receiver, u: [f64; 2]) -> Option<LightSample> {
        if self.half_angle == 0.0 {
            let cy = at.n.dot(self.dir);
            return (cy > 0.0).then(|| LightSample {
                target: ShadowTarget::Direction(self.dir),
                emission: self.normal_irradiance.map(|e| PI * e),
                g: cy / PI,
                pdf: 1.0,
            });
        }
        let w = uniform_cone_about((self.dir, self.tangents), self.one_minus_cos, u);
        let cy = at.n.dot(w);
        (cy > 0.0).then(|| LightSample {
            target: ShadowTarget::Direction(w),
            emission: self.disc_emission,
            g: cy / PI,
            pdf: uniform_cone_pdf(self.one_minus_cos),
        })
    }

    fn escaped(&self, dir: DVec3) -> Bands {
        if self.in_disc(dir) {
            self.disc_emission
        } else {
            [0.0; BANDS]
        }
    }

    fn escaped_pdf(&self, _at: &Receiver, dir: DVec3) -> f64 {
        if self.in_disc(dir) {
            uniform_cone_pdf(self.one_minus_cos)
        } else {
            0.0
        }
    }

    fn is_delta(&self) -> bool {
        self.half_angle == 0.0
    }

    fn power(&self, radius: f64) -> f64 {
        PI * radius * radius * self.normal_irradiance.iter().sum::<f64>() / BANDS as f64
    }

    fn is_grey(&self) -> bool {
        super::grey(&self.normal_irradiance)
    }

    fn describe(&self) -> String {
        format!(
            "sun toward ({:.4}, {:.4}, {:.4}), {} normal irradiance, {}° across",
            self.dir.x,
            self.dir.y,
            self.dir.z,
            self.normal_irradiance[0],
            (2.0 * self.half_angle).to_degrees()
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Over the disc the samples' mean of E·g/p is E_n cos θ for a receiver that sees the whole
    /// disc: the radiance normalisation and the cone's density agree (to 1e-9 of quadrature).
    #[test]
    fn a_facing_receiver_gets_the_normal_irradiance_times_the_cosine() {
        for diameter in [0.0, 0.53, 5.0] {
            let sun = Sun::new(DVec3::new(0.3, 1.0, -0.2), [1000.0; BANDS], diameter).unwrap();
            let at = Receiver {
                p: DVec3::ZERO,
                n: DVec3::Y,
            };
            let n = 256;
            let mut sum = 0.0;
            for i in 0..n {
                for j in 0..n {
                    let u = [(i as f64 + 0.5) / n as f64, (j as f64 + 0.5) / n as f64];
                    let s = sun.sample(&at, u).unwrap();
                    sum += s.emission[0] * s.g / s.pdf;
                }
            }
            let mean = sum / (n * n) as f64;
            let exact = 1000.0 * sun.direction().y;
            assert!(
                (mean / exact - 1.0).abs() < 1e-4,
                "{diameter}°: {mean} vs {exact}"
            );
            assert_eq!(sun.is_delta(), diameter == 0.0);
        }
    }

    /// A ray inside the disc sees the disc's radiance and the cone's density; one outside sees 0.
    #[test]
    fn escaping_rays_see_the_disc() {
        let sun = Sun::new(DVec3::Y, [1.0; BANDS], 0.53).unwrap();
        let at = Receiver {
            p: DVec3::ZERO,
            n: DVec3::Y,
        };
        let inside = DVec3::new(0.004, 1.0, 0.0).normalize();
        let outside = DVec3::new(0.005, 1.0, 0.0).normalize();
        assert!(sun.escaped(inside)[0] > 0.0 && sun.escaped_pdf(&at, inside) > 0.0);
        assert_eq!(sun.escaped(outside)[0], 0.0);
        assert_eq!(sun.escaped_pdf(&at, outside), 0.0);
        assert!(Sun::new(DVec3::ZERO, [1.0; BANDS], 0.5).is_none());
        assert!(Sun::new(DVec3::Y, [-1.0; BANDS], 0.5).is_none());
        assert!(Sun::new(DVec3::Y, [1.0; BANDS], 30.0).is_none());
    }
}
