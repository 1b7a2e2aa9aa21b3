//! The scene's emitters as one table: every emitting face (segment) with its measure, drawn in
//! proportion to its power (the ray gather's direct light, [`crate::gather`]) or to its area (the
//! senders of shot rays, [`crate::shooting`]), through `scene_sampler`'s [`Discrete`].

use crate::domain::Domain;
use scene_sampler::Discrete;

/// The emitting faces (segments) of a scene with their sampling tables.
#[derive(Clone, Debug)]
pub struct Emitters {
    /// Emitting faces, ascending.
    faces: Vec<u32>,
    /// Their areas (Flatland: lengths).
    measure: Vec<f64>,
    /// Selection ∝ measure × mean emission.
    by_power: Option<Discrete>,
    /// Selection ∝ measure.
    by_area: Option<Discrete>,
}

impl Emitters {
    /// Collects the emitting faces (segments) of the domain.
    pub fn new(domain: &Domain) -> Self {
        let (mut faces, mut measure, mut power) = (Vec::new(), Vec::new(), Vec::new());
        let mut add = |i: usize, m: f64, emission: &scene_sampler::Spectrum| {
            if m > 0.0 && !emission.is_zero() {
                faces.push(i as u32);
                measure.push(m);
                power.push(m * emission.mean());
            }
        };
        match domain {
            Domain::ThreeD(k) => {
                for (i, f) in k.scene.faces.iter().enumerate() {
                    add(i, f.area, &f.emission);
                }
            }
            Domain::Flat(k) => {
                for (i, s) in k.scene.segments.iter().enumerate() {
                    add(i, s.length, &s.emission);
                }
            }
        }
        Self {
            by_power: Discrete::new(&power),
            by_area: Discrete::new(&measure),
            faces,
            measure,
        }
    }

    /// True when the scene has no emitter.
    pub fn is_empty(&self) -> bool {
        self.faces.is_empty()
    }

    /// Whether `face` emits.
    pub(crate) fn emits(&self, face: u32) -> bool {
        self.faces.binary_search(&face).is_ok()
    }

    /// Total emitting area (length).
    pub(crate) fn area(&self) -> f64 {
        self.by_area.as_ref().map_or(0.0, Discrete::total)
    }

    /// Area (length) density of the power-proportional selection at a point of `face`: the
    /// probability of choosing the face over its measure, 0 for a face that does not emit.
    pub(crate) fn power_density(&self, face: u32) -> f64 {
        match (self.faces.binary_search(&face), &self.by_power) {
            (Ok(i), Some(d)) => d.probability(i) / self.measure[i],
            _ => 0.0,
        }
    }

    /// An emitter face drawn by power from `u ∈ [0,1)` (a point on it then has
    /// [`Emitters::power_density`]). Only for a scene with emitters.
    pub(crate) fn pick_by_power(&self, u: f64) -> u32 {
        self.pick(&self.by_power, u)
    }

    /// An emitter face drawn by area from `u ∈ [0,1)`. Only for a scene with emitters.
    pub(crate) fn pick_by_area(&self, u: f64) -> u32 {
        self.pick(&self.by_area, u)
    }

    fn pick(&self, table: &Option<Discrete>, u: f64) -> u32 {
        let table = table
            .as_ref()
            .expect("picking from a scene without emitters");
        self.faces[table.sample(u)]
    }
}
