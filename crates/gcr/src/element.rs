//! Per-band values and the surface elements integrals run over.

use glam::DVec3;

/// Maximum colour bands.
pub const MAX_BANDS: usize = 3;

/// Per-band values (grey scenes use band 0 only).
pub type Bands = [f64; MAX_BANDS];

/// A surface element of an integration domain: a segment (Flatland, z = 0) or a triangle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Element {
    /// A Flatland segment in the z = 0 plane.
    Segment([DVec3; 2]),
    /// A 3-D triangle.
    Triangle([DVec3; 3]),
}

impl Element {
    /// Axis-aligned bounds.
    pub fn bounds(&self) -> (DVec3, DVec3) {
        match self {
            Element::Segment(p) => (p[0].min(p[1]), p[0].max(p[1])),
            Element::Triangle(p) => (p[0].min(p[1]).min(p[2]), p[0].max(p[1]).max(p[2])),
        }
    }
}
