//! The lights of a run beside the scene's own, as every front end takes them (the `gcr` program's
//! `--sun`, `--sky`, `--env`, `--point-light`, `--spot-light`, `--portal`, `--auto-portals`,
//! `--lights FILE`; the Python package's keyword arguments): [`LightOptions`] puts them
//! together into one [`Lighting`] (the file's, then the options') and lights a loaded scene with
//! it, in one place.

use crate::lights::lighting::{
    EnvSpec, Lighting, PointSpec, SkyKind, SkySpec, SpotSpec, SunSpec, Up,
};
use crate::{AnyScene, Result, SceneError};
use std::path::PathBuf;

/// A sky portal as four corners in order around a parallelogram.
pub type PortalCorners = [[f64; 3]; 4];

/// The ground reflectance of a sky unless given (Radiance's ground glow, `--ground-reflectance`).
pub const DEFAULT_GROUND_REFLECTANCE: f64 = 0.2;

/// Lights given beside the scene's own emitting faces (3-D scenes; [`crate::lights::lighting`] has the
/// conventions, docs/guide/lights.md the workflow). The default gives no light.
#[derive(Clone, Debug, PartialEq)]
pub struct LightOptions {
    /// A sun (`--sun AZ,EL,LUX[,DIAM]`).
    pub sun: Option<SunSpec>,
    /// A sky (`--sky MODEL:LUX`); its ground reflectance is replaced by
    /// [`LightOptions::ground_reflectance`].
    pub sky: Option<SkySpec>,
    /// An environment map (`--env FILE[,ROT[,SCALE]]`).
    pub env: Option<EnvSpec>,
    /// The ground's reflectance below the horizon of the sky given here.
    pub ground_reflectance: f64,
    /// The zenith axis of the sun and the sky; `None` keeps the lighting file's (default y).
    pub up: Option<Up>,
    /// Sky portals (`--portal`).
    pub portals: Vec<PortalCorners>,
    /// Find the scene's openings and use them as sky portals (`--auto-portals`).
    pub auto_portals: bool,
    /// Point lights (`--point-light`).
    pub point_lights: Vec<PointSpec>,
    /// Spot lights (`--spot-light`).
    pub spot_lights: Vec<SpotSpec>,
    /// A JSON lighting file (`--lights FILE`); the options above add to it.
    pub file: Option<PathBuf>,
}

impl Default for LightOptions {
    fn default() -> Self {
        Self {
            sun: None,
            sky: None,
            env: None,
            ground_reflectance: DEFAULT_GROUND_REFLECTANCE,
            up: None,
            portals: Vec::new(),
            auto_portals: false,
            point_lights: Vec::new(),
            spot_lights: Vec::new(),
            file: None,
        }
    }
}

/// A scene lit by [`LightOptions::light`].
#[derive(Debug)]
pub struct Lit {
    /// The scene with the lights added.
    pub scene: AnyScene,
    /// The openings found with [`LightOptions::auto_portals`] (already among the portals).
    pub found_portals: Vec<PortalCorners>,
}

impl LightOptions {
    /// The lighting these options describe: the file's, then the options'.
    pub fn lighting(&self) -> Result<Lighting> {
        let mut l = match &self.file {
            Some(path) => Lighting::read(path)?,
            None => Lighting::default(),
        };
        if let Some(up) = self.up {
            l.up = up;
        }
        if let Some(sun) = &self.sun {
            l.sun = Some(sun.clone());
        }
        if let Some(sky) = &self.sky {
            l.sky = Some(SkySpec {
                ground_reflectance: self.ground_reflectance,
                ..sky.clone()
            });
        }
        if let Some(env) = &self.env {
            l.env = Some(env.clone());
        }
        l.portals.extend(self.portals.iter().cloned());
        l.point_lights.extend(self.point_lights.iter().cloned());
        l.spot_lights.extend(self.spot_lights.iter().cloned());
        Ok(l)
    }

    /// The outdoor horizontal illuminance of daylight factors: a CIE overcast sky's, when the
    /// lighting is that sky and no sun (`None` otherwise, or when the lighting file is bad: its
    /// error comes when the scene is lit).
    pub fn outdoor_illuminance(&self) -> Option<f64> {
        let l = self.lighting().ok()?;
        match (&l.sky, &l.sun, &l.env) {
            (Some(sky), None, None) if sky.model == SkyKind::CieOvercast => Some(sky.illuminance),
            _ => None,
        }
    }

    /// Lights `loaded` (a 3-D scene) with these options, its openings as portals with
    /// [`LightOptions::auto_portals`], and refuses a scene nothing lights; errs for a Flatland
    /// scene given lights.
    pub fn light(&self, loaded: AnyScene) -> Result<Lit> {
        let mut lighting = self.lighting()?;
        if self.auto_portals && lighting.sky.is_none() && lighting.env.is_none() {
            return Err(SceneError::LightOptions(
                "--auto-portals: portals are openings to a sky; give one (--sky or --env)".into(),
            ));
        }
        match loaded {
            AnyScene::ThreeD(mut s) => {
                let found_portals = if self.auto_portals {
                    crate::openings::openings(&s)
                } else {
                    Vec::new()
                };
                lighting.portals.extend(found_portals.iter().cloned());
                s.add_lights(lighting.lights()?);
                s.check_lit()?;
                Ok(Lit {
                    scene: AnyScene::ThreeD(s),
                    found_portals,
                })
            }
            AnyScene::Flatland(_) if !lighting.is_empty() || self.auto_portals => {
                Err(SceneError::LightOptions(
                    "lights (--sun, --sky, --env, --point-light, --spot-light, --lights) need a \
                     3-D scene; a Flatland scene is lit by its emitting segments"
                        .into(),
                ))
            }
            flat => Ok(Lit {
                scene: flat,
                found_portals: Vec::new(),
            }),
        }
    }
}
