#!/usr/bin/env python3
"""Blender Cycles irradiance at points (Radiance's `rtrace -I`), the peer of `mitsuba_irradiance.py`.

Usage: cycles_irradiance.py [--guiding] [--emitters JSON] FACES POINTS OUT SPP [SPP ...]

FACES:  one triangle per line, as mitsuba_field.py.
POINTS: one point per line, `x y z nx ny nz`: in the air, n the unit normal of the hemisphere whose
        irradiance E = ∫ L cos θ dω is wanted.
OUT:    for each SPP, OUT.<spp> gets one line `E_r E_g E_b se_r se_g se_b` per point (se: standard error),
        and the script prints `spp=<spp> sampler=<cycles|cycles-guided> scene=<s> load=<s> render=<s>` per
        SPP to stdout.
--emitters JSON: a list of lights as the Mitsuba dicts `mitsuba_irradiance.py` reads (point, directional,
        constant, cie-overcast: `cycles_scene.py`).

Each point gets a probe (`cycles_scene.py`): Cycles' baker gives E/pi there. Two bakes per SPP with seeds 0
and 1: E is their mean, the standard error half their difference; the seconds are both bakes'.
Exit code 3 when bpy is not importable.
"""
import json
import sys
import time

t_start = time.perf_counter()
try:
    import bpy  # noqa: F401
except ImportError as e:  # the bench skips Cycles with a note
    print(f"bpy not importable: {e}", file=sys.stderr)
    sys.exit(3)
import numpy as np

from cycles_scene import add_lights, add_probes, bake, build_scene  # noqa: E402


def main():
    args = sys.argv[1:]
    guiding = "--guiding" in args
    args = [a for a in args if a != "--guiding"]
    emitters = []
    if "--emitters" in args:
        i = args.index("--emitters")
        with open(args[i + 1]) as f:
            emitters = json.load(f)
        args = args[:i] + args[i + 2:]
    faces_path, points_path, out, *spps = args
    spps = [int(s) for s in spps]
    t0 = time.perf_counter()
    tri = np.loadtxt(faces_path, ndmin=2)
    pts = np.loadtxt(points_path, ndmin=2)
    lo, hi = tri[:, :9].reshape(-1, 3).min(0), tri[:, :9].reshape(-1, 3).max(0)
    build_scene(tri, guiding)
    add_lights(emitters)
    t_scene = time.perf_counter() - t0
    t0 = time.perf_counter()
    probes = add_probes(pts, float(np.linalg.norm(hi - lo)), lift=0.0)
    t_load = time.perf_counter() - t0
    for spp in spps:
        t0 = time.perf_counter()
        runs = [np.pi * bake(probes, len(pts), spp, seed) for seed in (0, 1)]
        t_render = time.perf_counter() - t0
        e, se = 0.5 * (runs[0] + runs[1]), 0.5 * np.abs(runs[0] - runs[1])
        np.savetxt(f"{out}.{spp}", np.hstack([e, se]), fmt="%.9g")
        used = "cycles-guided" if guiding else "cycles"
        print(f"spp={spp} sampler={used} scene={t_scene:.3f} load={t_load:.3f} render={t_render:.3f} "
              f"import={t0 - t_start:.3f}", flush=True)


main()
