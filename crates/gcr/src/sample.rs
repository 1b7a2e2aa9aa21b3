//! A training sample of the kernel network: a ray (x, y) with its emitting strength.

use crate::domain::Ray;
use crate::element::Bands;

/// One training sample: a ray with its current emitting strength s = E(x) + B_refl(x).
#[derive(Clone, Copy, Debug)]
pub struct Sample {
    /// The ray and its kernel value.
    pub ray: Ray,
    /// Emitting strength s at the sender (docs/design/math.md §4).
    pub s: Bands,
    /// `1/p_x(x)` of a shot ray (`shooting.rs`); 0 for area-uniform samples.
    pub inv_px: f64,
}
