"""Sharded bakes on a Dask cluster: the points split into shards, each shard estimated by a
worker, the values joined in the points' order, bit for bit those of one solve.

Each worker process loads the scene and solves it once (the first shard it runs; later shards
reuse the solution), and the points reach every worker once (scattered with ``broadcast``).
Nothing but the scene's name or path, the options and the shard numbers travel with a task::

    from dask.distributed import Client, LocalCluster
    import gcr.distributed

    with Client(LocalCluster(n_workers=4, threads_per_worker=1)) as client:
        values, std_errors = gcr.distributed.shard_values(
            client, "building.glb", points, normals, shards=16, block_points=2000,
            load={"sky": "cie-overcast:10000"}, quantity="irradiance")

equals ``gcr.solve(gcr.Scene.load("building.glb", sky=...), block_points=2000)
.irradiance(points, normals)`` exactly (``Solution.shard_values``: the shards are whole blocks
of the paths gather). A lightmap the same way: ``bake_lightmap(client, "level.glb",
"out/level.glb", shards=16, block_points=4096, write={"lightmap_density": 40})`` writes the files
``Solution.write(lightmap=..., ...)`` writes, byte for byte (each worker bakes its shard's texels
with ``Solution.write(shard=...)``; the client merges them with ``from_shards``), and a per-pixel
image from a fixed camera: ``render_image(client, "hall.glb", "hall.exr", shards=16,
block_points=1024, write={"resolution": (1920, 1080)})``. Any Dask cluster works (``dask-jobqueue`` on Slurm or PBS,
``dask-kubernetes``); the scene's files must be readable at the same path on every worker.
Dask is imported only when this module is used (``pip install "dask[distributed]"``). Give each
worker one Dask thread and leave the gather's threads at their default (every core): the last
shard then runs on the cores the others left (docs/design/sharding.md).
"""

from __future__ import annotations

import functools
import json
import os
import tempfile
from typing import Any

import numpy as np

import gcr

__all__ = ["bake_lightmap", "render_image", "shard_values"]


def shard_values(
    client: Any,
    scene: str,
    points: Any,
    normals: Any,
    *,
    shards: int,
    block_points: int,
    quantity: str = "radiosity",
    tolerance: float | None = None,
    load: dict[str, Any] | None = None,
    solve: dict[str, Any] | None = None,
    timeout: float | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """The values and standard errors at ``points`` (N × 3) with ``normals``, as
    ``gcr.solve(gcr.Scene.load(scene, **load), block_points=block_points, **solve)`` and its
    :meth:`~gcr.Solution.radiosity` (``quantity="radiosity"``), ``irradiance`` or
    ``daylight_factor`` give them, computed as ``shards`` shards on the Dask ``client``'s
    workers. ``scene``: a file path (the same on every worker) or a built-in name; ``load`` and
    ``solve``: keyword arguments of :meth:`gcr.Scene.load` and :func:`gcr.solve` (JSON values);
    ``timeout``: seconds to wait for all shards (``TimeoutError`` after), default forever.
    """
    from dask.distributed import wait

    if shards < 1:
        raise ValueError(f"shards {shards}: at least 1")
    points = np.ascontiguousarray(points, dtype=np.float64)
    normals = np.ascontiguousarray(normals, dtype=np.float64)
    settings = _settings(scene, load, solve, block_points)
    # unique keys: a later call with the same arrays must not meet this one's release
    at = client.scatter((points, normals), broadcast=True, hash=False)
    futures = [
        client.submit(_shard, settings, at, (i, shards), quantity, tolerance, pure=False)
        for i in range(shards)
    ]
    wait(futures, timeout=timeout)
    values = errors = None
    for rows, v, e in client.gather(futures):
        if values is None:
            values = np.empty((len(points), v.shape[1]))
            errors = np.empty((len(points), e.shape[1]))
            seen = np.zeros(len(points), dtype=bool)
        values[rows], errors[rows] = v, e
        seen[rows] = True
    if values is None or not seen.all():
        raise gcr.GcrError("the shards did not cover every point")
    return values, errors


def bake_lightmap(
    client: Any,
    scene: str,
    lightmap: str,
    *,
    shards: int,
    block_points: int,
    write: dict[str, Any] | None = None,
    load: dict[str, Any] | None = None,
    solve: dict[str, Any] | None = None,
    timeout: float | None = None,
) -> dict[str, Any]:
    """Writes the lightmap ``lightmap`` (a .glb, its EXR pages beside it) as
    ``gcr.solve(gcr.Scene.load(scene, **load), block_points=block_points, **solve)
    .write(lightmap=lightmap, **write)`` writes it, byte for byte, its texels estimated as
    ``shards`` shards on the Dask ``client``'s workers; returns the metrics of the writing run.
    ``write``: the lightmap options of :meth:`gcr.Solution.write` (``lightmap_density``,
    ``lightmap_size``, ``lightmap_padding``, ``lightmap_quantity``, ``lightmap_denoise``); the
    rest as :func:`shard_values`. Each worker returns its shard's part as text, so no file system is
    shared; the client lays the atlas out again and writes the files.
    """
    settings = _settings(scene, load, solve, block_points)
    return _sharded_write(client, settings, ("lightmap", lightmap), shards, write or {}, timeout)


def render_image(
    client: Any,
    scene: str,
    image: str,
    *,
    shards: int,
    block_points: int,
    write: dict[str, Any] | None = None,
    load: dict[str, Any] | None = None,
    solve: dict[str, Any] | None = None,
    timeout: float | None = None,
) -> dict[str, Any]:
    """Writes the per-pixel image ``image`` (.exr, .png, .jpg) as ``gcr.solve(gcr.Scene.load(
    scene, **load), block_points=block_points, **solve).write(image=image, image_mode="pixel",
    **write)`` writes it, byte for byte, its pixels estimated as ``shards`` shards on the Dask
    ``client``'s workers (the blocks are strips of whole rows of at least ``block_points``
    pixels; a row or a few balance the shards best and cost the rounds little); returns the
    metrics of the writing run. ``write``: the camera and image options of
    :meth:`gcr.Solution.write`, a fixed camera (``camera_eye`` and ``camera_target``, or the
    scene's: not ``auto_camera``), ``resolution``, ``exposure``; the rest as :func:`shard_values`.
    """
    settings = _settings(scene, load, solve, block_points)
    write = {"image_mode": "pixel", **(write or {})}
    return _sharded_write(client, settings, ("image", image), shards, write, timeout)


def _sharded_write(
    client: Any,
    settings: str,
    target: tuple[str, str],
    shards: int,
    write: dict[str, Any],
    timeout: float | None,
) -> dict[str, Any]:
    """The output ``target`` (``(keyword, path)`` of :meth:`gcr.Solution.write`: a lightmap or an
    image) written from ``shards`` shards run on the workers, each returning its part as text."""
    from dask.distributed import wait

    if shards < 1:
        raise ValueError(f"shards {shards}: at least 1")
    key, path = target
    suffix = os.path.splitext(str(path))[1] or ".out"
    futures = [
        client.submit(_part, settings, (key, suffix), (i, shards), write, pure=False)
        for i in range(shards)
    ]
    wait(futures, timeout=timeout)
    texts = client.gather(futures)
    with tempfile.TemporaryDirectory() as d:
        parts = []
        for i, text in enumerate(texts):
            parts.append(os.path.join(d, f"part-{i}-of-{shards}.txt"))
            with open(parts[-1], "w", encoding="utf-8") as f:
                f.write(text)
        return _solution(settings).write(**{key: path}, from_shards=parts, **write)


def _settings(scene: str, load: dict | None, solve: dict | None, block_points: int) -> str:
    """A canonical text of the settings: the key of each worker's cached solution."""
    return json.dumps(
        {"scene": str(scene), "load": load or {}, "solve": {**(solve or {}), "block_points": block_points}},
        sort_keys=True,
    )


def _shard(settings: str, at: tuple, shard: tuple[int, int], quantity: str, tolerance):
    """One shard on a worker: its rows, values and standard errors."""
    points, normals = at
    with _reported(shard):
        solution = _solution(settings)
        return solution.shard_values(
            points, normals, shard=shard, quantity=quantity, tolerance=tolerance
        )


def _part(settings: str, target: tuple[str, str], shard: tuple[int, int], write: dict) -> str:
    """One shard of a lightmap or an image on a worker: its part (``Solution.write(shard=...)``,
    ``NAME.shard-I-of-N.txt``) as text. ``target``: the output's keyword and file extension."""
    key, suffix = target
    with _reported(shard), tempfile.TemporaryDirectory() as d:
        _solution(settings).write(**{key: os.path.join(d, "out" + suffix)}, shard=shard, **write)
        part = os.path.join(d, f"out.shard-{shard[0]}-of-{shard[1]}.txt")
        with open(part, encoding="utf-8") as f:
            return f.read()


class _reported:
    """Raises a Rust panic in a shard as an ordinary error: it arrives as pyo3's
    PanicException, a BaseException, which Dask's workers do not report (the task would never
    end)."""

    def __init__(self, shard: tuple[int, int]):
        self.shard = shard

    def __enter__(self):
        return self

    def __exit__(self, kind, e, tb):
        if kind is not None and kind.__name__ == "PanicException":
            raise RuntimeError(f"gcr panicked in shard {self.shard}: {e}") from None
        return False


@functools.lru_cache(maxsize=4)
def _solution(settings: str) -> gcr.Solution:
    """The scene loaded and solved once per worker process and settings."""
    s = json.loads(settings)
    scene = gcr.Scene.load(s["scene"], **s["load"])
    return gcr.solve(scene, **s["solve"])
