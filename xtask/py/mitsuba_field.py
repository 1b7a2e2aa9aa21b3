#!/usr/bin/env python3
"""Mitsuba 3 radiosity at surface points, for `cargo xtask bench --only field` (issue 16).

Usage: mitsuba_field.py [--sampler NAME] FACES POINTS OUT SPP [SPP ...]

FACES:  one triangle per line, `x0 y0 z0 x1 y1 z1 x2 y2 z2 rho_r rho_g rho_b Ke_r Ke_g Ke_b`
        (Ke = emitted radiance, E = pi*Ke; winding gives the front side, as in scene-sampler).
POINTS: one point per line, `x y z nx ny nz` (the surface normal, front side).
OUT:    for each SPP, OUT.<spp> gets one line `B_r B_g B_b` per point, and the script prints one line
        `spp=<spp> load=<s> render=<s>` per render to stdout.

One `batch` sensor of `radiancemeter`s, one per point, each `meter_distance` along the normal (10⁻⁵ of the
diagonal, at least 2·10⁻⁴: Mitsuba skips hits closer than 10⁻⁴ to a ray origin; mitsuba_scene.py) and looking back at
the surface (direction -n): it measures the radiance L leaving the point toward +n; for a Lambertian surface
the exitance is B = pi*L. Integrator `path` (unbounded depth, Russian roulette from depth 5), sampler
`ldsampler` by default (low-discrepancy; falls back to `multijitter`; `--sampler`: see mitsuba_scene.py), variant `scalar_rgb`, one render call per SPP.
Exit code 3 when mitsuba is not importable.
"""
import sys
import time

t_start = time.perf_counter()
try:
    import mitsuba as mi
except ImportError as e:  # the bench skips Mitsuba with a note
    print(f"mitsuba not importable: {e}", file=sys.stderr)
    sys.exit(3)
import numpy as np

mi.set_variant("scalar_rgb")
from mitsuba_scene import load_batch, meter_distance, read_textures, scene_dict, split_sampler  # noqa: E402


def main():
    sampler, args = split_sampler(sys.argv[1:])
    faces_path, points_path, out, *spps = args
    spps = [int(s) for s in spps]
    t0 = time.perf_counter()
    tri = np.loadtxt(faces_path, ndmin=2)
    pts = np.loadtxt(points_path, ndmin=2)
    lo, hi = tri[:, :9].reshape(-1, 3).min(0), tri[:, :9].reshape(-1, 3).max(0)
    offset = meter_distance(float(np.linalg.norm(hi - lo)))
    scene = scene_dict(tri, read_textures(faces_path))
    n = len(pts)
    t_scene = time.perf_counter() - t0
    for spp in spps:
        t0 = time.perf_counter()
        sensors = {}
        for i, p in enumerate(pts):
            o = p[:3] + offset * p[3:]
            sensors[f"s{i:07d}"] = {
                "type": "radiancemeter",
                "origin": o.tolist(),
                "direction": (-p[3:]).tolist(),
                "film": {"type": "hdrfilm", "width": 1, "height": 1, "rfilter": {"type": "box"},
                         "pixel_format": "rgb"},
            }
        s, used = load_batch(scene, sensors, sampler, spp)
        t_load = time.perf_counter() - t0
        t0 = time.perf_counter()
        img = np.array(mi.render(s, spp=spp))
        t_render = time.perf_counter() - t0
        b = np.pi * img.reshape(-1, img.shape[-1])[:n, :3]
        np.savetxt(f"{out}.{spp}", b, fmt="%.9g")
        print(
            f"spp={spp} sampler={used} scene={t_scene:.3f} load={t_load:.3f} render={t_render:.3f} "
            f"import={t0 - t_start:.3f}",
            flush=True,
        )


main()
