#!/usr/bin/env python3
"""Blender Cycles radiosity at surface points: the peer `cargo xtask bench --only field` runs beside Mitsuba 3.

Usage: cycles_field.py [--guiding] FACES POINTS OUT SPP [SPP ...]

FACES:  one triangle per line, `x0 y0 z0 x1 y1 z1 x2 y2 z2 rho_r rho_g rho_b Ke_r Ke_g Ke_b`
        (Ke = emitted radiance, E = pi*Ke; winding gives the front side), as mitsuba_field.py reads.
POINTS: one point per line, `x y z nx ny nz face` (the surface normal, front side; the face's line in FACES,
        from 0: its reflectance turns the baked light into B).
OUT:    for each SPP, OUT.<spp> gets one line `B_r B_g B_b` per point, and the script prints one line
        `spp=<spp> sampler=<cycles|cycles-guided> scene=<s> load=<s> render=<s>` per bake to stdout.

How (Blender's own baker, as our game and arch-viz users run it; `cycles_scene.py`): each point gets a probe
whose baked light is E/pi; its radiosity is B = pi * (Ke + rho * the probe's mean over its three corners).
`--guiding` turns Cycles' path guiding (Open PGL) on.

Exit code 3 when bpy is not importable (`pip install bpy==5.0.1` under Python 3.11; the bench reads the
interpreter from CYCLES_PYTHON).
"""
import sys
import time

t_start = time.perf_counter()
try:
    import bpy  # noqa: F401
except ImportError as e:  # the bench skips Cycles with a note
    print(f"bpy not importable: {e}", file=sys.stderr)
    sys.exit(3)
import numpy as np

from cycles_scene import add_probes, bake, build_scene  # noqa: E402


def main():
    args = sys.argv[1:]
    guiding = "--guiding" in args
    args = [a for a in args if a != "--guiding"]
    faces_path, points_path, out, *spps = args
    spps = [int(s) for s in spps]
    t0 = time.perf_counter()
    tri = np.loadtxt(faces_path, ndmin=2)
    pts = np.loadtxt(points_path, ndmin=2)
    lo, hi = tri[:, :9].reshape(-1, 3).min(0), tri[:, :9].reshape(-1, 3).max(0)
    diagonal = float(np.linalg.norm(hi - lo))
    build_scene(tri, guiding)
    t_scene = time.perf_counter() - t0
    t0 = time.perf_counter()
    probes = add_probes(pts, diagonal)
    t_load = time.perf_counter() - t0
    face = pts[:, 6].astype(np.int64)
    rho, ke = tri[face, 9:12], tri[face, 12:15]
    for spp in spps:
        t0 = time.perf_counter()
        v = bake(probes, len(pts), spp)
        t_render = time.perf_counter() - t0
        np.savetxt(f"{out}.{spp}", np.pi * (ke + rho * v), fmt="%.9g")
        used = "cycles-guided" if guiding else "cycles"
        print(f"spp={spp} sampler={used} scene={t_scene:.3f} load={t_load:.3f} render={t_render:.3f} "
              f"import={t0 - t_start:.3f}", flush=True)


main()
