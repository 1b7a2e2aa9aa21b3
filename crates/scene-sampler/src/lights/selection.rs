//! Light selection: which light a shadow ray goes to. [`LightSet`] draws among the emitting faces
//! (as one group, then a face within it by power: [`EmitterTable`]) and the scene's other lights
//! ([`crate::Scene::lights`]) in proportion to their power ([`Light::power`]). It is the one
//! place an estimator asks "which light, with what probability", so that a better strategy (a
//! light tree, a learned selection) replaces this file, not the estimators.
//!
//! With faces only (every scene the dissertation knows) a pick is exactly the face table's: the
//! same face for the same random number, the same density.

use super::{EmitterTable, Light, Receiver};
use crate::{BANDS, Bands, Discrete};
use glam::DVec3;
use std::f64::consts::PI;
use std::sync::Arc;

/// A light drawn by [`LightSet::pick`].
#[derive(Clone, Copy, Debug)]
pub enum Pick<'a> {
    /// An emitting face; its point's area density is [`LightSet::face_density`].
    Face(u32),
    /// Another light, with the probability it was drawn with.
    Light(&'a dyn Light, f64),
}

/// The lights of a scene and the choice among them (module docs).
#[derive(Clone, Debug, Default)]
pub struct LightSet {
    faces: EmitterTable,
    lights: Vec<Arc<dyn Light>>,
    /// Selection among [faces, lights…] by power; `None` with faces only.
    select: Option<Discrete>,
    /// Probability of the face group.
    face_share: f64,
}

impl LightSet {
    /// The emitting faces `faces` and the lights `lights` of a scene whose bounding sphere has
    /// radius `radius` (the infinite lights' power is their flux through its disc).
    pub fn new(faces: EmitterTable, lights: Vec<Arc<dyn Light>>, radius: f64) -> Self {
        if lights.is_empty() {
            let face_share = if faces.is_empty() { 0.0 } else { 1.0 };
            return Self {
                faces,
                lights,
                select: None,
                face_share,
            };
        }
        let mut power = vec![faces.power()];
        power.extend(lights.iter().map(|l| {
            let p = l.power(radius);
            if p.is_finite() { p.max(0.0) } else { 0.0 }
        }));
        let select = Discrete::new(&power);
        let face_share = select.as_ref().map_or(0.0, |d| d.probability(0));
        Self {
            faces,
            lights,
            select,
            face_share,
        }
    }

    /// True when nothing gives light: no emitting face, and no other light of positive power.
    pub fn is_empty(&self) -> bool {
        self.faces.is_empty() && self.select.is_none()
    }

    /// The emitting faces.
    pub fn faces(&self) -> &EmitterTable {
        &self.faces
    }

    /// The lights other than faces.
    pub fn lights(&self) -> &[Arc<dyn Light>] {
        &self.lights
    }

    /// Whether a ray that escapes the scene may receive light (some light is at infinity and not
    /// a delta direction).
    pub fn has_infinite(&self) -> bool {
        self.lights.iter().any(|l| !l.is_delta())
    }

    /// The area density with which a shadow ray's point falls on a point of `face` (the face
    /// group's probability times the face table's density); 0 for a face that does not emit.
    pub fn face_density(&self, face: u32) -> f64 {
        if self.select.is_none() {
            // faces only: the table's density itself (bit for bit)
            return self.faces.power_density(face);
        }
        self.face_share * self.faces.power_density(face)
    }

    /// A light drawn by power from `u ∈ [0, 1)`, with `u` left for a face's choice within the
    /// face table; `None` when nothing gives light.
    pub fn pick(&self, u: f64) -> Option<Pick<'_>> {
        let Some(select) = &self.select else {
            return self.faces.pick_by_power(u).map(Pick::Face);
        };
        let (i, v) = select.sample_remapped(u);
        if i == 0 {
            return self.faces.pick_by_power(v).map(Pick::Face);
        }
        Some(Pick::Light(&*self.lights[i - 1], select.probability(i)))
    }

    /// The light a cosine-weighted ray from `at` receives when it escapes the scene in the unit
    /// direction `dir`, per unit reflectance and MIS-weighted: Σ over the infinite lights of
    /// E_l(dir)·`weight`(cos θ/π, P_l·p_l(dir)), with `weight(g, p)` the estimator's cosine-ray
    /// weight ([`crate::PowerHeuristic::cosine`]) for the cosine density g and the light's selected
    /// density p.
    pub fn escaped(&self, at: &Receiver, dir: DVec3, weight: impl Fn(f64, f64) -> f64) -> Bands {
        let mut out = [0.0; BANDS];
        let Some(select) = &self.select else {
            return out;
        };
        let g = at.n.dot(dir).max(0.0) / PI;
        for (i, l) in self.lights.iter().enumerate() {
            let e = l.escaped(dir);
            if e.iter().all(|v| *v == 0.0) {
                continue;
            }
            let w = weight(g, select.probability(i + 1) * l.escaped_pdf(at, dir));
            for k in 0..BANDS {
                out[k] += w * e[k];
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lights::{PointLight, Sun};

    /// With faces only, picks and densities are the face table's; with other lights, each is
    /// drawn in proportion to its power and the face density is scaled by the faces' share.
    #[test]
    fn selection_by_power() {
        let faces = || EmitterTable::new([(0, 1.0, 1.0), (2, 3.0, 1.0)]);
        let only = LightSet::new(faces(), Vec::new(), 1.0);
        let t = faces();
        for u in [0.0, 0.2, 0.26, 0.9] {
            assert!(matches!(only.pick(u), Some(Pick::Face(f)) if Some(f) == t.pick_by_power(u)));
        }
        assert_eq!(only.face_density(2), t.power_density(2));
        // faces' power 4, a point light of power 4π·(1/π) = 4: half each
        let point: Arc<dyn Light> =
            Arc::new(PointLight::new(DVec3::ZERO, [1.0 / PI; BANDS]).unwrap());
        let mixed = LightSet::new(faces(), vec![point], 1.0);
        assert!((mixed.face_density(2) - 0.5 * t.power_density(2)).abs() < 1e-15);
        assert!(matches!(mixed.pick(0.1), Some(Pick::Face(0))));
        match mixed.pick(0.75) {
            Some(Pick::Light(_, p)) => assert!((p - 0.5).abs() < 1e-15),
            other => panic!("{other:?}"),
        }
        assert!(!mixed.is_empty() && !mixed.has_infinite());
        let sun: Arc<dyn Light> = Arc::new(Sun::new(DVec3::Y, [1.0; BANDS], 0.53).unwrap());
        let lit = LightSet::new(EmitterTable::default(), vec![sun], 1.0);
        assert!(!lit.is_empty() && lit.has_infinite());
        assert!(matches!(lit.pick(0.3), Some(Pick::Light(_, p)) if p == 1.0));
        assert!(LightSet::new(EmitterTable::default(), Vec::new(), 1.0).is_empty());
    }
}
