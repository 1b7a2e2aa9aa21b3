"""Embree's ray throughput on the triangles and rays gcr's `rays` bench writes (issue 36 item 2).

Usage: python embree_rays.py TRIS.f32 RAYS.f32 TMAX THREADS

TRIS.f32: float32 triangles (9 numbers each); RAYS.f32: float32 rays (origin xyz, unit direction
xyz). Builds an Embree scene through `embreex` (Embree 4), then times closest-hit queries
(`INTERSECT`, t in (0, inf)) and occlusion queries (`OCCLUDED`, t in (0, TMAX)) over all rays,
THREADS processes each taking a contiguous share of the rays with its own copy of the scene (the
queries of `embreex` loop over rtcIntersect1/rtcOccluded1 in C; the wall time of the slowest
process counts; best of three runs of each kind). Prints one JSON line: build seconds, seconds per query kind, hits and the sum of
hit distances (for agreement with gcr), or {"skipped": why} when embreex is missing.
"""
import json
import sys
import time
from multiprocessing import Pool


def load(tris_path, rays_path):
    import numpy as np

    tris = np.fromfile(tris_path, dtype=np.float32).reshape(-1, 3, 3)
    rays = np.fromfile(rays_path, dtype=np.float32).reshape(-1, 6)
    return tris, rays


def work(args):
    tris_path, rays_path, tmax, lo, hi = args
    import numpy as np
    from embreex import rtcore_scene as rtcs
    from embreex.mesh_construction import TriangleMesh

    tris, rays = load(tris_path, rays_path)
    t0 = time.perf_counter()
    scene = rtcs.EmbreeScene()
    TriangleMesh(scene, tris)
    origins = np.ascontiguousarray(rays[lo:hi, :3])
    dirs = np.ascontiguousarray(rays[lo:hi, 3:])
    # the first query commits (builds) the scene: time it apart on one ray
    scene.run(origins[:1], dirs[:1], query="OCCLUDED")
    build = time.perf_counter() - t0
    # best of three runs of each query kind, as gcr's side
    intersect, occluded = float("inf"), float("inf")
    for _ in range(3):
        dists = np.full(len(origins), tmax, dtype=np.float32)
        t1 = time.perf_counter()
        hit = scene.run(origins, dirs, query="INTERSECT", output=1)
        t2 = time.perf_counter()
        occ = scene.run(origins, dirs, dists=dists, query="OCCLUDED")
        t3 = time.perf_counter()
        intersect, occluded = min(intersect, t2 - t1), min(occluded, t3 - t2)
    got = hit["primID"] >= 0
    return {
        "build": build,
        "intersect": intersect,
        "occluded": occluded,
        "hits": int(got.sum()),
        "t_sum": float(hit["tfar"][got].astype(np.float64).sum()),
        "occluded_count": int((np.asarray(occ) >= 0).sum()),
    }


def main():
    try:
        import embreex  # noqa: F401
        import numpy  # noqa: F401
    except ImportError as e:
        print(json.dumps({"skipped": f"embreex not importable ({e}); pip install embreex numpy"}))
        return
    tris_path, rays_path, tmax, threads = sys.argv[1], sys.argv[2], float(sys.argv[3]), int(sys.argv[4])
    _, rays = load(tris_path, rays_path)
    n = len(rays)
    cuts = [n * k // threads for k in range(threads + 1)]
    jobs = [(tris_path, rays_path, tmax, cuts[k], cuts[k + 1]) for k in range(threads)]
    with Pool(threads) as pool:
        parts = pool.map(work, jobs)
    print(json.dumps({
        "build": max(p["build"] for p in parts),
        "intersect": max(p["intersect"] for p in parts),
        "occluded": max(p["occluded"] for p in parts),
        "hits": sum(p["hits"] for p in parts),
        "t_sum": sum(p["t_sum"] for p in parts),
        "occluded_count": sum(p["occluded_count"] for p in parts),
    }))


if __name__ == "__main__":
    main()
