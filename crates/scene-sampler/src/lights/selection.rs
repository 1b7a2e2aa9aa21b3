//! Light selection: which light a shadow ray goes to. [`LightSet`] draws first among the group of
//! lights with a position (the emitting faces, point and spot lights) and each light at infinity
//! (the sun, a sky, an environment map) in proportion to their power ([`Light::power`]); within the
//! group, a 3-D scene's light tree ([`LightTree`], `tree.rs`) draws by a bound of what each light
//! can send to the receiver, so that shadow rays are not spent on lamps that are far away or face
//! elsewhere (many lamps in many rooms). It is the one place an estimator asks "which light, with
//! what probability", so that a better strategy (a learned selection) replaces this file, not the
//! estimators.
//!
//! Without a tree (Flatland, whose only lights are its emitting segments) the group is the
//! emitting faces, drawn by power ([`EmitterTable`]).

use super::{EmitterTable, Light, LightBounds, LightTree, Receiver};
use crate::{BANDS, Bands, Discrete};
use glam::DVec3;
use std::f64::consts::PI;
use std::sync::Arc;

/// A light drawn by [`LightSet::pick`].
#[derive(Clone, Copy, Debug)]
pub enum Pick<'a> {
    /// An emitting face, and the area density of a point drawn uniformly on it
    /// ([`LightSet::face_density`] for the same receiver).
    Face(u32, f64),
    /// Another light, with the probability it was drawn with.
    Light(&'a dyn Light, f64),
}

/// The lights of a scene and the choice among them (module docs).
#[derive(Clone, Debug, Default)]
pub struct LightSet {
    faces: EmitterTable,
    lights: Vec<Arc<dyn Light>>,
    /// The tree over the group: leaf i < faces.len() is the face table's i-th face, leaf
    /// faces.len() + j is `lights[j]`. `None`: the group is the faces, by power.
    tree: Option<LightTree>,
    /// Selection among [the group, lights[others[0]], lights[others[1]], …] by power; `None`
    /// without a tree and with faces only.
    select: Option<Discrete>,
    /// The lights drawn by power beside the group: every light without a tree, the lights at
    /// infinity with one.
    others: Vec<usize>,
    /// Probability of the group.
    group_share: f64,
}

impl LightSet {
    /// The emitting faces `faces` and the lights `lights` of a scene whose bounding sphere has
    /// radius `radius` (the infinite lights' power is their flux through its disc), every one
    /// drawn by power (no tree).
    pub fn new(faces: EmitterTable, lights: Vec<Arc<dyn Light>>, radius: f64) -> Self {
        let face_share = if faces.is_empty() { 0.0 } else { 1.0 };
        let mut set = Self {
            faces,
            lights,
            tree: None,
            select: None,
            others: Vec::new(),
            group_share: face_share,
        };
        if set.lights.is_empty() {
            return set;
        }
        set.others = (0..set.lights.len()).collect();
        let group = set.faces.power();
        set.select_by_power(group, radius);
        set
    }

    /// [`LightSet::new`] with a light tree over the faces (`face_bounds[i]` the bounds of the
    /// face table's i-th face) and the lights that have [`Light::bounds`] (no tree when it would
    /// draw the faces by power: [`LightTree::is_leaf`]).
    pub fn with_tree(
        faces: EmitterTable,
        face_bounds: Vec<LightBounds>,
        lights: Vec<Arc<dyn Light>>,
        radius: f64,
    ) -> Self {
        debug_assert_eq!(face_bounds.len(), faces.len());
        let mut leaves = face_bounds;
        let (mut others, mut bounded_power) = (Vec::new(), 0.0);
        for (j, l) in lights.iter().enumerate() {
            match l.bounds() {
                Some(b) => {
                    leaves.push(b);
                    bounded_power += finite_power(&**l, radius);
                }
                None => {
                    // a light at infinity: never a leaf (zero power keeps the indices aligned)
                    leaves.push(LightBounds::point(DVec3::ZERO, 0.0));
                    others.push(j);
                }
            }
        }
        let tree = LightTree::new(&leaves);
        if tree.as_ref().is_some_and(LightTree::is_leaf) && others.len() == lights.len() {
            // one leaf of faces (a rectangular lamp): the tree would draw them by power
            return Self::new(faces, lights, radius);
        }
        let group = if tree.is_some() {
            faces.power() + bounded_power
        } else {
            0.0
        };
        let mut set = Self {
            faces,
            lights,
            tree,
            select: None,
            others,
            group_share: 0.0,
        };
        set.select_by_power(group, radius);
        set
    }

    /// Sets the selection among the group (of power `group`) and the `others` by power.
    fn select_by_power(&mut self, group: f64, radius: f64) {
        let mut power = vec![group];
        power.extend((self.others.iter()).map(|&j| finite_power(&*self.lights[j], radius)));
        self.select = Discrete::new(&power);
        self.group_share = self.select.as_ref().map_or(0.0, |d| d.probability(0));
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

    /// The area density with which a shadow ray from the receiver `at` falls on a point of
    /// `face` (the group's probability, the face's within it, over its area); 0 for a face that
    /// does not emit.
    pub fn face_density(&self, at: &Receiver, face: u32) -> f64 {
        let Some(tree) = &self.tree else {
            // by power (faces only: the share is 1, the table's density itself)
            return self.group_share * self.faces.power_density(face);
        };
        let Some(i) = self.faces.position(face) else {
            return 0.0;
        };
        self.group_share * tree.probability(at, i as u32) / self.faces.get(i).1
    }

    /// A light drawn for the receiver `at` from `u ∈ [0, 1)` (with `u` remapped for the choice
    /// within the group); `None` when nothing gives light, or nothing the draw leads to can light
    /// the receiver.
    pub fn pick(&self, at: &Receiver, u: f64) -> Option<Pick<'_>> {
        let by_power = |u: f64| {
            let f = self.faces.pick_by_power(u)?;
            Some(Pick::Face(f, self.face_density(at, f)))
        };
        let Some(select) = &self.select else {
            return by_power(u);
        };
        let (i, v) = select.sample_remapped(u);
        if i > 0 {
            let l = &*self.lights[self.others[i - 1]];
            return Some(Pick::Light(l, select.probability(i)));
        }
        let Some(tree) = &self.tree else {
            return by_power(v);
        };
        let (leaf, p) = tree.sample(at, v)?;
        let n = self.faces.len();
        Some(match (leaf as usize).checked_sub(n) {
            None => {
                let (face, area) = self.faces.get(leaf as usize);
                Pick::Face(face, self.group_share * p / area)
            }
            Some(j) => Pick::Light(&*self.lights[j], self.group_share * p),
        })
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
        for (i, &j) in self.others.iter().enumerate() {
            let l = &self.lights[j];
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

/// A light's power for selection: 0 unless finite and positive.
fn finite_power(l: &dyn Light, radius: f64) -> f64 {
    let p = l.power(radius);
    if p.is_finite() { p.max(0.0) } else { 0.0 }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lights::{PointLight, Sun};

    const AT: Receiver = Receiver {
        p: DVec3::new(0.0, -1.0, 0.0),
        n: DVec3::Y,
    };

    /// With faces only, picks and densities are the face table's; with other lights, each is
    /// drawn in proportion to its power and the face density is scaled by the faces' share.
    #[test]
    fn selection_by_power() {
        let faces = || EmitterTable::new([(0, 1.0, 1.0), (2, 3.0, 1.0)]);
        let only = LightSet::new(faces(), Vec::new(), 1.0);
        let t = faces();
        for u in [0.0, 0.2, 0.26, 0.9] {
            assert!(
                matches!(only.pick(&AT, u), Some(Pick::Face(f, d)) if Some(f) == t.pick_by_power(u) && d == t.power_density(f))
            );
        }
        assert_eq!(only.face_density(&AT, 2), t.power_density(2));
        // faces' power 4, a point light of power 4π·(1/π) = 4: half each
        let point: Arc<dyn Light> =
            Arc::new(PointLight::new(DVec3::ZERO, [1.0 / PI; BANDS]).unwrap());
        let mixed = LightSet::new(faces(), vec![point], 1.0);
        assert!((mixed.face_density(&AT, 2) - 0.5 * t.power_density(2)).abs() < 1e-15);
        assert!(matches!(mixed.pick(&AT, 0.1), Some(Pick::Face(0, _))));
        match mixed.pick(&AT, 0.75) {
            Some(Pick::Light(_, p)) => assert!((p - 0.5).abs() < 1e-15),
            other => panic!("{other:?}"),
        }
        assert!(!mixed.is_empty() && !mixed.has_infinite());
        let sun: Arc<dyn Light> = Arc::new(Sun::new(DVec3::Y, [1.0; BANDS], 0.53).unwrap());
        let lit = LightSet::new(EmitterTable::default(), vec![sun], 1.0);
        assert!(!lit.is_empty() && lit.has_infinite());
        assert!(matches!(lit.pick(&AT, 0.3), Some(Pick::Light(_, p)) if p == 1.0));
        assert!(LightSet::new(EmitterTable::default(), Vec::new(), 1.0).is_empty());
    }

    /// With a tree: the group (faces and a point light) against a sun by power; within the group
    /// the lamp over the receiver wins, and the densities are the draws' probabilities.
    #[test]
    fn selection_with_a_tree() {
        // two unit right triangles facing down at y = 1, one over the receiver, one 20 m away
        let faces = EmitterTable::new([(0, 0.5, 2.0), (1, 0.5, 2.0)]);
        let tri = |x: f64| {
            [
                DVec3::new(x, 1.0, 0.0),
                DVec3::new(x + 1.0, 1.0, 0.0),
                DVec3::new(x, 1.0, 1.0),
            ]
        };
        let bounds = vec![
            LightBounds::face(tri(0.0), -DVec3::Y, 1.0),
            LightBounds::face(tri(20.0), -DVec3::Y, 1.0),
        ];
        let point: Arc<dyn Light> =
            Arc::new(PointLight::new(DVec3::new(40.0, 0.0, 0.0), [0.5 / PI; BANDS]).unwrap());
        let sun: Arc<dyn Light> = Arc::new(Sun::new(DVec3::Y, [1.0; BANDS], 0.53).unwrap());
        let set = LightSet::with_tree(faces, bounds, vec![point, sun.clone()], 1.0);
        let at = Receiver {
            p: DVec3::new(0.3, 0.0, 0.3),
            n: DVec3::Y,
        };
        let group = 2.0 + 2.0; // faces 0.5·2 each, the point light 4π·0.5/π
        let share = group / (group + sun.power(1.0));
        let (near, far) = (set.face_density(&at, 0), set.face_density(&at, 1));
        assert!(near > 0.0 && far > 0.0 && near > 20.0 * far, "{near} {far}");
        let mut light_p = 0.0;
        let n = 20_000;
        let mut count = [0usize; 3];
        for k in 0..n {
            match set.pick(&at, (k as f64 + 0.5) / n as f64) {
                Some(Pick::Face(f, d)) => {
                    assert!((d - set.face_density(&at, f)).abs() < 1e-12 * d);
                    count[f as usize] += 1
                }
                Some(Pick::Light(l, p)) if l.is_delta() => {
                    count[2] += 1;
                    light_p = p;
                }
                Some(Pick::Light(_, p)) => assert_eq!(p, 1.0 - share),
                None => panic!("nothing drawn"),
            }
        }
        for (f, d) in [(0, near), (1, far)] {
            let want = d * 0.5 * n as f64;
            assert!(
                (count[f] as f64 - want).abs() < 5.0 * want.sqrt() + 1.0,
                "{count:?}"
            );
        }
        assert!(
            (count[2] as f64 - light_p * n as f64).abs() < 5.0 * (light_p * n as f64).sqrt() + 1.0
        );
        let total = (near + far) * 0.5 + light_p;
        assert!((total - share).abs() < 1e-12, "{total} vs {share}");
        assert_eq!(set.face_density(&at, 7), 0.0);
    }
}
