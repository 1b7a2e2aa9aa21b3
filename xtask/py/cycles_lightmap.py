#!/usr/bin/env python3
"""Cycles' bake of a gcr lightmap's own texels, compared with gcr's pages (issue 33).

Usage: cycles_lightmap.py [--guiding] [--emitters JSON] [--reference REF.glb REF_METRICS] GLB METRICS SPP [SPP ...]

GLB:     a lightmap written by `gcr solve SCENE --lightmap GLB --metrics METRICS` (the default quantity,
         irradiance E); its linear pages `<stem>-lightmap-<k>.exr` beside it.
METRICS: that run's metrics (its `relative_std_error`: gcr's own estimate of its error).
--emitters JSON: the scene's lights other than its emitting faces (a sun, a sky, point lights), as the list of
         Mitsuba dicts `cycles_scene.py`'s `add_lights` reads (the .glb holds only the faces).

The scene is rebuilt from the .glb itself (`POSITION`, `TEXCOORD_1`; each primitive's material: albedo
`baseColorFactor`, emitted radiance `emissiveFactor` × `KHR_materials_emissive_strength`) as `cycles_scene.py`
builds scenes (Lambertian, front side only), with the lightmap coordinates as its UV map (v flipped: Blender's
row 0 is the image's bottom, glTF's v = 0 its top). Cycles bakes the `DIFFUSE` pass (direct + indirect, no
colour: E/pi) into one image per page at the atlas' size, margin 0, twice per SPP (seeds 0 and 1). Compared over
the texels both hold (Cycles writes alpha 1 where a triangle covers a texel's centre; gcr's padding is left
out) that Cycles does not bake black (`dark_in_cycles`: centres under or inside geometry, which gcr moves to
the visible surface so that no darkness leaks out): the relative L2 difference ‖E_gcr − E_cycles‖/‖E_cycles‖, Cycles' own error (half the seeds'
difference) and gcr's (METRICS), and d² / (e_gcr² + e_cycles²), which is about 1 when the two differ by their
noises alone, and the ratio of the sums (a bias). One line per SPP:
`spp=… texels=… dark_in_cycles=… render=<s> cycles_error=… gcr_error=… difference=… ratio=… mean_ratio=…`.
Texels that straddle an edge are where the two may differ beyond noise: gcr moves a texel centre that falls
inside geometry to the visible surface and super-samples texels that edges cross; Cycles bakes the centre.

With `--reference`: a gcr bake of the same atlas to a tighter target with another seed (`gcr solve SCENE
--lightmap REF.glb --target-error 0.005 --seed 2 --metrics REF_METRICS` with GLB's other options: the layout is a
function of the scene and the options; with the same seed the default bake's rays are the reference's first ones,
and the two errors would be correlated) is the converged answer. Each SPP is then one bake (seed 0), timed, and the same bake denoised as
Blender's users denoise bakes (the compositor's Denoise node, Open Image Denoise, HDR, on the baked image, which
was baked with Blender's default 16-texel margin so that the denoiser sees no black around the charts), timed on
its own; each, and gcr's GLB, is compared with the reference over the texels all of them hold:
`error = sqrt(‖E − E_ref‖² / ‖E_ref‖² − e_ref²)`, the reference's own estimated error taken out, and the bias
(ratio of sums). One line per SPP: `spp=… bake=<s> denoise=<s> cycles_error=… denoised_error=… gcr_error=…
cycles_mean_ratio=… denoised_mean_ratio=… gcr_mean_ratio=…`. The denoiser's error is mostly bias (blur across
shadow edges and chart edges), which no seed difference shows: hence the reference. Every spp is compared over
one set of texels: those some bake of the run lit (black in all: centres under or inside geometry).
Exit code 3 when bpy is not importable.
"""
import json
import os
import struct
import sys
import time

try:
    import bpy
except ImportError as e:
    print(f"bpy not importable: {e}", file=sys.stderr)
    sys.exit(3)
import numpy as np

from cycles_scene import add_lights, material, mesh_object, setup  # noqa: E402

COMPONENTS = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4}


def read_glb(path):
    """The .glb's JSON and binary chunk."""
    with open(path, "rb") as f:
        data = f.read()
    magic, _, _ = struct.unpack_from("<III", data, 0)
    if magic != 0x46546C67:
        raise SystemExit(f"{path}: not a .glb")
    offset, doc, binary = 12, None, b""
    while offset < len(data):
        length, kind = struct.unpack_from("<II", data, offset)
        chunk = data[offset + 8: offset + 8 + length]
        if kind == 0x4E4F534A:
            doc = json.loads(chunk)
        elif kind == 0x004E4942:
            binary = chunk
        offset += 8 + length
    return doc, binary


def accessor(doc, binary, index):
    """A float accessor's values as an (count, components) array."""
    a = doc["accessors"][index]
    if a["componentType"] != 5126:
        raise SystemExit("cycles_lightmap.py reads float accessors only")
    view = doc["bufferViews"][a["bufferView"]]
    start = view.get("byteOffset", 0) + a.get("byteOffset", 0)
    n = COMPONENTS[a["type"]]
    return np.frombuffer(binary, dtype="<f4", count=a["count"] * n, offset=start).reshape(-1, n)


def lightmap_scene(doc, binary):
    """Triangles (rows as cycles_scene.build_scene reads them), their lightmap UVs and pages."""
    rows, uvs, pages = [], [], []
    for mesh in doc["meshes"]:
        for prim in mesh["primitives"]:
            if prim.get("mode", 4) != 4 or "indices" in prim:
                raise SystemExit("cycles_lightmap.py reads gcr's triangle soups only")
            pos = accessor(doc, binary, prim["attributes"]["POSITION"]).astype(np.float64)
            uv = accessor(doc, binary, prim["attributes"]["TEXCOORD_1"]).astype(np.float64)
            m = doc["materials"][prim["material"]]
            rho = m["pbrMetallicRoughness"]["baseColorFactor"][:3]
            strength = m.get("extensions", {}).get("KHR_materials_emissive_strength", {})
            ke = np.asarray(m.get("emissiveFactor", [0, 0, 0])) * strength.get("emissiveStrength", 1.0)
            page = m["extensions"]["MOZ_lightmap"]["index"]
            for t in range(len(pos) // 3):
                rows.append(np.concatenate([pos[3 * t: 3 * t + 3].ravel(), rho, ke]))
                uvs.append(uv[3 * t: 3 * t + 3])
                pages.append(page)
    return np.asarray(rows), np.asarray(uvs), np.asarray(pages)


def read_pages(glb, w, h, n_pages):
    """gcr's linear pages beside GLB, as (h, w, 3) arrays (Blender's row order: bottom first)."""
    stem = os.path.splitext(glb)[0]
    pages = []
    for k in range(n_pages):
        img = bpy.data.images.load(os.path.abspath(f"{stem}-lightmap-{k}.exr"))
        pages.append(np.asarray(img.pixels[:], dtype=np.float64).reshape(h, w, 4)[..., :3])
    return pages


def denoiser(images):
    """A compositor that runs the Denoise node (OIDN, HDR) on an image, and the function that applies it
    to every page (in place) and returns the seconds it took."""
    scene = bpy.context.scene
    tree = bpy.data.node_groups.new("denoise", "CompositorNodeTree")
    tree.interface.new_socket("Image", in_out="OUTPUT", socket_type="NodeSocketColor")
    source = tree.nodes.new("CompositorNodeImage")
    node = tree.nodes.new("CompositorNodeDenoise")
    node.inputs["HDR"].default_value = True
    out = tree.nodes.new("NodeGroupOutput")
    tree.links.new(source.outputs["Image"], node.inputs["Image"])
    tree.links.new(node.outputs["Image"], out.inputs[0])
    scene.compositing_node_group = tree
    render = scene.render
    render.resolution_x, render.resolution_y = images[0].size
    render.resolution_percentage = 100
    render.image_settings.file_format = "OPEN_EXR"
    render.image_settings.color_depth = "32"
    path = os.path.join(os.environ.get("TMPDIR", "/tmp"), f"gcr-denoised-{os.getpid()}.exr")
    render.filepath = path

    def run():
        t0 = time.perf_counter()
        for img in images:
            source.image = img
            bpy.ops.render.render(write_still=True)  # no render layer: the compositor alone
            result = bpy.data.images.load(path)
            img.pixels.foreach_set(np.asarray(result.pixels[:], dtype=np.float32))
            bpy.data.images.remove(result)
        os.remove(path)
        return time.perf_counter() - t0

    return run


def main():
    args = sys.argv[1:]
    guiding = "--guiding" in args
    args = [a for a in args if a != "--guiding"]
    emitters = []
    if "--emitters" in args:
        i = args.index("--emitters")
        with open(args[i + 1]) as f:
            emitters = json.load(f)
        del args[i: i + 2]
    reference = None
    if "--reference" in args:
        i = args.index("--reference")
        reference = args[i + 1: i + 3]
        del args[i: i + 3]
    glb, metrics, *spps = args
    doc, binary = read_glb(glb)
    tri, uvs, pages = lightmap_scene(doc, binary)
    with open(metrics) as f:
        m = json.load(f)
    gcr_error = m.get("relative_std_error") or 0.0
    record = m["lightmap"]
    w, h, n_pages = record["width"], record["height"], record["pages"]
    ours = read_pages(glb, w, h, n_pages)
    setup(guiding)
    add_lights(emitters)
    # the scene as one mesh with the lightmap coordinates, each page's image on its faces
    keys, index = np.unique(np.round(np.hstack([tri[:, 9:15], pages[:, None]]), 12), axis=0,
                            return_inverse=True)
    images = [bpy.data.images.new(f"page{k}", w, h, float_buffer=True, alpha=True) for k in range(n_pages)]
    mats = []
    for key in keys:
        mat = material(key[:3], key[3:6])
        node = mat.node_tree.nodes.new("ShaderNodeTexImage")
        node.image = images[int(key[6])]
        mat.node_tree.nodes.active = node
        mats.append(mat)
    verts = tri[:, :9].reshape(-1, 3)
    ob = mesh_object("lightmapped", verts, np.arange(len(verts)).reshape(-1, 3), index.ravel(), mats)
    layer = ob.data.uv_layers.new(name="lightmap")
    flat = uvs.reshape(-1, 2)
    layer.data.foreach_set("uv", np.stack([flat[:, 0], 1.0 - flat[:, 1]], axis=1).astype(np.float32).ravel())
    bpy.ops.object.select_all(action="DESELECT")
    ob.select_set(True)
    bpy.context.view_layer.objects.active = ob
    scene = bpy.context.scene
    bake = scene.render.bake
    bake.target = "IMAGE_TEXTURES"
    bake.margin = 0
    bake.use_clear = True
    bake.use_pass_direct = bake.use_pass_indirect = True
    bake.use_pass_color = False

    def bake_pages(spp, seed, margin):
        scene.cycles.samples = spp
        scene.cycles.seed = seed
        for img in images:
            img.pixels.foreach_set(np.zeros(w * h * 4, dtype=np.float32))
        bpy.ops.object.bake(type="DIFFUSE", pass_filter={"DIRECT", "INDIRECT"}, margin=margin, use_clear=False)
        return [np.asarray(img.pixels[:], dtype=np.float64).reshape(h, w, 4) for img in images]

    if reference:
        compare_with_reference(reference, ours, [int(s) for s in spps], images, bake_pages, w, h, n_pages)
        return
    for spp in [int(s) for s in spps]:
        t0 = time.perf_counter()
        runs = [bake_pages(spp, seed, 0) for seed in (0, 1)]
        seconds = time.perf_counter() - t0
        covered = np.concatenate([(a[..., 3] > 0.5) & (b[..., 3] > 0.5) for a, b in zip(*runs)]).ravel()
        cyc = np.pi * 0.5 * np.concatenate([a[..., :3] + b[..., :3] for a, b in zip(*runs)]).reshape(-1, 3)
        se = np.pi * 0.5 * np.abs(np.concatenate([a[..., :3] - b[..., :3] for a, b in zip(*runs)])).reshape(-1, 3)
        g = np.concatenate(ours).reshape(-1, 3)
        if os.environ.get("CYCLES_LIGHTMAP_DUMP"):  # the texels, for a closer look
            np.savez(f"{os.environ['CYCLES_LIGHTMAP_DUMP']}.{spp}.npz", cycles=cyc, se=se, gcr=g, covered=covered,
                     width=w, height=h)
        # texels Cycles bakes black (their centres under or inside geometry: gcr moves those to the
        # visible surface, so that no darkness leaks out) are counted, not compared
        lit = covered & (cyc.sum(axis=1) > 0)
        dark = int((covered & ~lit).sum())
        cyc, se, g = cyc[lit], se[lit], g[lit]
        norm = np.sqrt((cyc ** 2).sum())
        cycles_error = np.sqrt((se ** 2).sum()) / norm
        difference = np.sqrt(((g - cyc) ** 2).sum()) / norm
        ratio = difference ** 2 / (gcr_error ** 2 + cycles_error ** 2)
        print(f"spp={spp} sampler={'cycles-guided' if guiding else 'cycles'} texels={int(lit.sum())} "
              f"dark_in_cycles={dark} render={seconds:.3f} cycles_error={cycles_error:.5f} "
              f"gcr_error={gcr_error:.5f} difference={difference:.5f} ratio={ratio:.3f} "
              f"mean_ratio={g.sum() / cyc.sum():.5f}", flush=True)


def compare_with_reference(reference, ours, spps, images, bake_pages, w, h, n_pages):
    """Cycles' bake, raw and denoised, and gcr's, each against a converged gcr bake (module docs)."""
    ref_glb, ref_metrics = reference
    with open(ref_metrics) as f:
        rm = json.load(f)
    lm = rm["lightmap"]
    if (lm["width"], lm["height"], lm["pages"]) != (w, h, n_pages):
        raise SystemExit("the reference's atlas is not GLB's: bake it with the same options")
    ref_error = rm.get("relative_std_error") or 0.0
    ref = np.concatenate(read_pages(ref_glb, w, h, n_pages)).reshape(-1, 3)
    g = np.concatenate(ours).reshape(-1, 3)
    # the texels Cycles covers (margin 0) and bakes lit: the others are where gcr moves texels
    covered = np.concatenate([p[..., 3] > 0.5 for p in bake_pages(1, 0, 0)]).ravel()
    denoise = denoiser(images)

    def error(e, keep):
        d2 = ((e[keep] - ref[keep]) ** 2).sum() / (ref[keep] ** 2).sum()
        return np.sqrt(max(d2 - ref_error ** 2, 0.0)), e[keep].sum() / ref[keep].sum()

    runs = []
    for spp in spps:
        t0 = time.perf_counter()
        raw = bake_pages(spp, 0, 16)
        seconds = time.perf_counter() - t0
        cyc = np.pi * np.concatenate([p[..., :3] for p in raw]).reshape(-1, 3)
        denoise_seconds = denoise()
        den = np.pi * np.concatenate(
            [np.asarray(img.pixels[:], dtype=np.float64).reshape(h, w, 4)[..., :3] for img in images]).reshape(-1, 3)
        runs.append((spp, seconds, denoise_seconds, cyc, den))
    # one set of texels for every spp: those some bake lit (a texel black in every bake has its centre
    # under or inside geometry); a texel black at a low spp only (no sample found light: a sun patch
    # room at 16 spp leaves half of them so) counts, with its error
    lit_any = np.zeros(len(ref), dtype=bool)
    for *_, cyc, _ in runs:
        lit_any |= cyc.sum(axis=1) > 0
    keep = covered & lit_any & (ref.sum(axis=1) > 0)
    for spp, seconds, denoise_seconds, cyc, den in runs:
        (ce, cr), (de, dr), (ge, gr) = error(cyc, keep), error(den, keep), error(g, keep)
        print(f"spp={spp} texels={int(keep.sum())} bake={seconds:.3f} denoise={denoise_seconds:.3f} "
              f"reference_error={ref_error:.5f} cycles_error={ce:.5f} denoised_error={de:.5f} gcr_error={ge:.5f} "
              f"cycles_mean_ratio={cr:.5f} denoised_mean_ratio={dr:.5f} gcr_mean_ratio={gr:.5f}", flush=True)

main()
