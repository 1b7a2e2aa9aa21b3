"""The scene, lights and probes the Cycles scripts (`cycles_field.py`, `cycles_irradiance.py`) share.

The scene is one mesh, one material per distinct (rho, Ke): a Lambertian `Diffuse BSDF` (roughness 0) plus an
`Emission` of radiance Ke, both on the front side only (the back side is black and emits nothing, as in
scene-sampler and Mitsuba's `diffuse` and `area`). A probe is a white (rho = 1) triangle 10⁻⁵ of the scene's
diagonal across, 10⁻⁴ of it above a surface point along the normal (at a point in the air) and facing along it, invisible to every ray a
light path traces; Cycles bakes the `DIFFUSE` pass (direct + indirect light, no colour) to the probes' vertex
colours: the outgoing radiance of a white Lambertian receiver, E/pi (a furnace of rho 0.5 and E 1 bakes
B = 2.000 ± 0.007 at 256 spp). Integrator: path tracing, CPU, 2 threads, every bounce limit at Cycles' maximum
(1024), no clamping and no light threshold (both bias), the light tree on (Cycles' default); `guiding` turns
Open PGL's path guiding on (surface guiding, Cycles' default training). The world is black unless a light
says otherwise.

Lights (`add_lights`), as the Mitsuba dicts the benches write for `mitsuba_irradiance.py`:
`{"type": "point", "position": [x, y, z], "intensity": I}` (W/sr, a number or Mitsuba's
{"type": "rgb", "value": [r, g, b]}; a Blender point light of radius 0 and power
4 pi I), `{"type": "directional", "direction": [x, y, z], "irradiance": E}` (a Blender sun of strength E and
angle 0: a delta, as Mitsuba's), `{"type": "constant", "radiance": L}` (the world at L) and
`{"type": "cie-overcast", "zenith": L_z}` (the CIE overcast sky about +Y, black below the horizon) and
`{"type": "envmap", "filename": F}` (an equirectangular map in Mitsuba's layout), both resampled into the
world's equirectangular texture (1024 × 512, nearest texel).
"""
import json
import math
import sys
import time

import bpy
import numpy as np

PROBE_SIZE = 1e-5
PROBE_LIFT = 1e-4


def material(rho, ke):
    """A front-only Lambertian reflector of reflectance `rho` emitting radiance `ke`."""
    m = bpy.data.materials.new(f"m{len(bpy.data.materials)}")
    m.use_nodes = True
    nt = m.node_tree
    for n in list(nt.nodes):
        nt.nodes.remove(n)
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    diffuse = nt.nodes.new("ShaderNodeBsdfDiffuse")
    diffuse.inputs["Color"].default_value = (*rho, 1.0)
    diffuse.inputs["Roughness"].default_value = 0.0
    front = diffuse.outputs["BSDF"]
    if max(ke) > 0:
        emission = nt.nodes.new("ShaderNodeEmission")
        emission.inputs["Color"].default_value = (*ke, 1.0)
        emission.inputs["Strength"].default_value = 1.0
        add = nt.nodes.new("ShaderNodeAddShader")
        nt.links.new(front, add.inputs[0])
        nt.links.new(emission.outputs["Emission"], add.inputs[1])
        front = add.outputs["Shader"]
        m.cycles.emission_sampling = "FRONT"
    black = nt.nodes.new("ShaderNodeBsdfDiffuse")
    black.inputs["Color"].default_value = (0.0, 0.0, 0.0, 1.0)
    geometry = nt.nodes.new("ShaderNodeNewGeometry")
    mix = nt.nodes.new("ShaderNodeMixShader")
    nt.links.new(geometry.outputs["Backfacing"], mix.inputs["Fac"])
    nt.links.new(front, mix.inputs[1])
    nt.links.new(black.outputs["BSDF"], mix.inputs[2])
    nt.links.new(mix.outputs["Shader"], out.inputs["Surface"])
    return m


def mesh_object(name, verts, tris, material_index=None, materials=()):
    me = bpy.data.meshes.new(name)
    me.vertices.add(len(verts))
    me.vertices.foreach_set("co", np.asarray(verts, dtype=np.float32).ravel())
    me.loops.add(3 * len(tris))
    me.loops.foreach_set("vertex_index", np.asarray(tris, dtype=np.int32).ravel())
    me.polygons.add(len(tris))
    me.polygons.foreach_set("loop_start", np.arange(0, 3 * len(tris), 3, dtype=np.int32))
    me.polygons.foreach_set("use_smooth", np.zeros(len(tris), dtype=bool))
    for m in materials:
        me.materials.append(m)
    if material_index is not None:
        me.polygons.foreach_set("material_index", np.asarray(material_index, dtype=np.int32))
    me.update(calc_edges=True)
    me.validate()
    ob = bpy.data.objects.new(name, me)
    bpy.context.scene.collection.objects.link(ob)
    return ob


def build_scene(tri, guiding):
    """An empty Cycles scene (`setup`) with the triangles of `tri` as one mesh, a material per (rho, Ke)."""
    setup(guiding)
    keys, index = np.unique(np.round(tri[:, 9:15], 12), axis=0, return_inverse=True)
    mats = [material(k[:3], k[3:]) for k in keys]
    verts = tri[:, :9].reshape(-1, 3)
    tris = np.arange(len(verts)).reshape(-1, 3)
    return mesh_object("scene", verts, tris, index.ravel(), mats)


def setup(guiding):
    """An empty scene rendered by Cycles as the module docs say, in a black world."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    c = scene.cycles
    c.device = "CPU"
    scene.render.threads_mode = "FIXED"
    scene.render.threads = 2
    c.max_bounces = c.diffuse_bounces = c.glossy_bounces = c.transmission_bounces = 1024
    c.transparent_max_bounces = c.volume_bounces = 1024
    c.sample_clamp_direct = c.sample_clamp_indirect = 0.0
    c.light_sampling_threshold = 0.0
    c.use_light_tree = True
    c.use_adaptive_sampling = False
    c.use_denoising = False
    c.use_guiding = guiding
    if guiding:
        c.use_surface_guiding = True
    world = bpy.data.worlds.new("black")
    world.use_nodes = True
    world.node_tree.nodes["Background"].inputs["Strength"].default_value = 0.0
    scene.world = world


def add_probes(pts, diagonal, lift=PROBE_LIFT):
    """A probe per point (module docs), `lift` of the diagonal above it (points in the air need none)."""
    n = len(pts)
    normal = pts[:, 3:6] / np.linalg.norm(pts[:, 3:6], axis=1, keepdims=True)
    helper = np.where(np.abs(normal[:, :1]) < 0.9, [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]])
    t = np.cross(normal, helper)
    t /= np.linalg.norm(t, axis=1, keepdims=True)
    b = np.cross(normal, t)
    c = pts[:, :3] + lift * diagonal * normal
    s = PROBE_SIZE * diagonal
    corners = [c + s * t, c + s * (-0.5 * t + 0.866 * b), c + s * (-0.5 * t - 0.866 * b)]
    verts = np.stack(corners, axis=1).reshape(-1, 3)
    ob = mesh_object("probes", verts, np.arange(3 * n).reshape(-1, 3), materials=[material((1, 1, 1), (0, 0, 0))])
    # invisible to every ray the light paths trace; visible to the camera (there is none), since an object
    # invisible to every ray is left out of the render and the bake writes zeros (measured)
    for flag in ("visible_diffuse", "visible_glossy", "visible_transmission", "visible_volume_scatter",
                 "visible_shadow"):
        setattr(ob, flag, False)
    ob.data.color_attributes.new("bake", "FLOAT_COLOR", "CORNER")
    ob.data.color_attributes.active_color = ob.data.color_attributes["bake"]
    return ob


def bake(probes, n, spp, seed=0):
    """The probes' baked light (E/pi, RGB) at `spp` samples with `seed`: one row per probe."""
    scene = bpy.context.scene
    scene.cycles.samples = spp
    scene.cycles.seed = seed
    bpy.ops.object.select_all(action="DESELECT")
    probes.select_set(True)
    bpy.context.view_layer.objects.active = probes
    b = scene.render.bake
    b.target = "VERTEX_COLORS"
    b.use_pass_direct = b.use_pass_indirect = True
    b.use_pass_color = False
    bpy.ops.object.bake(type="DIFFUSE", pass_filter={"DIRECT", "INDIRECT"}, target="VERTEX_COLORS")
    colours = np.empty(3 * n * 4, dtype=np.float32)
    probes.data.color_attributes["bake"].data.foreach_get("color", colours)
    return colours.reshape(n, 3, 4)[:, :, :3].mean(axis=1)




def add_lights(emitters):
    """The lights of `emitters` (Mitsuba dicts, module docs) added to the scene."""
    scene = bpy.context.scene
    for i, e in enumerate(emitters):
        kind = e.get("type")
        if kind == "point":
            light = bpy.data.lights.new(f"point{i}", "POINT")
            light.shadow_soft_size = 0.0
            light.use_soft_falloff = False
            rgb = colour(e["intensity"])
            light.energy = 4 * math.pi * max(rgb)
            light.color = [c / max(rgb) for c in rgb] if max(rgb) > 0 else [1.0, 1.0, 1.0]
            place(light, e["position"])
        elif kind == "directional":
            light = bpy.data.lights.new(f"sun{i}", "SUN")
            light.angle = 0.0
            light.energy = scalar(e["irradiance"])
            ob = place(light, [0.0, 0.0, 0.0])
            ob.rotation_mode = "QUATERNION"
            # a sun shines along its local -Z
            ob.rotation_quaternion = mathutils_track(e["direction"])
        elif kind == "constant":
            world_texture(lambda d: np.full(d.shape[:-1], scalar(e["radiance"])))
        elif kind == "envmap":
            world_texture(equirect_lookup(e["filename"], float(e.get("scale", 1.0))))
        elif kind == "cie-overcast":
            lz = float(e["zenith"])
            world_texture(lambda d: np.where(d[..., 1] > 0, lz * (1 + 2 * d[..., 1]) / 3, 0.0))
        else:  # exit code 3: the bench skips Cycles with this note
            print(f"light type {kind!r} is not translated for Cycles", file=sys.stderr)
            sys.exit(3)
    return scene


def equirect_lookup(filename, scale):
    """Radiance toward directions from an equirectangular EXR or HDR in Mitsuba's `envmap` layout (which
    scene-sampler's `EnvMap` follows): +Y up, row 0 the zenith, column i at azimuth phi = 2 pi (i + 1/2) / w
    with d = (sin θ sin φ, cos θ, −sin θ cos φ); nearest texel, as ours."""
    img = bpy.data.images.load(filename)
    w, h = img.size
    # Blender's pixels run from the bottom row up
    texels = np.asarray(img.pixels[:], dtype=np.float64).reshape(h, w, 4)[::-1, :, :3] * scale

    def radiance(d):
        theta = np.arccos(np.clip(d[..., 1], -1, 1))
        phi = np.mod(np.arctan2(d[..., 0], -d[..., 2]), 2 * np.pi)
        i = np.minimum((phi / (2 * np.pi) * w).astype(int), w - 1)
        j = np.minimum((theta / np.pi * h).astype(int), h - 1)
        return texels[j, i]

    return radiance


def scalar(v):
    """A Mitsuba spectrum given as a number or {"type": "rgb", "value": [r, g, b]}: its grey value."""
    return float(np.mean(colour(v)))


def colour(v):
    """A Mitsuba spectrum given as a number or {"type": "rgb", "value": [r, g, b]}: its RGB."""
    if isinstance(v, dict):
        value = v["value"]
        return [float(x) for x in value] if isinstance(value, list) else [float(value)] * 3
    return [float(v)] * 3


def place(light, position):
    ob = bpy.data.objects.new(light.name, light)
    ob.location = position
    bpy.context.scene.collection.objects.link(ob)
    return ob


def mathutils_track(direction):
    """The rotation that turns -Z into `direction`."""
    from mathutils import Vector

    return Vector(direction).normalized().to_track_quat("-Z", "Y")


def world_texture(radiance, w=1024, h=512):
    """The world as an equirectangular image of `radiance(direction)` (direction (..., 3), scene axes).

    Blender's mapping: u = -atan2(d.y, d.x) / 2 pi + 1/2, v = atan2(d.z, |d.xy|) / pi + 1/2 (row 0 at the
    bottom); each texel holds the radiance at its centre's direction."""
    u = (np.arange(w) + 0.5) / w
    v = (np.arange(h) + 0.5) / h
    phi = -(u - 0.5) * 2 * np.pi
    elevation = (v - 0.5) * np.pi
    pe, ee = np.meshgrid(phi, elevation)
    d = np.stack([np.cos(ee) * np.cos(pe), np.cos(ee) * np.sin(pe), np.sin(ee)], axis=-1)
    lum = radiance(d).astype(np.float32)
    img = bpy.data.images.new("sky", w, h, float_buffer=True, alpha=False)
    rgba = np.ones((h, w, 4), dtype=np.float32)
    rgba[..., :3] = lum if lum.ndim == 3 else lum[..., None]
    img.pixels.foreach_set(rgba.ravel())
    world = bpy.context.scene.world
    nt = world.node_tree
    tex = nt.nodes.new("ShaderNodeTexEnvironment")
    tex.image = img
    tex.interpolation = "Closest"
    bg = nt.nodes["Background"]
    bg.inputs["Strength"].default_value = 1.0
    nt.links.new(tex.outputs["Color"], bg.inputs["Color"])


def run_at_points(argv, t_start, lift, values):
    """The point scripts' main: `[--guiding] [--emitters JSON] FACES POINTS OUT SPP [SPP ...]`. Builds the scene,
    its lights and a probe per point (`lift` of the diagonal above it); for each SPP writes the rows of
    `values(tri, pts, probes, spp)` to OUT.<spp> and prints `spp=… sampler=… scene=… load=… render=…`."""
    guiding = "--guiding" in argv
    args = [a for a in argv if a != "--guiding"]
    emitters = []
    if "--emitters" in args:
        i = args.index("--emitters")
        with open(args[i + 1]) as f:
            emitters = json.load(f)
        args = args[:i] + args[i + 2:]
    faces_path, points_path, out, *spps = args
    t0 = time.perf_counter()
    tri = np.loadtxt(faces_path, ndmin=2)
    pts = np.loadtxt(points_path, ndmin=2)
    lo, hi = tri[:, :9].reshape(-1, 3).min(0), tri[:, :9].reshape(-1, 3).max(0)
    build_scene(tri, guiding)
    add_lights(emitters)
    t_scene = time.perf_counter() - t0
    t0 = time.perf_counter()
    probes = add_probes(pts, float(np.linalg.norm(hi - lo)), lift)
    t_load = time.perf_counter() - t0
    for spp in [int(s) for s in spps]:
        t0 = time.perf_counter()
        rows = values(tri, pts, probes, spp)
        t_render = time.perf_counter() - t0
        np.savetxt(f"{out}.{spp}", rows, fmt="%.9g")
        print(f"spp={spp} sampler={'cycles-guided' if guiding else 'cycles'} scene={t_scene:.3f} "
              f"load={t_load:.3f} render={t_render:.3f} import={t0 - t_start:.3f}", flush=True)
