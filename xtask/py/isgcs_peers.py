#!/usr/bin/env python3
"""Python peers of `cargo xtask bench --only isgcs-peers`.

Usage: isgcs_peers.py DIR, where DIR holds one JSON file per case written by the bench
(problem, cells, n, x, y, tx, ty; x/tx row-major). Prints one JSON object per line:
{"problem", "cells", "method", "rms", "fit", "predict"}; rms is RMS error over the standard
deviation of the noise-free test targets. When scikit-learn or scipy is missing it prints a
single {"skipped": reason} line and exits 0, so the bench notes it instead of failing.

Models (inputs standardized for all; two threads where the library supports it):
  scipy-rbf  scipy.interpolate.RBFInterpolator, thin-plate spline with a linear tail,
             64 nearest neighbours, smoothing chosen on a 20 % holdout from {0, 1e-3, 1e-1, 1}
  knn        KNeighborsRegressor, distance weights, k from {3, 5, 10, 20} by 5-fold CV
  mlp        MLPRegressor (64, 64), adam, early stopping, max 2000 iterations
  gp         GaussianProcessRegressor, ARD RBF + white kernel, on at most 2000 rows (O(N^3))
  gbr        HistGradientBoostingRegressor (default settings, early stopping)
"""

import glob
import json
import os
import sys
import time

os.environ.setdefault("OMP_NUM_THREADS", "2")

try:
    import numpy as np
    from scipy.interpolate import RBFInterpolator
    from sklearn.ensemble import HistGradientBoostingRegressor
    from sklearn.gaussian_process import GaussianProcessRegressor
    from sklearn.gaussian_process.kernels import RBF, ConstantKernel, WhiteKernel
    from sklearn.model_selection import GridSearchCV
    from sklearn.neighbors import KNeighborsRegressor
    from sklearn.neural_network import MLPRegressor
except ImportError as e:  # pragma: no cover - depends on the machine
    print(json.dumps({"skipped": f"scikit-learn/scipy/numpy not installed ({e})"}))
    sys.exit(0)


def rms_over_sd(pred, truth):
    return float(np.sqrt(np.mean((pred - truth) ** 2)) / np.std(truth))


def scipy_rbf(x, y):
    k = int(0.8 * len(x))
    best = None
    for s in [0.0, 1e-3, 1e-1, 1.0]:
        m = RBFInterpolator(x[:k], y[:k], neighbors=64, smoothing=s)
        e = np.mean((m(x[k:]) - y[k:]) ** 2)
        if best is None or e < best[0]:
            best = (e, s)
    return RBFInterpolator(x, y, neighbors=64, smoothing=best[1])


def knn(x, y):
    g = GridSearchCV(KNeighborsRegressor(weights="distance"), {"n_neighbors": [3, 5, 10, 20]}, cv=5)
    return g.fit(x, y)


def mlp(x, y):
    return MLPRegressor(hidden_layer_sizes=(64, 64), max_iter=2000, early_stopping=True, random_state=1).fit(x, y)


def gp(x, y):
    rows = min(len(x), 2000)
    n = x.shape[1]
    kernel = ConstantKernel() * RBF(length_scale=np.ones(n)) + WhiteKernel(1e-3)
    return GaussianProcessRegressor(kernel=kernel, normalize_y=True, random_state=1).fit(x[:rows], y[:rows])


def gbr(x, y):
    return HistGradientBoostingRegressor(random_state=1).fit(x, y)


METHODS = {"scipy-rbf": scipy_rbf, "knn": knn, "mlp": mlp, "gp": gp, "gbr": gbr}


def main():
    files = sorted(glob.glob(os.path.join(sys.argv[1], "*.json")))
    for f in files:
        case = json.load(open(f))
        n = case["n"]
        x = np.array(case["x"]).reshape(-1, n)
        tx = np.array(case["tx"]).reshape(-1, n)
        y, ty = np.array(case["y"]), np.array(case["ty"])
        mu, sd = x.mean(0), x.std(0)
        sd[sd == 0] = 1
        x, tx = (x - mu) / sd, (tx - mu) / sd
        for name, fit in METHODS.items():
            t = time.perf_counter()
            model = fit(x, y)
            fit_s = time.perf_counter() - t
            t = time.perf_counter()
            pred = model(tx) if name == "scipy-rbf" else model.predict(tx)
            pred_s = time.perf_counter() - t
            print(json.dumps({"problem": case["problem"], "cells": case["cells"], "method": name,
                              "rms": rms_over_sd(pred, ty), "fit": fit_s, "predict": pred_s}),
                  flush=True)


if __name__ == "__main__":
    main()
