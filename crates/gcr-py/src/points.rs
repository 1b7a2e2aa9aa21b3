//! B, irradiance and daylight factors at a caller's points, as the program's probe output gets
//! them: the rows checked as a probe file's lines ([`scene_sampler::probes_from_rows`]), radiosity
//! probes snapped onto the surfaces ([`gcr::output::place_probes`], `crates/gcr/src/output/
//! probes.rs`), the values gathered together ([`gcr::output::gather_probes`]: neighbouring points
//! share paths, the rounds run until the points' estimated error meets the target). The same
//! points as a probe file's, in the same order, give the program's numbers exactly.

use crate::errors::{gcr_error, value_error, warn_all};
use crate::runner;
use crate::solve::Solved;
use gcr::Emitters;
use gcr::output::{
    ProbePoints, ProbeQuantity, ProbeSettings, gather_probes, gather_warnings, place_probes,
};
use numpy::{AllowTypeChange, PyArray1, PyArrayDyn, PyArrayLikeDyn, PyArrayMethods};
use pyo3::prelude::*;
use std::sync::Arc;

/// How the points' rows are named in messages: `points:3: …` is the third row.
const SOURCE: &str = "points";

/// N × bands values and their standard errors.
pub(crate) type Values<'py> = (Bound<'py, PyArrayDyn<f64>>, Bound<'py, PyArrayDyn<f64>>);

/// The probe settings of `quantity` for `solved`'s scene.
pub(crate) fn settings(
    solved: &Solved,
    quantity: ProbeQuantity,
    tolerance: Option<f64>,
) -> ProbeSettings {
    ProbeSettings {
        quantity,
        tolerance,
        outdoor_illuminance: solved.scene.outdoor_illuminance,
    }
}

/// The values at `points` with `normals` (N × 3, Flatland N × 2), with the GIL released.
pub(crate) fn at_points<'py>(
    py: Python<'py>,
    solved: &Arc<Solved>,
    (points, normals): (
        PyArrayLikeDyn<'py, f64, AllowTypeChange>,
        PyArrayLikeDyn<'py, f64, AllowTypeChange>,
    ),
    settings: ProbeSettings,
    progress: Option<&Bound<'py, PyAny>>,
) -> PyResult<Values<'py>> {
    settings.validate().map_err(gcr_error)?;
    let dim = solved.scene.dim();
    let rows = rows(&points, &normals, dim)?;
    let probes = match dim {
        3 => ProbePoints::ThreeD(
            scene_sampler::probes_from_rows(SOURCE, &fixed::<6>(&rows)).map_err(gcr_error)?,
        ),
        _ => ProbePoints::Flat(
            scene_sampler::flat_probes_from_rows(SOURCE, &fixed::<4>(&rows)).map_err(gcr_error)?,
        ),
    };
    let n = rows.len() / (2 * dim);
    let (gathered, stats) = runner::run(py, progress, |monitor| {
        monitor.observing(|| {
            solved.scene.with_domain(|domain| {
                let placed = place_probes(domain, &probes, &settings, SOURCE)?;
                if placed.is_empty() {
                    return Ok((Vec::new(), Default::default()));
                }
                let emitters = Emitters::new(domain);
                let probes = (placed.as_slice(), &settings);
                gather_probes(domain, &solved.trained, &emitters, &solved.config, probes)
            })
        })
    })?
    .map_err(gcr_error)?;
    warn_all(py, &gather_warnings(&stats, &solved.config))?;
    let bands = columns(solved);
    let pick = |f: fn(&gcr::Gathered) -> [f64; 3]| -> Vec<f64> {
        gathered
            .iter()
            .flat_map(|g| f(g)[..bands].to_vec())
            .collect()
    };
    let values = PyArray1::from_vec(py, pick(|g| g.radiosity)).reshape(vec![n, bands])?;
    let errors = PyArray1::from_vec(py, pick(|g| g.std_error)).reshape(vec![n, bands])?;
    Ok((values, errors))
}

/// Flat numbers as rows of `K`.
fn fixed<const K: usize>(flat: &[f64]) -> Vec<[f64; K]> {
    (flat.chunks_exact(K))
        .map(|r| r.try_into().expect("chunks of K"))
        .collect()
}

/// The columns of the values: 3 (RGB), 1 for a grey Flatland scene (as the probe output).
fn columns(solved: &Solved) -> usize {
    let grey = solved.scene.dim() == 2 && solved.scene.with_domain(|d| d.bands()) == 1;
    if grey { 1 } else { 3 }
}

/// The rows `x y z nx ny nz` (Flatland `x y nx ny`) of two N × dim arrays, flat.
fn rows(
    points: &PyArrayLikeDyn<'_, f64, AllowTypeChange>,
    normals: &PyArrayLikeDyn<'_, f64, AllowTypeChange>,
    dim: usize,
) -> PyResult<Vec<f64>> {
    let (p, n) = (points.as_array(), normals.as_array());
    for (what, shape) in [("points", p.shape()), ("normals", n.shape())] {
        if shape.len() != 2 || shape[1] != dim {
            return Err(value_error(format!(
                "{what}: expected an N×{dim} array for a {dim}-D scene, got shape {shape:?}"
            )));
        }
    }
    if p.shape()[0] != n.shape()[0] {
        return Err(value_error(format!(
            "points and normals: {} points but {} normals",
            p.shape()[0],
            n.shape()[0]
        )));
    }
    let mut out = Vec::with_capacity(2 * p.len());
    for (pr, nr) in p.outer_iter().zip(n.outer_iter()) {
        out.extend(pr.iter().chain(nr.iter()));
    }
    Ok(out)
}
