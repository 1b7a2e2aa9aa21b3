//! The light arguments of `Scene.load` as the library takes them
//! ([`scene_sampler::LightOptions`]): each value is the program's option text (`sun="135,40,80000"`
//! as `--sun 135,40,80000`) or a sequence of numbers (`sun=(135, 40, 80000)`, joined by commas
//! with each number printed so that it parses back to the same float), read by the program's own
//! parsers, so that values, defaults and messages are the program's.

use crate::errors::value_error;
use pyo3::prelude::*;
use scene_sampler::LightOptions;
use scene_sampler::lights::lighting::{self, EnvSpec, Up};
use std::path::PathBuf;

/// The light arguments as Python gives them (`None`: not given).
pub(crate) struct LightArgs<'py> {
    pub sun: Option<Bound<'py, PyAny>>,
    pub sky: Option<String>,
    pub env: Option<Bound<'py, PyAny>>,
    pub ground_reflectance: Option<f64>,
    pub up: Option<String>,
    pub portals: Vec<Bound<'py, PyAny>>,
    pub auto_portals: bool,
    pub point_lights: Vec<Bound<'py, PyAny>>,
    pub spot_lights: Vec<Bound<'py, PyAny>>,
    pub lights: Option<PathBuf>,
}

impl LightArgs<'_> {
    /// The library's light options, or a `ValueError` naming the argument that does not parse.
    pub(crate) fn options(&self) -> PyResult<LightOptions> {
        let up = match self.up.as_deref() {
            None => None,
            Some("y") => Some(Up::Y),
            Some("z") => Some(Up::Z),
            Some(other) => {
                return Err(value_error(format!(
                    "up `{other}`: expected \"y\" or \"z\""
                )));
            }
        };
        if self.ground_reflectance.is_some() && self.sky.is_none() {
            return Err(value_error(
                "ground_reflectance needs a sky (as --ground-reflectance needs --sky)",
            ));
        }
        let sky = (self.sky.as_deref())
            .map(|s| parsed_text(s, "sky", lighting::parse_sky))
            .transpose()?;
        Ok(LightOptions {
            sun: (self.sun.as_ref())
                .map(|v| parsed(v, "sun", lighting::parse_sun))
                .transpose()?,
            sky,
            env: self.env.as_ref().map(env).transpose()?,
            ground_reflectance: (self.ground_reflectance)
                .unwrap_or(scene_sampler::DEFAULT_GROUND_REFLECTANCE),
            up,
            portals: all(&self.portals, "portal", lighting::parse_portal)?,
            auto_portals: self.auto_portals,
            point_lights: all(&self.point_lights, "point light", lighting::parse_point)?,
            spot_lights: all(&self.spot_lights, "spot light", lighting::parse_spot)?,
            file: self.lights.clone(),
        })
    }
}

/// `value` as the program's option text: a string as given, a (nested) sequence of numbers
/// joined by commas.
fn option_text(value: &Bound<'_, PyAny>, what: &str) -> PyResult<String> {
    if let Ok(s) = value.extract::<String>() {
        return Ok(s);
    }
    let numbers: Vec<f64> = match value.extract::<Vec<Vec<f64>>>() {
        Ok(rows) => rows.concat(),
        Err(_) => value.extract().map_err(|_| {
            value_error(format!(
                "{what}: expected the program's option text (a string) or a sequence of numbers"
            ))
        })?,
    };
    let text: Vec<String> = numbers.iter().map(f64::to_string).collect();
    Ok(text.join(","))
}

/// `value` read by the program's parser of that option.
fn parsed<T>(
    value: &Bound<'_, PyAny>,
    what: &str,
    parse: fn(&str) -> Result<T, String>,
) -> PyResult<T> {
    parsed_text(&option_text(value, what)?, what, parse)
}

fn parsed_text<T>(text: &str, what: &str, parse: fn(&str) -> Result<T, String>) -> PyResult<T> {
    parse(text).map_err(|m| value_error(format!("invalid {what} `{text}`: {m}")))
}

/// Each of `values` read by `parse`.
fn all<T>(
    values: &[Bound<'_, PyAny>],
    what: &str,
    parse: fn(&str) -> Result<T, String>,
) -> PyResult<Vec<T>> {
    values.iter().map(|v| parsed(v, what, parse)).collect()
}

/// An environment map: the program's `FILE[,ROT[,SCALE]]` text, or a path (no turn, scale 1).
fn env(value: &Bound<'_, PyAny>) -> PyResult<EnvSpec> {
    if let Ok(text) = value.extract::<String>() {
        return parsed_text(&text, "env", lighting::parse_env);
    }
    let file: PathBuf = value
        .extract()
        .map_err(|_| value_error("env: expected \"FILE[,ROT[,SCALE]]\" or a path"))?;
    Ok(EnvSpec {
        file,
        rotation: 0.0,
        scale: 1.0,
    })
}
