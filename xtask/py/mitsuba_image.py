#!/usr/bin/env python3
"""Mitsuba 3 images of a scene, for `cargo xtask bench --only images` (issue 18).

Usage: mitsuba_image.py [--sampler NAME] [--emitters JSON] FACES CAMERA OUT SPP [SPP ...]

FACES:  one triangle per line, `x0 y0 z0 x1 y1 z1 x2 y2 z2 rho_r rho_g rho_b Ke_r Ke_g Ke_b`
        (Ke = emitted radiance; the format of mitsuba_field.py).
CAMERA: one line `ex ey ez tx ty tz ux uy uz fov_y width height` (Mitsuba's `perspective` sensor with
        to_world = look_at(eye, target, up), fov_axis = y).
OUT:    for each SPP, OUT.<spp> gets the linear radiance, one line `L_r L_g L_b` per pixel, row-major,
        top row first; the script prints `spp=<spp> scene=<s> load=<s> render=<s>` per render.

Integrator `path` (unbounded depth), sampler `ldsampler` by default (falls back to `multijitter` where it
refuses the count; `--sampler`: see mitsuba_scene.py), box reconstruction filter (the pixel's mean, as `gcr --image-mode pixel --pixel-samples`),
variant `scalar_rgb`. `--emitters JSON`: lights besides the emitting faces, as mitsuba_irradiance.py's
(a sun as a `directional` emitter, a CIE overcast sky as an `envmap`, which pixels that see no surface
show). Exit code 3 when mitsuba is not importable.
"""
import sys
import time

try:
    import mitsuba as mi
except ImportError as e:  # the bench skips Mitsuba with a note
    print(f"mitsuba not importable: {e}", file=sys.stderr)
    sys.exit(3)
import numpy as np

mi.set_variant("scalar_rgb")
from mitsuba_scene import (  # noqa: E402
    emitter_dict, load_with_sampler, read_textures, scene_dict, split_emitters, split_sampler,
)


def main():
    emitters, argv = split_emitters(sys.argv[1:])
    sampler, args = split_sampler(argv)
    faces_path, camera_path, out, *spps = args
    t0 = time.perf_counter()
    tri = np.loadtxt(faces_path, ndmin=2)
    cam = np.loadtxt(camera_path)
    eye, target, up = cam[0:3].tolist(), cam[3:6].tolist(), cam[6:9].tolist()
    fov, width, height = float(cam[9]), int(cam[10]), int(cam[11])
    scene = scene_dict(tri, read_textures(faces_path))
    for i, e in enumerate(emitters):
        scene[f"light{i}"] = emitter_dict(e)
    t_scene = time.perf_counter() - t0
    for spp in (int(s) for s in spps):
        t0 = time.perf_counter()
        sensor = {
            "type": "perspective",
            "fov": fov,
            "fov_axis": "y",
            "to_world": mi.ScalarTransform4f().look_at(origin=eye, target=target, up=up),
            "film": {"type": "hdrfilm", "width": width, "height": height,
                     "rfilter": {"type": "box"}, "pixel_format": "rgb"},
        }
        s, used = load_with_sampler(scene, sensor, sampler, spp)
        t_load = time.perf_counter() - t0
        t0 = time.perf_counter()
        img = np.array(mi.render(s, spp=spp))
        t_render = time.perf_counter() - t0
        np.savetxt(f"{out}.{spp}", img.reshape(-1, img.shape[-1])[:, :3], fmt="%.7g")
        print(
            f"spp={spp} sampler={used} scene={t_scene:.3f} load={t_load:.3f} render={t_render:.3f}",
            flush=True,
        )


main()
