//! The `gcr` Python package's extension module, `gcr._gcr` (built by maturin: `pyproject.toml`
//! beside this crate's `Cargo.toml`; the package's Python side is `python/gcr/`).
//!
//! It drives the library as the `gcr` program does, with one implementation of everything the
//! program decides: scenes load and light through `scene_sampler` (`scene`, `lights`:
//! `scene_sampler::LightOptions`), solves take the program's settings and defaults and train
//! the networks only when something reads them (`solve`: `gcr::SolveOptions`,
//! `gcr::solve_for_outputs`), B and irradiance at points go through the probes' own snapping
//! and gather (`points`), images and files through the output stage (`images`:
//! `gcr::output::render_linear`, `OutputPlan`, `write_outputs`). Long work runs with the GIL
//! released and reports progress to an optional callback (`runner`); errors carry the
//! program's messages (`errors`). `regressor` is the Rust side of the scikit-learn
//! estimator `gcr.isgcs.IsgcsRegressor`.

mod errors;
mod images;
mod lights;
mod points;
mod regressor;
mod runner;
mod scene;
mod solution;
mod solve;

use pyo3::prelude::*;

/// The compiled part of the ``gcr`` package; import ``gcr``, which re-exports it.
#[pymodule]
fn _gcr(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("GcrError", py.get_type::<errors::GcrError>())?;
    m.add("GcrWarning", py.get_type::<errors::GcrWarning>())?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_class::<scene::Scene>()?;
    m.add_class::<solve::Solution>()?;
    m.add_class::<regressor::IsgcsModel>()?;
    m.add_function(wrap_pyfunction!(solve::solve, m)?)?;
    m.add_function(wrap_pyfunction!(scene::builtin_scenes, m)?)?;
    Ok(())
}
