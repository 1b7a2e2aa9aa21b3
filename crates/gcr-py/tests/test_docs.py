"""The Python in the package's README and in docs/guide/python.md runs as written."""

from __future__ import annotations

import re
from pathlib import Path

import pytest


def python_blocks(path: Path) -> list[str]:
    return re.findall(r"```python\n(.*?)```", path.read_text(), re.S)


@pytest.fixture
def workdir(root, tmp_path, monkeypatch) -> Path:
    """An empty directory with the repository's scenes/ beside it, as the current directory."""
    (tmp_path / "scenes").symlink_to(root / "scenes")
    monkeypatch.chdir(tmp_path)
    return tmp_path


def test_the_packages_readme_api_block_runs(root, workdir):
    block = python_blocks(root / "crates" / "gcr-py" / "README.md")[0]
    assert len(block.strip().splitlines()) <= 12
    env: dict = {}
    exec(compile(block, "crates/gcr-py/README.md", "exec"), env)
    assert env["values"].shape == (19, 3) and env["img"].shape == (256, 384, 3)
    assert {p.name for p in workdir.iterdir()} >= {"c.png", "c.glb", "c.json"}


def test_the_guides_blocks_run_in_order(root, workdir):
    env: dict = {}
    for block in python_blocks(root / "docs" / "guide" / "python.md"):
        exec(compile(block, "docs/guide/python.md", "exec"), env)
    assert env["values"].shape == (19, 3)
    assert env["df"].shape == (20, 3) and env["df"].min() > 0
