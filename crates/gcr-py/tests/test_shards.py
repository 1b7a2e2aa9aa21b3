"""Sharded bakes (issue 34): `Solution.shard_values` gives each shard's rows exactly as one
solve gives them, and `gcr.distributed` runs the shards on a local Dask cluster of worker
processes, byte for byte against the single run (and against `gcr solve --shard` + `gcr merge`);
a lightmap baked in shards (`Solution.write(shard=...)`, `from_shards`, and
`gcr.distributed.bake_lightmap`) is the single bake's files, byte for byte, and so is a per-pixel
image (`gcr.distributed.render_image`).
"""

from __future__ import annotations

import subprocess

import numpy as np
import pytest

import gcr

BLOCK = 48


def floor_and_wall(n: int) -> tuple[np.ndarray, np.ndarray]:
    """`n` points on the Cornell box's floor (facing up) and back wall (facing the room)."""
    i = np.arange(n)
    u, v = (i * 0.618034) % 1.0, (i * 0.754878) % 1.0
    x, z = 0.02 + 0.5 * u, 0.02 + 0.5 * v
    floor = i % 2 == 0
    points = np.where(floor[:, None], np.c_[x, 0 * x, z], np.c_[x, z, 0 * x + 0.5592])
    normals = np.where(floor[:, None], [0.0, 1.0, 0.0], [0.0, 0.0, -1.0])
    return points, normals


@pytest.fixture(scope="module")
def single():
    points, normals = floor_and_wall(400)
    solution = gcr.solve(gcr.Scene.load("cornell-box"), quality="draft", block_points=BLOCK)
    return points, normals, solution, solution.radiosity(points, normals)


def test_shards_are_the_single_solves_rows(single):
    points, normals, solution, (values, errors) = single
    seen = np.zeros(len(points), dtype=int)
    for k in range(3):
        rows, v, e = solution.shard_values(points, normals, shard=(k, 3))
        assert np.all(np.diff(rows.astype(np.int64)) > 0)
        assert np.array_equal(v, values[rows]) and np.array_equal(e, errors[rows])
        seen[rows] += 1
    assert np.all(seen == 1)


def test_too_many_shards_and_bad_shards_are_errors(single):
    points, normals, solution, _ = single
    with pytest.raises(gcr.GcrError, match="fewer than the shards"):
        solution.shard_values(points, normals, shard=(999, 1000))
    with pytest.raises(ValueError, match="0 <= index < count"):
        solution.shard_values(points, normals, shard=(3, 3))


def test_a_dask_cluster_gives_the_single_runs_bytes(single, gcr_bin, tmp_path):
    distributed = pytest.importorskip("dask.distributed")
    import gcr.distributed

    points, normals, _, (values, errors) = single
    cluster = distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
    )
    with cluster, distributed.Client(cluster) as client:
        got, got_errors = gcr.distributed.shard_values(
            client, "cornell-box", points, normals, shards=4, block_points=BLOCK,
            solve={"quality": "draft"}, timeout=120,
        )
        # each worker process solved once and ran its shards
        assert len(client.scheduler_info()["workers"]) == 2
        # a lightmap the same way: the program's single bake, byte for byte
        dask_dir = tmp_path / "dask"
        dask_dir.mkdir()
        gcr.distributed.bake_lightmap(
            client, "cornell-box", str(dask_dir / "room.glb"), shards=3, block_points=LM_BLOCK,
            write=LM_OPTS, solve={"quality": "draft"}, timeout=120,
        )
        # and a per-pixel image
        gcr.distributed.render_image(
            client, "cornell-box", str(dask_dir / "view.exr"), shards=3, block_points=IMG_BLOCK,
            write=IMG_OPTS, solve={"quality": "draft"}, timeout=120,
        )
    cli_dir = tmp_path / "cli"
    cli_dir.mkdir()
    subprocess.run(
        [gcr_bin, "solve", "cornell-box", "--lightmap", cli_dir / "room.glb", "--quality", "draft",
         "--block-points", str(LM_BLOCK), "--lightmap-density", str(LM_OPTS["lightmap_density"])],
        check=True, capture_output=True,
    )
    subprocess.run(
        [gcr_bin, "solve", "cornell-box", "--image", cli_dir / "view.exr", "--image-mode", "pixel",
         "--resolution", "24x20", "--quality", "draft", "--block-points", str(IMG_BLOCK)],
        check=True, capture_output=True,
    )
    assert same_files(dask_dir, cli_dir)
    assert got.tobytes() == values.tobytes() and got_errors.tobytes() == errors.tobytes()
    # and the program's sharded run, merged, has the same numbers
    pts = tmp_path / "in.pts"
    np.savetxt(pts, np.c_[points, normals], fmt="%.17g")
    parts = []
    for k in range(2):
        part = tmp_path / f"part{k}.txt"
        subprocess.run(
            [gcr_bin, "solve", "cornell-box", "--probes", pts, "--probe-out", part,
             "--quality", "draft", "--block-points", str(BLOCK), "--shard", f"{k}/2"],
            check=True, capture_output=True,
        )
        parts.append(part)
    merged = tmp_path / "merged.txt"
    subprocess.run([gcr_bin, "merge", *parts, "--probe-out", merged], check=True, capture_output=True)
    assert np.array_equal(np.loadtxt(merged), values)


LM_BLOCK = 128
LM_OPTS = {"lightmap_density": 30}
IMG_BLOCK = 48
IMG_OPTS = {"resolution": (24, 20)}


def same_files(a, b) -> bool:
    """Whether folders `a` and `b` hold the same names with the same bytes."""
    names = sorted(p.name for p in a.iterdir())
    assert names == sorted(p.name for p in b.iterdir()), names
    return all((a / n).read_bytes() == (b / n).read_bytes() for n in names)


def test_a_lightmap_baked_in_shards_is_the_single_bake(tmp_path):
    solution = gcr.solve(gcr.Scene.load("cornell-box"), quality="draft", block_points=LM_BLOCK)
    single, parts, merged = (tmp_path / n for n in ("single", "parts", "merged"))
    for d in (single, parts, merged):
        d.mkdir()
    solution.write(lightmap=single / "room.glb", **LM_OPTS)
    for k in (2, 0, 1):
        solution.write(lightmap=parts / "room.glb", shard=(k, 3), **LM_OPTS)
    assert sorted(p.name for p in parts.iterdir()) == [f"room.shard-{k}-of-3.txt" for k in range(3)]
    solution.write(lightmap=merged / "room.glb", from_shards=sorted(parts.iterdir()), **LM_OPTS)
    assert same_files(single, merged)
    with pytest.raises(gcr.GcrError, match="shard 1/3 is missing"):
        solution.write(lightmap=tmp_path / "x.glb", from_shards=[parts / "room.shard-0-of-3.txt"], **LM_OPTS)
    with pytest.raises(ValueError, match="0 <= index < count"):
        solution.write(lightmap=tmp_path / "x.glb", shard=(3, 3), **LM_OPTS)
    assert not (tmp_path / "x.glb").exists()


def test_an_image_rendered_in_shards_is_the_single_image(tmp_path):
    solution = gcr.solve(gcr.Scene.load("cornell-box"), quality="draft", block_points=IMG_BLOCK)
    opts = {"image_mode": "pixel", **IMG_OPTS}
    solution.write(image=tmp_path / "single.exr", **opts)
    for k in (1, 0):
        solution.write(image=tmp_path / "view.exr", shard=(k, 2), **opts)
    assert not (tmp_path / "view.exr").exists()
    parts = [tmp_path / f"view.shard-{k}-of-2.txt" for k in range(2)]
    solution.write(image=tmp_path / "view.exr", from_shards=parts, **opts)
    assert (tmp_path / "view.exr").read_bytes() == (tmp_path / "single.exr").read_bytes()
    with pytest.raises(gcr.GcrError, match="from the automatic camera"):
        solution.write(image=tmp_path / "x.exr", shard=(0, 2), auto_camera=True, **opts)


def test_unaligned_arrays_are_read_as_aligned_ones(single):
    """Dask hands workers numpy arrays out of message buffers, at unaligned addresses: viewing
    them panicked ("The pointer must be aligned")."""
    points, normals, solution, (values, _) = single
    buf = np.zeros(points.nbytes + 1, dtype=np.uint8)
    unaligned = np.frombuffer(buf.data, dtype=np.uint8, count=points.nbytes, offset=1).view(np.float64)
    unaligned = unaligned.reshape(points.shape)
    unaligned[:] = points
    assert not unaligned.flags.aligned
    got, _ = solution.radiosity(unaligned, normals)
    assert np.array_equal(got, values)
