"""Probes on a scene's faces for the overhead measurement: N area-uniform points on the
triangles of an OBJ file, each with its face's normal (from the winding), one
`x y z nx ny nz` line each at full precision.

    python make_probes.py ../../../scenes/cornell-box.obj 20000 probes20k.txt
"""

import sys

import numpy as np


def main(obj: str, n: int, out: str) -> None:
    verts, tris = [], []
    for line in open(obj):
        w = line.split()
        if w and w[0] == "v":
            verts.append([float(x) for x in w[1:4]])
        elif w and w[0] == "f":
            tris.append([int(x.split("/")[0]) - 1 for x in w[1:4]])
    v = np.array(verts)[np.array(tris)]  # triangles × corners × xyz
    cross = np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0])
    area = 0.5 * np.linalg.norm(cross, axis=1)
    normal = cross / (2 * area[:, None])
    rng = np.random.default_rng(n)
    t = rng.choice(len(v), size=n, p=area / area.sum())
    s, r = np.sqrt(rng.random(n)), rng.random(n)
    p = (1 - s)[:, None] * v[t, 0] + (s * (1 - r))[:, None] * v[t, 1] + (s * r)[:, None] * v[t, 2]
    with open(out, "w") as f:
        for pt, nm in zip(p, normal[t]):
            f.write(" ".join(repr(float(x)) for x in (*pt, *nm)) + "\n")


if __name__ == "__main__":
    main(sys.argv[1], int(sys.argv[2]), sys.argv[3])
