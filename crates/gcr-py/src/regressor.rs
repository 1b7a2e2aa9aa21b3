//! The Rust side of `gcr.isgcs.IsgcsRegressor`: [`isgcs::regressor::Regressor`] fitted and evaluated on
//! NumPy arrays with the GIL released, and its state as text for pickling (exact: every float
//! kept as its bits).

use crate::errors::{gcr_error, value_error};
use crate::runner;
use numpy::{AllowTypeChange, PyArray1, PyArrayDyn, PyArrayLikeDyn, PyArrayMethods};
use pyo3::prelude::*;
use serde_json::{Map, Number, Value};
use std::sync::Arc;

/// An array-like of float64 numbers.
type Numbers<'py> = PyArrayLikeDyn<'py, f64, AllowTypeChange>;

/// A fitted ISGCS regressor (the Rust model behind ``gcr.isgcs.IsgcsRegressor``; use that).
#[pyclass(module = "gcr._gcr", frozen)]
pub struct IsgcsModel {
    model: Arc<isgcs::regressor::Regressor>,
}

#[pymethods]
impl IsgcsModel {
    /// Fits ``x`` (N × n) to ``y`` (N × m) with the hyperparameters ``params`` (the JSON of
    /// ``isgcs::regressor::RegressorParams``: every field). Raises ``ValueError`` with the library's
    /// message for data or parameters it refuses.
    #[staticmethod]
    fn fit(py: Python<'_>, x: Numbers<'_>, y: Numbers<'_>, params: &str) -> PyResult<Self> {
        let params: isgcs::regressor::RegressorParams =
            serde_json::from_str(params).map_err(|e| value_error(format!("params: {e}")))?;
        let (xs, n) = matrix(&x, "x")?;
        let (ys, m) = matrix(&y, "y")?;
        let model = runner::run(py, None, |_| {
            isgcs::regressor::Regressor::fit(&params, &xs, &ys, n, m)
        })?
        .map_err(|e| value_error(e.to_string()))?;
        Ok(Self {
            model: Arc::new(model),
        })
    }

    /// Predictions for ``x`` (N × n): N × m float64.
    fn predict<'py>(
        &self,
        py: Python<'py>,
        x: Numbers<'py>,
    ) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
        let (xs, n) = matrix(&x, "x")?;
        if n != self.model.input_dim() {
            return Err(value_error(format!(
                "x has {n} features, but the model was fitted on {}",
                self.model.input_dim()
            )));
        }
        let (rows, m) = (xs.len() / n.max(1), self.model.output_dim());
        let model = Arc::clone(&self.model);
        let out = runner::run(py, None, move |_| {
            let mut out = vec![0.0; rows * m];
            model.predict(&xs, &mut out).map(|()| out)
        })?
        .map_err(|e| value_error(e.to_string()))?;
        PyArray1::from_vec(py, out).reshape(vec![rows, m])
    }

    /// Input dimension n.
    #[getter]
    fn input_dim(&self) -> usize {
        self.model.input_dim()
    }

    /// Output dimension m.
    #[getter]
    fn output_dim(&self) -> usize {
        self.model.output_dim()
    }

    /// Cells (Gaussians) of the fitted network.
    #[getter]
    fn cells(&self) -> usize {
        self.model.len()
    }

    /// What the fit chose (``isgcs::RegressorReport``) as JSON.
    #[getter]
    fn report(&self) -> PyResult<String> {
        serde_json::to_string(self.model.report()).map_err(gcr_error)
    }

    /// The model as text (JSON with every float as its bits), for pickling:
    /// :meth:`from_state` gives it back exactly.
    fn state(&self) -> PyResult<String> {
        let value = serde_json::to_value(&*self.model).map_err(gcr_error)?;
        Ok(encode(value).to_string())
    }

    /// The model of :meth:`state`'s text.
    #[staticmethod]
    fn from_state(state: &str) -> PyResult<Self> {
        let value: Value =
            serde_json::from_str(state).map_err(|e| value_error(format!("state: {e}")))?;
        let model = serde_json::from_value(decode(value))
            .map_err(|e| value_error(format!("state: {e}")))?;
        Ok(Self {
            model: Arc::new(model),
        })
    }
}

/// A 2-D array's numbers row-major and its column count.
fn matrix(a: &Numbers<'_>, what: &str) -> PyResult<(Vec<f64>, usize)> {
    let v = a.as_array();
    match v.shape() {
        [_, cols] => Ok((v.iter().copied().collect(), *cols)),
        shape => Err(value_error(format!(
            "{what}: expected a 2-D array, got shape {shape:?}"
        ))),
    }
}

/// The key of an encoded float.
const BITS: &str = "$f64";

/// `value` with every float replaced by `{"$f64": "<bits in hex>"}` (JSON text then keeps it
/// exactly).
fn encode(value: Value) -> Value {
    match value {
        Value::Number(n) if n.is_f64() => {
            let bits = n.as_f64().unwrap_or(f64::NAN).to_bits();
            Value::Object(Map::from_iter([(
                BITS.to_string(),
                Value::String(format!("{bits:016x}")),
            )]))
        }
        Value::Array(a) => Value::Array(a.into_iter().map(encode).collect()),
        Value::Object(o) => Value::Object(o.into_iter().map(|(k, v)| (k, encode(v))).collect()),
        other => other,
    }
}

/// The inverse of [`encode`].
fn decode(value: Value) -> Value {
    match value {
        Value::Object(o) if o.len() == 1 && o.contains_key(BITS) => {
            let bits = o[BITS]
                .as_str()
                .and_then(|s| u64::from_str_radix(s, 16).ok());
            (bits.map(f64::from_bits))
                .and_then(Number::from_f64)
                .map_or(Value::Null, Value::Number)
        }
        Value::Array(a) => Value::Array(a.into_iter().map(decode).collect()),
        Value::Object(o) => Value::Object(o.into_iter().map(|(k, v)| (k, decode(v))).collect()),
        other => other,
    }
}
