//! Probe outputs: radiosity at surface points, or irradiance at any points (Radiance's
//! `rtrace -I`), one line per probe in the input's order.
//!
//! A radiosity probe snaps onto the nearest face whose front faces the probe's normal, within a
//! distance tolerance (default 10⁻⁴ of the scene's diagonal, `--probe-tolerance`): the closest
//! point of that face (over its interior, the foot of the probe along the face's normal). An
//! irradiance probe is used where it is, with its normal. Every probe's value comes from a seed
//! of its own coordinates ([`crate::point_seed`]): it does not depend on its line or on the
//! other probes.

use super::OutputError;
use super::stage::Stage;
use crate::config::SolveConfig;
use crate::domain::Domain;
use crate::emitters::Emitters;
use crate::estimator::{GatherStats, irradiance_at_shard, radiosity_at_shard};
use crate::gather::Gathered;
use crate::solve::Trained;
use glam::DVec3;
use rayon::prelude::*;
use scene_sampler::NO_FACE;
use std::path::Path;
use std::time::Instant;

/// The probes' step of the output stage: their values gathered ([`probe_values`]; a shard's
/// partial output for a shard) and staged for `path`.
pub(super) fn write_probes(
    domain: &Domain,
    (trained, emitters): (&Trained, &Emitters),
    config: &SolveConfig,
    probes: (&[(DVec3, DVec3, u32)], &ProbeSettings),
    path: &Path,
    stage: &mut Stage,
) -> Result<(), OutputError> {
    let tg = Instant::now();
    let _phase = crate::progress::phase("probes");
    let (text, stats) = probe_values(domain, trained, emitters, config, probes)?;
    stage.metrics.probe_quantity = probes.1.quantity.name().into();
    stage.push_gather(stats);
    stage.metrics.seconds.gather += tg.elapsed().as_secs_f64();
    stage.files.write_bytes(path, text.as_bytes())
}

/// What the probe output holds.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ProbeQuantity {
    /// Radiosity B (exitance, W/m²) at surface points.
    #[default]
    Radiosity,
    /// Irradiance E = ∫ L cos θ dω (W/m²) at any points, for the hemisphere about the probe's
    /// normal (`rtrace -I`); needs the paths gather.
    Irradiance,
    /// The daylight factor DF = 100 · E / E_out in percent: the irradiance as
    /// [`ProbeQuantity::Irradiance`] over the horizontal illuminance E_out of the CIE overcast sky
    /// on an unobstructed plane ([`ProbeSettings::outdoor_illuminance`]).
    DaylightFactor,
}

impl ProbeQuantity {
    /// `radiosity`, `irradiance` or `daylight-factor`.
    pub fn name(self) -> &'static str {
        match self {
            ProbeQuantity::Radiosity => "radiosity",
            ProbeQuantity::Irradiance => "irradiance",
            ProbeQuantity::DaylightFactor => "daylight-factor",
        }
    }

    /// Whether the probes measure irradiance where they are (irradiance and daylight factors),
    /// rather than radiosity on the surface they snap to.
    pub fn is_irradiance(self) -> bool {
        self != ProbeQuantity::Radiosity
    }
}

impl std::str::FromStr for ProbeQuantity {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "radiosity" => Ok(Self::Radiosity),
            "irradiance" => Ok(Self::Irradiance),
            "daylight-factor" => Ok(Self::DaylightFactor),
            _ => Err(format!(
                "unknown probe quantity `{s}` (expected radiosity, irradiance or daylight-factor)"
            )),
        }
    }
}

/// How probes are read and what is computed at them.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ProbeSettings {
    /// The quantity.
    pub quantity: ProbeQuantity,
    /// Radiosity probes: the largest distance from a facing surface (scene units); `None`:
    /// 10⁻⁴ of the scene's diagonal. Irradiance probes are not snapped.
    pub tolerance: Option<f64>,
    /// Daylight factors: the horizontal illuminance of the CIE overcast sky on an unobstructed
    /// plane (its `--sky cie-overcast:LUX`); `None` when the lighting is not such a sky alone.
    pub outdoor_illuminance: Option<f64>,
}

impl ProbeSettings {
    /// Checks the tolerance: finite and positive, and only for radiosity probes.
    pub fn validate(&self) -> Result<(), OutputError> {
        match self.tolerance {
            Some(t) if !(t.is_finite() && t > 0.0) => Err(OutputError::ProbeTolerance(format!(
                "{t} (expected a positive distance in scene units)"
            ))),
            Some(_) if self.quantity.is_irradiance() => Err(OutputError::ProbeTolerance(
                "irradiance probes are used where they are, not snapped: drop the tolerance".into(),
            )),
            _ if self.quantity == ProbeQuantity::DaylightFactor
                && !self
                    .outdoor_illuminance
                    .is_some_and(|e| e.is_finite() && e > 0.0) =>
            {
                Err(OutputError::DaylightWithoutOvercast)
            }
            _ => Ok(()),
        }
    }
}

/// Probes as read from a file or given by a caller: 3-D (`x y z nx ny nz`) or Flatland
/// (`x y nx ny`), normals normalized (`scene_sampler::probes_from_rows` checks a caller's rows as
/// a file's lines are checked).
#[derive(Clone, Debug, PartialEq)]
pub enum ProbePoints {
    /// 3-D probes.
    ThreeD(Vec<scene_sampler::Probe>),
    /// Flatland probes.
    Flat(Vec<scene_sampler::FlatProbe>),
}

/// Reads the probe file: radiosity probes snapped onto the domain's surfaces `(point, normal,
/// face)`, irradiance probes as given with face [`NO_FACE`]; Flatland with z = 0.
pub(super) fn read_probes(
    domain: &Domain,
    path: &Path,
    settings: &ProbeSettings,
) -> Result<Vec<(DVec3, DVec3, u32)>, OutputError> {
    let source = path.display().to_string();
    let probes = match domain {
        Domain::ThreeD(_) => ProbePoints::ThreeD(scene_sampler::read_probes(path)?),
        Domain::Flat(_) => ProbePoints::Flat(scene_sampler::read_flat_probes(path)?),
    };
    place_probes(domain, &probes, settings, &source)
}

/// Where the probes are computed, as for a probe file ([`OutputPlan`](super::OutputPlan) reads
/// one): radiosity probes snapped onto the domain's surfaces `(point, normal, face)` within the
/// tolerance (module docs), irradiance probes as given with face [`NO_FACE`]; Flatland with
/// z = 0. `source` names the probes in messages (a file's name; errors give its line).
pub fn place_probes(
    domain: &Domain,
    probes: &ProbePoints,
    settings: &ProbeSettings,
    source: &str,
) -> Result<Vec<(DVec3, DVec3, u32)>, OutputError> {
    let snap = settings.quantity == ProbeQuantity::Radiosity;
    let tolerance = |diagonal: f64| {
        (settings.tolerance).unwrap_or_else(|| scene_sampler::probe::default_tolerance(diagonal))
    };
    Ok(match (domain, probes) {
        (Domain::ThreeD(_), ProbePoints::ThreeD(probes)) if !snap => probes
            .iter()
            .map(|p| (p.point, p.normal, NO_FACE))
            .collect(),
        (Domain::ThreeD(k), ProbePoints::ThreeD(probes)) => {
            let tol = tolerance(k.scene.diagonal());
            let snapper = scene_sampler::ProbeSnapper::new(k.scene);
            // in parallel, the first failing line reported (as a scan in file order would)
            let snapped: Vec<_> = probes
                .par_iter()
                .map(|p| snapper.snap(p, tol, source))
                .collect();
            snapped
                .into_iter()
                .map(|s| s.map(|s| (s.point, s.normal, s.face)))
                .collect::<Result<_, scene_sampler::SceneError>>()?
        }
        (Domain::Flat(_), ProbePoints::Flat(probes)) if !snap => probes
            .iter()
            .map(|p| (p.point.extend(0.0), p.normal.extend(0.0), NO_FACE))
            .collect(),
        (Domain::Flat(k), ProbePoints::Flat(probes)) => {
            let tol = tolerance(k.scene.diagonal());
            probes
                .iter()
                .map(|p| {
                    let s = k.scene.snap_probe(p, tol, source)?;
                    Ok((s.point.extend(0.0), s.normal.extend(0.0), s.segment))
                })
                .collect::<Result<_, scene_sampler::SceneError>>()?
        }
        (Domain::ThreeD(_), ProbePoints::Flat(_)) => return Err(wrong_dimension(source, 3)),
        (Domain::Flat(_), ProbePoints::ThreeD(_)) => return Err(wrong_dimension(source, 2)),
    })
}

/// Probes of the other dimension than the scene's.
fn wrong_dimension(source: &str, dim: usize) -> OutputError {
    let (scene, points) = match dim {
        3 => ("a 3-D scene", "x y z nx ny nz"),
        _ => ("a Flatland scene", "x y nx ny"),
    };
    OutputError::Probes(scene_sampler::SceneError::WrongDimension(format!(
        "{source}: {scene} takes probes as {points}"
    )))
}

/// The probes' values ([`crate::radiosity_at_points`] or [`crate::irradiance_at_points`]; daylight factors in
/// percent, their standard errors too), in the probes' order, and what the gather measured.
pub fn gather_probes(
    domain: &Domain,
    trained: &Trained,
    emitters: &Emitters,
    config: &SolveConfig,
    probes: (&[(DVec3, DVec3, u32)], &ProbeSettings),
) -> Result<(Vec<Gathered>, GatherStats), OutputError> {
    let (gathered, stats, _) = gather_probe_shard(domain, trained, emitters, config, probes)?;
    Ok((gathered, stats))
}

/// [`gather_probes`] and the indices (ascending) of the probes estimated: those of the shard
/// `config` asks for ([`crate::shard_points`]; the others are left at `Gathered::default()` and
/// out of the statistics), else every one.
pub fn gather_probe_shard(
    domain: &Domain,
    trained: &Trained,
    emitters: &Emitters,
    config: &SolveConfig,
    (probes, settings): (&[(DVec3, DVec3, u32)], &ProbeSettings),
) -> Result<(Vec<Gathered>, GatherStats, Vec<usize>), OutputError> {
    let (quantity, outdoor) = (settings.quantity, settings.outdoor_illuminance);
    let (mut gathered, mine) = match quantity {
        ProbeQuantity::Radiosity => {
            radiosity_at_shard(domain, trained, emitters, config, (probes, None))?
        }
        ProbeQuantity::Irradiance | ProbeQuantity::DaylightFactor => {
            let at: Vec<(DVec3, DVec3)> = probes.iter().map(|&(y, n, _)| (y, n)).collect();
            irradiance_at_shard(domain, trained, emitters, config, (&at, None))?
        }
    };
    // a shard's probes only ([`crate::shard_points`]); the others were not estimated
    let stats = match config.paths.shard {
        None => GatherStats::of(&gathered),
        Some(_) => GatherStats::of(&mine.iter().map(|&i| gathered[i]).collect::<Vec<_>>()),
    };
    // daylight factors in percent of the outdoor illuminance (checked positive by `validate`)
    if let (ProbeQuantity::DaylightFactor, Some(e)) = (quantity, outdoor) {
        let scale = 100.0 / e;
        for g in &mut gathered {
            g.radiosity = g.radiosity.map(|v| v * scale);
            g.std_error = g.std_error.map(|v| v * scale);
        }
    }
    Ok((gathered, stats, mine))
}

/// The probes' values as the probe output holds them ([`gather_probes`]), one line each:
/// `r g b`, or one value for a grey Flatland scene.
pub fn probe_values(
    domain: &Domain,
    trained: &Trained,
    emitters: &Emitters,
    config: &SolveConfig,
    probes: (&[(DVec3, DVec3, u32)], &ProbeSettings),
) -> Result<(String, GatherStats), OutputError> {
    let grey = domain.bands() == 1 && domain.dim() == 2;
    let (gathered, stats, mine) = gather_probe_shard(domain, trained, emitters, config, probes)?;
    let lines: Vec<String> = gathered
        .iter()
        .map(|g| {
            let b = g.radiosity;
            if grey {
                format!("{}\n", b[0])
            } else {
                format!("{} {} {}\n", b[0], b[1], b[2])
            }
        })
        .collect();
    // ⟨A shard writes its probes' lines with their indices (`super::shards`)⟩
    let text = match config.paths.shard {
        None => lines.concat(),
        Some(shard) => {
            let print = super::shards::fingerprint(domain, probes.0, config, "");
            super::shards::partial_text(super::shards::Kind::Probes, shard, print, &lines, &mine)
        }
    };
    Ok((text, stats))
}
