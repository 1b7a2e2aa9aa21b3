"""A textured stand-in for a large model, for timing the load (docs/guide/textures.md): a 194 x 194 grid of
quads (75 272 triangles) over a 1024^2 PNG, a third of the vertices' texture coordinates scaled so
their triangles tile the texture twice, the rest spanning about 20 texels; one emitting triangle.

    python3 xtask/py/make_textured_grid.py OUT_DIR    # writes big.obj, t.mtl, t.png
"""
import os
import random
import struct
import sys
import zlib


def png(path, w, h, pixel):
    raw = bytearray()
    for y in range(h):
        raw.append(0)
        for x in range(w):
            raw += bytes(pixel(x, y))

    def chunk(t, d):
        return struct.pack(">I", len(d)) + t + d + struct.pack(">I", zlib.crc32(t + d) & 0xFFFFFFFF)

    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0))
                + chunk(b"IDAT", zlib.compress(bytes(raw), 6)) + chunk(b"IEND", b""))


def main(out):
    os.makedirs(out, exist_ok=True)
    random.seed(1)

    def pixel(x, y):
        v = (x * 7 + y * 13) % 256
        return [v, (v * 3) % 256, random.randrange(256)]

    png(os.path.join(out, "t.png"), 1024, 1024, pixel)
    with open(os.path.join(out, "t.mtl"), "w") as f:
        f.write("newmtl m\nKd 0.8 0.8 0.8\nmap_Kd t.png\nnewmtl l\nKe 1 1 1\n")
    n = 194
    lines = ["mtllib t.mtl"]
    lines += [f"v {i / n} 0 {j / n}" for j in range(n + 1) for i in range(n + 1)]
    for j in range(n + 1):
        for i in range(n + 1):
            s = 2.0 if (i + j) % 3 == 0 else 0.02
            lines.append(f"vt {i * s} {j * s}")
    lines.append("o floor\nusemtl m")

    def idx(i, j):
        return j * (n + 1) + i + 1

    for j in range(n):
        for i in range(n):
            a, b, c, d = idx(i, j), idx(i + 1, j), idx(i + 1, j + 1), idx(i, j + 1)
            lines.append(f"f {a}/{a} {d}/{d} {c}/{c}")
            lines.append(f"f {a}/{a} {c}/{c} {b}/{b}")
    base = (n + 1) ** 2
    lines.append(f"v 0 1 0\nv 0 1 1\nv 1 1 0\no lamp\nusemtl l\nf {base + 1} {base + 3} {base + 2}")
    with open(os.path.join(out, "big.obj"), "w") as f:
        f.write("\n".join(lines) + "\n")


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else ".")
