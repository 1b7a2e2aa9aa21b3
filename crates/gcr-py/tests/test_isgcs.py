"""gcr.isgcs.IsgcsRegressor: scikit-learn's estimator checks, accuracy, exact pickles, and the
NumPy-only fallback without scikit-learn."""

from __future__ import annotations

import pickle
import subprocess
import sys

import numpy as np
import pytest

from gcr.isgcs import HAVE_SKLEARN, IsgcsRegressor

sklearn = pytest.importorskip(
    "sklearn", reason="scikit-learn is not installed: its estimator checks cannot run"
)
from sklearn.utils.estimator_checks import parametrize_with_checks  # noqa: E402

# Checks that cannot apply, with why (each is run and expected to fail: xfail, strict).
EXPECTED_FAILED_CHECKS: dict[str, str] = {}


@parametrize_with_checks(
    [IsgcsRegressor(max_cells=20)],
    expected_failed_checks=lambda est: EXPECTED_FAILED_CHECKS,
    xfail_strict=True,
)
def test_sklearn_estimator_checks(estimator, check):
    check(estimator)


def franke(x: np.ndarray) -> np.ndarray:
    """Franke's function on [0, 1]²."""
    a, b = 9 * x[:, 0], 9 * x[:, 1]
    return (
        0.75 * np.exp(-((a - 2) ** 2) / 4 - (b - 2) ** 2 / 4)
        + 0.75 * np.exp(-((a + 1) ** 2) / 49 - (b + 1) / 10)
        + 0.5 * np.exp(-((a - 7) ** 2) / 4 - (b - 3) ** 2 / 4)
        - 0.2 * np.exp(-((a - 4) ** 2) - (b - 7) ** 2)
    )


def test_it_learns_franke_and_is_deterministic():
    rng = np.random.default_rng(1)
    x, x_test = rng.random((800, 2)), rng.random((400, 2))
    model = IsgcsRegressor(max_cells=60).fit(x, franke(x))
    assert HAVE_SKLEARN and model.score(x_test, franke(x_test)) > 0.98
    assert model.n_features_in_ == 2 and model.n_cells_ <= 60 and model.n_outputs_ == 1
    again = IsgcsRegressor(max_cells=60).fit(x, franke(x))
    assert np.array_equal(model.predict(x_test), again.predict(x_test))


def test_several_outputs():
    rng = np.random.default_rng(2)
    x = rng.random((300, 2))
    y = np.stack([franke(x), x[:, 0] - x[:, 1]], axis=1)
    model = IsgcsRegressor(max_cells=40).fit(x, y)
    assert model.predict(x).shape == (300, 2) and model.n_outputs_ == 2


def test_a_pickled_model_predicts_exactly_the_same():
    rng = np.random.default_rng(3)
    x = rng.random((200, 3))
    model = IsgcsRegressor(max_cells=30).fit(x, np.sin(4 * x).sum(axis=1))
    copy = pickle.loads(pickle.dumps(model))
    assert np.array_equal(copy.predict(x), model.predict(x))
    assert copy.get_params() == model.get_params()


def test_bad_parameters_raise_value_errors_in_fit():
    x = np.random.default_rng(4).random((50, 2))
    with pytest.raises(ValueError, match="topology_dim"):
        IsgcsRegressor(topology_dim=5).fit(x, x[:, 0])
    with pytest.raises(ValueError, match="max_cells"):
        IsgcsRegressor(max_cells=0).fit(x, x[:, 0])


FALLBACK = """
import sys
sys.modules['sklearn'] = None  # scikit-learn cannot be imported
import numpy as np
from gcr.isgcs import HAVE_SKLEARN, IsgcsRegressor
assert not HAVE_SKLEARN
x = np.random.default_rng(5).random((100, 2))
m = IsgcsRegressor(max_cells=20).set_params(random_state=3)
assert m.get_params()['random_state'] == 3
m.fit(x, x.sum(axis=1))
assert m.predict(x).shape == (100,) and m.score(x, x.sum(axis=1)) > 0.9
try:
    m.predict(x[:, :1])
except ValueError as e:
    assert 'features' in str(e)
else:
    raise AssertionError('no error for a wrong feature count')
print('ok')
"""


def test_without_sklearn_the_numpy_fallback_works():
    out = subprocess.run([sys.executable, "-c", FALLBACK], capture_output=True, text=True)
    assert out.returncode == 0 and out.stdout.strip() == "ok", out.stderr
