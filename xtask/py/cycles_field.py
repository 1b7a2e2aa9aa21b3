#!/usr/bin/env python3
"""Blender Cycles radiosity at surface points: the peer `cargo xtask bench --only field` runs beside Mitsuba 3.

Usage: cycles_field.py [--guiding] [--emitters JSON] FACES POINTS OUT SPP [SPP ...]

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

from cycles_scene import PROBE_LIFT, bake, run_at_points  # noqa: E402


def radiosity(tri, pts, probes, spp):
    """B = pi (Ke + rho E/pi) at each point, from its face's rho and Ke and its probe's bake."""
    face = pts[:, 6].astype(np.int64)
    rho, ke = tri[face, 9:12], tri[face, 12:15]
    return np.pi * (ke + rho * bake(probes, len(pts), spp))


run_at_points(sys.argv[1:], t_start, PROBE_LIFT, radiosity)
