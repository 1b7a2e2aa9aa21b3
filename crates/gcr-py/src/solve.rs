//! `gcr.solve`: the program's solve (`gcr solve`'s settings and defaults, through
//! [`gcr::SolveOptions`]) with the networks trained only when something reads them
//! ([`gcr::solve_for_outputs`]), giving a [`Solution`].

use crate::errors::{gcr_error, value_error, warn_all};
use crate::runner;
use crate::scene::{Loaded, Scene};
use gcr::{SolveConfig, SolveOptions, Trained};
use pyo3::prelude::*;
use std::sync::Arc;
use std::time::Instant;

/// A solved scene: B anywhere on its surfaces, irradiance anywhere, images and bakes.
/// Immutable; its methods can run from several threads at once.
#[pyclass(module = "gcr", frozen)]
pub struct Solution {
    pub(crate) inner: Arc<Solved>,
}

/// What a solution holds.
pub(crate) struct Solved {
    pub scene: Arc<Loaded>,
    pub options: SolveOptions,
    pub config: SolveConfig,
    pub trained: Trained,
    /// When the solve started: the metrics' total time counts from here.
    pub started: Instant,
}

/// Solves ``scene`` with the program's settings and defaults (``gcr solve SCENE`` with the
/// options of the same names; ``gcr solve --help`` explains them).
///
/// ``quality``: ``"draft"``, ``"good"`` (the default) or ``"final"``, the estimated relative
/// error (5 / 2 / 1 %) the default paths gather runs to; or ``target_error`` as a fraction (not
/// both). ``seed`` seeds every random choice (the same seed gives the same numbers as the
/// program). The research options (``cells``, ``shading_cells``, ``time_budget``, ``gather``,
/// ``output_fit``, ``network_target``, ``gather_rays``, ``corrections``, ``share_paths``,
/// ``guiding`` (``"auto"``, ``"on"`` or ``"off"``), ``block_points`` (``--block-points``), ``keep_base``, ``keep_networks``, ``kernel_facing``, ``cluster_min_elements``,
/// ``cluster_theta``) are the program's; ``None`` is its default. The networks are trained
/// only when the gather reads them or ``keep_networks`` is set (the default gather reads none).
///
/// ``progress``: a callable given a dict per progress event (at most ten a second, on this
/// thread; see the package docs); an exception it raises stops the solve and is raised here.
/// The GIL is released while the solve runs. Raises :class:`gcr.GcrError` with the program's
/// message for a setting out of range or a scene that cannot be solved, ``ValueError`` for an
/// option that does not parse.
#[pyfunction]
#[pyo3(signature = (
    scene, *, quality=None, target_error=None, seed=None, cells=None, shading_cells=None,
    time_budget=None, gather=None, output_fit=None, network_target=None, gather_rays=None,
    corrections=None, share_paths=None, guiding=None, block_points=None, keep_base=false,
    keep_networks=false,
    kernel_facing=false, cluster_min_elements=None, cluster_theta=None, progress=None
))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn solve<'py>(
    py: Python<'py>,
    scene: &Scene,
    quality: Option<&str>,
    target_error: Option<f64>,
    seed: Option<u64>,
    cells: Option<usize>,
    shading_cells: Option<usize>,
    time_budget: Option<f64>,
    gather: Option<&str>,
    output_fit: Option<&str>,
    network_target: Option<&str>,
    gather_rays: Option<usize>,
    corrections: Option<usize>,
    share_paths: Option<usize>,
    guiding: Option<&str>,
    block_points: Option<usize>,
    keep_base: bool,
    keep_networks: bool,
    kernel_facing: bool,
    cluster_min_elements: Option<usize>,
    cluster_theta: Option<f64>,
    progress: Option<Bound<'py, PyAny>>,
) -> PyResult<Solution> {
    if quality.is_some() && target_error.is_some() {
        return Err(value_error(
            "quality and target_error cannot be used together: give one",
        ));
    }
    let defaults = SolveOptions::default();
    let options = SolveOptions {
        quality: quality.map(choice).transpose()?,
        target_error,
        seed: seed.unwrap_or(defaults.seed),
        cells: cells.unwrap_or(defaults.cells),
        shading_cells,
        time_budget,
        gather: gather.map_or(Ok(defaults.gather), choice)?,
        output_fit: output_fit.map_or(Ok(defaults.output_fit), choice)?,
        network_target: network_target.map_or(Ok(defaults.network_target), choice)?,
        gather_rays,
        corrections,
        share_paths: share_paths.unwrap_or(defaults.share_paths),
        guiding: guiding.map_or(Ok(defaults.guiding), choice)?,
        block_points: block_points.unwrap_or(defaults.block_points),
        shard: None,
        keep_base,
        keep_networks,
        kernel_facing,
        surface_clusters: gcr::SurfaceClusters {
            min_elements: (cluster_min_elements).unwrap_or(defaults.surface_clusters.min_elements),
            theta: cluster_theta.unwrap_or(defaults.surface_clusters.theta),
        },
    };
    if options.block_points == 0 {
        return Err(value_error("block_points 0: at least 1"));
    }
    if !(1..=64).contains(&options.share_paths) {
        return Err(value_error(format!(
            "share_paths {} is not in 1..=64",
            options.share_paths
        )));
    }
    solve_with(py, &scene.inner, options, progress.as_ref())
}

/// A setting's name parsed as the program parses it (its message on failure).
fn choice<T: std::str::FromStr<Err: std::fmt::Display>>(s: &str) -> PyResult<T> {
    s.parse().map_err(|e: T::Err| value_error(e.to_string()))
}

/// The solve proper, with the GIL released; the solve's warnings issued as `GcrWarning`.
fn solve_with(
    py: Python<'_>,
    scene: &Arc<Loaded>,
    options: SolveOptions,
    progress: Option<&Bound<'_, PyAny>>,
) -> PyResult<Solution> {
    let started = Instant::now();
    let config = options.config();
    let trained = runner::run(py, progress, |monitor| {
        scene.with_domain(|domain| {
            let mut observer = monitor.solve_observer();
            gcr::solve_for_outputs(domain, &options, &config, false, &mut observer)
        })
    })?
    .map_err(gcr_error)?;
    warn_all(py, &trained.metrics.warnings)?;
    let solved = Solved {
        scene: Arc::clone(scene),
        options,
        config,
        trained,
        started,
    };
    Ok(Solution {
        inner: Arc::new(solved),
    })
}
