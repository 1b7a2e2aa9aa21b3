#!/usr/bin/env python3
"""Mitsuba 3 irradiance at points (Radiance's `rtrace -I`), for `cargo xtask bench --only irradiance`.

Usage: mitsuba_irradiance.py FACES POINTS OUT DIRS SPP [SPP ...]

FACES:  one triangle per line, as mitsuba_field.py.
POINTS: one point per line, `x y z nx ny nz`: anywhere (in the air or on a surface), n the unit normal of
        the hemisphere whose irradiance E = ∫ L cos θ dω is wanted.
OUT:    for each SPP, OUT.<spp> gets one line `E_r E_g E_b se_r se_g se_b` per point (se: standard error),
        and the script prints `spp=<spp> scene=<s> load=<s> render=<s>` per render to stdout.

E is estimated by cosine-weighted directions: E = π · mean_i L(ω_i) with ω_i drawn from the density
cos θ/π about n. Each point gets DIRS directions (DIRS even), one `radiancemeter` each looking along ω_i from
the point (lifted 10⁻⁵ of the diagonal along n), all in one `batch` sensor, each measured with SPP samples by
the `path` integrator (unbounded depth) and `ldsampler`. The directions are random (seeded): the two halves
are independent estimates, and their difference gives the standard error. Exit code 3 when mitsuba is
not importable.
"""
import sys
import time

t_start = time.perf_counter()
try:
    import mitsuba as mi
    import numpy as np
except ImportError as e:  # the bench skips Mitsuba with a note
    print(f"mitsuba or numpy not importable: {e}", file=sys.stderr)
    sys.exit(3)

mi.set_variant("scalar_rgb")
from mitsuba_scene import scene_dict  # noqa: E402  (after the variant)


def cosine_directions(n, count, rng):
    """`count` directions with density cos θ/π about the unit normal `n`."""
    u1, u2 = rng.random(count), rng.random(count)
    r, phi = np.sqrt(u1), 2 * np.pi * u2
    local = np.stack([r * np.cos(phi), r * np.sin(phi), np.sqrt(np.maximum(0, 1 - u1))], 1)
    a = np.array([1.0, 0, 0]) if abs(n[0]) < 0.9 else np.array([0, 1.0, 0])
    t = np.cross(n, a)
    t /= np.linalg.norm(t)
    b = np.cross(n, t)
    return local[:, :1] * t + local[:, 1:2] * b + local[:, 2:] * n


def main():
    faces_path, points_path, out, dirs, *spps = sys.argv[1:]
    dirs, spps = int(dirs), [int(s) for s in spps]
    t0 = time.perf_counter()
    tri = np.loadtxt(faces_path, ndmin=2)
    pts = np.loadtxt(points_path, ndmin=2)
    lo, hi = tri[:, :9].reshape(-1, 3).min(0), tri[:, :9].reshape(-1, 3).max(0)
    lift = 1e-5 * float(np.linalg.norm(hi - lo))
    scene = scene_dict(tri)
    rng = np.random.default_rng(7)
    rays = []
    for p in pts:
        n = p[3:] / np.linalg.norm(p[3:])
        for d in cosine_directions(n, dirs, rng):
            rays.append((p[:3] + lift * n, d))
    m = len(rays)
    t_scene = time.perf_counter() - t0
    for spp in spps:
        t0 = time.perf_counter()
        film = {"type": "hdrfilm", "width": 1, "height": 1, "rfilter": {"type": "box"},
                "pixel_format": "rgb"}
        sensors = {
            f"s{i:08d}": {"type": "radiancemeter", "origin": o.tolist(), "direction": d.tolist(),
                          "film": film}
            for i, (o, d) in enumerate(rays)
        }
        sd = dict(scene)
        sd["sensor"] = {
            "type": "batch",
            "sampler": {"type": "ldsampler", "sample_count": spp},
            "film": {"type": "hdrfilm", "width": m, "height": 1, "rfilter": {"type": "box"},
                     "pixel_format": "rgb"},
            **sensors,
        }
        s = mi.load_dict(sd)
        t_load = time.perf_counter() - t0
        t0 = time.perf_counter()
        img = np.array(mi.render(s, spp=spp))
        t_render = time.perf_counter() - t0
        radiance = img.reshape(-1, img.shape[-1])[:m, :3].reshape(len(pts), dirs, 3)
        half = dirs // 2
        e1 = np.pi * radiance[:, :half].mean(1)
        e2 = np.pi * radiance[:, half:].mean(1)
        e, se = 0.5 * (e1 + e2), 0.5 * np.abs(e1 - e2)
        np.savetxt(f"{out}.{spp}", np.hstack([e, se]), fmt="%.9g")
        print(
            f"spp={spp} sampler=ldsampler scene={t_scene:.3f} load={t_load:.3f} render={t_render:.3f} "
            f"import={t0 - t_start:.3f}",
            flush=True,
        )


main()
