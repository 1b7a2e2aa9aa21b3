//! Point and spot lights (glTF `KHR_lights_punctual`): intensity I (candela for photometric
//! scenes) from a point, so a receiver at distance r with cos θ toward it gets E = I cos θ/r².
//! A spot light scales I by glTF's smooth cone falloff: with cd the cosine of the angle to the
//! spot's axis, t = clamp((cd − cos θ_outer)/(cos θ_inner − cos θ_outer), 0, 1), the factor is t²
//! (the glTF extension's reference implementation). A delta light: only shadow rays reach it.

use super::{Light, LightBounds, LightSample, Receiver, ShadowTarget, toward};
use crate::{BANDS, Bands};
use glam::DVec3;
use std::f64::consts::PI;

/// A point light, optionally a spot (module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct PointLight {
    position: DVec3,
    intensity: Bands,
    spot: Option<Spot>,
    /// glTF's `range`: the distance at which the light is cut off smoothly.
    range: Option<f64>,
}

/// A spot light's cone.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Spot {
    /// Unit axis the light shines along.
    axis: DVec3,
    cos_inner: f64,
    cos_outer: f64,
}

impl PointLight {
    /// A point light at `position` with intensity `intensity`; `None` when either is not finite or
    /// the intensity is negative.
    pub fn new(position: DVec3, intensity: Bands) -> Option<Self> {
        (position.is_finite() && intensity.iter().all(|i| i.is_finite() && *i >= 0.0)).then_some(
            Self {
                position,
                intensity,
                spot: None,
                range: None,
            },
        )
    }

    /// A spot light shining along `axis` with full intensity inside `inner` radians of it and
    /// none beyond `outer` (0 ≤ inner < outer ≤ π/2, as glTF requires); `None` otherwise.
    pub fn spot(
        position: DVec3,
        intensity: Bands,
        axis: DVec3,
        inner: f64,
        outer: f64,
    ) -> Option<Self> {
        let axis = axis.try_normalize()?;
        if !(0.0 <= inner && inner < outer && outer <= PI / 2.0 + 1e-12) {
            return None;
        }
        Some(Self {
            spot: Some(Spot {
                axis,
                cos_inner: inner.cos(),
                cos_outer: outer.cos(),
            }),
            ..Self::new(position, intensity)?
        })
    }

    /// The light cut off smoothly at distance `range` (glTF `KHR_lights_punctual`): the
    /// intensity at distance d is scaled by clamp(1 − (d/range)⁴, 0, 1)², the extension's
    /// recommended window. `None` leaves it unbounded; `Some` of a range ≤ 0 or not finite is
    /// refused (`None` returned).
    pub fn with_range(self, range: Option<f64>) -> Option<Self> {
        match range {
            None => Some(self),
            Some(r) if r > 0.0 && r.is_finite() => Some(Self {
                range: Some(r),
                ..self
            }),
            Some(_) => None,
        }
    }

    /// The range window at squared distance `r2` (1 without a range).
    fn window(&self, r2: f64) -> f64 {
        self.range.map_or(1.0, |range| {
            let q = r2 * r2 / range.powi(4);
            (1.0 - q).clamp(0.0, 1.0).powi(2)
        })
    }

    /// The spot's falloff toward the unit direction `w` from the light (1 for a point light).
    fn falloff(&self, w: DVec3) -> f64 {
        let Some(s) = self.spot else { return 1.0 };
        let t =
            ((s.axis.dot(w) - s.cos_outer) / (s.cos_inner - s.cos_outer).max(1e-3)).clamp(0.0, 1.0);
        t * t
    }
}

impl Light for PointLight {
    fn sample(&self, at: &Receiver, _u: [f64; 2]) -> Option<LightSample> {
        let (w, r2, cy) = toward(at, self.position)?;
        let f = self.falloff(-w) * self.window(r2);
        (f > 0.0).then(|| LightSample {
            target: ShadowTarget::Point {
                point: self.position,
                normal: DVec3::ZERO,
                face: None,
            },
            emission: self.intensity.map(|i| PI * i * f),
            g: cy / (PI * r2),
            pdf: 1.0,
        })
    }

    fn is_delta(&self) -> bool {
        true
    }

    fn bounds(&self) -> Option<LightBounds> {
        let power = self.power(0.0);
        Some(match self.spot {
            None => LightBounds::point(self.position, power),
            Some(s) => LightBounds::spot(self.position, power, s.axis, s.cos_inner, s.cos_outer),
        })
    }

    fn power(&self, _radius: f64) -> f64 {
        let i = self.intensity.iter().sum::<f64>() / BANDS as f64;
        match self.spot {
            None => 4.0 * PI * i,
            Some(s) => 2.0 * PI * i * (1.0 - 0.5 * (s.cos_inner + s.cos_outer)),
        }
    }

    fn is_grey(&self) -> bool {
        super::grey(&self.intensity)
    }

    fn describe(&self) -> String {
        let p = self.position;
        let range = self.range.map_or(String::new(), |r| format!(", range {r}"));
        let kind = if self.spot.is_some() { "spot" } else { "point" };
        format!(
            "{kind} light at ({}, {}, {}), intensity {}{range}",
            p.x, p.y, p.z, self.intensity[0]
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// E = I cos θ/r² over a plane, and a spot's cone: full inside the inner angle, the glTF
    /// falloff between, nothing beyond the outer angle or behind the receiver.
    #[test]
    fn inverse_square_cosine_law_and_the_cone() {
        let light = PointLight::new(DVec3::new(0.0, 2.0, 0.0), [100.0; BANDS]).unwrap();
        for x in [0.0, 1.0, 3.0] {
            let at = Receiver {
                p: DVec3::new(x, 0.0, 0.0),
                n: DVec3::Y,
            };
            let s = light.sample(&at, [0.5; 2]).unwrap();
            let r2 = 4.0 + x * x;
            let exact = 100.0 * (2.0 / r2.sqrt()) / r2;
            assert!((s.emission[0] * s.g / s.pdf - exact).abs() < 1e-12 * exact);
        }
        let down = Receiver {
            p: DVec3::ZERO,
            n: -DVec3::Y,
        };
        assert!(
            light.sample(&down, [0.5; 2]).is_none(),
            "behind the receiver"
        );
        let (inner, outer) = (20f64.to_radians(), 30f64.to_radians());
        let spot = PointLight::spot(
            DVec3::new(0.0, 1.0, 0.0),
            [1.0; BANDS],
            -DVec3::Y,
            inner,
            outer,
        )
        .unwrap();
        let at = |deg: f64| Receiver {
            p: DVec3::new(deg.to_radians().tan(), 0.0, 0.0),
            n: DVec3::Y,
        };
        let value = |deg: f64| {
            spot.sample(&at(deg), [0.5; 2])
                .map_or(0.0, |s| s.emission[0] / PI)
        };
        assert!((value(10.0) - 1.0).abs() < 1e-12);
        assert!((value(19.9) - 1.0).abs() < 1e-12);
        let t = (25f64.to_radians().cos() - outer.cos()) / (inner.cos() - outer.cos());
        assert!((value(25.0) - t * t).abs() < 1e-9);
        assert_eq!(value(30.1), 0.0);
        assert!(PointLight::spot(DVec3::ZERO, [1.0; BANDS], DVec3::Y, 0.5, 0.4).is_none());
        // glTF's range window: 1 − (d/range)⁴ squared, nothing beyond the range
        let ranged = light.clone().with_range(Some(4.0)).unwrap();
        let at = |x: f64| Receiver {
            p: DVec3::new(x, 0.0, 0.0),
            n: DVec3::Y,
        };
        let ratio = |x: f64| {
            let e = |l: &PointLight| l.sample(&at(x), [0.5; 2]).map_or(0.0, |s| s.emission[0]);
            e(&ranged) / e(&light)
        };
        let d2: f64 = 4.0 + 1.0;
        assert!((ratio(1.0) - (1.0 - d2 * d2 / 256.0).powi(2)).abs() < 1e-12);
        assert!(light.sample(&at(4.0), [0.5; 2]).is_some());
        assert!(
            ranged.sample(&at(4.0), [0.5; 2]).is_none(),
            "beyond the range"
        );
        assert!(light.clone().with_range(Some(0.0)).is_none());
        assert!(PointLight::new(DVec3::ZERO, [f64::NAN; BANDS]).is_none());
    }
}
