#!/usr/bin/env python3
"""Mitsuba 3 irradiance at points (Radiance's `rtrace -I`), for `cargo xtask bench --only irradiance`.

Usage: mitsuba_irradiance.py [--sampler NAME] [--emitters JSON] FACES POINTS OUT SPP [SPP ...]

FACES:  one triangle per line, as mitsuba_field.py.
POINTS: one point per line, `x y z nx ny nz`: in the air, n the unit normal of the hemisphere whose
        irradiance E = ∫ L cos θ dω is wanted.
OUT:    for each SPP, OUT.<spp> gets one line `E_r E_g E_b se_r se_g se_b` per point (se: standard error),
        and the script prints `spp=<spp> scene=<s> load=<s> render=<s>` per SPP to stdout.

Each point gets a white (ρ = 1) diffuse square facing n and a `radiancemeter` above it looking down at it,
`meter_distance` away (10⁻⁵ of the diagonal, at least 2·10⁻⁴: Mitsuba skips hits closer than 10⁻⁴ to a ray
origin; mitsuba_scene.py), the square's half-size half that: the square's exitance is πL = ρ·E = E, estimated by Mitsuba's own path tracer at the square
(next-event estimation and BSDF sampling, unbounded depth, `ldsampler` by default; `--sampler`: see
mitsuba_scene.py). The squares block and reflect a
negligible 10⁻¹⁰ of the diagonal² each (or 4·10⁻⁸ square units). The scene is loaded once per SPP and rendered with two seeds: E is their mean, the
standard error half their difference. Exit code 3 when mitsuba or numpy is not importable.

`--emitters JSON`: a file with a list of Mitsuba emitter dicts added to the scene (`point`,
`directional`, `constant`, …), and one of ours: `{"type": "cie-overcast", "zenith": L_z}`, the CIE
overcast sky L(θ) = L_z (1 + 2 cos θ)/3 above the horizon about +Y (black below) as an `envmap`
(mitsuba_scene.py; Mitsuba's envmap has +Y up, the zenith at the image's top row).
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
from mitsuba_scene import (  # noqa: E402
    emitter_dict, load_batch, meter_distance, read_textures, scene_dict, split_emitters, split_sampler,
)


def frame(n):
    """Two unit tangents completing the unit normal `n`."""
    a = np.array([1.0, 0, 0]) if abs(n[0]) < 0.9 else np.array([0, 1.0, 0])
    t = np.cross(n, a)
    t /= np.linalg.norm(t)
    return t, np.cross(n, t)


def main():
    emitters, argv = split_emitters(sys.argv[1:])
    sampler, args = split_sampler(argv)
    faces_path, points_path, out, *spps = args
    spps = [int(s) for s in spps]
    t0 = time.perf_counter()
    tri = np.loadtxt(faces_path, ndmin=2)
    pts = np.loadtxt(points_path, ndmin=2)
    lo, hi = tri[:, :9].reshape(-1, 3).min(0), tri[:, :9].reshape(-1, 3).max(0)
    diag = float(np.linalg.norm(hi - lo))
    above = meter_distance(diag)
    half = 0.5 * above
    squares = []
    for p in pts:
        n = p[3:] / np.linalg.norm(p[3:])
        t, b = frame(n)  # t × b = n: counter-clockwise about n
        c = [p[:3] + half * (sx * t + sy * b) for sx, sy in ((-1, -1), (1, -1), (1, 1), (-1, 1))]
        for i, j, k in ((0, 1, 2), (0, 2, 3)):
            squares.append(np.concatenate([c[i], c[j], c[k], [1, 1, 1, 0, 0, 0]]))
    squares = np.asarray(squares)
    if tri.shape[1] > 15:  # a textured scene's rows: the squares have no texture
        squares = np.hstack([squares, np.tile([-1, 0, 0, 0, 0, 0, 0], (len(squares), 1))])
    scene = scene_dict(np.vstack([tri, squares]), read_textures(faces_path))
    for i, e in enumerate(emitters):
        scene[f"light{i}"] = emitter_dict(e)
    n = len(pts)
    film = {"type": "hdrfilm", "width": 1, "height": 1, "rfilter": {"type": "box"},
            "pixel_format": "rgb"}
    sensors = {}
    for i, p in enumerate(pts):
        nrm = p[3:] / np.linalg.norm(p[3:])
        sensors[f"s{i:07d}"] = {"type": "radiancemeter", "origin": (p[:3] + above * nrm).tolist(),
                                "direction": (-nrm).tolist(), "film": film}
    t_scene = time.perf_counter() - t0
    for spp in spps:
        t0 = time.perf_counter()
        s, used = load_batch(scene, sensors, sampler, spp)
        t_load = time.perf_counter() - t0
        t0 = time.perf_counter()
        renders = []
        for seed in (0, 1):
            img = np.array(mi.render(s, spp=spp, seed=seed))
            renders.append(np.pi * img.reshape(-1, img.shape[-1])[:n, :3])
        t_render = time.perf_counter() - t0
        e, se = 0.5 * (renders[0] + renders[1]), 0.5 * np.abs(renders[0] - renders[1])
        np.savetxt(f"{out}.{spp}", np.hstack([e, se]), fmt="%.9g")
        print(
            f"spp={spp} sampler={used} scene={t_scene:.3f} load={t_load:.3f} render={t_render:.3f} "
            f"import={t0 - t_start:.3f}",
            flush=True,
        )


main()
