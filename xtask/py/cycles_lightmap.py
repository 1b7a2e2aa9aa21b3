#!/usr/bin/env python3
"""Cycles' bake of a gcr lightmap's own texels, compared with gcr's pages (issue 33).

Usage: cycles_lightmap.py [--guiding] GLB METRICS SPP [SPP ...]

GLB:     a lightmap written by `gcr solve SCENE --lightmap GLB --metrics METRICS` (the default quantity,
         irradiance E); its linear pages `<stem>-lightmap-<k>.exr` beside it.
METRICS: that run's metrics (its `relative_std_error`: gcr's own estimate of its error).

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

from cycles_scene import material, mesh_object, setup  # noqa: E402

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


def main():
    args = sys.argv[1:]
    guiding = "--guiding" in args
    args = [a for a in args if a != "--guiding"]
    glb, metrics, *spps = args
    doc, binary = read_glb(glb)
    tri, uvs, pages = lightmap_scene(doc, binary)
    with open(metrics) as f:
        m = json.load(f)
    gcr_error = m.get("relative_std_error") or 0.0
    record = m["lightmap"]
    w, h, n_pages = record["width"], record["height"], record["pages"]
    stem = os.path.splitext(glb)[0]
    ours = []
    for k in range(n_pages):
        img = bpy.data.images.load(os.path.abspath(f"{stem}-lightmap-{k}.exr"))
        ours.append(np.asarray(img.pixels[:], dtype=np.float64).reshape(h, w, 4)[..., :3])
    setup(guiding)
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
    for spp in [int(s) for s in spps]:
        scene.cycles.samples = spp
        t0 = time.perf_counter()
        runs = []
        for seed in (0, 1):
            scene.cycles.seed = seed
            for img in images:
                img.pixels.foreach_set(np.zeros(w * h * 4, dtype=np.float32))
            bpy.ops.object.bake(type="DIFFUSE", pass_filter={"DIRECT", "INDIRECT"}, margin=0,
                                use_clear=False)
            runs.append([np.asarray(img.pixels[:], dtype=np.float64).reshape(h, w, 4) for img in images])
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

main()
