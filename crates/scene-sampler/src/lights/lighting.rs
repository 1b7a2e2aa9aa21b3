//! Where lights come from when the scene file has none of its own: a description — program
//! options (`gcr solve --sun 135,40,80000 --sky cie-overcast:12000`) or a small JSON lighting file
//! (`--lights lights.json`) — turned into [`crate::Light`]s for [`crate::Scene::lights`]
//! ([`Lighting::lights`]).
//!
//! Units are the scene's: with photometric values (lux, candela) B comes out in lm/m² (lux of
//! exitance), as Radiance's `gensky` and glTF's punctual lights give them.
//!
//! **Directions**: azimuth as a compass bearing (0° north, 90° east), elevation above the horizon.
//! With `"up": "y"` (the default, glTF's convention) north is −Z and east +X; with `"up": "z"`
//! (Radiance's) north is +Y and east +X.
//!
//! ```json
//! { "up": "y",
//!   "sun": { "azimuth": 135, "elevation": 40, "illuminance": 80000, "diameter": 0.53 },
//!   "sky": { "model": "cie-overcast", "illuminance": 12000, "ground_reflectance": 0.2 },
//!   "portals": [ [[1.2, 0.9, 5], [2.8, 0.9, 5], [2.8, 2.1, 5], [1.2, 2.1, 5]] ],
//!   "env": { "file": "studio.hdr", "rotation": 90, "scale": 1.0 },
//!   "point_lights": [ { "position": [0, 2.5, 0], "intensity": 800 } ],
//!   "spot_lights": [ { "position": [1, 2.5, 0], "direction": [0, -1, 0], "intensity": 1200,
//!                      "inner_angle": 20, "outer_angle": 35 } ] }
//! ```

use super::{EnvMap, Light, PointLight, Portal, Portals, Sky, SkyModel, Sun};
use crate::{BANDS, Result, SceneError};
use glam::DVec3;
use serde::Deserialize;
use std::f64::consts::PI;
use std::sync::Arc;

/// The zenith axis of a lighting description.
#[derive(Clone, Copy, Debug, Default, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum Up {
    /// +Y up (glTF); north −Z, east +X.
    #[default]
    Y,
    /// +Z up (Radiance); north +Y, east +X.
    Z,
}

impl Up {
    /// (up, north, east) unit vectors.
    pub fn frame(self) -> (DVec3, DVec3, DVec3) {
        match self {
            Up::Y => (DVec3::Y, -DVec3::Z, DVec3::X),
            Up::Z => (DVec3::Z, DVec3::Y, DVec3::X),
        }
    }

    /// The unit direction of compass bearing `azimuth_deg` at `elevation_deg` above the horizon.
    pub fn direction(self, azimuth_deg: f64, elevation_deg: f64) -> DVec3 {
        let (up, north, east) = self.frame();
        let (az, el) = (azimuth_deg.to_radians(), elevation_deg.to_radians());
        (east * az.sin() + north * az.cos()) * el.cos() + up * el.sin()
    }
}

/// The sun of a lighting description.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SunSpec {
    /// Compass bearing of the sun, degrees.
    pub azimuth: f64,
    /// Elevation above the horizon, degrees (0 < elevation ≤ 90).
    pub elevation: f64,
    /// Normal illuminance (irradiance on a plane facing the sun).
    pub illuminance: f64,
    /// Angular diameter, degrees (default 0.53; 0: a delta direction).
    #[serde(default = "default_diameter")]
    pub diameter: f64,
}

fn default_diameter() -> f64 {
    Sun::DIAMETER_DEG
}

/// The sky models of a lighting description.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum SkyKind {
    /// Constant radiance.
    Uniform,
    /// CIE overcast.
    CieOvercast,
    /// CIE clear (needs the sun's position: the description's sun).
    CieClear,
    /// The Perez all-weather sky ([`super::perez`]): needs the description's sun, whose normal
    /// illuminance and the sky's diffuse horizontal illuminance (both in lux) give its clearness
    /// and brightness.
    Perez,
}

/// The sky of a lighting description.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SkySpec {
    /// The luminance distribution.
    pub model: SkyKind,
    /// Horizontal illuminance of the sky alone (diffuse horizontal).
    pub illuminance: f64,
    /// Ground reflectance below the horizon (Radiance's ground glow; default 0.2, 0 = black).
    #[serde(default = "default_ground")]
    pub ground_reflectance: f64,
}

fn default_ground() -> f64 {
    0.2
}

/// The environment map of a lighting description ([`EnvMap`]).
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct EnvSpec {
    /// An equirectangular `.hdr` or `.exr` image. In a lighting file, relative to the file's
    /// folder and confined to it (as a scene's textures are); on the command line, as given.
    pub file: std::path::PathBuf,
    /// The map's turn about the zenith, degrees: its north column then looks toward this bearing.
    #[serde(default)]
    pub rotation: f64,
    /// A factor on the map's radiance (default 1).
    #[serde(default = "default_scale")]
    pub scale: f64,
}

fn default_scale() -> f64 {
    1.0
}

/// A point light of a lighting description.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct PointSpec {
    /// Position.
    pub position: [f64; 3],
    /// Intensity (candela).
    pub intensity: f64,
}

/// A spot light of a lighting description.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct SpotSpec {
    /// Position.
    pub position: [f64; 3],
    /// The direction it shines along.
    pub direction: [f64; 3],
    /// Intensity on its axis (candela).
    pub intensity: f64,
    /// Half-angle of full intensity, degrees.
    pub inner_angle: f64,
    /// Half-angle beyond which it gives nothing, degrees (≤ 90).
    pub outer_angle: f64,
}

/// A lighting description (module docs).
#[derive(Clone, Debug, Default, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct Lighting {
    /// The zenith axis.
    #[serde(default)]
    pub up: Up,
    /// The sun.
    pub sun: Option<SunSpec>,
    /// The sky.
    pub sky: Option<SkySpec>,
    /// An environment map (beside or instead of a sky).
    pub env: Option<EnvSpec>,
    /// Point lights.
    #[serde(default)]
    pub point_lights: Vec<PointSpec>,
    /// Spot lights.
    #[serde(default)]
    pub spot_lights: Vec<SpotSpec>,
    /// Sky portals: the openings (windows, skylights) through which the interior sees the sky,
    /// each four corners in order around a parallelogram; the sky then draws most of its shadow
    /// rays through them.
    #[serde(default)]
    pub portals: Vec<[[f64; 3]; 4]>,
}

impl Lighting {
    /// Reads a JSON lighting file (module docs); errors name the file and the field.
    pub fn read(path: &std::path::Path) -> Result<Self> {
        let text = std::fs::read_to_string(path).map_err(|source| SceneError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        let mut lighting: Self = serde_json::from_str(&text)
            .map_err(|e| lighting_error(&path.display().to_string(), e))?;
        if let Some(env) = &mut lighting.env {
            // the map is the file's neighbour: resolved in its folder, never outside it
            let folder = crate::confine::Folder::of(path, &crate::LoadOptions::default())?;
            env.file = folder.locate(&env.file).ok_or_else(|| {
                lighting_message(&format!(
                    "{}: the environment map {} is outside the lighting file's folder",
                    path.display(),
                    env.file.display()
                ))
            })?;
        }
        Ok(lighting)
    }

    /// Whether the description gives no light.
    pub fn is_empty(&self) -> bool {
        self.portals.is_empty()
            && self.sun.is_none()
            && self.sky.is_none()
            && self.env.is_none()
            && self.point_lights.is_empty()
            && self.spot_lights.is_empty()
    }

    /// The portals, checked.
    fn sky_portals(&self) -> Result<Portals> {
        let portals = (self.portals.iter().enumerate())
            .map(|(i, c)| {
                Portal::new(c.map(DVec3::from_array)).ok_or_else(|| {
                    lighting_message(&format!(
                        "bad portal {}: its four corners must be finite and form a parallelogram, \
                         in order around it",
                        i + 1
                    ))
                })
            })
            .collect::<Result<Vec<_>>>()?;
        Ok(Portals::new(portals))
    }

    /// The Perez sky of `sky` under the description's sun: ε and Δ from the sun's normal
    /// illuminance and the sky's diffuse horizontal illuminance ([`super::perez`]).
    fn perez(&self, sky: &SkySpec) -> Result<SkyModel> {
        let s = self.sun.as_ref().ok_or_else(|| {
            lighting_message(
                "bad sky: the Perez sky needs a sun (--sun AZ,EL,LUX: its position and direct \
                 normal illuminance)",
            )
        })?;
        let zenith = (90.0 - s.elevation).to_radians();
        let (epsilon, delta) =
            super::perez::parameters_from_illuminance(s.illuminance, sky.illuminance, zenith);
        let model = SkyModel::Perez {
            sun: self.up.direction(s.azimuth, s.elevation),
            epsilon,
            delta,
        };
        let (up, _, _) = self.up.frame();
        if Sky::new(model.clone(), up, [1.0; BANDS], [0.0; BANDS]).is_none() {
            return Err(lighting_message(&format!(
                "bad sky: the Perez sky of ε = {epsilon:.3}, Δ = {delta:.3} (from the sun's and \
                 the sky's illuminances) would brighten toward the horizon without bound; \
                 gendaylit refuses it too"
            )));
        }
        Ok(model)
    }

    /// The lights of the description, checked: an error names the bad value.
    pub fn lights(&self) -> Result<Vec<Arc<dyn Light>>> {
        let mut out: Vec<Arc<dyn Light>> = Vec::new();
        let bad = |what: &str| lighting_message(&format!("bad {what}"));
        let sun = match &self.sun {
            Some(s) => {
                if !(s.elevation > 0.0 && s.elevation <= 90.0 && s.azimuth.is_finite()) {
                    return Err(bad("sun position: elevation must be in (0, 90] degrees"));
                }
                let dir = self.up.direction(s.azimuth, s.elevation);
                let sun = Sun::new(dir, [s.illuminance; BANDS], s.diameter).ok_or_else(|| {
                    bad("sun: illuminance must be ≥ 0 and the diameter in [0, 20] degrees")
                })?;
                out.push(Arc::new(sun));
                Some((dir, s.illuminance * s.elevation.to_radians().sin()))
            }
            None => None,
        };
        if let Some(s) = &self.sky {
            let model = match s.model {
                SkyKind::Uniform => SkyModel::Uniform,
                SkyKind::CieOvercast => SkyModel::CieOvercast,
                SkyKind::CieClear => SkyModel::CieClear {
                    sun: sun
                        .ok_or_else(|| bad("sky: the CIE clear sky needs a sun (--sun)"))?
                        .0,
                },
                SkyKind::Perez => self.perez(s)?,
            };
            if !(0.0..1.0).contains(&s.ground_reflectance) {
                return Err(bad("sky: ground reflectance must be in [0, 1)"));
            }
            // Radiance's ground glow: ρ_g × the horizontal illuminance of sky and sun, over π
            let e_g = s.illuminance + sun.map_or(0.0, |(_, e)| e);
            let ground = [s.ground_reflectance * e_g / PI; BANDS];
            let (up, _, _) = self.up.frame();
            let sky = Sky::new(model, up, [s.illuminance; BANDS], ground)
                .ok_or_else(|| bad("sky: illuminance must be ≥ 0 and finite"))?;
            out.push(Arc::new(sky.with_portals(self.sky_portals()?)));
        }
        if let Some(e) = &self.env {
            let (up, north, east) = self.up.frame();
            let map = EnvMap::read(&e.file, (up, north, east), e.rotation, e.scale)?;
            out.push(Arc::new(map.with_portals(self.sky_portals()?)));
        }
        if self.sky.is_none() && self.env.is_none() && !self.portals.is_empty() {
            return Err(bad(
                "portals: they are openings to a sky; give one (--sky or --env)",
            ));
        }
        for p in &self.point_lights {
            let light = PointLight::new(DVec3::from_array(p.position), [p.intensity; BANDS])
                .ok_or_else(|| bad("point light: position and intensity ≥ 0 must be finite"))?;
            out.push(Arc::new(light));
        }
        for s in &self.spot_lights {
            let light = PointLight::spot(
                DVec3::from_array(s.position),
                [s.intensity; BANDS],
                DVec3::from_array(s.direction),
                s.inner_angle.to_radians(),
                s.outer_angle.to_radians(),
            )
            .ok_or_else(|| {
                bad("spot light: needs a direction, intensity ≥ 0 and 0 ≤ inner < outer ≤ 90 degrees")
            })?;
            out.push(Arc::new(light));
        }
        Ok(out)
    }
}

fn lighting_error(source: &str, e: serde_json::Error) -> SceneError {
    SceneError::Lighting {
        message: format!("{source}: {e}"),
    }
}

fn lighting_message(message: &str) -> SceneError {
    SceneError::Lighting {
        message: message.to_string(),
    }
}

/// Parses `--sun AZ,EL,LUX[,DIAMETER]`.
pub fn parse_sun(s: &str) -> std::result::Result<SunSpec, String> {
    let v = numbers(s)?;
    match v[..] {
        [azimuth, elevation, illuminance] => Ok(SunSpec {
            azimuth,
            elevation,
            illuminance,
            diameter: Sun::DIAMETER_DEG,
        }),
        [azimuth, elevation, illuminance, diameter] => Ok(SunSpec {
            azimuth,
            elevation,
            illuminance,
            diameter,
        }),
        _ => Err("expected AZIMUTH,ELEVATION,ILLUMINANCE[,DIAMETER] (degrees, lux)".into()),
    }
}

/// Parses `--sky MODEL:LUX` (models `uniform`, `cie-overcast`, `cie-clear`, `perez`).
pub fn parse_sky(s: &str) -> std::result::Result<SkySpec, String> {
    let (model, lux) = s
        .split_once(':')
        .ok_or("expected MODEL:ILLUMINANCE, e.g. cie-overcast:10000")?;
    let model = match model {
        "uniform" => SkyKind::Uniform,
        "cie-overcast" | "overcast" => SkyKind::CieOvercast,
        "cie-clear" | "clear" => SkyKind::CieClear,
        "perez" => SkyKind::Perez,
        m => {
            return Err(format!(
                "unknown sky `{m}` (uniform, cie-overcast, cie-clear, perez)"
            ));
        }
    };
    let illuminance = lux
        .trim()
        .parse::<f64>()
        .map_err(|_| format!("`{lux}` is not a number"))?;
    Ok(SkySpec {
        model,
        illuminance,
        ground_reflectance: default_ground(),
    })
}

/// Parses `--env FILE[,ROTATION[,SCALE]]` (the trailing numbers, if any, are the rotation in
/// degrees and the scale).
pub fn parse_env(s: &str) -> std::result::Result<EnvSpec, String> {
    let mut parts: Vec<&str> = s.split(',').collect();
    let mut numbers = Vec::new();
    while parts.len() > 1 && numbers.len() < 2 {
        match parts.last().map(|p| p.trim().parse::<f64>()) {
            Some(Ok(v)) if v.is_finite() => {
                numbers.insert(0, v);
                parts.pop();
            }
            _ => break,
        }
    }
    let file = parts.join(",");
    if file.is_empty() {
        return Err("expected FILE[,ROTATION[,SCALE]]".into());
    }
    Ok(EnvSpec {
        file: file.into(),
        rotation: numbers.first().copied().unwrap_or(0.0),
        scale: numbers.get(1).copied().unwrap_or(1.0),
    })
}

/// Parses `--portal X,Y,Z,X,Y,Z,X,Y,Z,X,Y,Z` (four corners in order around a parallelogram).
pub fn parse_portal(s: &str) -> std::result::Result<[[f64; 3]; 4], String> {
    let v = numbers(s)?;
    if v.len() != 12 {
        return Err("expected the four corners X,Y,Z,X,Y,Z,X,Y,Z,X,Y,Z in order".into());
    }
    Ok(std::array::from_fn(|i| {
        [v[3 * i], v[3 * i + 1], v[3 * i + 2]]
    }))
}

/// Parses `--point-light X,Y,Z,CANDELA`.
pub fn parse_point(s: &str) -> std::result::Result<PointSpec, String> {
    match numbers(s)?[..] {
        [x, y, z, intensity] => Ok(PointSpec {
            position: [x, y, z],
            intensity,
        }),
        _ => Err("expected X,Y,Z,CANDELA".into()),
    }
}

/// Parses `--spot-light X,Y,Z,DX,DY,DZ,CANDELA,INNER,OUTER` (angles in degrees).
pub fn parse_spot(s: &str) -> std::result::Result<SpotSpec, String> {
    match numbers(s)?[..] {
        [x, y, z, dx, dy, dz, intensity, inner_angle, outer_angle] => Ok(SpotSpec {
            position: [x, y, z],
            direction: [dx, dy, dz],
            intensity,
            inner_angle,
            outer_angle,
        }),
        _ => Err("expected X,Y,Z,DX,DY,DZ,CANDELA,INNER_DEG,OUTER_DEG".into()),
    }
}

fn numbers(s: &str) -> std::result::Result<Vec<f64>, String> {
    s.split(',')
        .map(|v| {
            let v = v.trim();
            v.parse::<f64>()
                .ok()
                .filter(|x| x.is_finite())
                .ok_or_else(|| format!("`{v}` is not a finite number"))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn compass_directions_and_parsing() {
        let d = Up::Y.direction(90.0, 0.0);
        assert!((d - DVec3::X).length() < 1e-12, "east");
        let d = Up::Z.direction(0.0, 0.0);
        assert!((d - DVec3::Y).length() < 1e-12, "north");
        assert!((Up::Y.direction(10.0, 90.0) - DVec3::Y).length() < 1e-12);
        assert_eq!(parse_sun("135,40,80000").unwrap().diameter, 0.53);
        assert!(parse_sun("135,40").is_err() && parse_sun("a,b,c").is_err());
        assert_eq!(
            parse_sky("cie-overcast:10000").unwrap().model,
            SkyKind::CieOvercast
        );
        assert!(parse_sky("foggy:1").is_err() && parse_sky("uniform").is_err());
        let env = parse_env("maps/a,b.hdr,90,2.5").unwrap();
        assert_eq!(
            (env.file.to_str(), env.rotation, env.scale),
            (Some("maps/a,b.hdr"), 90.0, 2.5)
        );
        assert_eq!(parse_env("sky.exr").unwrap().scale, 1.0);
        let l: Lighting = serde_json::from_str(
            r#"{"up":"z","sun":{"azimuth":180,"elevation":30,"illuminance":50000},
               "sky":{"model":"cie-clear","illuminance":10000}}"#,
        )
        .unwrap();
        assert_eq!(l.lights().unwrap().len(), 2);
        let e = serde_json::from_str::<Lighting>(r#"{"sunn":{}}"#).unwrap_err();
        assert!(e.to_string().contains("unknown field"), "{e}");
        let clear = Lighting {
            sky: Some(parse_sky("cie-clear:1000").unwrap()),
            ..Lighting::default()
        };
        assert!(
            clear
                .lights()
                .unwrap_err()
                .to_string()
                .contains("needs a sun")
        );
        let perez = Lighting {
            sky: Some(parse_sky("perez:15000").unwrap()),
            ..Lighting::default()
        };
        assert!(
            perez
                .lights()
                .unwrap_err()
                .to_string()
                .contains("needs a sun")
        );
        let l: Lighting = serde_json::from_str(
            r#"{"sun":{"azimuth":200,"elevation":25,"illuminance":60000},
               "sky":{"model":"perez","illuminance":15000}}"#,
        )
        .unwrap();
        let lights = l.lights().unwrap();
        assert!(
            lights[1].describe().starts_with("Perez (ε = 3.54"),
            "{}",
            lights[1].describe()
        );
        let low = Lighting {
            sun: Some(parse_sun("0,-5,1000").unwrap()),
            ..Lighting::default()
        };
        assert!(low.lights().is_err());
    }
}
