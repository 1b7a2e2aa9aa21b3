#!/usr/bin/env python3
"""Checks the Cycles peer scripts against closed forms (run it under the Python that has bpy):

    CYCLES_PYTHON=/path/to/python3.11 $CYCLES_PYTHON xtask/py/cycles_check.py

* a white furnace: a closed cube of rho 0.5 emitting E = 1 everywhere has B = E / (1 - rho) = 2
  (`cycles_field.py`, 256 spp: within 1 %);
* over a black plane (`cycles_irradiance.py`, 256 spp): a point light of intensity 100 at height 2 gives
  E = I cos θ / d² (within 0.1 %); a sun of irradiance 1000 at 45° gives E = 1000 cos 45° (0.1 %); a constant
  sky of radiance 1 gives E = π, the CIE overcast sky of zenith radiance 1 gives E = 7π/9 (both 0.5 %).

Prints each case with its value and the closed form; exits 1 when one is off, 3 when bpy is missing.
"""
import json
import math
import os
import subprocess
import sys
import tempfile

try:
    import bpy  # noqa: F401
    import numpy as np
except ImportError as e:
    print(f"bpy not importable: {e}", file=sys.stderr)
    sys.exit(3)

HERE = os.path.dirname(os.path.abspath(__file__))


def run(script, args, cwd):
    subprocess.run([sys.executable, os.path.join(HERE, script), *args], cwd=cwd, check=True,
                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)


def furnace(d):
    v = np.array([[x, y, z] for x in (0, 1) for y in (0, 1) for z in (0, 1)], float)
    quads = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    rows, points = [], []
    for q in quads:
        for t in ((q[0], q[1], q[2]), (q[0], q[2], q[3])):
            a, b, c = v[list(t)]
            if np.dot(np.cross(b - a, c - a), v.mean(0) - a) < 0:
                b, c = c, b
            rows.append(np.concatenate([a, b, c, [0.5] * 3, [1 / math.pi] * 3]))
            n = np.cross(b - a, c - a)
            points.append(np.concatenate([(a + b + c) / 3, n / np.linalg.norm(n), [len(rows) - 1]]))
    np.savetxt(os.path.join(d, "faces.txt"), rows)
    np.savetxt(os.path.join(d, "points.txt"), points)
    run("cycles_field.py", ["faces.txt", "points.txt", "b", "256"], d)
    return [("furnace B", float(np.loadtxt(os.path.join(d, "b.256")).mean()), 2.0, 0.01)]


def open_plane(d):
    s = 100
    np.savetxt(os.path.join(d, "plane.txt"), [[-s, 0, -s, -s, 0, s, s, 0, s] + [0] * 6,
                                                [-s, 0, -s, s, 0, s, s, 0, -s] + [0] * 6])
    np.savetxt(os.path.join(d, "up.txt"), [[0, 0.01, 0, 0, 1, 0], [1, 0.01, 0, 0, 1, 0]])
    d2 = 1 + 1.99 ** 2
    cases = [
        ("point light", {"type": "point", "position": [0, 2, 0], "intensity": 100.0},
         [100 / 1.99 ** 2, 100 * 1.99 / d2 ** 1.5], 0.001),
        ("sun at 45°", {"type": "directional", "direction": [0, -0.5 ** 0.5, -0.5 ** 0.5], "irradiance": 1000.0},
         [1000 * 0.5 ** 0.5] * 2, 0.001),
        ("constant sky", {"type": "constant", "radiance": 1.0}, [math.pi] * 2, 0.005),
        ("CIE overcast", {"type": "cie-overcast", "zenith": 1.0}, [7 * math.pi / 9] * 2, 0.005),
    ]
    out = []
    for name, light, exact, tol in cases:
        with open(os.path.join(d, "light.json"), "w") as f:
            json.dump([light], f)
        run("cycles_irradiance.py", ["--emitters", "light.json", "plane.txt", "up.txt", "e", "256"], d)
        e = np.loadtxt(os.path.join(d, "e.256"))[:, 0]
        out += [(f"{name}, point {i}", float(e[i]), exact[i], tol) for i in range(2)]
    return out


def main():
    bad = 0
    with tempfile.TemporaryDirectory() as d:
        for name, value, exact, tol in furnace(d) + open_plane(d):
            ok = abs(value / exact - 1) <= tol
            bad += not ok
            print(f"{'ok ' if ok else 'OFF'} {name}: {value:.6g} (exact {exact:.6g}, {100 * (value / exact - 1):+.3f} %)")
    sys.exit(1 if bad else 0)


main()
