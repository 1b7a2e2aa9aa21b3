"""Shared fixtures: the workspace, the `gcr` program to compare against, a small solved scene.

The package under test must be importable (build it: `.ci/run`, or `pip install crates/gcr-py`);
a missing `gcr` is an error, never a skip. The program is `$GCR_BIN` when set (`.ci/run` sets
it), else built with `cargo build --release -p gcr-cli`.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

import gcr

ROOT = Path(__file__).resolve().parents[3]


@pytest.fixture(scope="session")
def root() -> Path:
    """The workspace root (README.md, scenes/)."""
    return ROOT


@pytest.fixture(scope="session")
def gcr_bin() -> Path:
    """The `gcr` program: `$GCR_BIN`, or built with cargo (release) when unset."""
    given = os.environ.get("GCR_BIN")
    if given:
        path = Path(given)
        assert path.is_file(), f"GCR_BIN={given} is not a file"
        return path
    cargo = shutil.which("cargo")
    if cargo is None:
        pytest.skip("the gcr program is needed to compare with: set GCR_BIN or install cargo")
    out = subprocess.run(
        [cargo, "build", "--release", "-p", "gcr-cli", "--message-format=json"],
        cwd=ROOT,
        check=True,
        capture_output=True,
        text=True,
    ).stdout
    for line in out.splitlines():
        msg = json.loads(line)
        if msg.get("reason") == "compiler-artifact" and msg["target"]["name"] == "gcr":
            if msg.get("executable"):
                return Path(msg["executable"])
    raise AssertionError("cargo built no `gcr` executable")


def run_gcr(gcr_bin: Path, *args: str, cwd: Path | None = None, check: bool = True):
    """Runs the program; returns the completed process (stderr as text)."""
    proc = subprocess.run(
        [str(gcr_bin), *args], cwd=cwd, capture_output=True, text=True, check=False
    )
    if check:
        assert proc.returncode == 0, proc.stderr
    return proc


@pytest.fixture(scope="session")
def probes(root: Path) -> tuple[np.ndarray, np.ndarray]:
    """The README's probe file as (points, normals)."""
    rows = np.loadtxt(root / "scenes" / "cornell-box.probes.txt")
    return rows[:, :3], rows[:, 3:]


@pytest.fixture(scope="session")
def draft() -> gcr.Solution:
    """The Cornell box solved at draft quality (quick; shared by the tests that only need some
    solution)."""
    return gcr.solve(gcr.Scene.load("cornell-box"), quality="draft")
