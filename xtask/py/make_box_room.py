"""A stand-in for a model of a million triangles, for timing the load and the BVH (docs/results/
benchmarks-rays.md): a 20 x 4 x 20 room lit by a ceiling panel, filled with 83 000 small boxes
(12 triangles each; 996 014 triangles in all), and a 20 x 20 work plane of probes above its floor.

    python3 xtask/py/make_box_room.py OUT_DIR    # writes big.obj, big.mtl, big.pts
    gcr solve OUT_DIR/big.obj --max-file-mib 200 --probes OUT_DIR/big.pts \\
        --probe-quantity irradiance --probe-out p.txt --quality draft --metrics m.json
"""
import os
import random
import sys

W, H, BOXES = 20.0, 4.0, 83000


def main(out):
    os.makedirs(out, exist_ok=True)
    rng = random.Random(1)
    lines = ["mtllib big.mtl"]
    count = 0

    def quad(corners, mat):
        nonlocal count
        lines.append(f"usemtl {mat}")
        lines.extend("v %g %g %g" % p for p in corners)
        count += 4
        lines.append("f %d %d %d %d" % tuple(range(count - 3, count + 1)))

    quad([(0, 0, W), (W, 0, W), (W, 0, 0), (0, 0, 0)], "floor")
    quad([(0, H, 0), (W, H, 0), (W, H, W), (0, H, W)], "wall")
    quad([(0, 0, 0), (0, H, 0), (0, H, W), (0, 0, W)], "wall")
    quad([(W, 0, W), (W, H, W), (W, H, 0), (W, 0, 0)], "wall")
    quad([(0, 0, 0), (W, 0, 0), (W, H, 0), (0, H, 0)], "wall")
    quad([(0, H, W), (W, H, W), (W, 0, W), (0, 0, W)], "wall")
    c = H - 0.01
    quad([(9, c, 9), (11, c, 9), (11, c, 11), (9, c, 11)], "lamp")
    lines.append("usemtl box")
    for _ in range(BOXES):
        x, z = rng.uniform(0.5, W - 0.5), rng.uniform(0.5, W - 0.5)
        y, s = rng.uniform(0, 3), rng.uniform(0.02, 0.08)
        base = count + 1
        for dx in (0, s):
            for dy in (0, s):
                for dz in (0, s):
                    lines.append("v %.5f %.5f %.5f" % (x + dx, y + dy, z + dz))
        count += 8

        def at(a, b, c):
            return base + a * 4 + b * 2 + c

        for f in [
            (at(0, 0, 0), at(0, 0, 1), at(0, 1, 1), at(0, 1, 0)),
            (at(1, 0, 0), at(1, 1, 0), at(1, 1, 1), at(1, 0, 1)),
            (at(0, 0, 0), at(1, 0, 0), at(1, 0, 1), at(0, 0, 1)),
            (at(0, 1, 0), at(0, 1, 1), at(1, 1, 1), at(1, 1, 0)),
            (at(0, 0, 0), at(0, 1, 0), at(1, 1, 0), at(1, 0, 0)),
            (at(0, 0, 1), at(1, 0, 1), at(1, 1, 1), at(0, 1, 1)),
        ]:
            lines.append("f %d %d %d" % (f[0], f[1], f[2]))
            lines.append("f %d %d %d" % (f[0], f[2], f[3]))
    with open(os.path.join(out, "big.obj"), "w") as f:
        f.write("\n".join(lines) + "\n")
    with open(os.path.join(out, "big.mtl"), "w") as f:
        f.write(
            "newmtl floor\nKd 0.3 0.3 0.3\nnewmtl wall\nKd 0.6 0.6 0.6\n"
            "newmtl box\nKd 0.5 0.5 0.5\nnewmtl lamp\nKd 0 0 0\nKe 20 20 20\n"
        )
    with open(os.path.join(out, "big.pts"), "w") as f:
        for i in range(20):
            for j in range(20):
                f.write("%g 0.8 %g 0 1 0\n" % (1 + i * 0.9, 1 + j * 0.9))


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else ".")
