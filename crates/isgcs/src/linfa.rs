//! [linfa](https://crates.io/crates/linfa) integration (cargo feature `linfa`): the network as a
//! regressor behind linfa's `Fit` and `PredictInplace` traits.
//!
//! Following linfa's conventions, [`IsgcsRegressorParams`] holds unchecked hyperparameters and
//! implements [`ParamGuard`]; its checked form [`IsgcsRegressorValidParams`] implements
//! [`Fit`] for any `ndarray` record matrix (N × n, `f64`) with single-output (`Array1`, N) or
//! multi-output (`Array2`, N × m, one column per output) targets, and returns an
//! [`IsgcsRegressor`]. The fitted model implements [`PredictInplace`] (hence linfa's `predict`)
//! with the same target shape it was trained on, using the network's parallel
//! [`Isgcs::predict_batch`].
//!
//! ```
//! use isgcs::linfa::IsgcsRegressor;
//! use linfa::prelude::*;
//! use ndarray::{Array1, Array2};
//!
//! // y = x₀ + 2 x₁ on 400 scattered points of the unit square.
//! let x = Array2::from_shape_fn((400, 2), |(i, j)| {
//!     ((i as f64 + 1.0) * [0.754_877_666, 0.569_840_291][j]).fract()
//! });
//! let y: Array1<f64> = x.rows().into_iter().map(|r| r[0] + 2.0 * r[1]).collect();
//! let data = Dataset::new(x, y);
//! let model = IsgcsRegressor::params().max_cells(30).seed(7).fit(&data)?;
//! let prediction = model.predict(&data); // Array1, like the targets
//! assert!(prediction.mean_squared_error(&data)?.sqrt() < 0.05);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! # Training
//!
//! By default `fit` runs the chosen-from-data pipeline of [`crate::regressor`]: inputs and
//! outputs standardized, k and the initial simplex from a principal component analysis,
//! growth in rounds that insert where the least-squares residual is largest, and an output
//! layer whose basis, width multiplier and ridge minimise the error on held-out rows (the exact
//! leave-one-out error below 1000 rows). Only `max_cells`
//! and `seed` need setting; `ridge` and `width_multiplier` fix what is otherwise chosen.
//!
//! Setting [`IsgcsRegressorParams::network_params`] or
//! [`IsgcsRegressorParams::least_squares`] selects the native pipeline instead, three phases
//! on the raw data:
//!
//! 1. **Growth**: [`Isgcs::fit`] on a [`DatasetGoal`] (uniformly random rows of the dataset,
//!    seeded) until the cell budget is reached, or earlier by the optional step budget or
//!    target error (the RMS error of a block of λ steps, see [`Termination`]).
//! 2. **Settling**: insertion off, [`Isgcs::train`] for `settle` × the growth steps more (⅓ by
//!    default, as in the `franke` example and docs/design/isgcs.md's measurements).
//! 3. **Least squares** (unless `None`): [`Isgcs::fit_outputs`] on every row of the
//!    dataset, with the fixed relative ridge given.
//!
//! [`Params::thesis`] with `least_squares(None)` gives the dissertation's delta-rule network.
//!
//! The native pipeline's network starts from one k-simplex at the records' mean: vertex 0 is the mean, vertex i
//! (1 ≤ i ≤ k) is the mean moved by one standard deviation of feature i − 1 along that feature
//! (features without spread use the largest standard deviation, or 1).
//!
//! A dataset can only be evaluated at its records. Growth only asks for sampled rows, but a
//! caller driving [`Isgcs::fit`] or the resampling of sec. 2.5 ([`Isgcs::resample_positions`])
//! with a [`DatasetGoal`] may ask for the value at a new position: the goal then answers with
//! the target of the nearest record (Euclidean; the first of equally near ones), i.e. the
//! nearest-neighbour interpolant of the data, the only value the dataset itself supports.

use crate::regressor::{Regressor, RegressorError, RegressorParams};
use crate::{GoalFunction, Isgcs, IsgcsError, Params, Stopped, Termination};
use ::linfa::dataset::{AsTargets, DatasetBase, TargetDim};
use ::linfa::param_guard::ParamGuard;
use ::linfa::traits::{Fit, PredictInplace};
use ndarray::{Array1, Array2, ArrayBase, ArrayView2, ArrayViewMut2, Data, Ix1, Ix2};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::marker::PhantomData;
use std::ops::ControlFlow;

/// Everything that can go wrong when fitting through linfa.
#[derive(Debug, thiserror::Error)]
pub enum IsgcsRegressorError {
    /// The dataset has no rows.
    #[error("empty dataset: no records to fit")]
    EmptyDataset,
    /// The records have no columns.
    #[error("the records have no features (n = 0)")]
    NoFeatures,
    /// The targets have no columns.
    #[error("the targets have no outputs (m = 0)")]
    NoOutputs,
    /// Records and targets disagree in their number of rows, or prediction inputs have the
    /// wrong number of features.
    #[error("shape mismatch: {0}")]
    ShapeMismatch(String),
    /// A NaN or infinite value in the data.
    #[error("non-finite value {value} in the {what} at row {row}, column {column}")]
    NonFinite {
        /// `"records"` or `"targets"`.
        what: &'static str,
        /// Row of the value.
        row: usize,
        /// Column of the value.
        column: usize,
        /// The value itself.
        value: f64,
    },
    /// The topology dimension k exceeds the input dimension n.
    #[error("topology dimension k = {k} exceeds the number of features n = {n}")]
    TopologyDim {
        /// The requested k.
        k: usize,
        /// The input dimension.
        n: usize,
    },
    /// The cell budget is below the k + 1 cells of the initial simplex (0 included).
    #[error("cell budget {cells} is below the initial simplex's k + 1 = {min} cells")]
    CellBudget {
        /// The requested budget.
        cells: usize,
        /// k + 1.
        min: usize,
    },
    /// A hyperparameter out of range (the message names it).
    #[error("invalid parameter: {0}")]
    InvalidParams(String),
    /// The network rejected its parameters or the least-squares polish failed.
    #[error(transparent)]
    Network(#[from] IsgcsError),
    /// The default pipeline failed (its message says why).
    #[error(transparent)]
    Regressor(#[from] RegressorError),
    /// An error reported by linfa.
    #[error(transparent)]
    Linfa(#[from] ::linfa::Error),
}

/// Checked hyperparameters of [`IsgcsRegressor`]; obtained from [`IsgcsRegressorParams`] by
/// [`ParamGuard::check`], and what [`Fit`] is implemented for.
#[derive(Clone, Debug, PartialEq)]
pub struct IsgcsRegressorValidParams {
    network: Params,
    topology_dim: Option<usize>,
    max_cells: usize,
    max_steps: Option<u64>,
    target_error: Option<f64>,
    settle: f64,
    least_squares: Option<f64>,
    /// The chosen-from-data pipeline of [`crate::regressor`] (the default); `false` after
    /// [`IsgcsRegressorParams::least_squares`] or [`IsgcsRegressorParams::network_params`].
    auto: bool,
    ridge: Option<f64>,
    width_multiplier: Option<f64>,
    seed: u64,
}

impl IsgcsRegressorValidParams {
    /// The network's training parameters.
    pub fn network_params(&self) -> &Params {
        &self.network
    }
    /// The topology dimension k, if set (otherwise min(n, 2) for n features).
    pub fn topology_dim(&self) -> Option<usize> {
        self.topology_dim
    }
    /// The cell budget of the growth phase.
    pub fn max_cells(&self) -> usize {
        self.max_cells
    }
    /// The step budget of the growth phase, if any.
    pub fn max_steps(&self) -> Option<u64> {
        self.max_steps
    }
    /// The target block RMS error ending the growth phase, if any.
    pub fn target_error(&self) -> Option<f64> {
        self.target_error
    }
    /// Length of the settling phase as a multiple of the growth steps.
    pub fn settle(&self) -> f64 {
        self.settle
    }
    /// The relative ridge of the least-squares polish of the native pipeline, `None` when it is
    /// off (only used when [`IsgcsRegressorValidParams::is_auto`] is false).
    pub fn least_squares(&self) -> Option<f64> {
        self.least_squares
    }
    /// Whether the default, chosen-from-data pipeline ([`crate::regressor`]) is used.
    pub fn is_auto(&self) -> bool {
        self.auto
    }
    /// The fixed relative ridge of the default pipeline, `None` when chosen from the data.
    pub fn ridge(&self) -> Option<f64> {
        self.ridge
    }
    /// The fixed width multiplier of the default pipeline, `None` when chosen from the data.
    pub fn width_multiplier(&self) -> Option<f64> {
        self.width_multiplier
    }
    /// The seed of the row sampling.
    pub fn seed(&self) -> u64 {
        self.seed
    }
}

/// Unchecked hyperparameters of [`IsgcsRegressor`] (builder; linfa's `ParamGuard` checks them,
/// and `fit` on these checks before fitting).
#[derive(Clone, Debug, PartialEq)]
pub struct IsgcsRegressorParams(IsgcsRegressorValidParams);

impl Default for IsgcsRegressorParams {
    fn default() -> Self {
        Self(IsgcsRegressorValidParams {
            network: Params::accurate(),
            topology_dim: None,
            max_cells: 100,
            max_steps: None,
            target_error: None,
            settle: 1.0 / 3.0,
            least_squares: Some(1e-9),
            auto: true,
            ridge: None,
            width_multiplier: None,
            seed: 0,
        })
    }
}

impl IsgcsRegressorParams {
    /// The defaults: the chosen-from-data pipeline of [`crate::regressor`] (standardized
    /// inputs and outputs, k and the start simplex from a principal component analysis,
    /// growth by least-squares residuals, width multiplier and ridge on held-out rows),
    /// 100 cells, seed 0.
    pub fn new() -> Self {
        Self::default()
    }
    /// The network's training parameters for the native pipeline ([`Params::accurate`] by
    /// default; [`Params::thesis`] for the dissertation's defaults, usually with
    /// `least_squares(None)`). Switches to the native pipeline (module docs): `Isgcs::fit` on
    /// the raw data, settling, optional least-squares polish with a fixed ridge.
    pub fn network_params(mut self, params: Params) -> Self {
        self.0.network = params;
        self.0.auto = false;
        self
    }
    /// Fixed relative ridge of the default pipeline's output layer instead of the selection on
    /// held-out rows (`None`, the default: chosen from the data).
    /// A fixed ridge is used as given: one below the rounding level of AᵀA fails to factorise
    /// (an error naming the ridge).
    pub fn ridge(mut self, ridge: Option<f64>) -> Self {
        self.0.ridge = ridge;
        self
    }
    /// Fixed width multiplier of the default pipeline's output layer instead of the selection
    /// on held-out rows (`None`, the default: chosen from the data).
    pub fn width_multiplier(mut self, multiplier: Option<f64>) -> Self {
        self.0.width_multiplier = multiplier;
        self
    }
    /// The topology dimension k of the simplicial complex (1 ≤ k ≤ n; default: from the data
    /// in the default pipeline, min(n, 2) in the native one).
    pub fn topology_dim(mut self, k: usize) -> Self {
        self.0.topology_dim = Some(k);
        self
    }
    /// Grow until the network has this many cells (at least k + 1; default 100).
    pub fn max_cells(mut self, cells: usize) -> Self {
        self.0.max_cells = cells;
        self
    }
    /// Also end growth after this many training steps (required with deletion, `kappa > 0`,
    /// which may keep the network below its cell budget). `Some` selects the native pipeline.
    pub fn max_steps(mut self, steps: Option<u64>) -> Self {
        self.0.max_steps = steps;
        self.0.auto &= steps.is_none();
        self
    }
    /// Also end growth once a block of λ steps has an RMS output error of at most this
    /// (measured on each sample before the network adapts to it). `Some` selects the native
    /// pipeline.
    pub fn target_error(mut self, error: Option<f64>) -> Self {
        self.0.target_error = error;
        self.0.auto &= error.is_none();
        self
    }
    /// Steps of the settling phase (insertion off) as a multiple of the growth steps (≥ 0;
    /// default ⅓).
    pub fn settle(mut self, fraction: f64) -> Self {
        self.0.settle = fraction;
        self
    }
    /// Switches to the native pipeline with the least-squares polish of the output layer
    /// ([`Isgcs::fit_outputs`]) at this fixed relative ridge, or `None` for the delta rule
    /// alone (the native pipeline's default is `Some(1e-9)`, which can overfit noisy data:
    /// prefer the default pipeline).
    pub fn least_squares(mut self, ridge: Option<f64>) -> Self {
        self.0.least_squares = ridge;
        self.0.auto = false;
        self
    }
    /// Seed of the random row sampling (default 0); equal seeds give equal models.
    pub fn seed(mut self, seed: u64) -> Self {
        self.0.seed = seed;
        self
    }
}

impl ParamGuard for IsgcsRegressorParams {
    type Checked = IsgcsRegressorValidParams;
    type Error = IsgcsRegressorError;

    fn check_ref(&self) -> Result<&Self::Checked, Self::Error> {
        let p = &self.0;
        let invalid = |s: String| Err(IsgcsRegressorError::InvalidParams(s));
        if p.topology_dim == Some(0) {
            return invalid("topology_dim must be at least 1".into());
        }
        let min = p.topology_dim.unwrap_or(1) + 1;
        if p.max_cells < min {
            return Err(IsgcsRegressorError::CellBudget {
                cells: p.max_cells,
                min,
            });
        }
        if p.max_steps == Some(0) {
            return invalid("max_steps must be at least 1".into());
        }
        if p.target_error.is_some_and(|t| !(t.is_finite() && t >= 0.0)) {
            return invalid(format!(
                "target_error {:?} must be finite and >= 0",
                p.target_error
            ));
        }
        if !(p.settle.is_finite() && p.settle >= 0.0) {
            return invalid(format!("settle {} must be finite and >= 0", p.settle));
        }
        if p.least_squares
            .is_some_and(|r| !(r.is_finite() && r >= 0.0))
        {
            return invalid(format!(
                "least_squares ridge {:?} must be finite and >= 0",
                p.least_squares
            ));
        }
        if p.ridge.is_some_and(|r| !(r.is_finite() && r >= 0.0)) {
            return invalid(format!("ridge {:?} must be finite and >= 0", p.ridge));
        }
        if p.width_multiplier
            .is_some_and(|w| !(w.is_finite() && w > 0.0))
        {
            return invalid(format!(
                "width_multiplier {:?} must be finite and > 0",
                p.width_multiplier
            ));
        }
        if p.network.kappa > 0 && p.max_steps.is_none() {
            return invalid(
                "deletion (kappa > 0) may keep the network below its cell budget: \
                 set max_steps"
                    .into(),
            );
        }
        // The network's own range checks, on a throwaway 1-D network.
        Isgcs::new(p.network, 1, 1, 1, vec![vec![0.0], vec![1.0]])?;
        Ok(p)
    }

    fn check(self) -> Result<Self::Checked, Self::Error> {
        self.check_ref()?;
        Ok(self.0)
    }
}

/// A [`GoalFunction`] backed by a dataset: `sample` draws a uniformly random row (seeded),
/// `evaluate` returns that row's target, or for any other position the target of the nearest
/// record (module docs).
#[derive(Clone, Debug)]
pub struct DatasetGoal {
    records: Vec<f64>,
    targets: Vec<f64>,
    n: usize,
    m: usize,
    rng: ChaCha8Rng,
    last: Option<usize>,
}

impl DatasetGoal {
    /// A goal on N records (N × n) and their targets (N × m), copied; errors for an empty
    /// dataset, no features or outputs, differing row counts and non-finite values.
    pub fn new(
        records: ArrayView2<'_, f64>,
        targets: ArrayView2<'_, f64>,
        seed: u64,
    ) -> Result<Self, IsgcsRegressorError> {
        validate(records, targets)?;
        Ok(Self {
            records: records.iter().copied().collect(),
            targets: targets.iter().copied().collect(),
            n: records.ncols(),
            m: targets.ncols(),
            rng: ChaCha8Rng::seed_from_u64(seed),
            last: None,
        })
    }

    /// Number of records N.
    pub fn len(&self) -> usize {
        self.records.len() / self.n
    }

    /// Always false (an empty dataset is rejected by [`DatasetGoal::new`]).
    pub fn is_empty(&self) -> bool {
        self.records.is_empty()
    }

    /// The records, N × n row-major.
    pub fn records(&self) -> &[f64] {
        &self.records
    }

    /// The targets, N × m row-major.
    pub fn targets(&self) -> &[f64] {
        &self.targets
    }

    fn record(&self, i: usize) -> &[f64] {
        &self.records[i * self.n..(i + 1) * self.n]
    }

    /// The record nearest to `x` (Euclidean; the first of equally near ones).
    pub fn nearest(&self, x: &[f64]) -> usize {
        let mut best = (0, f64::INFINITY);
        for (i, r) in self.records.chunks_exact(self.n).enumerate() {
            let d: f64 = r.iter().zip(x).map(|(a, b)| (a - b) * (a - b)).sum();
            if d < best.1 {
                best = (i, d);
            }
        }
        best.0
    }
}

impl GoalFunction for DatasetGoal {
    fn sample(&mut self, x: &mut [f64]) {
        let i = self.rng.random_range(0..self.len());
        self.last = Some(i);
        x.copy_from_slice(self.record(i));
    }

    fn evaluate(&mut self, x: &[f64], y: &mut [f64]) {
        let i = match self.last {
            Some(i) if self.record(i) == x => i,
            _ => self.nearest(x),
        };
        y.copy_from_slice(&self.targets[i * self.m..(i + 1) * self.m]);
    }
}

/// The checks of [`DatasetGoal::new`].
fn validate(
    records: ArrayView2<'_, f64>,
    targets: ArrayView2<'_, f64>,
) -> Result<(), IsgcsRegressorError> {
    if records.nrows() == 0 {
        return Err(IsgcsRegressorError::EmptyDataset);
    }
    if records.ncols() == 0 {
        return Err(IsgcsRegressorError::NoFeatures);
    }
    if targets.nrows() != records.nrows() {
        return Err(IsgcsRegressorError::ShapeMismatch(format!(
            "{} records but {} target rows",
            records.nrows(),
            targets.nrows()
        )));
    }
    if targets.ncols() == 0 {
        return Err(IsgcsRegressorError::NoOutputs);
    }
    for (what, a) in [("records", records.view()), ("targets", targets.view())] {
        if let Some(((row, column), &value)) = a.indexed_iter().find(|(_, v)| !v.is_finite()) {
            return Err(IsgcsRegressorError::NonFinite {
                what,
                row,
                column,
                value,
            });
        }
    }
    Ok(())
}

/// How a fit went.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct FitReport {
    /// Why growth ended.
    pub stopped: Stopped,
    /// Training steps of the growth phase.
    pub growth_steps: u64,
    /// Training steps of the settling phase.
    pub settle_steps: u64,
    /// The relative ridge the least-squares output layer used, `None` when it was off.
    pub ridge: Option<f64>,
    /// What the default pipeline chose (`None` for the native pipeline).
    pub auto: Option<crate::regressor::RegressorReport>,
}

/// A fitted ISGCS network as a linfa regressor. `D` is the target shape it was fitted on:
/// [`Ix1`](type@Ix1) (single output, predicts `Array1`) or [`Ix2`](type@Ix2) (m outputs,
/// predicts `Array2`). The shape is part of the type so that `model.predict(&x)` needs no
/// annotation and returns what the targets were.
///
/// Serde-serializable (save with e.g. `serde_json::to_string(&model)`, load with
/// `serde_json::from_str::<IsgcsRegressor<Ix1>>`): the model keeps the network, its output
/// layer and the standardization.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
#[serde(bound = "")]
pub struct IsgcsRegressor<D = Ix2> {
    net: Isgcs,
    report: FitReport,
    /// The default pipeline's fitted model; predictions come from it when present.
    auto: Option<Regressor>,
    #[serde(skip)]
    dim: PhantomData<D>,
}

impl IsgcsRegressor {
    /// The default hyperparameters ([`IsgcsRegressorParams::new`]); they fit either target
    /// shape.
    pub fn params() -> IsgcsRegressorParams {
        IsgcsRegressorParams::new()
    }
}

impl<D> IsgcsRegressor<D> {
    /// The trained network (for the default pipeline: in standardized input coordinates, its
    /// outputs those of the delta rule; predictions use the least-squares output layer).
    pub fn network(&self) -> &Isgcs {
        &self.net
    }

    /// The default pipeline's fitted model, `None` for the native pipeline.
    pub fn regressor(&self) -> Option<&Regressor> {
        self.auto.as_ref()
    }

    /// The trained network, e.g. to keep training it or to serialize it (it derives serde).
    pub fn into_network(self) -> Isgcs {
        self.net
    }

    /// How the fit went.
    pub fn report(&self) -> &FitReport {
        &self.report
    }

    /// Predictions for N inputs (N × n) as N × m, without panicking: errors when the inputs
    /// do not have the n features the model was fitted on. Rows with a non-finite input get NaN
    /// outputs.
    pub fn predict_outputs<S: Data<Elem = f64>>(
        &self,
        x: &ArrayBase<S, Ix2>,
    ) -> Result<Array2<f64>, IsgcsRegressorError> {
        self.check_features(x)?;
        let mut y = Array2::zeros((x.nrows(), self.net.output_dim()));
        self.predict_into(x, y.view_mut());
        Ok(y)
    }

    fn check_features<S: Data<Elem = f64>>(
        &self,
        x: &ArrayBase<S, Ix2>,
    ) -> Result<(), IsgcsRegressorError> {
        if x.ncols() != self.net.input_dim() {
            return Err(IsgcsRegressorError::ShapeMismatch(format!(
                "the model was fitted on {} features, the input has {}",
                self.net.input_dim(),
                x.ncols()
            )));
        }
        Ok(())
    }

    /// Ψ of every row of `x` into `y` (N × m); the shapes are checked by the caller.
    fn predict_into<S: Data<Elem = f64>>(&self, x: &ArrayBase<S, Ix2>, mut y: ArrayViewMut2<f64>) {
        let inputs = x.as_standard_layout();
        let inputs = inputs.as_slice().expect("standard layout is contiguous");
        let m = self.net.output_dim();
        let shapes = "predict_batch shapes are checked";
        let run = |out: &mut [f64]| match &self.auto {
            Some(model) => model.predict(inputs, out).expect(shapes),
            None => self.net.predict_batch(inputs, out).expect(shapes),
        };
        match y.as_slice_mut() {
            Some(out) => run(out),
            None => {
                let mut out = vec![0.0; x.nrows() * m];
                run(&mut out);
                y.iter_mut().zip(out).for_each(|(a, b)| *a = b);
            }
        }
        for (row, mut o) in x.rows().into_iter().zip(y.rows_mut()) {
            if row.iter().any(|v| !v.is_finite()) {
                o.fill(f64::NAN);
            }
        }
    }

    fn assert_features<S: Data<Elem = f64>>(&self, x: &ArrayBase<S, Ix2>) {
        if let Err(e) = self.check_features(x) {
            panic!("{e}");
        }
    }
}

/// Single-output prediction (the model was fitted on `Array1` targets).
///
/// # Panics
/// When `x` does not have the n features of the training records or `y` not `x.nrows()`
/// entries (linfa's convention; [`IsgcsRegressor::predict_outputs`] returns an error instead).
impl<S: Data<Elem = f64>> PredictInplace<ArrayBase<S, Ix2>, Array1<f64>> for IsgcsRegressor<Ix1> {
    fn predict_inplace<'a>(&'a self, x: &'a ArrayBase<S, Ix2>, y: &mut Array1<f64>) {
        self.assert_features(x);
        assert_eq!(
            y.len(),
            x.nrows(),
            "the prediction target must have one entry per record"
        );
        let n = y.len();
        self.predict_into(x, y.view_mut().into_shape_with_order((n, 1)).unwrap());
    }

    fn default_target(&self, x: &ArrayBase<S, Ix2>) -> Array1<f64> {
        Array1::zeros(x.nrows())
    }
}

/// Multi-output prediction (the model was fitted on `Array2` targets).
///
/// # Panics
/// When `x` does not have the n features of the training records or `y` is not
/// `x.nrows()` × m (linfa's convention; [`IsgcsRegressor::predict_outputs`] returns an error
/// instead).
impl<S: Data<Elem = f64>> PredictInplace<ArrayBase<S, Ix2>, Array2<f64>> for IsgcsRegressor<Ix2> {
    fn predict_inplace<'a>(&'a self, x: &'a ArrayBase<S, Ix2>, y: &mut Array2<f64>) {
        self.assert_features(x);
        assert_eq!(
            y.dim(),
            (x.nrows(), self.net.output_dim()),
            "the prediction target must be records × outputs"
        );
        self.predict_into(x, y.view_mut());
    }

    fn default_target(&self, x: &ArrayBase<S, Ix2>) -> Array2<f64> {
        Array2::zeros((x.nrows(), self.net.output_dim()))
    }
}

impl<S, T> Fit<ArrayBase<S, Ix2>, T, IsgcsRegressorError> for IsgcsRegressorValidParams
where
    S: Data<Elem = f64>,
    T: AsTargets<Elem = f64>,
    T::Ix: TargetDim + 'static,
{
    type Object = IsgcsRegressor<T::Ix>;

    fn fit(
        &self,
        dataset: &DatasetBase<ArrayBase<S, Ix2>, T>,
    ) -> Result<Self::Object, IsgcsRegressorError> {
        let x = dataset.records().view();
        let y = dataset.as_targets();
        // Single-output targets become one column.
        let m = if y.ndim() == 2 { y.shape()[1] } else { 1 };
        let rows = y.shape()[0];
        let y = Array2::from_shape_vec((rows, m), y.iter().copied().collect())
            .map_err(::linfa::Error::from)?;
        if self.auto {
            let model = self.fit_auto(x, y.view())?;
            let r = *model.report();
            return Ok(IsgcsRegressor {
                net: model.network().clone(),
                report: FitReport {
                    stopped: Stopped::CellBudget,
                    growth_steps: r.growth_steps,
                    settle_steps: r.settle_steps,
                    ridge: Some(r.ridge),
                    auto: Some(r),
                },
                auto: Some(model),
                dim: PhantomData,
            });
        }
        let net = self.fit_network(x, y.view())?;
        Ok(IsgcsRegressor {
            net: net.0,
            report: net.1,
            auto: None,
            dim: PhantomData,
        })
    }
}

impl IsgcsRegressorValidParams {
    /// The default pipeline ([`crate::regressor`]) on records (N × n) and targets (N × m).
    fn fit_auto(
        &self,
        x: ArrayView2<'_, f64>,
        y: ArrayView2<'_, f64>,
    ) -> Result<Regressor, IsgcsRegressorError> {
        validate(x, y)?;
        let (n, m) = (x.ncols(), y.ncols());
        if let Some(k) = self.topology_dim.filter(|&k| k > n) {
            return Err(IsgcsRegressorError::TopologyDim { k, n });
        }
        let params = RegressorParams {
            max_cells: self.max_cells,
            seed: self.seed,
            topology_dim: self.topology_dim,
            settle: self.settle,
            ridge: self.ridge,
            width_multiplier: self.width_multiplier,
            ..RegressorParams::default()
        };
        let xs: Vec<f64> = x.iter().copied().collect();
        let ys: Vec<f64> = y.iter().copied().collect();
        Regressor::fit(&params, &xs, &ys, n, m).map_err(|e| match e {
            RegressorError::CellBudget { cells, min, .. } if cells < min => {
                IsgcsRegressorError::CellBudget { cells, min }
            }
            e => e.into(),
        })
    }

    /// The three phases of the module docs on records (N × n) and targets (N × m).
    fn fit_network(
        &self,
        x: ArrayView2<'_, f64>,
        y: ArrayView2<'_, f64>,
    ) -> Result<(Isgcs, FitReport), IsgcsRegressorError> {
        let mut goal = DatasetGoal::new(x, y, self.seed)?;
        let (n, m) = (x.ncols(), y.ncols());
        let k = self.topology_dim.unwrap_or(n.min(2));
        if k > n {
            return Err(IsgcsRegressorError::TopologyDim { k, n });
        }
        if self.max_cells < k + 1 {
            return Err(IsgcsRegressorError::CellBudget {
                cells: self.max_cells,
                min: k + 1,
            });
        }
        let mut net = Isgcs::new(self.network, n, m, k, initial_simplex(x, k))?;
        let go_on = |_: &Isgcs, _: &crate::Event| ControlFlow::Continue(());
        let stopped = net.fit(
            &mut goal,
            &Termination {
                max_cells: Some(self.max_cells),
                max_steps: self.max_steps,
                target_error: self.target_error,
            },
            go_on,
        )?;
        let growth_steps = net.steps();
        net.set_growing(false);
        let settle_steps = (growth_steps as f64 * self.settle).round() as u64;
        net.fit(
            &mut goal,
            &Termination {
                max_steps: Some(settle_steps),
                ..Termination::default()
            },
            go_on,
        )?;
        let ridge = match self.least_squares {
            Some(r) => Some(net.fit_outputs(goal.records(), goal.targets(), r)?),
            None => None,
        };
        let report = FitReport {
            stopped,
            growth_steps,
            settle_steps,
            ridge,
            auto: None,
        };
        Ok((net, report))
    }
}

/// k + 1 points: the records' mean, and the mean moved by one standard deviation along each of
/// the first k features (features without spread use the largest standard deviation, or 1).
fn initial_simplex(x: ArrayView2<'_, f64>, k: usize) -> Vec<Vec<f64>> {
    let rows = x.nrows() as f64;
    let mean: Vec<f64> = x.columns().into_iter().map(|c| c.sum() / rows).collect();
    let sd: Vec<f64> = x
        .columns()
        .into_iter()
        .zip(&mean)
        .map(|(c, mu)| (c.iter().map(|v| (v - mu) * (v - mu)).sum::<f64>() / rows).sqrt())
        .collect();
    let widest = sd.iter().copied().fold(0.0, f64::max);
    let fallback = if widest > 0.0 { widest } else { 1.0 };
    let mut points = vec![mean.clone()];
    for a in 0..k {
        let mut p = mean.clone();
        p[a] += if sd[a] > 0.0 { sd[a] } else { fallback };
        points.push(p);
    }
    points
}

#[cfg(test)]
mod tests {
    use super::*;
    use ndarray::array;

    #[test]
    fn goal_returns_the_sampled_row_and_the_nearest_record_elsewhere() {
        let x = array![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]];
        let y = array![[10.0], [20.0], [30.0]];
        let mut goal = DatasetGoal::new(x.view(), y.view(), 3).unwrap();
        let (mut p, mut v) = ([0.0; 2], [0.0]);
        for _ in 0..20 {
            goal.sample(&mut p);
            goal.evaluate(&p, &mut v);
            let row = x.rows().into_iter().position(|r| r.to_vec() == p).unwrap();
            assert_eq!(v[0], y[[row, 0]]);
        }
        goal.evaluate(&[0.9, 0.2], &mut v);
        assert_eq!(v[0], 20.0);
        goal.evaluate(&[-0.1, 0.7], &mut v);
        assert_eq!(v[0], 30.0);
    }

    #[test]
    fn initial_simplex_spans_the_features_and_survives_constant_data() {
        let x = array![[1.0, 5.0, 2.0], [3.0, 5.0, 2.0]];
        let s = initial_simplex(x.view(), 2);
        assert_eq!(
            s,
            vec![
                vec![2.0, 5.0, 2.0],
                vec![3.0, 5.0, 2.0],
                vec![2.0, 6.0, 2.0]
            ]
        );
        let c = array![[4.0], [4.0]];
        assert_eq!(initial_simplex(c.view(), 1), vec![vec![4.0], vec![5.0]]);
    }
}
