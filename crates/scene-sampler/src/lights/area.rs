//! Emissive faces as lights (OBJ `Ke`, glTF `emissiveFactor`; Flatland `emission`): the first
//! implementation of the light interface, and the one the dissertation knows. A face's light is
//! sampled by area: a face drawn in proportion to its power (area × mean E), then a point uniform
//! on it ([`crate::uniform_triangle`]), with area density [`EmitterTable::power_density`]; a
//! cosine ray that hits the face is weighted against that density. Shot rays (the networks'
//! training) draw their senders from the same table by area.

use crate::Discrete;
use glam::DVec3;
use std::f64::consts::PI;

/// The emitting faces (segments) of a scene with their measures, drawn in proportion to their
/// power (measure × mean emission: next-event estimation, the ray gather) or to their area (the
/// senders of shot rays), each then a point uniform on the chosen face.
#[derive(Clone, Debug, Default)]
pub struct EmitterTable {
    /// Emitting faces, ascending.
    faces: Vec<u32>,
    /// Their areas (Flatland: lengths).
    measure: Vec<f64>,
    /// Selection ∝ measure × mean emission.
    by_power: Option<Discrete>,
    /// Selection ∝ measure.
    by_area: Option<Discrete>,
}

impl EmitterTable {
    /// From `(face, measure, mean emission)` of faces in ascending order; those with zero (or
    /// non-finite) measure or emission are left out.
    pub fn new(faces: impl IntoIterator<Item = (u32, f64, f64)>) -> Self {
        let (mut ids, mut measure, mut power) = (Vec::new(), Vec::new(), Vec::new());
        for (i, m, e) in faces {
            if m > 0.0 && e > 0.0 && (m * e).is_finite() {
                ids.push(i);
                measure.push(m);
                power.push(m * e);
            }
        }
        Self {
            by_power: Discrete::new(&power),
            by_area: Discrete::new(&measure),
            faces: ids,
            measure,
        }
    }

    /// True when nothing emits.
    pub fn is_empty(&self) -> bool {
        self.faces.is_empty()
    }

    /// Whether `face` emits.
    pub fn emits(&self, face: u32) -> bool {
        self.faces.binary_search(&face).is_ok()
    }

    /// Total emitted power Σ measure × mean E (0 when nothing emits).
    pub fn power(&self) -> f64 {
        self.by_power.as_ref().map_or(0.0, Discrete::total)
    }

    /// Total emitting area (length).
    pub fn area(&self) -> f64 {
        self.by_area.as_ref().map_or(0.0, Discrete::total)
    }

    /// Area (length) density of the power-proportional selection at a point of `face`: the
    /// probability of choosing the face over its measure; 0 for a face that does not emit.
    pub fn power_density(&self, face: u32) -> f64 {
        match (self.faces.binary_search(&face), &self.by_power) {
            (Ok(i), Some(d)) => d.probability(i) / self.measure[i],
            _ => 0.0,
        }
    }

    /// An emitter face drawn by power from `u ∈ [0,1)` (a uniform point on it then has
    /// [`EmitterTable::power_density`]); `None` when nothing emits.
    pub fn pick_by_power(&self, u: f64) -> Option<u32> {
        let d = self.by_power.as_ref()?;
        Some(self.faces[d.sample(u)])
    }

    /// The number of emitting faces.
    pub fn len(&self) -> usize {
        self.faces.len()
    }

    /// The position of `face` among the emitting faces (ascending), if it emits.
    pub fn position(&self, face: u32) -> Option<usize> {
        self.faces.binary_search(&face).ok()
    }

    /// The `i`-th emitting face (ascending) and its measure.
    pub fn get(&self, i: usize) -> (u32, f64) {
        (self.faces[i], self.measure[i])
    }

    /// An emitter face drawn by area from `u ∈ [0,1)`; `None` when nothing emits.
    pub fn pick_by_area(&self, u: f64) -> Option<u32> {
        let d = self.by_area.as_ref()?;
        Some(self.faces[d.sample(u)])
    }
}

/// G(y, x) = cos θ_y cos θ_x/(π r²) of the receiver (y, n) and the surface point (x, n_x), 0
/// unless they face each other (or it is not finite): the area density of a cosine-weighted ray
/// from y at x (visibility aside), and the kernel's geometry term (eq. 1.2).
pub fn geometry(y: DVec3, n: DVec3, x: DVec3, nx: DVec3) -> f64 {
    let d = x - y;
    let (cy, cx, r2) = (n.dot(d), -nx.dot(d), d.length_squared());
    if cy <= 0.0 || cx <= 0.0 || r2 == 0.0 {
        return 0.0;
    }
    let g = cy * cx / (PI * r2 * r2);
    if g.is_finite() { g } else { 0.0 }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_emitter_table_draws_by_power_and_by_area() {
        // faces 1 and 3 emit: areas 1 and 3, emissions 3 and 1 (equal power)
        let t = EmitterTable::new([(0, 2.0, 0.0), (1, 1.0, 3.0), (3, 3.0, 1.0)]);
        assert!(!t.is_empty() && t.emits(1) && t.emits(3) && !t.emits(0));
        assert_eq!(t.area(), 4.0);
        assert_eq!(t.power_density(1), 0.5);
        assert!((t.power_density(3) - 0.5 / 3.0).abs() < 1e-15);
        assert_eq!(t.power_density(0), 0.0);
        assert_eq!(t.pick_by_power(0.49), Some(1));
        assert_eq!(t.pick_by_power(0.51), Some(3));
        assert_eq!(t.pick_by_area(0.24), Some(1));
        assert_eq!(t.pick_by_area(0.26), Some(3));
        let none = EmitterTable::new([(0, 1.0, 0.0)]);
        assert!(none.is_empty() && none.pick_by_power(0.5).is_none() && none.area() == 0.0);
    }
}
