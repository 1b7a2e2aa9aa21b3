"""Images as NumPy arrays (mesh and pixel modes) and the image files."""

from __future__ import annotations

import numpy as np

import gcr


def test_mesh_and_pixel_images_are_linear_radiance(draft):
    mesh = draft.image(resolution=(48, 32))
    pixel = draft.image(resolution=(48, 32), image_mode="pixel")
    for img in (mesh, pixel):
        assert img.shape == (32, 48, 3) and img.dtype == np.float32
        assert np.all(np.isfinite(img)) and np.all(img >= 0) and img.mean() > 0
    # the same scene through the same camera: the two modes agree on the mean radiance
    assert abs(mesh.mean() / pixel.mean() - 1.0) < 0.1


def test_a_given_camera_is_used(draft):
    eye, target = (0.278, 0.273, -0.8), (0.278, 0.273, 0.0)
    img = draft.image(camera_eye=eye, camera_target=target, fov=39, resolution=(16, 16))
    assert img.shape == (16, 16, 3)
    # looking away from the box: nothing is seen
    away = draft.image(camera_eye=eye, camera_target=(0.278, 0.273, -2.0), resolution=(16, 16))
    assert away.max() == 0.0


def test_the_writers_write_every_format(draft, tmp_path):
    files = {
        "image": tmp_path / "a.exr",
        "mesh": tmp_path / "a.glb",
        "ply": tmp_path / "a.ply",
        "metrics": tmp_path / "a.json",
    }
    metrics = draft.write(**files, views=[(tmp_path / "v.png", (0.3, 0.3, -0.5), (0.3, 0.3, 0.3))])
    assert all(p.stat().st_size > 0 for p in files.values())
    assert (tmp_path / "v.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert metrics["scene"] == "cornell-box" and metrics["output_vertices"] > 0
    assert [i["camera_source"] for i in metrics["images"]] == ["scene", "view"]
