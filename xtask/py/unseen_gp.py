"""A Gaussian process on the rows `cargo run --release -p isgcs --example unseen -- --dump DIR`
wrote (DIR/NAME.train.csv and NAME.test.csv: inputs, then targets; test targets noise-free):
scikit-learn's GaussianProcessRegressor with a constant x ARD RBF + white-noise kernel,
normalize_y, hyperparameters fitted by marginal likelihood on the first HYP rows (default 1500),
then the GP refitted with them on all rows. Prints rms/σ on the test points (the mean over
output columns) and the seconds taken.

    python3 xtask/py/unseen_gp.py DIR NAME INPUT_DIM [HYP]

Skips with a note when scikit-learn or numpy is missing.
"""
import sys
import time

try:
    import numpy as np
    from sklearn.gaussian_process import GaussianProcessRegressor as GPR
    from sklearn.gaussian_process.kernels import RBF, WhiteKernel, ConstantKernel as C
except ImportError as e:
    print(f"skipped: {e} (pip install scikit-learn numpy)")
    sys.exit(0)

if len(sys.argv) < 4:
    sys.exit(__doc__)
d, name, n = sys.argv[1], sys.argv[2], int(sys.argv[3])
hyp = int(sys.argv[4]) if len(sys.argv) > 4 else 1500
tr = np.loadtxt(f"{d}/{name}.train.csv", delimiter=",")
te = np.loadtxt(f"{d}/{name}.test.csv", delimiter=",")
X, Y = tr[:, :n], tr[:, n:]
TX, TY = te[:, :n], te[:, n:]
mu, sd = X.mean(0), X.std(0)
sd[sd == 0] = 1
X = (X - mu) / sd
TX = (TX - mu) / sd
t = time.time()
out = []
for c in range(Y.shape[1]):
    k = C(1.0) * RBF(np.ones(n), (1e-2, 1e3)) + WhiteKernel(1e-2, (1e-8, 1e1))
    g = GPR(k, normalize_y=True, n_restarts_optimizer=0, random_state=0).fit(X[:hyp], Y[:hyp, c])
    if len(X) > hyp:
        g = GPR(g.kernel_, normalize_y=True, optimizer=None).fit(X, Y[:, c])
    p = g.predict(TX)
    out.append(np.sqrt(np.mean((p - TY[:, c]) ** 2)) / TY[:, c].std())
    print(f"  {name} col {c} kernel {g.kernel_}", file=sys.stderr)
print(
    f"GP {name} rows {len(X)} hyp-rows {min(hyp, len(X))} rms/sd {np.mean(out):.4f} "
    f"{['%.4f' % o for o in out]} {time.time() - t:.0f}s"
)
