#!/usr/bin/env bash
# CI for the Python package, run by .ci/run from the workspace root after `cargo test`: builds
# the wheel with maturin (in the dev profile, below), installs it with
# what the tests need in a fresh virtual environment, and runs the pytest suite against the `gcr`
# program that `cargo test` built (its profile differs from the wheel's: the numbers must not,
# and the tests compare them bit for bit).
set -euo pipefail
cd "$(dirname "$0")/../.."
target="$(realpath -m "${CARGO_TARGET_DIR:-target}")"
venv="$target/py-venv"
started=$(date +%s)

python3 --version
if ! python3 -m venv --clear "$venv"; then
    echo "python3 -m venv failed (is python3-venv installed?): falling back to pip --user" >&2
    python3 -m pip install --user --break-system-packages -q virtualenv
    python3 -m virtualenv --clear "$venv"
fi
# pandas and SCIPY_ARRAY_API let scikit-learn run its pandas and array-API estimator checks
# instead of skipping them; dask[distributed] for the sharded bake on a local cluster (test_shards.py)
"$venv/bin/python" -m pip install -q maturin numpy pytest scikit-learn pandas "dask[distributed]"

rm -rf "$target/wheels"
# the dev profile (optimized, as the workspace sets it) reuses the dependencies `cargo test` has
# built: 57 s here against about 4 min for a release build of every dependency; users'
# `pip install crates/gcr-py` builds release, and the numbers do not depend on the profile (the
# tests compare this wheel with the program bit for bit)
"$venv/bin/maturin" build --profile dev -m crates/gcr-py/Cargo.toml -o "$target/wheels" \
    --interpreter "$venv/bin/python"
"$venv/bin/python" -m pip install -q --force-reinstall --no-deps "$target"/wheels/gcr-*.whl

# the program the numbers are compared with: `cargo test --workspace --all-features` built it
# (gcr-cli's tests run it); with the same packages and features this build is up to date
cargo build --workspace --all-features --bin gcr
export GCR_BIN="$target/debug/gcr"
# run from outside the sources, so that `import gcr` is the installed wheel
tests="$PWD/crates/gcr-py/tests"
(cd "$target" && SCIPY_ARRAY_API=1 "$venv/bin/python" -m pytest -q -p no:cacheprovider "$tests")
echo "Python package: $(( $(date +%s) - started )) s"
