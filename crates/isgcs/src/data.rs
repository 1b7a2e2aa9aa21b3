//! The training data checks and the error type shared by [`crate::regressor::Regressor`] and
//! [`crate::rbf::KMeansRbf`].

use crate::IsgcsError;

/// Everything that can go wrong in [`crate::regressor::Regressor`] and [`crate::rbf::KMeansRbf`] (fit and predict).
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum RegressorError {
    /// Inputs or outputs of the wrong length, or no rows.
    #[error("shape: {0}")]
    Shape(String),
    /// A NaN or infinite value in the training data.
    #[error("non-finite value {value} in the {what} at row {row}, column {column}")]
    NonFinite {
        /// `"inputs"` or `"targets"`.
        what: &'static str,
        /// Row of the value.
        row: usize,
        /// Column of the value.
        column: usize,
        /// The value.
        value: f64,
    },
    /// A hyperparameter out of range (the message names it).
    #[error("invalid parameter: {0}")]
    InvalidParams(String),
    /// The cell budget is below the k + 1 cells of the initial simplex or above the rows.
    #[error("cell budget {cells} is outside {min} (k + 1) … {max} (the number of rows)")]
    CellBudget {
        /// The requested budget.
        cells: usize,
        /// k + 1.
        min: usize,
        /// The number of rows.
        max: usize,
    },
    /// The network rejected its parameters.
    #[error(transparent)]
    Network(#[from] IsgcsError),
    /// The least-squares output layer could not be solved (a fixed ridge too small for the
    /// factorisation, or no row activates any cell).
    #[error("the output layer could not be fitted: {0}")]
    Solve(String),
}

/// Checks N × n inputs and N × m targets; returns N.
pub(crate) fn check_data(
    inputs: &[f64],
    targets: &[f64],
    n: usize,
    m: usize,
) -> Result<usize, RegressorError> {
    if n == 0 || m == 0 {
        return Err(RegressorError::Shape(format!(
            "n = {n} inputs and m = {m} outputs must be at least 1"
        )));
    }
    if inputs.is_empty() || inputs.len() % n != 0 {
        return Err(RegressorError::Shape(format!(
            "{} input numbers are not N × {n} with N ≥ 1",
            inputs.len()
        )));
    }
    let rows = inputs.len() / n;
    if targets.len() != rows * m {
        return Err(RegressorError::Shape(format!(
            "{rows} input rows need {} target numbers (× {m}), got {}",
            rows * m,
            targets.len()
        )));
    }
    for (what, data, d) in [("inputs", inputs, n), ("targets", targets, m)] {
        if let Some(i) = data.iter().position(|v| !v.is_finite()) {
            return Err(RegressorError::NonFinite {
                what,
                row: i / d,
                column: i % d,
                value: data[i],
            });
        }
    }
    Ok(rows)
}
