//! Colour bands: a [`Spectrum`] holds one value per RGB band.

use std::ops::{Add, AddAssign, Div, Mul, MulAssign, Sub};

/// Colour bands of every scene and solver: r, g, b.
pub const BANDS: usize = 3;

/// One value per colour band, the plain array the solvers compute with (grey scenes: band 0, or
/// the same value in every band); [`Spectrum`] wraps it for materials, with arithmetic.
pub type Bands = [f64; BANDS];

/// One value per colour band (r, g, b).
///
/// Grey scenes (`bands == 1` on the scene) store the same value in all three slots, so that callers can always
/// compute in RGB and report only band 0 for grey scenes. Arithmetic is component-wise.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Spectrum(pub Bands);

impl Spectrum {
    /// All bands zero.
    pub const ZERO: Spectrum = Spectrum([0.0; 3]);
    /// All bands one.
    pub const ONE: Spectrum = Spectrum([1.0; 3]);

    /// The same value in every band (a grey value).
    pub const fn grey(v: f64) -> Self {
        Spectrum([v, v, v])
    }
    /// An RGB value.
    pub const fn rgb(r: f64, g: f64, b: f64) -> Self {
        Spectrum([r, g, b])
    }
    /// Largest band value.
    pub fn max(&self) -> f64 {
        self.0[0].max(self.0[1]).max(self.0[2])
    }
    /// Mean over the three bands.
    pub fn mean(&self) -> f64 {
        (self.0[0] + self.0[1] + self.0[2]) / 3.0
    }
    /// True if every band is exactly zero.
    pub fn is_zero(&self) -> bool {
        self.0 == [0.0; 3]
    }
    /// True if every band is finite.
    pub fn is_finite(&self) -> bool {
        self.0.iter().all(|v| v.is_finite())
    }
    /// True if all three bands are equal (a grey value).
    pub fn is_grey(&self) -> bool {
        self.0[0] == self.0[1] && self.0[1] == self.0[2]
    }
    /// Component-wise map.
    pub fn map(self, f: impl Fn(f64) -> f64) -> Self {
        Spectrum(self.0.map(f))
    }
}

impl Add for Spectrum {
    type Output = Spectrum;
    fn add(self, o: Spectrum) -> Spectrum {
        Spectrum([self.0[0] + o.0[0], self.0[1] + o.0[1], self.0[2] + o.0[2]])
    }
}
impl AddAssign for Spectrum {
    fn add_assign(&mut self, o: Spectrum) {
        *self = *self + o;
    }
}
impl Sub for Spectrum {
    type Output = Spectrum;
    fn sub(self, o: Spectrum) -> Spectrum {
        Spectrum([self.0[0] - o.0[0], self.0[1] - o.0[1], self.0[2] - o.0[2]])
    }
}
impl Mul for Spectrum {
    type Output = Spectrum;
    fn mul(self, o: Spectrum) -> Spectrum {
        Spectrum([self.0[0] * o.0[0], self.0[1] * o.0[1], self.0[2] * o.0[2]])
    }
}
impl Mul<f64> for Spectrum {
    type Output = Spectrum;
    fn mul(self, s: f64) -> Spectrum {
        self.map(|v| v * s)
    }
}
impl MulAssign<f64> for Spectrum {
    fn mul_assign(&mut self, s: f64) {
        *self = *self * s;
    }
}
impl Div<f64> for Spectrum {
    type Output = Spectrum;
    fn div(self, s: f64) -> Spectrum {
        self.map(|v| v / s)
    }
}
