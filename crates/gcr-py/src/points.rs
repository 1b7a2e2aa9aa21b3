//! B, irradiance and daylight factors at a caller's points, as the program's probe output gets
//! them: the rows checked as a probe file's lines ([`scene_sampler::probes_from_rows`]), radiosity
//! probes snapped onto the surfaces ([`gcr::output::place_probes`], `crates/gcr/src/output/
//! probes.rs`), the values gathered together ([`gcr::output::gather_probes`]: neighbouring points
//! share paths, the rounds run until the points' estimated error meets the target). The same
//! points as a probe file's, in the same order, give the program's numbers exactly.

use crate::errors::{gcr_error, value_error, warn_all};
use crate::runner;
use crate::solve::Solved;
use gcr::output::{
    ProbePoints, ProbeQuantity, ProbeSettings, gather_probe_shard, gather_warnings, place_probes,
};
use gcr::{Emitters, Shard};
use numpy::{
    AllowTypeChange, PyArray1, PyArrayDyn, PyArrayLikeDyn, PyArrayMethods, PyUntypedArrayMethods,
};
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
    let (gathered, _) = gathered(py, solved, (&points, &normals), settings, None, progress)?;
    let all: Vec<usize> = (0..gathered.len()).collect();
    arrays(py, solved, &gathered, &all)
}

/// The values of shard `shard` of `points` with `normals`: the rows' indices (ascending), their
/// values and standard errors, each exactly as [`at_points`] gives them for those rows when the
/// solve has the same `block_points` (`gcr solve --shard`; `estimator/blocks.rs`).
pub(crate) fn shard_at_points<'py>(
    py: Python<'py>,
    solved: &Arc<Solved>,
    (points, normals): (
        PyArrayLikeDyn<'py, f64, AllowTypeChange>,
        PyArrayLikeDyn<'py, f64, AllowTypeChange>,
    ),
    settings: ProbeSettings,
    shard: Shard,
    progress: Option<&Bound<'py, PyAny>>,
) -> PyResult<(Bound<'py, PyArray1<usize>>, Values<'py>)> {
    let (gathered, mine) = gathered(
        py,
        solved,
        (&points, &normals),
        settings,
        Some(shard),
        progress,
    )?;
    let values = arrays(py, solved, &gathered, &mine)?;
    Ok((PyArray1::from_vec(py, mine), values))
}

/// The gather at the rows of `points` and `normals`, as the probe output gets it (with `shard`:
/// only its points, whose indices come second; else every index).
fn gathered<'py>(
    py: Python<'py>,
    solved: &Arc<Solved>,
    (points, normals): (
        &PyArrayLikeDyn<'py, f64, AllowTypeChange>,
        &PyArrayLikeDyn<'py, f64, AllowTypeChange>,
    ),
    settings: ProbeSettings,
    shard: Option<Shard>,
    progress: Option<&Bound<'py, PyAny>>,
) -> PyResult<(Vec<gcr::Gathered>, Vec<usize>)> {
    settings.validate().map_err(gcr_error)?;
    let dim = solved.scene.dim();
    let rows = rows(points, normals, dim)?;
    let probes = match dim {
        3 => ProbePoints::ThreeD(
            scene_sampler::probes_from_rows(SOURCE, &fixed::<6>(&rows)).map_err(gcr_error)?,
        ),
        _ => ProbePoints::Flat(
            scene_sampler::flat_probes_from_rows(SOURCE, &fixed::<4>(&rows)).map_err(gcr_error)?,
        ),
    };
    let mut config = solved.config.clone();
    config.paths.shard = shard;
    let (gathered, stats, mine) = runner::run(py, progress, |monitor| {
        monitor.observing(|| {
            solved.scene.with_domain(|domain| {
                let placed = place_probes(domain, &probes, &settings, SOURCE)?;
                if placed.is_empty() {
                    return Ok((Vec::new(), Default::default(), Vec::new()));
                }
                let emitters = Emitters::new(domain);
                let probes = (placed.as_slice(), &settings);
                gather_probe_shard(domain, &solved.trained, &emitters, &config, probes)
            })
        })
    })?
    .map_err(gcr_error)?;
    warn_all(py, &gather_warnings(&stats, &config))?;
    Ok((gathered, mine))
}

/// The values and standard errors of the points `rows` of `gathered` as numpy arrays (one row
/// per index, the scene's bands wide).
fn arrays<'py>(
    py: Python<'py>,
    solved: &Solved,
    gathered: &[gcr::Gathered],
    rows: &[usize],
) -> PyResult<Values<'py>> {
    let bands = columns(solved);
    let pick = |f: fn(&gcr::Gathered) -> [f64; 3]| -> Vec<f64> {
        (rows.iter())
            .flat_map(|&i| f(&gathered[i])[..bands].to_vec())
            .collect()
    };
    let n = rows.len();
    let values = PyArray1::from_vec(py, pick(|g| g.radiosity)).reshape(vec![n, bands])?;
    let errors = PyArray1::from_vec(py, pick(|g| g.std_error)).reshape(vec![n, bands])?;
    Ok((values, errors))
}

/// The numbers of `a` as an owned array. numpy arrays may sit at unaligned addresses (Dask and
/// pickle hand them out of message buffers), where viewing them panics: those are copied by
/// numpy first.
fn aligned(a: &PyArrayLikeDyn<'_, f64, AllowTypeChange>) -> PyResult<numpy::ndarray::ArrayD<f64>> {
    if a.is_aligned() {
        return Ok(a.as_array().to_owned());
    }
    let copy = a.as_any().call_method0("copy")?;
    let copy: numpy::PyReadonlyArrayDyn<'_, f64> = copy.extract()?;
    Ok(copy.as_array().to_owned())
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
    let (p, n) = (aligned(points)?, aligned(normals)?);
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
