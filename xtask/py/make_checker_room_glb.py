#!/usr/bin/env python3
"""Writes scenes/checker-room.glb from scenes/checker-room.obj/.mtl and its PNG textures: the same room
as binary glTF with the PNGs embedded (bufferView images), TEXCOORD_0 = (u, 1 − v) of the OBJ's vt (glTF
puts v = 0 at the image's top), baseColorFactor = Kd, the light's Ke as emissiveFactor 1 with
KHR_materials_emissive_strength. Pure Python (struct, json). Run from the repository root:

    python3 xtask/py/make_checker_room_glb.py
"""
import json
import struct

SCENES = "scenes"


def read_obj(path):
    v, vt, objects, cur = [], [], [], None
    for line in open(path):
        w = line.split()
        if not w or w[0].startswith("#"):
            continue
        if w[0] == "v":
            v.append([float(x) for x in w[1:4]])
        elif w[0] == "vt":
            vt.append([float(x) for x in w[1:3]])
        elif w[0] == "o":
            cur = {"name": w[1], "material": None, "faces": []}
            objects.append(cur)
        elif w[0] == "usemtl":
            cur["material"] = w[1]
        elif w[0] == "f":
            corners = []
            for c in w[1:]:
                parts = c.split("/")
                corners.append((int(parts[0]) - 1, int(parts[1]) - 1 if len(parts) > 1 and parts[1] else None))
            cur["faces"].append(corners)
    return v, vt, objects


def read_mtl(path):
    mats, cur = {}, None
    for line in open(path):
        w = line.split()
        if not w or w[0].startswith("#"):
            continue
        if w[0] == "newmtl":
            cur = mats.setdefault(w[1], {})
        elif w[0] in ("Kd", "Ke"):
            cur[w[0]] = [float(x) for x in w[1:4]]
        elif w[0] == "map_Kd":
            cur["map_Kd"] = w[1]
    return mats


def main():
    v, vt, objects = read_obj(f"{SCENES}/checker-room.obj")
    mats = read_mtl(f"{SCENES}/checker-room.mtl")
    bin_ = bytearray()
    views, accessors, meshes, nodes, images, textures, materials = [], [], [], [], [], [], []
    mat_index = {}

    def view(data, target=None):
        while len(bin_) % 4:
            bin_.append(0)
        views.append({"buffer": 0, "byteOffset": len(bin_), "byteLength": len(data)})
        if target:
            views[-1]["target"] = target
        bin_.extend(data)
        return len(views) - 1

    for name, m in mats.items():
        mat = {"name": name, "pbrMetallicRoughness": {"baseColorFactor": m.get("Kd", [0, 0, 0]) + [1],
                                                      "metallicFactor": 0, "roughnessFactor": 1}}
        if "map_Kd" in m:
            png = open(f"{SCENES}/{m['map_Kd']}", "rb").read()
            images.append({"name": m["map_Kd"], "mimeType": "image/png", "bufferView": view(png)})
            textures.append({"source": len(images) - 1, "sampler": 0})
            mat["pbrMetallicRoughness"]["baseColorTexture"] = {"index": len(textures) - 1}
        ke = m.get("Ke", [0, 0, 0])
        if max(ke) > 0:
            s = max(ke)
            mat["emissiveFactor"] = [k / s for k in ke]
            mat["extensions"] = {"KHR_materials_emissive_strength": {"emissiveStrength": s}}
        mat_index[name] = len(materials)
        materials.append(mat)
    for o in objects:
        pos, uv = [], []
        for f in o["faces"]:
            for vi, ti in f:
                pos.append(v[vi])
                uv.append([vt[ti][0], 1.0 - vt[ti][1]] if ti is not None else [0.0, 0.0])
        pb = b"".join(struct.pack("<3f", *p) for p in pos)
        ub = b"".join(struct.pack("<2f", *t) for t in uv)
        lo = [min(p[k] for p in pos) for k in range(3)]
        hi = [max(p[k] for p in pos) for k in range(3)]
        accessors.append({"bufferView": view(pb, 34962), "componentType": 5126, "count": len(pos),
                          "type": "VEC3", "min": lo, "max": hi})
        attrs = {"POSITION": len(accessors) - 1}
        if "map_Kd" in mats[o["material"]]:
            accessors.append({"bufferView": view(ub, 34962), "componentType": 5126, "count": len(uv),
                              "type": "VEC2"})
            attrs["TEXCOORD_0"] = len(accessors) - 1
        meshes.append({"name": o["name"], "primitives": [
            {"attributes": attrs, "material": mat_index[o["material"]], "mode": 4}]})
        nodes.append({"name": o["name"], "mesh": len(meshes) - 1})
    while len(bin_) % 4:
        bin_.append(0)
    doc = {
        "asset": {"version": "2.0", "generator": "gcr xtask/py/make_checker_room_glb.py"},
        "extensionsUsed": ["KHR_materials_emissive_strength"],
        "scene": 0, "scenes": [{"name": "checker-room", "nodes": list(range(len(nodes)))}],
        "nodes": nodes, "meshes": meshes, "materials": materials,
        "textures": textures, "images": images,
        "samplers": [{"magFilter": 9729, "minFilter": 9729, "wrapS": 10497, "wrapT": 10497}],
        "buffers": [{"byteLength": len(bin_)}], "bufferViews": views, "accessors": accessors,
    }
    js = json.dumps(doc, separators=(",", ":")).encode()
    js += b" " * (-len(js) % 4)
    out = bytearray(b"glTF" + struct.pack("<II", 2, 12 + 8 + len(js) + 8 + len(bin_)))
    out += struct.pack("<I", len(js)) + b"JSON" + js
    out += struct.pack("<I", len(bin_)) + b"BIN\x00" + bin_
    open(f"{SCENES}/checker-room.glb", "wb").write(out)
    print(f"wrote {SCENES}/checker-room.glb ({len(out)} bytes)")


main()
