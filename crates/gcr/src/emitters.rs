//! The scene's emitters for the ray gather's direct light ([`crate::gather`]) and the senders of
//! shot rays ([`crate::shooting`]): `scene_sampler`'s [`EmitterTable`] of the domain's scene.

use crate::domain::Domain;
use scene_sampler::EmitterTable;

/// The emitting faces (segments) of a domain's scene with their sampling tables.
#[derive(Clone, Debug)]
pub struct Emitters(EmitterTable);

impl Emitters {
    /// Collects the emitting faces (segments) of the domain.
    pub fn new(domain: &Domain) -> Self {
        Self(match domain {
            Domain::ThreeD(k) => EmitterTable::of_scene(k.scene),
            Domain::Flat(k) => EmitterTable::of_flatland(k.scene),
        })
    }

    /// True when the scene has no emitter.
    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }

    /// The table.
    pub(crate) fn table(&self) -> &EmitterTable {
        &self.0
    }
}
