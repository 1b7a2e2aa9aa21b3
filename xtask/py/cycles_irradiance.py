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
import sys
import time

t_start = time.perf_counter()
try:
    import bpy  # noqa: F401
except ImportError as e:  # the bench skips Cycles with a note
    print(f"bpy not importable: {e}", file=sys.stderr)
    sys.exit(3)
import numpy as np

from cycles_scene import bake, run_at_points  # noqa: E402


def irradiance(tri, pts, probes, spp):
    """E = pi * the probe's bake, the mean of seeds 0 and 1, and half their difference (its standard error)."""
    runs = [np.pi * bake(probes, len(pts), spp, seed) for seed in (0, 1)]
    return np.hstack([0.5 * (runs[0] + runs[1]), 0.5 * np.abs(runs[0] - runs[1])])


run_at_points(sys.argv[1:], t_start, 0.0, irradiance)
