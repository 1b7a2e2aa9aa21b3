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
of the paths gather). Any Dask cluster works (``dask-jobqueue`` on Slurm or PBS,
``dask-kubernetes``); the scene's files must be readable at the same path on every worker.
Dask is imported only when this module is used (``pip install "dask[distributed]"``).
"""

from __future__ import annotations

import functools
import json
from typing import Any

import numpy as np

import gcr

__all__ = ["shard_values"]


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
    # a canonical text of the settings: the key of each worker's cached solution
    settings = json.dumps(
        {"scene": str(scene), "load": load or {}, "solve": {**(solve or {}), "block_points": block_points}},
        sort_keys=True,
    )
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


def _shard(settings: str, at: tuple, shard: tuple[int, int], quantity: str, tolerance):
    """One shard on a worker: its rows, values and standard errors."""
    points, normals = at
    try:
        solution = _solution(settings)
        return solution.shard_values(
            points, normals, shard=shard, quantity=quantity, tolerance=tolerance
        )
    except BaseException as e:
        # a Rust panic arrives as pyo3's PanicException, a BaseException, which Dask's workers
        # do not report (the task would never end): raise it as an ordinary error
        if type(e).__name__ == "PanicException":
            raise RuntimeError(f"gcr panicked in shard {shard}: {e}") from None
        raise


@functools.lru_cache(maxsize=4)
def _solution(settings: str) -> gcr.Solution:
    """The scene loaded and solved once per worker process and settings."""
    s = json.loads(settings)
    scene = gcr.Scene.load(s["scene"], **s["load"])
    return gcr.solve(scene, **s["solve"])
