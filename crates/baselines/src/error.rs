//! Errors of the reference solvers: bad parameters and bad input points give these, never a panic.

use thiserror::Error;

/// What can go wrong when a reference solver is asked to run.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum BaselineError {
    /// A numeric parameter is out of its allowed range (the message says which range).
    #[error("invalid parameter `{name}` = {value}: {expected}")]
    InvalidParameter {
        /// Parameter name as in the API.
        name: &'static str,
        /// The value given.
        value: f64,
        /// What was expected.
        expected: &'static str,
    },
    /// An input point refers to a face or segment the scene does not have.
    #[error("point {index} refers to {what} {id}, but the scene has {count}")]
    NoSuchElement {
        /// Index of the point in the input slice.
        index: usize,
        /// "face" or "segment".
        what: &'static str,
        /// The id given.
        id: u32,
        /// How many the scene has.
        count: usize,
    },
    /// A mesh would have more elements than the solver accepts (dense row storage would not fit).
    #[error(
        "the mesh would have {elements} elements, more than the limit {limit}; use a larger element size"
    )]
    TooManyElements {
        /// Elements the requested size gives.
        elements: usize,
        /// The limit.
        limit: usize,
    },
    /// An iterative solver did not converge.
    #[error("no convergence after {iterations} iterations (last change {change})")]
    NotConverged {
        /// Iterations run.
        iterations: usize,
        /// The last change (solver-specific measure).
        change: f64,
    },
}

/// Checks `lo < value < hi` (open interval; pass infinities for one-sided) and that `value` is finite.
pub(crate) fn check_range(
    name: &'static str,
    value: f64,
    lo: f64,
    hi: f64,
    expected: &'static str,
) -> Result<(), BaselineError> {
    if value.is_finite() && value > lo && value < hi {
        Ok(())
    } else {
        Err(BaselineError::InvalidParameter {
            name,
            value,
            expected,
        })
    }
}
