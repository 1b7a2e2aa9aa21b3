"""Python gives exactly the program's numbers: the README's main job (files) and its probes."""

from __future__ import annotations

import json
import re
import shlex
from pathlib import Path

import numpy as np
import pytest

import gcr
from conftest import run_gcr

# fields of the metrics that measure the run, not the result
TIMINGS = {"seconds", "peak_memory_bytes"}


def readme_python_block(root: Path) -> str:
    """The README's first ```python block."""
    text = (root / "README.md").read_text()
    match = re.search(r"```python\n(.*?)```", text, re.S)
    assert match, "README.md has a ```python block"
    return match.group(1)


def readme_main_command(root: Path) -> list[str]:
    """The README's main command as `gcr` arguments."""
    text = (root / "README.md").read_text()
    line = next(l for l in text.splitlines() if l.startswith("cargo run --release -p gcr-cli -- solve "))
    return shlex.split(line.split(" -- ", 1)[1])


def without_timings(metrics: dict) -> dict:
    return {k: v for k, v in metrics.items() if k not in TIMINGS}


def test_readme_python_block_is_five_lines(root):
    assert len(readme_python_block(root).strip().splitlines()) == 5


def test_readme_python_block_reproduces_the_main_command(root, gcr_bin, tmp_path, monkeypatch):
    program, python = tmp_path / "program", tmp_path / "python"
    program.mkdir()
    python.mkdir()
    args = readme_main_command(root)
    run_gcr(gcr_bin, *args, "--quiet", cwd=program)
    monkeypatch.chdir(python)
    exec(compile(readme_python_block(root), "README.md", "exec"), {})
    outputs = [args[i + 1] for i, a in enumerate(args) if a in ("--image", "--mesh", "--metrics")]
    assert sorted(p.name for p in python.iterdir()) == sorted(outputs)
    for name in outputs:
        a, b = (program / name).read_bytes(), (python / name).read_bytes()
        if name.endswith(".json"):
            assert without_timings(json.loads(a)) == without_timings(json.loads(b))
        else:
            assert a == b, f"{name} differs"


def test_probes_give_the_programs_numbers_bit_for_bit(root, gcr_bin, tmp_path, probes):
    probe_file = root / "scenes" / "cornell-box.probes.txt"
    out = tmp_path / "x.txt"
    run_gcr(gcr_bin, "solve", "cornell-box", "--probes", str(probe_file), "--probe-out", str(out), "--quiet")
    program = np.array([[float(v) for v in line.split()] for line in out.read_text().splitlines()])
    solution = gcr.solve(gcr.Scene.load("cornell-box"))
    values, std_errors = solution.radiosity(*probes)
    assert values.dtype == np.float64 and values.shape == (len(probe_file.read_text().splitlines()), 3)
    assert std_errors.shape == values.shape and np.all(std_errors >= 0) and std_errors.max() > 0
    assert np.array_equal(values, program)
    # the program's writer through Python: the same bytes
    written = tmp_path / "y.txt"
    solution.write(probes=probe_file, probe_out=written)
    assert written.read_bytes() == out.read_bytes()


@pytest.mark.parametrize("denoise", [False, True])
def test_lightmaps_are_the_programs_bytes(gcr_bin, tmp_path, denoise):
    """`Solution.write(lightmap=...)` writes the glTF and the EXR pages `gcr solve --lightmap`
    writes, byte for byte (issue 33: lightmaps from Python), denoised too
    (`lightmap_denoise=True`, `--lightmap-denoise`), whose metrics say what the denoiser did."""
    (tmp_path / "cli").mkdir()
    (tmp_path / "py").mkdir()
    args = ["--lightmap-size", "128", "--lightmap-quantity", "radiosity", "--quality", "draft"]
    args += ["--lightmap-denoise"] if denoise else []
    run_gcr(gcr_bin, "solve", "cornell-box", "--lightmap", str(tmp_path / "cli" / "b.glb"), *args, "--quiet")
    solution = gcr.solve(gcr.Scene.load("cornell-box"), quality="draft")
    metrics = solution.write(lightmap=tmp_path / "py" / "b.glb", lightmap_size=128, lightmap_quantity="radiosity",
                             lightmap_denoise=denoise)
    cli = sorted(p.name for p in (tmp_path / "cli").iterdir())
    assert cli == sorted(p.name for p in (tmp_path / "py").iterdir()) and len(cli) >= 2, cli
    for name in cli:
        assert (tmp_path / "cli" / name).read_bytes() == (tmp_path / "py" / name).read_bytes(), name
    denoised = metrics["lightmap"]["denoised"]
    if denoise:
        assert denoised["raw_error"] > metrics["relative_std_error"] > 0, denoised
    else:
        assert denoised is None
    with pytest.raises(ValueError, match="unknown lightmap quantity"):
        solution.write(lightmap=tmp_path / "py" / "c.glb", lightmap_quantity="albedo")


def test_irradiance_gives_the_programs_numbers(root, gcr_bin, tmp_path, probes):
    probe_file = root / "scenes" / "cornell-box.probes.txt"
    out = tmp_path / "e.txt"
    run_gcr(gcr_bin, "solve", "cornell-box", "--quality", "draft", "--probes", str(probe_file),
            "--probe-out", str(out), "--probe-quantity", "irradiance", "--quiet")
    program = np.loadtxt(out)
    values, _ = gcr.solve(gcr.Scene.load("cornell-box"), quality="draft").irradiance(*probes)
    assert np.array_equal(values, program)


def test_lights_are_the_programs(root, gcr_bin, tmp_path):
    """A daylit room: the sky, the sun and the daylight factors as the program's options."""
    pts = np.loadtxt(root / "scenes" / "side-lit-room.pts")
    out = tmp_path / "df.txt"
    scene_file = root / "scenes" / "side-lit-room.obj"
    run_gcr(gcr_bin, "solve", str(scene_file), "--sky", "cie-overcast:10000", "--quality", "draft",
            "--probes", str(root / "scenes" / "side-lit-room.pts"), "--probe-out", str(out),
            "--probe-quantity", "daylight-factor", "--quiet")
    scene = gcr.Scene.load(scene_file, sky="cie-overcast:10000")
    values, _ = gcr.solve(scene, quality="draft").daylight_factor(pts[:, :3], pts[:, 3:])
    assert np.array_equal(values, np.loadtxt(out).reshape(values.shape))


def test_flatland_points_and_kernel_image_are_the_programs(root, gcr_bin, tmp_path):
    """A Flatland scene: N×2 points give the program's probe values; a kernel image (which reads
    the networks the default solve skips) is trained for the write, as the program trains for it."""
    probe_file = root / "scenes" / "flatland-corner.probes.txt"
    out, kernel = tmp_path / "b.txt", tmp_path / "k.png"
    run_gcr(gcr_bin, "solve", "flatland-corner", "--probes", str(probe_file), "--probe-out", str(out),
            "--kernel-image", str(kernel), "--quiet")
    rows = np.loadtxt(probe_file)
    solution = gcr.solve(gcr.Scene.load("flatland-corner"))
    assert not solution.networks_trained
    values, _ = solution.radiosity(rows[:, :2], rows[:, 2:])
    program = np.loadtxt(out).reshape(len(rows), -1)
    assert values.shape == program.shape and np.array_equal(values, program)
    mine = tmp_path / "mine.png"
    solution.write(kernel_image=mine)
    assert mine.read_bytes() == kernel.read_bytes()
