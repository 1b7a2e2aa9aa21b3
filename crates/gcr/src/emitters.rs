//! The scene's lights for the gathers' direct light ([`crate::gather`], [`crate::paths`]) and
//! the senders of shot rays ([`crate::shooting`]): `scene_sampler`'s [`LightSet`] of the domain's
//! scene (its emitting faces and, in 3-D, [`scene_sampler::Scene::lights`]).

use crate::domain::Domain;
use scene_sampler::{EmitterTable, LightSet};

/// The lights of a domain's scene with their sampling tables.
#[derive(Clone, Debug)]
pub struct Emitters(LightSet);

impl Emitters {
    /// Collects the lights of the domain: emitting faces (segments), and a 3-D scene's other
    /// lights.
    pub fn new(domain: &Domain) -> Self {
        Self(match domain {
            Domain::ThreeD(k) => LightSet::of_scene(k.scene),
            Domain::Flat(k) => LightSet::of_flatland(k.scene),
        })
    }

    /// True when nothing gives light.
    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }

    /// The emitting faces (the shot rays' senders).
    pub(crate) fn table(&self) -> &EmitterTable {
        self.0.faces()
    }

    /// Every light, with light selection.
    pub(crate) fn lights(&self) -> &LightSet {
        &self.0
    }
}
