"""Errors are Python exceptions with the program's messages; warnings are Python warnings;
outputs are written all or nothing."""

from __future__ import annotations

import numpy as np
import pytest

import gcr
from conftest import run_gcr


def program_error(gcr_bin, *args: str) -> str:
    """The program's message of a failing run (its `error: ` line, without the prefix)."""
    proc = run_gcr(gcr_bin, *args, check=False)
    assert proc.returncode == 1, proc.stderr
    line = next(l for l in proc.stderr.splitlines() if l.startswith("error: "))
    return line.removeprefix("error: ")


def test_an_unknown_scene_raises_the_programs_message(gcr_bin):
    with pytest.raises(gcr.GcrError) as e:
        gcr.Scene.load("cornell-boxx")
    assert str(e.value) == program_error(gcr_bin, "solve", "cornell-boxx")
    assert "did you mean" in str(e.value) or "known:" in str(e.value)


def test_a_missing_file_raises_the_programs_message(gcr_bin, tmp_path):
    missing = str(tmp_path / "nothing.obj")
    with pytest.raises(gcr.GcrError) as e:
        gcr.Scene.load(missing)
    assert str(e.value) == program_error(gcr_bin, "solve", missing)


def test_a_setting_out_of_range_raises_the_programs_message(gcr_bin):
    scene = gcr.Scene.load("cornell-box")
    with pytest.raises(gcr.GcrError) as e:
        gcr.solve(scene, target_error=-1.0)
    assert str(e.value) == program_error(gcr_bin, "solve", "cornell-box", "--target-error=-1")


def test_lights_for_a_flatland_scene_raise_the_programs_message(gcr_bin):
    with pytest.raises(gcr.GcrError) as e:
        gcr.Scene.load("flatland-corner", sun=(135, 40, 80000))
    args = ("solve", "flatland-corner", "--sun", "135,40,80000")
    assert str(e.value) == program_error(gcr_bin, *args)


def test_bad_arguments_raise_value_errors(draft):
    scene = gcr.Scene.load("cornell-box")
    with pytest.raises(ValueError, match="unknown quality"):
        gcr.solve(scene, quality="best")
    with pytest.raises(ValueError, match="cannot be used together"):
        gcr.solve(scene, quality="good", target_error=0.02)
    with pytest.raises(ValueError, match="unknown guiding"):
        gcr.solve(scene, guiding="sometimes")
    with pytest.raises(ValueError, match="invalid sun"):
        gcr.Scene.load("cornell-box", sun="north")
    with pytest.raises(ValueError, match="N×3"):
        draft.radiosity(np.zeros((2, 2)), np.zeros((2, 2)))
    with pytest.raises(ValueError, match="unknown image mode"):
        draft.image(image_mode="photo")


def test_a_point_off_the_surfaces_names_its_row(draft, probes):
    points, normals = (a.copy() for a in probes)
    points[2] += 0.1 * normals[2]
    with pytest.raises(gcr.GcrError, match=r"^points:3: probe is .* from the nearest surface"):
        draft.radiosity(points, normals)
    with pytest.raises(gcr.GcrError, match=r"^points:1: bad probe: zero normal"):
        draft.radiosity(points[:1], np.zeros((1, 3)))


def test_outputs_are_written_all_or_nothing(draft, tmp_path):
    image = tmp_path / "ok.png"
    with pytest.raises(gcr.GcrError, match="directory .* does not exist"):
        draft.write(image=image, mesh=tmp_path / "missing" / "x.glb")
    assert not image.exists()
    with pytest.raises(gcr.GcrError, match="expected a .glb file"):
        draft.write(image=image, mesh=tmp_path / "x.gltf")
    assert list(tmp_path.iterdir()) == []


QUAD = """v 0 0 0
v 1 0 0
v 1 0 1
v 0 0 1
f 1 4 3
f 1 3 2
"""


def test_warnings_are_the_programs_as_python_warnings(gcr_bin, tmp_path):
    """A floor without a material lit by a point light: the loader's warning; then points that
    no light reaches: the gather's."""
    obj = tmp_path / "floor.obj"
    obj.write_text(QUAD)
    proc = run_gcr(gcr_bin, "solve", str(obj), "--point-light", "0.5,1,0.5,100", check=False)
    program = [l.removeprefix("warning: ") for l in proc.stderr.splitlines() if l.startswith("warning: ")]
    with pytest.warns(gcr.GcrWarning) as caught:
        scene = gcr.Scene.load(obj, point_lights=[(0.5, 1, 0.5, 100)])
    assert [str(w.message) for w in caught] == program[:1]
    assert "without material" in program[0]
    solution = gcr.solve(scene, quality="draft")
    with pytest.warns(gcr.GcrWarning, match="every output point got 0"):
        values, _ = solution.irradiance([[0.5, -1.0, 0.5]], [[0.0, -1.0, 0.0]])
    assert values.tolist() == [[0.0, 0.0, 0.0]]
