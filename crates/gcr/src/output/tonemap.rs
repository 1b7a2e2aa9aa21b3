//! Tone mapping from radiosity (exitance) to display values.
//!
//! A Lambertian surface with radiosity B has radiance L = B/π. We scale radiance by one exposure
//! per image so that the 95th percentile of the luminance of non-emitting vertices maps to 0.8,
//! clip to [0, 1] (emitters usually saturate to white, as in photographs), and encode with the
//! sRGB transfer curve for 8-bit output. The glTF writer stores the linear (pre-sRGB) values:
//! glTF vertex colours are linear and viewers apply the display encoding themselves.

/// Relative luminance of a linear RGB triple (Rec. 709 primaries).
pub fn luminance(rgb: [f64; 3]) -> f64 {
    0.2126 * rgb[0] + 0.7152 * rgb[1] + 0.0722 * rgb[2]
}

/// A fixed exposure: display_linear = clamp(B / π · scale).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Exposure {
    /// Multiplier applied to radiance L = B/π.
    pub scale: f64,
}

impl Exposure {
    /// Chooses the exposure from sample radiosities (emitters excluded by the caller): the 95th
    /// percentile of luminance maps to 0.8. Falls back to scale 1 when everything is black.
    pub fn auto(radiosities: impl IntoIterator<Item = [f64; 3]>) -> Self {
        let mut lum: Vec<f64> = radiosities
            .into_iter()
            .map(|b| luminance(b) / std::f64::consts::PI)
            .filter(|l| l.is_finite() && *l > 0.0)
            .collect();
        if lum.is_empty() {
            return Self { scale: 1.0 };
        }
        lum.sort_by(f64::total_cmp);
        let p95 = lum[((lum.len() - 1) as f64 * 0.95).round() as usize];
        Self { scale: 0.8 / p95 }
    }

    /// Linear display value in [0, 1] per channel. NaN maps to 0 (never a silent bright pixel).
    pub fn linear(&self, b: [f64; 3]) -> [f64; 3] {
        b.map(|c| {
            let v = c / std::f64::consts::PI * self.scale;
            if v.is_nan() { 0.0 } else { v.clamp(0.0, 1.0) }
        })
    }

    /// 8-bit sRGB-encoded display value.
    pub fn srgb8(&self, b: [f64; 3]) -> [u8; 3] {
        self.linear(b)
            .map(|v| (srgb_encode(v) * 255.0).round() as u8)
    }
}

/// The sRGB transfer function (IEC 61966-2-1) for a linear value in [0, 1].
pub fn srgb_encode(v: f64) -> f64 {
    if v <= 0.003_130_8 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn auto_exposure_maps_the_95th_percentile_to_0_8() {
        let pi = std::f64::consts::PI;
        let samples: Vec<[f64; 3]> = (1..=100).map(|i| [i as f64 * pi; 3]).collect();
        let e = Exposure::auto(samples);
        // 95th percentile of 1..=100 (index 94.05 → 94) is radiance 95.
        assert!((e.linear([95.0 * pi; 3])[0] - 0.8).abs() < 1e-12);
        assert_eq!(e.srgb8([1e9; 3]), [255; 3]);
        assert_eq!(e.srgb8([f64::NAN; 3]), [0; 3]);
        assert_eq!(Exposure::auto(Vec::new()).scale, 1.0);
    }

    #[test]
    fn srgb_curve_is_continuous_and_monotone() {
        assert!((srgb_encode(0.003_130_8) - 0.040_449_936).abs() < 1e-6);
        assert!((srgb_encode(1.0) - 1.0).abs() < 1e-12);
        let mut last = -1.0;
        for i in 0..=1000 {
            let v = srgb_encode(i as f64 / 1000.0);
            assert!(v > last);
            last = v;
        }
    }
}
