//! Errors and warnings as Python sees them: what gcr reports (a scene that cannot be loaded or
//! lit, a setting out of range, an output that cannot be written) as [`GcrError`] with the
//! program's message (the error and its causes joined by `: `, as `gcr` prints them after
//! `error: `); arguments of the wrong shape or spelling as `ValueError`; warnings (the
//! program's `warning: …` lines) through Python's `warnings` as [`GcrWarning`].

use pyo3::exceptions::{PyException, PyUserWarning, PyValueError};
use pyo3::prelude::*;
use std::ffi::CString;

pyo3::create_exception!(
    gcr,
    GcrError,
    PyException,
    "An error gcr reports: a scene that cannot be loaded or lit, a setting out of range, an \
     output that cannot be written. The message is the program's (`gcr solve` prints it after \
     `error: `)."
);

pyo3::create_exception!(
    gcr,
    GcrWarning,
    PyUserWarning,
    "A warning gcr reports (the program prints it after `warning: `): a scene read with \
     something dropped, a target error not met, no light reaching the output points."
);

/// The program's message of `e` (the context, then each cause: [`gcr::error_message`]) as a
/// [`GcrError`].
pub(crate) fn gcr_error(e: impl Into<anyhow::Error>) -> PyErr {
    GcrError::new_err(gcr::error_message(e.into().as_ref()))
}

/// A `ValueError` for an argument that does not parse or has the wrong shape.
pub(crate) fn value_error(message: impl Into<String>) -> PyErr {
    PyValueError::new_err(message.into())
}

/// Issues each message as a [`GcrWarning`] at the caller's line.
pub(crate) fn warn_all<'a>(
    py: Python<'_>,
    messages: impl IntoIterator<Item = &'a String>,
) -> PyResult<()> {
    let category = py.get_type::<GcrWarning>();
    for m in messages {
        let text = CString::new(m.replace('\0', " ")).expect("NULs replaced");
        PyErr::warn(py, &category, &text, 1)?;
    }
    Ok(())
}
