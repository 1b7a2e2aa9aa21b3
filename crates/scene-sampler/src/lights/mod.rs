//! Lights: where a receiver's direct light comes from, behind one interface.
//!
//! Every estimator of the workspace lights a receiver (y, n) the same two ways (docs/design/math.md §8; Veach
//! 1997 ch. 9): **light sampling** — pick a light ([`LightSet::pick`]), ask it for a sample toward
//! y ([`Light::sample`]), cast one shadow ray — and **cosine sampling** — a cosine-weighted ray
//! that happens to reach a light (an emitting face it hits, or an infinite light when it escapes
//! the scene, [`Light::escaped`]). The two are combined by the power heuristic
//! ([`crate::PowerHeuristic`]), which needs both techniques' densities of the same sample in one
//! measure: a [`LightSample`] carries them in the light's own measure (area for a face, solid
//! angle for an infinite light), so that the estimate `E·g/p` and its weight are measure-free.
//!
//! One file per light type (pbrt-v4's `lights.h`, Mitsuba's emitter plugins):
//!
//! | light | file | measure |
//! |---|---|---|
//! | emissive faces (OBJ `Ke`, glTF emissive) | `area.rs` ([`EmitterTable`]) | area |
//! | sun: a distant disc of directions | `sun.rs` ([`Sun`]) | solid angle (a direction when its diameter is 0) |
//! | sky: uniform, CIE overcast, CIE clear; a ground below the horizon; portals | `sky.rs` ([`Sky`]), `portal.rs` | solid angle |
//! | point and spot lights (glTF `KHR_lights_punctual`) | `point.rs` ([`PointLight`]) | a point (delta) |
//! | environment map: an equirectangular `.hdr`/`.exr` | `envmap.rs` ([`EnvMap`]) | solid angle |
//!
//! Light selection ([`LightSet`], `selection.rs`) draws the lights at infinity by power and the
//! lights with a position — emitting faces, point and spot lights — from a light tree
//! (`tree.rs`, [`LightTree`]) by a bound of what each can send to the receiver.
//!
//! A scene holds its lights other than faces in [`crate::Scene::lights`] as `Arc<dyn Light>`; a new
//! light type is its own file implementing [`Light`] and one line that creates it (the lighting
//! options, a loader). [`LightSet`] (`selection.rs`) draws among the faces and the other lights.
//! This module knows no scene (a scene holds lights: the scene depends on it, not the reverse);
//! the constructors from a scene, `EmitterTable::of_scene` and `LightSet::of_scene` (and their
//! Flatland twins), are written beside the scenes.
//!
//! # Units
//! The solvers compute radiosity B (exitance). A light's values are given as the exitance a
//! Lambertian emitter of the same radiance has, `E = π·L` ("emission" below): a face's E as stored
//! in [`crate::Face::emission`], π times an infinite light's radiance, π times a point light's
//! intensity. The direct light a sample brings to a receiver per unit reflectance is then
//! `E·g/p` (the receiver's irradiance), with `g` the cosine technique's density of the sample and
//! `p` the light's.

mod area;
mod envmap;
pub mod lighting;
pub mod perez;
mod point;
mod portal;
mod selection;
mod sky;
mod sun;
mod tree;

pub use area::{EmitterTable, geometry};
pub use envmap::EnvMap;
pub use lighting::Lighting;
pub use point::PointLight;
pub use portal::{Portal, Portals};
pub use selection::{LightSet, Pick};
pub use sky::{Sky, SkyModel};
pub use sun::Sun;
pub use tree::{LightBounds, LightTree};

use crate::Bands;
use glam::DVec3;
use std::fmt::Debug;
use std::panic::RefUnwindSafe;

/// A shading point: the receiver y and the unit normal n of the side it receives on.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Receiver {
    /// Position y.
    pub p: DVec3,
    /// Unit normal n.
    pub n: DVec3,
}

/// Where a light sample's shadow ray goes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ShadowTarget {
    /// To a point of space: on a face (which is then not an occluder), or a point light (no
    /// face, zero normal).
    Point {
        /// The point.
        point: DVec3,
        /// The unit normal of its face (zero for a point light).
        normal: DVec3,
        /// Its face, if it lies on one.
        face: Option<u32>,
    },
    /// Infinitely far along a unit direction: the ray must escape the scene.
    Direction(DVec3),
}

/// One sample of a light toward a receiver (module docs: its direct light per unit reflectance
/// is `emission · g / pdf`, before the MIS weight).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightSample {
    /// Where the shadow ray goes.
    pub target: ShadowTarget,
    /// The light's emission toward the receiver as exitance `π·L` (a point light: `π·I`).
    pub emission: Bands,
    /// The density with which a cosine-weighted ray from the receiver would have drawn this
    /// sample, in the light's measure: `G(y, x) = cos θ_y cos θ_x/(π r²)` per unit area for a
    /// face, `cos θ_y/π` per steradian for an infinite light, `cos θ_y/(π r²)` for a point light
    /// (whose "density" is a delta: [`Light::is_delta`]).
    pub g: f64,
    /// The light's own density of the sample in the same measure (1 for a delta light).
    pub pdf: f64,
}

/// A light other than an emitting face (module docs). Implementations are small and immutable
/// after construction (shared between threads, and across a caught panic); [`LightSet`] chooses
/// among them in proportion to [`Light::power`].
pub trait Light: Debug + Send + Sync + RefUnwindSafe {
    /// A sample of the light toward the receiver from `u ∈ [0, 1)²`; `None` when the light sends
    /// nothing to the receiver's side (below its horizon, outside a spot's cone).
    fn sample(&self, at: &Receiver, u: [f64; 2]) -> Option<LightSample>;

    /// The emission `π·L(ω)` a ray that escapes the scene in the unit direction ω receives from
    /// this light: 0 for lights at a finite distance.
    fn escaped(&self, _dir: DVec3) -> Bands {
        [0.0; crate::BANDS]
    }

    /// The solid-angle density with which [`Light::sample`] draws the escaping direction ω from
    /// `at` (0 where it never does, and for lights at a finite distance).
    fn escaped_pdf(&self, _at: &Receiver, _dir: DVec3) -> f64 {
        0.0
    }

    /// Whether the light is a delta (a point, or a direction): no cosine ray ever reaches it.
    fn is_delta(&self) -> bool;

    /// Whether the light fills the background: rays that escape the scene see it over a solid
    /// angle ([`Light::escaped`] not zero almost everywhere: a sky, an environment map), so an
    /// image's empty pixels show it rather than nothing.
    fn is_background(&self) -> bool {
        false
    }

    /// Where the light is and where it shines, for the light tree ([`LightTree`]): `None` for a
    /// light at infinity (the sun, a sky, an environment map), which is drawn by power alone.
    fn bounds(&self) -> Option<LightBounds> {
        None
    }

    /// The light's power for light selection, as flux (exitance × area): an infinite light's
    /// flux through a disc of the scene's bounding radius `radius`.
    fn power(&self, radius: f64) -> f64;

    /// Whether the light's colour is grey (equal in every band): a coloured light makes the
    /// scene's results RGB.
    fn is_grey(&self) -> bool;

    /// A one-line description for messages and metrics.
    fn describe(&self) -> String;
}

/// Whether every band of `b` equals the first.
pub(crate) fn grey(b: &Bands) -> bool {
    b.iter().all(|v| *v == b[0])
}

/// The geometric part of a point-to-point connection from receiver y to a point x: the unit
/// direction, the squared distance and cos θ_y; `None` when x is behind the receiver.
pub(crate) fn toward(at: &Receiver, x: DVec3) -> Option<(DVec3, f64, f64)> {
    let d = x - at.p;
    let r2 = d.length_squared();
    if !(r2 > 0.0 && r2.is_finite()) {
        return None;
    }
    let w = d / r2.sqrt();
    let cy = at.n.dot(w);
    (cy > 0.0).then_some((w, r2, cy))
}
