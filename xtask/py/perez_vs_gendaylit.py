#!/usr/bin/env python3
"""GCR's Perez sky against Radiance's gendaylit (the pyradiance wheel's binaries).

Usage: perez_vs_gendaylit.py [PEREZ_SKY_EXAMPLE]
  (default: $CARGO_TARGET_DIR/release/examples/perez_sky, built by
   `cargo build --release -p scene-sampler --example perez_sky`)

For each case (sun altitude, gendaylit azimuth = degrees west of south, direct normal and diffuse
horizontal illuminance) it runs `gendaylit -ang ALT AZ -L DN DH -O 2 -s` (luminance output), takes
the sky function it prints (`skybright perezlum.cal` with its 10 arguments) and evaluates
perezlum.cal's `intersky` (the sky without the ground blend) with `rcalc` at 16 x 10 directions
(altitudes 2-90 degrees, 16 azimuths). GCR's `perez_sky` example evaluates the same directions
twice:

* **same (epsilon, delta)**: the Perez sky at gendaylit's printed epsilon and Delta, normalised to
  DH. What is left is the normalisation: gendaylit sums 145 Tregenza directions of equal weight,
  GCR integrates by a 256 x 256 quadrature; the ratio is constant over the sky, so the spread
  after dividing by the mean ratio is the shape's own difference;
* **from lux**: GCR's own epsilon and Delta from DN and DH (`--sun ... --sky perez:DH`). Beyond the
  normalisation, gendaylit -ang takes the Earth-Sun distance of day number 0 (E0 = 1.035: Delta
  3.5 % smaller than at the mean distance, which GCR takes) and Kasten's 1966 air mass.

Prints per case epsilon, Delta of each, and the max |ours/gendaylit - 1| over the directions; exits
3 when pyradiance is not importable.

Measured with pyradiance 1.3.1 (gendaylit 2.5), `CARGO_TARGET_DIR=... python3
xtask/py/perez_vs_gendaylit.py`: at the same (epsilon, Delta) the max difference is 1.10 %, all of
it gendaylit's coarser normalisation (mean ratios 1.0042-1.0097) bar 4.5e-3 at the sun's own
direction (gendaylit prints the sun's direction to 6 decimals: gamma near 0 is off by ~1e-3 rad)
and at most 1.3e-4 elsewhere; from lux the max difference is 3.22 % (GCR's Delta 3.5-4.4 % larger:
the Earth-Sun distance).
"""
import math
import os
import re
import subprocess
import sys

try:
    import pyradiance
except ImportError as e:
    print(f"pyradiance not importable: {e}", file=sys.stderr)
    sys.exit(3)

RAD = os.path.dirname(pyradiance.__file__)
BIN, LIB = os.path.join(RAD, "bin"), os.path.join(RAD, "lib")
ENV = dict(os.environ, RAYPATH=f".{os.pathsep}{LIB}")

# (altitude, gendaylit azimuth west of south, direct normal lux, diffuse horizontal lux)
CASES = [
    (25, 20, 60000, 15000),  # the guide's --sun 200,25,60000 --sky perez:15000
    (60, 0, 80000, 12000),  # clear
    (35, -45, 85000, 9000),  # very clear
    (40, 45, 20000, 25000),  # intermediate
    (15, -70, 500, 8000),  # overcast, low sun
    (70, 30, 0, 20000),  # overcast, no direct light
]


def directions():
    out = []
    for alt in [2, 5, 10, 20, 30, 40, 50, 60, 75, 90]:
        for k in range(16 if alt < 90 else 1):
            a, phi = math.radians(alt), 2 * math.pi * k / 16
            out.append((math.cos(a) * math.sin(phi), math.cos(a) * math.cos(phi), math.sin(a)))
    return out


def gendaylit(alt, az, dn, dh):
    """(epsilon, delta, [10 sky-function arguments]) of gendaylit -L."""
    cmd = [os.path.join(BIN, "gendaylit"), "-ang", str(alt), str(az), "-L", str(dn), str(dh)]
    text = subprocess.run(cmd + ["-O", "2", "-s"], capture_output=True, text=True, check=True).stdout
    eps, delta = map(float, re.search(r"epsilon, delta.*: (\S+) (\S+)", text).groups())
    args = re.search(r"^10 (.*)$", text, re.M).group(1).split()
    return eps, delta, [float(a) for a in args]


def intersky(args, dirs):
    """perezlum.cal's intersky (the sky's luminance) at unit directions, through rcalc."""
    defs = ";".join(f"A{i + 1}={a!r}" for i, a in enumerate(args))
    expr = f"{defs};Dx=$1;Dy=$2;Dz=$3;$1=intersky"
    cmd = [os.path.join(BIN, "rcalc"), "-f", "rayinit.cal", "-f", "perezlum.cal", "-e", expr]
    stdin = "".join(f"{x!r} {y!r} {z!r}\n" for x, y, z in dirs)
    out = subprocess.run(cmd, input=stdin, capture_output=True, text=True, check=True, env=ENV)
    return [float(v) for v in out.stdout.split()]


def ours(example, bearing, alt, dn, dh, dirs, params=()):
    """(epsilon, delta, luminances) of GCR's perez_sky example."""
    cmd = [example, str(bearing), str(alt), str(dn), str(dh), *map(str, params)]
    stdin = "".join(f"{x!r} {y!r} {z!r}\n" for x, y, z in dirs)
    out = subprocess.run(cmd, input=stdin, capture_output=True, text=True, check=True).stdout
    lines = out.split("\n")
    eps, delta = map(float, lines[0].lstrip("# ").split())
    return eps, delta, [float(v) for v in lines[1:] if v.strip()]


def main():
    target = os.environ.get("CARGO_TARGET_DIR", "target")
    example = sys.argv[1] if len(sys.argv) > 1 else os.path.join(target, "release/examples/perez_sky")
    dirs = directions()
    worst_same, worst_shape, worst_lux = 0.0, 0.0, 0.0
    print("alt  az     DN     DH | gendaylit eps, delta | ours eps, delta |"
          " same (eps,delta): max, mean ratio, shape | from lux: max")
    for alt, az, dn, dh in CASES:
        eps, delta, args = gendaylit(alt, az, dn, dh)
        theirs = intersky(args, dirs)
        # gendaylit: x east, y north, azimuth west of south; GCR: bearing from north through east
        bearing = (180.0 + az) % 360.0
        _, _, same = ours(example, bearing, alt, dn, dh, dirs, (eps, delta))
        e2, d2, lux = ours(example, bearing, alt, dn, dh, dirs)
        ratio = [a / b for a, b in zip(same, theirs)]
        mean = sum(ratio) / len(ratio)
        same_max = max(abs(r - 1) for r in ratio)
        shape = max(abs(r / mean - 1) for r in ratio)
        lux_max = max(abs(a / b - 1) for a, b in zip(lux, theirs))
        worst_same, worst_shape = max(worst_same, same_max), max(worst_shape, shape)
        worst_lux = max(worst_lux, lux_max)
        print(f"{alt:3} {az:3} {dn:6} {dh:6} | {eps:7.4f} {delta:6.4f}       |"
              f" {e2:7.4f} {d2:6.4f}  | {same_max:7.2%} {mean:7.4f} {shape:8.2e} | {lux_max:7.2%}")
    print(f"worst: same (eps, delta) {worst_same:.2%} (shape {worst_shape:.1e});"
          f" from lux {worst_lux:.2%}")


if __name__ == "__main__":
    main()
