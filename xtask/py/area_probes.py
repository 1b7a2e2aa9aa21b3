#!/usr/bin/env python3
"""Area-uniform probes on the non-emitting faces of a scene in scenes/ (OBJ + MTL).

Usage: python3 xtask/py/area_probes.py SCENE N OUT [SEED]
Writes N lines `x y z nx ny nz` (the probe format of FORMATS.md): points drawn uniformly by area
over the triangles whose material has no Ke, each with its face's normal. Used for the shared-paths
measurements in docs/design/estimator.md (`gcr solve SCENE --probes OUT ...`).
"""
import math
import random
import sys
from pathlib import Path


def load(obj):
    verts, faces, mat, mtllib = [], [], None, None
    for line in obj.read_text().splitlines():
        t = line.split()
        if not t:
            continue
        if t[0] == "v":
            verts.append(tuple(map(float, t[1:4])))
        elif t[0] == "usemtl":
            mat = t[1]
        elif t[0] == "mtllib":
            mtllib = t[1]
        elif t[0] == "f":
            idx = [int(x.split("/")[0]) - 1 for x in t[1:]]
            for k in range(1, len(idx) - 1):
                faces.append((idx[0], idx[k], idx[k + 1], mat))
    emitting, cur = set(), None
    if mtllib:
        for line in (obj.parent / mtllib).read_text().splitlines():
            t = line.split()
            if t and t[0] == "newmtl":
                cur = t[1]
            elif t and t[0] == "Ke" and any(float(x) > 0 for x in t[1:4]):
                emitting.add(cur)
    return verts, faces, emitting


def main():
    if len(sys.argv) < 4:
        sys.exit(__doc__)
    scene, n, out = sys.argv[1], int(sys.argv[2]), sys.argv[3]
    seed = int(sys.argv[4]) if len(sys.argv) > 4 else 11
    root = Path(__file__).resolve().parents[2]
    verts, faces, emitting = load(root / "scenes" / f"{scene}.obj")
    tris, areas = [], []
    for a, b, c, m in faces:
        if m in emitting:
            continue
        pa, pb, pc = verts[a], verts[b], verts[c]
        e1 = [pb[i] - pa[i] for i in range(3)]
        e2 = [pc[i] - pa[i] for i in range(3)]
        cr = [e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]]
        area = 0.5 * math.sqrt(sum(x * x for x in cr))
        if area > 0:
            tris.append((pa, e1, e2, [x / (2 * area) for x in cr]))
            areas.append(area)
    rng = random.Random(seed)
    with open(out, "w") as f:
        for _ in range(n):
            pa, e1, e2, normal = rng.choices(tris, weights=areas)[0]
            u, v = rng.random(), rng.random()
            if u + v > 1:
                u, v = 1 - u, 1 - v
            p = [pa[i] + u * e1[i] + v * e2[i] for i in range(3)]
            f.write(" ".join(repr(x) for x in p + normal) + "\n")


if __name__ == "__main__":
    main()
