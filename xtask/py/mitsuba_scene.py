"""The scene shared by the Mitsuba scripts: triangles with a diffuse ρ and an emitted radiance Ke
(`x0 y0 z0 x1 y1 z1 x2 y2 z2 rho_r rho_g rho_b Ke_r Ke_g Ke_b` per row) as one Mitsuba 3 mesh per
material, in a scene dict with the `path` integrator at unbounded depth.

Textured scenes add seven columns per row, `T u0 v0 u1 v1 u2 v2`: the row's texture (−1: none) and its
corners' texture coordinates ((0, 0) the image's top-left, Mitsuba's convention too), ρ then being the
factor the texels are multiplied by; the textures are in `<faces>.textures`, one per line, `w h` and the
linear RGB texels row-major from the top. A textured material becomes a `bitmap` (raw linear data: both
renderers read the same texels; bilinear, repeat) of texels × factor.
The caller imports mitsuba and sets the variant first.

Lights besides the emitting faces (`--emitters FILE` before the positional arguments, `split_emitters`): a
JSON list of Mitsuba emitter dicts (`directional`, `point`, `constant`, …) and one of ours,
`{"type": "cie-overcast", "zenith": L_z}`: the CIE overcast sky L(θ) = L_z (1 + 2 cos θ)/3 above the
horizon about +Y (black below), an `envmap` of 16 × 8 192 texels (`emitter_dict`).

Samplers (`--sampler NAME` before the positional arguments, `split_sampler`): `ldsampler` (default, the
one that measured the lowest error at equal spp) or any other Mitsuba sampler. `ldsampler` is biased: a
closed furnace renders 0.42-0.44 % too bright at 256-4096 spp (mitsuba_furnace.py, Mitsuba 3.9.1), where
`multijitter` and `independent` agree with the exact value; references use `multijitter`."""
import os

import mitsuba as mi
import numpy as np


# Mitsuba 3 skips a hit closer to a ray's origin than between 7·10⁻⁵ and 10⁻⁴ scene units, whatever the
# coordinates' size (measured: a radiancemeter 7·10⁻⁵ above a square sees through it, 10⁻⁴ above sees it).
METER_MIN = 2e-4


def meter_distance(diagonal):
    """How far above a point its radiancemeter sits: 10⁻⁵ of the diagonal, at least METER_MIN. Close, so
    that nothing lies between: at 10⁻³ of the diagonal (17 cm on a public temple of 170 m) meters sat in
    or above the model's beams and ledges, and Mitsuba stalled at 7.2 % against a reference it reaches
    (0.95 % at 1 024 spp) with them at 1.7 mm."""
    return max(METER_MIN, 1e-5 * diagonal)


def split_emitters(argv):
    """(the emitter dicts of `--emitters FILE`, or [], and the other arguments)."""
    if "--emitters" in argv:
        i = argv.index("--emitters")
        import json

        with open(argv[i + 1]) as f:
            emitters = json.load(f)
        return emitters, argv[:i] + argv[i + 2 :]
    return [], argv


def overcast_envmap(zenith):
    """The CIE overcast sky about +Y as a lat-long bitmap (rows: zenith angle from the top). Tall and
    narrow: the sky does not change with the azimuth, and Mitsuba interpolates between rows, so at 256
    rows the sky faded to black over 0.7° at the horizon (a pixel row of a 96² image at 40°: 22 % dark
    against the exact sky there); 8 192 rows make it 0.02°."""
    h, w = 8192, 16
    theta = (np.arange(h) + 0.5) / h * np.pi
    c = np.cos(theta)
    radiance = np.where(c > 0, zenith * (1 + 2 * c) / 3, 0.0)
    img = np.repeat(radiance[:, None], w, axis=1)
    return mi.Bitmap(np.repeat(img[:, :, None], 3, axis=2).astype(np.float32))


def emitter_dict(e):
    if e.get("type") == "cie-overcast":
        return {"type": "envmap", "bitmap": overcast_envmap(float(e["zenith"]))}
    return e


def read_textures(faces_path):
    """The textures next to a faces file (an empty list when there are none)."""
    path = f"{faces_path}.textures"
    if not os.path.exists(path):
        return []
    out = []
    for line in open(path):
        v = line.split()
        w, h = int(v[0]), int(v[1])
        out.append(np.asarray(v[2:], dtype=np.float32).reshape(h, w, 3))
    return out


def scene_dict(tri, textures=()):
    """The rows of `tri` (N × 15, or N × 22 with textures) as a Mitsuba scene dict without a sensor."""
    groups = {}
    for row in tri:
        tex = int(row[15]) if len(row) > 15 else -1
        groups.setdefault((tuple(row[9:15]), tex), []).append(row)
    scene = {"type": "scene", "integrator": {"type": "path", "max_depth": -1}}
    for k, ((mat, tex), rows) in enumerate(groups.items()):
        rows = np.asarray(rows, dtype=np.float64)
        v = rows[:, :9].reshape(-1, 3)
        props = mi.Properties()
        if tex >= 0:
            texels = textures[tex] * np.asarray(mat[:3], dtype=np.float32)
            reflectance = {"type": "bitmap", "bitmap": mi.Bitmap(texels), "raw": True,
                           "filter_type": "bilinear", "wrap_mode": "repeat"}
        else:
            reflectance = {"type": "rgb", "value": list(mat[:3])}
        props["bsdf"] = mi.load_dict({"type": "diffuse", "reflectance": reflectance})
        if max(mat[3:]) > 0:
            props["emitter"] = mi.load_dict(
                {"type": "area", "radiance": {"type": "rgb", "value": list(mat[3:])}}
            )
        mesh = mi.Mesh(
            f"m{k}",
            vertex_count=len(v),
            face_count=len(rows),
            has_vertex_normals=False,
            has_vertex_texcoords=tex >= 0,
            props=props,
        )
        params = mi.traverse(mesh)
        params["vertex_positions"] = v.ravel().tolist()
        params["faces"] = list(range(len(v)))
        if tex >= 0:
            params["vertex_texcoords"] = rows[:, 16:22].ravel().tolist()
        params.update()
        scene[f"mesh{k}"] = mesh
    return scene


def split_sampler(argv):
    """(sampler, the other arguments): `--sampler NAME` anywhere in argv (default `ldsampler`)."""
    args, sampler = list(argv), "ldsampler"
    if "--sampler" in args:
        i = args.index("--sampler")
        sampler = args[i + 1]
        del args[i : i + 2]
    return sampler, args


def load_with_sampler(scene, sensor, sampler, spp):
    """Loads scene dict `scene` with `sensor` sampled by `sampler` at `spp`; `ldsampler` falls
    back to `multijitter` where it refuses the count. Returns (scene, the sampler used)."""
    def load(name):
        return mi.load_dict(dict(scene, sensor=dict(sensor, sampler={"type": name, "sample_count": spp})))
    try:
        return load(sampler), sampler
    except Exception:
        if sampler != "ldsampler":
            raise
        return load("multijitter"), "multijitter"


def load_batch(scene, sensors, sampler, spp):
    """Loads `scene` with one `batch` sensor of the `radiancemeter`s `sensors` (a dict of sensor
    dicts, one film pixel each) and `sampler` (`load_with_sampler`). Returns (scene, sampler used)."""
    batch = {
        "type": "batch",
        "film": {"type": "hdrfilm", "width": len(sensors), "height": 1, "rfilter": {"type": "box"},
                 "pixel_format": "rgb"},
        **sensors,
    }
    return load_with_sampler(scene, batch, sampler, spp)
