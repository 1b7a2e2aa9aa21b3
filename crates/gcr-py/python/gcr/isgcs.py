"""The ISGCS regressor (incremental supervised growing cell structures, Bohn 2000, ch. 2) with
scikit-learn's estimator API.

:class:`IsgcsRegressor` wraps the Rust ``isgcs::regressor::Regressor`` (``crates/isgcs``): a
network of Gaussians grown on the data, with an output layer fitted by ridge least squares and
everything else (topology, widths, ridge, an input metric) chosen from the data. With
scikit-learn (1.6 or later) installed it is a ``RegressorMixin, BaseEstimator`` (pipelines,
``GridSearchCV``, ``clone``, ``score``); without it, the same class with NumPy-only input checks
and its own ``get_params``/``set_params``/``score``.

Example::

    from gcr.isgcs import IsgcsRegressor
    model = IsgcsRegressor(max_cells=50).fit(X, y)
    y_hat = model.predict(X_test)
"""

from __future__ import annotations

import inspect
import json
import numbers

import numpy as np

from gcr._gcr import IsgcsModel

try:
    from sklearn.base import BaseEstimator, RegressorMixin
    from sklearn.utils import check_random_state
    from sklearn.utils.validation import check_is_fitted, validate_data

    HAVE_SKLEARN = True
except ImportError:  # scikit-learn missing or older than 1.6 (no validate_data)
    HAVE_SKLEARN = False

__all__ = ["IsgcsRegressor", "HAVE_SKLEARN"]


if not HAVE_SKLEARN:

    class BaseEstimator:  # type: ignore[no-redef]
        """``get_params``/``set_params`` as scikit-learn's, from ``__init__``'s signature."""

        @classmethod
        def _get_param_names(cls) -> list[str]:
            sig = inspect.signature(cls.__init__)
            return sorted(p for p in sig.parameters if p != "self")

        def get_params(self, deep: bool = True) -> dict:
            """The estimator's parameters (``__init__``'s arguments) by name."""
            return {name: getattr(self, name) for name in self._get_param_names()}

        def set_params(self, **params):
            """Sets parameters by name; returns the estimator."""
            valid = self._get_param_names()
            for name, value in params.items():
                if name not in valid:
                    raise ValueError(f"invalid parameter {name!r} for {type(self).__name__}")
                setattr(self, name, value)
            return self

        def __getstate__(self) -> dict:
            return self.__dict__.copy()

        def __setstate__(self, state: dict) -> None:
            self.__dict__.update(state)

        def __repr__(self) -> str:
            args = ", ".join(f"{k}={v!r}" for k, v in self.get_params().items())
            return f"{type(self).__name__}({args})"

    class RegressorMixin:  # type: ignore[no-redef]
        """``score``: the coefficient of determination R² of the predictions."""

        def score(self, X, y, sample_weight=None) -> float:
            """R² of ``predict(X)`` against ``y`` (uniform average over outputs)."""
            y = np.asarray(y, dtype=np.float64)
            pred = self.predict(X)
            w = None if sample_weight is None else np.asarray(sample_weight, dtype=np.float64)
            resid = np.average((y - pred) ** 2, axis=0, weights=w)
            total = np.average((y - np.average(y, axis=0, weights=w)) ** 2, axis=0, weights=w)
            return float(np.mean(1.0 - resid / np.where(total == 0.0, 1.0, total)))

    class NotFittedError(ValueError, AttributeError):
        """Raised by ``predict`` before ``fit``."""

    def check_is_fitted(estimator) -> None:
        if not any(k.endswith("_") and not k.startswith("__") for k in vars(estimator)):
            raise NotFittedError(
                f"This {type(estimator).__name__} instance is not fitted yet. Call 'fit' with "
                "appropriate arguments before using this estimator."
            )

    def check_random_state(seed):
        if seed is None or seed is np.random:
            return np.random.mtrand._rand
        if isinstance(seed, numbers.Integral):
            return np.random.RandomState(seed)
        if isinstance(seed, np.random.RandomState):
            return seed
        raise ValueError(f"{seed!r} cannot be used to seed a numpy.random.RandomState instance")

    def validate_data(estimator, X, y=None, reset=True, **_):
        """NumPy-only checks: 2-D finite float64 X (at least 2 rows to fit), y of as many rows."""
        X = np.asarray(X, dtype=np.float64)
        if X.ndim != 2:
            raise ValueError(f"Expected 2D array, got {X.ndim}D array instead")
        if not np.all(np.isfinite(X)):
            raise ValueError("Input X contains NaN or infinity.")
        if reset:
            estimator.n_features_in_ = X.shape[1]
        elif X.shape[1] != estimator.n_features_in_:
            raise ValueError(
                f"X has {X.shape[1]} features, but {type(estimator).__name__} is expecting "
                f"{estimator.n_features_in_} features as input."
            )
        if y is None:
            return X
        y = np.asarray(y, dtype=np.float64)
        if X.shape[0] < 2:
            raise ValueError(f"Found array with {X.shape[0]} sample(s) while a minimum of 2 is required.")
        if y.shape[0] != X.shape[0] or y.ndim not in (1, 2):
            raise ValueError(f"X has {X.shape[0]} rows but y has shape {y.shape}")
        if not np.all(np.isfinite(y)):
            raise ValueError("Input y contains NaN or infinity.")
        return X, y


class _ModelState:
    """A fitted model as text inside a pickle (:meth:`IsgcsModel.state`, exact)."""

    def __init__(self, text: str) -> None:
        self.text = text


class IsgcsRegressor(RegressorMixin, BaseEstimator):
    """ISGCS regression: Gaussians grown on the data, a ridge least-squares output layer.

    Parameters (every ``None`` is chosen from the data; ``crates/isgcs/src/regressor.rs`` has
    the method):

    max_cells : int, default 100
        Cells (Gaussians) to grow; capped at the number of training rows.
    random_state : int, RandomState or None, default 0
        Seed of the row order: equal seeds give equal models. ``None`` draws one.
    topology_dim : int or None
        Topology dimension k of the network (1 ≤ k ≤ n_features).
    steps_per_cell : int or None
        λ, online training steps per cell in each growth round (default 10).
    settle : float, default 1/3
        Settling steps after growth, as a multiple of the growth steps.
    ridge : float or None
        Relative ridge of the output layer.
    width_multiplier : float or None
        Factor on the nearest-centre widths of the Gaussians.
    normalized : bool, default True
        Normalized Gaussians (a partition of unity) during growth.
    affine : bool, default False
        Add the columns 1, x₁ … xₙ to the output layer.
    choose_basis : bool, default True
        Try normalized and plain Gaussians for the output layer, keep the better.
    metric : bool, default True
        Learn an input metric from the data.

    Attributes
    ----------
    model_ : gcr._gcr.IsgcsModel
        The fitted Rust model.
    n_features_in_ : int
        Features seen by ``fit``.
    n_outputs_ : int
        Targets per row (1 for a 1-D ``y``).
    n_cells_ : int
        Cells of the fitted network.
    report_ : dict
        What the fit chose (topology dimension, λ, width multiplier, ridge, degrees of freedom,
        blend share).
    """

    def __init__(
        self,
        max_cells: int = 100,
        *,
        random_state=0,
        topology_dim: int | None = None,
        steps_per_cell: int | None = None,
        settle: float = 1.0 / 3.0,
        ridge: float | None = None,
        width_multiplier: float | None = None,
        normalized: bool = True,
        affine: bool = False,
        choose_basis: bool = True,
        metric: bool = True,
    ) -> None:
        self.max_cells = max_cells
        self.random_state = random_state
        self.topology_dim = topology_dim
        self.steps_per_cell = steps_per_cell
        self.settle = settle
        self.ridge = ridge
        self.width_multiplier = width_multiplier
        self.normalized = normalized
        self.affine = affine
        self.choose_basis = choose_basis
        self.metric = metric

    def _params(self, n_samples: int) -> dict:
        """The Rust ``RegressorParams`` of these settings for ``n_samples`` rows."""
        if isinstance(self.random_state, numbers.Integral):
            seed = int(self.random_state)
        else:
            seed = int(check_random_state(self.random_state).randint(np.iinfo(np.int32).max))
        if not isinstance(self.max_cells, numbers.Integral) or self.max_cells < 1:
            raise ValueError(f"max_cells must be a positive integer, got {self.max_cells!r}")
        return {
            "max_cells": min(int(self.max_cells), n_samples),
            "seed": seed,
            "topology_dim": self.topology_dim,
            "lambda": self.steps_per_cell,
            "settle": self.settle,
            "ridge": self.ridge,
            "width_multiplier": self.width_multiplier,
            "normalized": self.normalized,
            "affine": self.affine,
            "choose_basis": self.choose_basis,
            "metric": self.metric,
        }

    def fit(self, X, y) -> "IsgcsRegressor":
        """Fits the network to ``X`` (n_samples × n_features) and ``y`` (n_samples, or
        n_samples × n_outputs). Returns the estimator."""
        X, y = validate_data(
            self, X, y, multi_output=True, y_numeric=True, ensure_min_samples=2, dtype=np.float64
        )
        y = np.asarray(y, dtype=np.float64)
        y2 = y.reshape(-1, 1) if y.ndim == 1 else y
        params = self._params(X.shape[0])
        self.model_ = IsgcsModel.fit(X, y2, json.dumps(params))
        self.n_outputs_ = y2.shape[1]
        self.n_cells_ = self.model_.cells
        self.report_ = json.loads(self.model_.report)
        self._y_ndim = y.ndim
        return self

    def predict(self, X) -> np.ndarray:
        """Predictions for ``X``: shape (n_samples,) for a 1-D training ``y``, else
        (n_samples, n_outputs)."""
        check_is_fitted(self)
        X = validate_data(self, X, reset=False, dtype=np.float64)
        out = self.model_.predict(X)
        return out[:, 0] if self._y_ndim == 1 else out

    if HAVE_SKLEARN:

        def __sklearn_tags__(self):
            """scikit-learn's tags: a regressor of one or many outputs."""
            tags = super().__sklearn_tags__()
            tags.target_tags.multi_output = True
            tags.target_tags.single_output = True
            return tags

    def __getstate__(self) -> dict:
        state = super().__getstate__()
        if isinstance(state.get("model_"), IsgcsModel):
            state = dict(state, model_=_ModelState(state["model_"].state()))
        return state

    def __setstate__(self, state: dict) -> None:
        if isinstance(state.get("model_"), _ModelState):
            state = dict(state, model_=IsgcsModel.from_state(state["model_"].text))
        super().__setstate__(state)
