#!/usr/bin/env python3
"""Mitsuba 3's samplers in a closed furnace: is each one unbiased?

Usage: mitsuba_furnace.py [RHO] [SPP ...]   (defaults: 0.5, and 256 1024)

A unit cube whose six inward faces all emit exitance E = 1 (radiance 1/pi) and reflect rho (grey): the
exact radiance everywhere is L = E / (pi (1 - rho)). Each sampler renders a 32 x 32 view from inside
(`perspective`, `path` at unbounded depth, `scalar_rgb`, box filter); the script prints the image mean
over the exact L per sampler and spp (1 = unbiased; the noise of the mean over 1024 pixels is ~1e-4).

Measured with Mitsuba 3.9.1 (`python3 xtask/py/mitsuba_furnace.py 0.5 256 1024 4096`): `ldsampler`
1.0044 / 1.0044 / 1.0042 at 256 / 1024 / 4096 spp, `multijitter` 0.9999 / 1.0001 / 1.0000, `independent`
1.0006 / 1.0003 / 1.0000; at rho = 0.85 and 256 spp (`... 0.85 256`) 1.0069, 1.0014 and 0.9998. The
`ldsampler` offset does not fall with the spp: a bias, not noise. The bench references use `multijitter`.
Exit code 3 when mitsuba is not importable.
"""
import math
import sys

try:
    import mitsuba as mi
except ImportError as e:
    print(f"mitsuba not importable: {e}", file=sys.stderr)
    sys.exit(3)
import numpy as np

mi.set_variant("scalar_rgb")
from mitsuba_scene import scene_dict  # noqa: E402  (after the variant)


def furnace(rho):
    """The cube's twelve triangles as scene rows, each wound to face the centre."""
    corners = {
        "y0": [(0, 0, 0), (1, 0, 0), (1, 0, 1), (0, 0, 1)],
        "y1": [(0, 1, 0), (0, 1, 1), (1, 1, 1), (1, 1, 0)],
        "z0": [(0, 0, 0), (0, 1, 0), (1, 1, 0), (1, 0, 0)],
        "z1": [(0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1)],
        "x0": [(0, 0, 0), (0, 0, 1), (0, 1, 1), (0, 1, 0)],
        "x1": [(1, 0, 0), (1, 1, 0), (1, 1, 1), (1, 0, 1)],
    }
    centre, ke = np.full(3, 0.5), 1.0 / math.pi
    rows = []
    for quad in corners.values():
        a, b, c, d = (np.array(p, dtype=float) for p in quad)
        for p, q, r in ((a, b, c), (a, c, d)):
            if np.dot(np.cross(q - p, r - p), centre - p) < 0:
                q, r = r, q
            rows.append(np.concatenate([p, q, r, [rho] * 3, [ke] * 3]))
    return np.asarray(rows)


def main():
    rho = float(sys.argv[1]) if len(sys.argv) > 1 else 0.5
    spps = [int(s) for s in sys.argv[2:]] or [256, 1024]
    exact = 1.0 / (math.pi * (1.0 - rho))
    scene = scene_dict(furnace(rho))
    sensor = {
        "type": "perspective",
        "fov": 60,
        "to_world": mi.ScalarTransform4f().look_at(
            origin=[0.5, 0.5, 0.9], target=[0.5, 0.5, 0.0], up=[0, 1, 0]
        ),
        "film": {"type": "hdrfilm", "width": 32, "height": 32, "rfilter": {"type": "box"},
                 "pixel_format": "rgb"},
    }
    for sampler in ("ldsampler", "multijitter", "independent"):
        for spp in spps:
            sd = dict(scene, sensor=dict(sensor, sampler={"type": sampler, "sample_count": spp}))
            img = np.array(mi.render(mi.load_dict(sd), spp=spp))[..., :3]
            print(f"rho={rho} sampler={sampler} spp={spp} mean/exact={img.mean() / exact:.5f}",
                  flush=True)


main()
