//! glTF `KHR_lights_punctual`: the lights a glTF node carries, placed by the node's world
//! transform (a light shines along its node's local −Z). Units as the extension gives them:
//! point and spot intensity in candela, directional illuminance in lux, each times the light's
//! linear `color`.
//!
//! * **point** → [`PointLight`]; **spot** → [`PointLight::spot`] with `innerConeAngle` (default
//!   0) and `outerConeAngle` (default π/4);
//! * **directional** → a [`Sun`] of the default 0.53° diameter (a glTF directional light in a
//!   daylit model is the sun; its soft shadow edges are the real ones);
//! * `range` is honoured with the extension's recommended window,
//!   `clamp(1 − (d/range)⁴, 0, 1)²` on top of the inverse square ([`PointLight::with_range`]).

use crate::{BANDS, Light, PointLight, Result, SceneError, Sun};
use glam::{DMat4, DVec3};
use gltf::khr_lights_punctual::Kind;
use std::sync::Arc;

/// The light of a glTF `node` (with world transform `world`), if it has one.
pub(crate) fn node_light(
    node: &gltf::Node,
    world: DMat4,
    source: &str,
) -> Result<Option<Arc<dyn Light>>> {
    let Some(light) = node.light() else {
        return Ok(None);
    };
    let name = light.name().map_or_else(
        || format!("light {}", light.index()),
        |n| format!("light `{n}`"),
    );
    let bad = |what: &str| SceneError::Parse {
        source_name: source.to_string(),
        message: format!(
            "{name} (KHR_lights_punctual) on node {}: {what}",
            node.index()
        ),
    };
    let color = light.color().map(f64::from);
    let intensity = f64::from(light.intensity());
    let value: [f64; BANDS] = std::array::from_fn(|k| intensity * color[k]);
    let position = world.transform_point3(DVec3::ZERO);
    let forward = world.transform_vector3(DVec3::NEG_Z);
    let range = light.range().map(f64::from);
    let made: Option<Arc<dyn Light>> = match light.kind() {
        Kind::Directional => {
            Sun::new(-forward, value, Sun::DIAMETER_DEG).map(|s| Arc::new(s) as Arc<dyn Light>)
        }
        Kind::Point => PointLight::new(position, value)
            .and_then(|p| p.with_range(range))
            .map(|p| Arc::new(p) as Arc<dyn Light>),
        Kind::Spot {
            inner_cone_angle,
            outer_cone_angle,
        } => PointLight::spot(
            position,
            value,
            forward,
            f64::from(inner_cone_angle),
            f64::from(outer_cone_angle),
        )
        .and_then(|p| p.with_range(range))
        .map(|p| Arc::new(p) as Arc<dyn Light>),
    };
    made.map(Some).ok_or_else(|| {
        bad(
            "a negative or non-finite intensity or colour, a degenerate transform, a range ≤ 0, \
             or spot cone angles outside 0 ≤ inner < outer ≤ π/2",
        )
    })
}
