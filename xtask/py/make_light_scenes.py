#!/usr/bin/env python3
"""Writes the shipped scenes of the lights guide (docs/guide/lights.md) into scenes/:

* atrium.obj/.mtl, atrium.pts, atrium.lights.json — a two-storey atrium open to the sky through a
  4 x 4 m roof opening, a gallery slab around the void at 4 m; work planes at 0.8 m on the ground
  floor and on the gallery; a CIE overcast sky with the roof opening as its portal.
* sun-patch-room.obj/.mtl, sun-patch-room.pts, sun-patch-room.lights.json — a 6 x 3 x 8 m room whose
  one small window (1.2 x 1.0 m, south wall) lets in a low sun and nothing else: a sun patch on the
  floor lights the rest of the room by reflection alone (hard indirect light).
* door-gap.obj/.mtl, door-gap.pts, door-gap.lights.json — two 4 x 2.5 x 3 m rooms side by side, a
  0.2 m door gap in the 0.1 m partition, a 100 cd lamp under the ceiling of the west room; the work
  plane (0.8 m) is in the east room, lit only through the gap (hard indirect light).
* uplight-room.obj/.mtl, uplight-room.pts, uplight-room.lights.json — a 6 x 3 x 6 m room with a
  spot light near the floor aimed at the ceiling (60 deg cone): the ceiling patch lights the room.
* many-rooms.obj/.mtl, many-rooms.pts — 20 rooms of 4 x 2.8 x 4 m in a 5 x 4 grid (0.1 m
  partitions, a 0.9 x 2.1 m door in each), a 0.6 x 0.6 m ceiling lamp (emissive) in every other room
  (a checkerboard: 10 lamps), work planes at 0.8 m in every room: many lamps in many rooms, and rooms
  lit only through their doors (issues 31 and 32). No lighting file: the lamps are its emitters.
* grille-lamp.gltf — a 6 x 3 x 6 m room split by a floor-to-ceiling grille (alphaMode MASK stripes,
  doubleSided), a KHR_lights_punctual point light on one side and a spot on the other.

Geometry: metres, +Y up, north -Z (glTF's frame, gcr's default `--up y`). Every interior surface is
one-sided and faces into the room. Run from the repository root: python3 xtask/py/make_light_scenes.py
"""
import base64
import json
import struct
import zlib


def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def sub(a, b):
    return tuple(x - y for x, y in zip(a, b))


def dot(a, b):
    return sum(x * y for x, y in zip(a, b))


class Obj:
    """Quads collected per material, each wound counter-clockwise about the normal it should face."""

    def __init__(self):
        self.verts, self.faces = [], []

    def quad(self, material, corners, normal):
        c = list(corners)
        if dot(cross(sub(c[1], c[0]), sub(c[2], c[0])), normal) < 0:
            c.reverse()
        base = len(self.verts) + 1
        self.verts.extend(c)
        self.faces.append((material, [base, base + 1, base + 2, base + 3]))

    def box_rect(self, material, axis, value, lo, hi, normal):
        """A rectangle in the plane `axis` = value spanning lo..hi in the other two axes."""
        others = [a for a in range(3) if a != axis]
        pts = []
        for u, v in ((lo[0], lo[1]), (hi[0], lo[1]), (hi[0], hi[1]), (lo[0], hi[1])):
            p = [0.0, 0.0, 0.0]
            p[axis], p[others[0]], p[others[1]] = value, u, v
            pts.append(tuple(p))
        self.quad(material, pts, normal)

    def write(self, stem, comment, materials):
        with open(f"scenes/{stem}.mtl", "w") as f:
            for name, kd in materials.items():
                f.write(f"newmtl {name}\nKd {kd} {kd} {kd}\n")
        with open(f"scenes/{stem}.obj", "w") as f:
            f.write(f"mtllib {stem}.mtl\n# {comment}\n")
            for v in self.verts:
                f.write("v {:g} {:g} {:g}\n".format(*v))
            current = None
            for material, idx in self.faces:
                if material != current:
                    f.write(f"usemtl {material}\n")
                    current = material
                f.write("f " + " ".join(map(str, idx)) + "\n")


def ring(obj, material, y, outer, inner, normal):
    """The square ring outer minus inner (x, z bounds) at height y as four rectangles."""
    (x0, x1), (z0, z1) = outer
    (i0, i1), (k0, k1) = inner
    for lo, hi in (((x0, z0), (x1, k0)), ((x0, k1), (x1, z1)), ((x0, k0), (i0, k1)), ((i1, k0), (x1, k1))):
        obj.box_rect(material, 1, y, lo, hi, normal)


def walls(obj, material, x, y, z):
    """The four walls of the box [x] x [y] x [z], facing in."""
    obj.box_rect(material, 0, x[0], (y[0], z[0]), (y[1], z[1]), (1, 0, 0))
    obj.box_rect(material, 0, x[1], (y[0], z[0]), (y[1], z[1]), (-1, 0, 0))
    obj.box_rect(material, 2, z[0], (x[0], y[0]), (x[1], y[1]), (0, 0, 1))
    obj.box_rect(material, 2, z[1], (x[0], y[0]), (x[1], y[1]), (0, 0, -1))


def pts(stem, planes):
    with open(f"scenes/{stem}.pts", "w") as f:
        f.write("# work planes: x y z nx ny nz (Radiance/Honeybee .pts)\n")
        for y, xs, zs in planes:
            for x in xs:
                for z in zs:
                    f.write(f"{x:g} {y:g} {z:g} 0 1 0\n")


def atrium():
    o = Obj()
    o.box_rect("floor", 1, 0.0, (0, 0), (10, 10), (0, 1, 0))
    walls(o, "wall", (0, 10), (0, 8), (0, 10))
    ring(o, "ceiling", 8.0, ((0, 10), (0, 10)), ((3, 7), (3, 7)), (0, -1, 0))
    # the gallery slab (0.3 m thick) around a 6 x 6 void: top, underside, edges facing the void
    ring(o, "floor", 4.0, ((0, 10), (0, 10)), ((2, 8), (2, 8)), (0, 1, 0))
    ring(o, "ceiling", 3.7, ((0, 10), (0, 10)), ((2, 8), (2, 8)), (0, -1, 0))
    o.box_rect("wall", 0, 2.0, (3.7, 2), (4.0, 8), (1, 0, 0))
    o.box_rect("wall", 0, 8.0, (3.7, 2), (4.0, 8), (-1, 0, 0))
    o.box_rect("wall", 2, 2.0, (2, 3.7), (8, 4.0), (0, 0, 1))
    o.box_rect("wall", 2, 8.0, (2, 3.7), (8, 4.0), (0, 0, -1))
    o.write("atrium", "a 10 x 8 x 10 atrium (y up), a 4 x 4 roof opening, a gallery at 4 m around a 6 x 6 void",
            {"floor": 0.3, "wall": 0.6, "ceiling": 0.8})
    grid = [0.5 + i for i in range(10)]
    with open("scenes/atrium.pts", "w") as f:
        f.write("# work planes at 0.8 m above the ground floor and the gallery: x y z nx ny nz\n")
        for x in grid:
            for z in grid:
                f.write(f"{x:g} 0.8 {z:g} 0 1 0\n")
        for x in grid:
            for z in grid:
                if not (2 < x < 8 and 2 < z < 8):
                    f.write(f"{x:g} 4.8 {z:g} 0 1 0\n")
    json.dump({"up": "y", "sky": {"model": "cie-overcast", "illuminance": 10000},
               "portals": [[[3, 8, 3], [7, 8, 3], [7, 8, 7], [3, 8, 7]]]},
              open("scenes/atrium.lights.json", "w"), indent=1)


def sun_patch_room():
    o = Obj()
    o.box_rect("floor", 1, 0.0, (0, 0), (6, 8), (0, 1, 0))
    o.box_rect("ceiling", 1, 3.0, (0, 0), (6, 8), (0, -1, 0))
    o.box_rect("wall", 0, 0.0, (0, 0), (3, 8), (1, 0, 0))
    o.box_rect("wall", 0, 6.0, (0, 0), (3, 8), (-1, 0, 0))
    o.box_rect("wall", 2, 0.0, (0, 0), (6, 3), (0, 0, 1))
    # the south wall (z = 8) around a 1.2 x 1.0 window at x 2.4..3.6, y 1..2
    for lo, hi in (((0, 0), (6, 1)), ((0, 2), (6, 3)), ((0, 1), (2.4, 2)), ((3.6, 1), (6, 2))):
        o.box_rect("wall", 2, 8.0, lo, hi, (0, 0, -1))
    o.write("sun-patch-room", "a 6 x 3 x 8 room (y up), one 1.2 x 1.0 window in the south (+z) wall",
            {"floor": 0.4, "wall": 0.7, "ceiling": 0.8})
    pts("sun-patch-room", [(0.8, [0.5 + i for i in range(6)], [0.5 + i for i in range(8)])])
    json.dump({"up": "y", "sun": {"azimuth": 180, "elevation": 30, "illuminance": 80000}},
              open("scenes/sun-patch-room.lights.json", "w"), indent=1)


def door_gap():
    o = Obj()
    o.box_rect("floor", 1, 0.0, (0, 0), (8.1, 3), (0, 1, 0))
    o.box_rect("ceiling", 1, 2.5, (0, 0), (8.1, 3), (0, -1, 0))
    o.box_rect("wall", 0, 0.0, (0, 0), (2.5, 3), (1, 0, 0))
    o.box_rect("wall", 0, 8.1, (0, 0), (2.5, 3), (-1, 0, 0))
    o.box_rect("wall", 2, 0.0, (0, 0), (8.1, 2.5), (0, 0, 1))
    o.box_rect("wall", 2, 3.0, (0, 0), (8.1, 2.5), (0, 0, -1))
    # the partition x 4.0..4.1 on both sides, around a door gap z 2.2..2.4, y 0..2
    for x, n in ((4.0, (-1, 0, 0)), (4.1, (1, 0, 0))):
        for lo, hi in (((0, 0), (2.5, 2.2)), ((0, 2.4), (2.5, 3)), ((2.0, 2.2), (2.5, 2.4))):
            o.box_rect("wall", 0, x, lo, hi, n)
    # the gap's jambs and lintel
    o.box_rect("wall", 2, 2.2, (4.0, 0), (4.1, 2.0), (0, 0, 1))
    o.box_rect("wall", 2, 2.4, (4.0, 0), (4.1, 2.0), (0, 0, -1))
    o.box_rect("wall", 1, 2.0, (4.0, 2.2), (4.1, 2.4), (0, -1, 0))
    o.write("door-gap", "two 4 x 2.5 x 3 rooms (y up), a 0.2 m door gap in the partition at x = 4",
            {"floor": 0.4, "wall": 0.7, "ceiling": 0.8})
    pts("door-gap", [(0.8, [4.35 + 0.5 * i for i in range(8)], [0.25 + 0.5 * i for i in range(6)])])
    json.dump({"up": "y", "point_lights": [{"position": [2.0, 2.2, 1.0], "intensity": 100}]},
              open("scenes/door-gap.lights.json", "w"), indent=1)


def uplight_room():
    o = Obj()
    o.box_rect("floor", 1, 0.0, (0, 0), (6, 6), (0, 1, 0))
    o.box_rect("ceiling", 1, 3.0, (0, 0), (6, 6), (0, -1, 0))
    walls(o, "wall", (0, 6), (0, 3), (0, 6))
    o.write("uplight-room", "a 6 x 3 x 6 room (y up) lit by a spot aimed at the ceiling",
            {"floor": 0.3, "wall": 0.6, "ceiling": 0.8})
    pts("uplight-room", [(0.8, [0.5 + i for i in range(6)], [0.5 + i for i in range(6)])])
    json.dump({"up": "y", "spot_lights": [{"position": [1.5, 0.3, 1.5], "direction": [0, 1, 0],
                                           "intensity": 500, "inner_angle": 25, "outer_angle": 30}]},
              open("scenes/uplight-room.lights.json", "w"), indent=1)


def png(width, height, rgba_rows):
    raw = b"".join(b"\x00" + bytes(r) for r in rgba_rows)

    def chunk(t, d):
        return struct.pack(">I", len(d)) + t + d + struct.pack(">I", zlib.crc32(t + d) & 0xFFFFFFFF)

    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 6, 0, 0, 0))
            + chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b""))


def grille_lamp():
    """Primitives: the room (inward), the grille (x = 3, doubleSided, MASK); lights on nodes."""
    room, room_n = [], []

    def rect(list_, a, b, c, d, n):
        q = [a, b, c, d]
        if dot(cross(sub(q[1], q[0]), sub(q[2], q[0])), n) < 0:
            q.reverse()
        list_.append(q)

    W, H, D = 6.0, 3.0, 6.0
    rect(room, (0, 0, 0), (W, 0, 0), (W, 0, D), (0, 0, D), (0, 1, 0))
    rect(room, (0, H, 0), (W, H, 0), (W, H, D), (0, H, D), (0, -1, 0))
    rect(room, (0, 0, 0), (0, H, 0), (0, H, D), (0, 0, D), (1, 0, 0))
    rect(room, (W, 0, 0), (W, H, 0), (W, H, D), (W, 0, D), (-1, 0, 0))
    rect(room, (0, 0, 0), (W, 0, 0), (W, H, 0), (0, H, 0), (0, 0, 1))
    rect(room, (0, 0, D), (W, 0, D), (W, H, D), (0, H, D), (0, 0, -1))
    grille = [[(3, 0, 0), (3, 0, D), (3, H, D), (3, H, 0)]]
    # u along z: 12 bar periods (the texture repeats) over the 6 m; v along y
    grille_uv = [[(0, 1), (12, 1), (12, 0), (0, 0)]]
    buf = bytearray()
    views, accessors = [], []

    def add(data, fmt, count, typ, comp, minmax=None):
        off = len(buf)
        buf.extend(struct.pack("<" + fmt * (len(data)), *data))
        while len(buf) % 4:
            buf.append(0)
        views.append({"buffer": 0, "byteOffset": off, "byteLength": len(data) * 4})
        acc = {"bufferView": len(views) - 1, "componentType": comp, "count": count, "type": typ}
        if minmax:
            acc["min"], acc["max"] = minmax
        accessors.append(acc)
        return len(accessors) - 1

    def prim(quads, uvs, material):
        flat = [c for q in quads for p in q for c in p]
        xs, ys, zs = flat[0::3], flat[1::3], flat[2::3]
        pos = add(flat, "f", len(quads) * 4, "VEC3", 5126,
                  ([min(xs), min(ys), min(zs)], [max(xs), max(ys), max(zs)]))
        idx = []
        for k in range(len(quads)):
            b = 4 * k
            idx += [b, b + 1, b + 2, b, b + 2, b + 3]
        ind = add(idx, "I", len(idx), "SCALAR", 5125)
        p = {"attributes": {"POSITION": pos}, "indices": ind, "material": material}
        if uvs:
            p["attributes"]["TEXCOORD_0"] = add([c for q in uvs for p_ in q for c in p_], "f",
                                                len(uvs) * 4, "VEC2", 5126)
        return p

    # a bar period: 32 texels open (alpha 0), 32 solid, all of one light grey: the bilinear alpha
    # crosses the 0.5 cut-off exactly at the half period (at every mip level down to 2 texels) and
    # the colour is the same everywhere, so the grille is exactly 12 bars z in [0.5 k + 0.25,
    # 0.5 k + 0.5] of one reflectance (the daylit bench gives the peers these bars as geometry)
    mask = png(64, 1, [bytes([230, 230, 230, 0] * 32 + [230, 230, 230, 255] * 32)])
    gltf = {
        "asset": {"version": "2.0", "generator": "xtask/py/make_light_scenes.py"},
        "extensionsUsed": ["KHR_lights_punctual"],
        "extensions": {"KHR_lights_punctual": {"lights": [
            {"type": "point", "name": "lamp", "intensity": 300.0, "color": [1.0, 0.9, 0.8]},
            {"type": "spot", "name": "spot", "intensity": 800.0,
             "spot": {"innerConeAngle": 0.35, "outerConeAngle": 0.6}}]}},
        "scene": 0,
        "scenes": [{"name": "grille-lamp", "nodes": [0, 1, 2]}],
        "nodes": [
            {"name": "room", "mesh": 0},
            {"name": "lamp", "translation": [1.5, 2.4, 3.0],
             "extensions": {"KHR_lights_punctual": {"light": 0}}},
            # a spot at (4.5, 2.9, 3) pointing down: its local -Z rotated onto -Y (90° about +X)
            {"name": "spot", "translation": [4.5, 2.9, 3.0], "rotation": [-0.7071068, 0, 0, 0.7071068],
             "extensions": {"KHR_lights_punctual": {"light": 1}}},
        ],
        "meshes": [{"name": "room", "primitives": [prim(room, None, 0), prim(grille, grille_uv, 1)]}],
        "materials": [
            {"name": "plaster", "pbrMetallicRoughness": {"baseColorFactor": [0.7, 0.7, 0.7, 1]}},
            {"name": "grille", "alphaMode": "MASK", "alphaCutoff": 0.5, "doubleSided": True,
             "pbrMetallicRoughness": {"baseColorFactor": [0.9, 0.9, 0.9, 1],
                                      "baseColorTexture": {"index": 0}}},
        ],
        "samplers": [{"magFilter": 9729, "minFilter": 9729, "wrapS": 10497, "wrapT": 10497}],
        "textures": [{"source": 0, "sampler": 0}],
        "images": [{"name": "bars", "uri": "data:image/png;base64," + base64.b64encode(mask).decode()}],
        "buffers": [{"byteLength": len(buf),
                     "uri": "data:application/octet-stream;base64," + base64.b64encode(bytes(buf)).decode()}],
        "bufferViews": views,
        "accessors": accessors,
    }
    with open("scenes/grille-lamp.gltf", "w") as f:
        json.dump(gltf, f, indent=1)


def many_rooms(nx=5, nz=4, size=4.0, wall=0.1, height=2.8, door=(0.9, 2.1), lamp=0.6):
    """Rooms in an nx x nz grid at pitch size + wall; the room (i, j) spans x in
    [i*pitch + wall, (i+1)*pitch], z in [j*pitch + wall, (j+1)*pitch]; doors centred in every wall
    between two rooms, with jambs, a lintel and a floor strip in the wall's thickness."""
    o = Obj()
    pitch = size + wall
    (dw, dh) = door
    for i in range(nx):
        for j in range(nz):
            x0, x1 = i * pitch + wall, (i + 1) * pitch
            z0, z1 = j * pitch + wall, (j + 1) * pitch
            o.box_rect("floor", 1, 0.0, (x0, z0), (x1, z1), (0, 1, 0))
            o.box_rect("ceiling", 1, height, (x0, z0), (x1, z1), (0, -1, 0))
            # walls: (axis, value, normal, span lo..hi along the other horizontal axis, has door)
            for axis, value, normal, (a0, a1), door_here in (
                (0, x0, (1, 0, 0), (z0, z1), i > 0),
                (0, x1, (-1, 0, 0), (z0, z1), i < nx - 1),
                (2, z0, (0, 0, 1), (x0, x1), j > 0),
                (2, z1, (0, 0, -1), (x0, x1), j < nz - 1),
            ):
                # box_rect's two coordinates are the other axes in order: (y, z) for x, (x, y) for z
                def rect(lo_a, hi_a, lo_y, hi_y):
                    if axis == 0:
                        o.box_rect("wall", 0, value, (lo_y, lo_a), (hi_y, hi_a), normal)
                    else:
                        o.box_rect("wall", 2, value, (lo_a, lo_y), (hi_a, hi_y), normal)
                if not door_here:
                    rect(a0, a1, 0.0, height)
                    continue
                m = 0.5 * (a0 + a1)
                d0, d1 = m - dw / 2, m + dw / 2
                rect(a0, d0, 0.0, height)
                rect(d1, a1, 0.0, height)
                rect(d0, d1, dh, height)
            if (i + j) % 2 == 0:
                cx, cz = 0.5 * (x0 + x1), 0.5 * (z0 + z1)
                o.box_rect("lamp", 1, height - 0.01, (cx - lamp / 2, cz - lamp / 2),
                           (cx + lamp / 2, cz + lamp / 2), (0, -1, 0))
    # the doorways in the partitions' thickness: jambs, lintel, floor strip
    for i in range(nx):
        for j in range(nz):
            if i < nx - 1:  # the door east of room (i, j): x in [(i+1)*pitch, (i+1)*pitch + wall]
                xa, xb = (i + 1) * pitch, (i + 1) * pitch + wall
                m = j * pitch + wall + size / 2
                d0, d1 = m - dw / 2, m + dw / 2
                o.box_rect("wall", 2, d0, (xa, 0.0), (xb, dh), (0, 0, 1))
                o.box_rect("wall", 2, d1, (xa, 0.0), (xb, dh), (0, 0, -1))
                o.box_rect("wall", 1, dh, (xa, d0), (xb, d1), (0, -1, 0))
                o.box_rect("floor", 1, 0.0, (xa, d0), (xb, d1), (0, 1, 0))
            if j < nz - 1:  # the door south of room (i, j): z in [(j+1)*pitch, (j+1)*pitch + wall]
                za, zb = (j + 1) * pitch, (j + 1) * pitch + wall
                m = i * pitch + wall + size / 2
                d0, d1 = m - dw / 2, m + dw / 2
                o.box_rect("wall", 0, d0, (0.0, za), (dh, zb), (1, 0, 0))
                o.box_rect("wall", 0, d1, (0.0, za), (dh, zb), (-1, 0, 0))
                o.box_rect("wall", 1, dh, (d0, za), (d1, zb), (0, -1, 0))
                o.box_rect("floor", 1, 0.0, (d0, za), (d1, zb), (0, 1, 0))
    o.write("many-rooms", f"{nx * nz} rooms of {size:g} x {height:g} x {size:g} (y up) in a {nx} x {nz} grid, "
            "doors between neighbours, a ceiling lamp in every other room",
            {"floor": 0.3, "wall": 0.6, "ceiling": 0.8, "lamp": 0.0})
    with open("scenes/many-rooms.mtl", "a") as f:
        f.write("Ke 10 10 10\n")
    with open("scenes/many-rooms.pts", "w") as f:
        f.write("# work planes at 0.8 m in every room, 10 x 10 each: x y z nx ny nz\n")
        for i in range(nx):
            for j in range(nz):
                for a in range(10):
                    for b in range(10):
                        x = i * pitch + wall + 0.2 + 0.4 * a
                        z = j * pitch + wall + 0.2 + 0.4 * b
                        f.write(f"{x:g} 0.8 {z:g} 0 1 0\n")


atrium()
sun_patch_room()
grille_lamp()
door_gap()
uplight_room()
many_rooms()
