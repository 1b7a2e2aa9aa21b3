#!/usr/bin/env python3
"""Radiance (`rtrace -I`) irradiance at points under a daylight sky, for `cargo xtask bench --only radiance`.

Usage: radiance_irradiance.py [options] FACES POINTS OUT SETTING [SETTING ...]

Options:
  --sky overcast|clear|uniform  the sky model (default overcast): gensky -c, gensky +s, gensky -u
  --eh E                        the sky's horizontal (diffuse) irradiance, in the scene's units
                                (default 10000)
  --ground RHO                  the ground reflectance of the ground glow (default 0.2; 0: black)
  --sun AZ,EL,EN                the sun: compass bearing (0 north, 90 east), elevation, normal
                                irradiance (with --sky clear; it also places the clear sky's peak)
  --sky-fn cie|gensky           the sky function (default cie): `gensky` is skybright.cal's `skybr`
                                as gensky writes it, which blends sky and ground over ~20 degrees
                                about the horizon, wmean((Dz+1.01)^10, sky, (Dz+1.01)^-10, ground);
                                `cie` is the same sky and ground without the blend (the CIE
                                formulas up to the horizon, the ground below: GCR's sky)
  --threads N                   rtrace -n N (default 2)
  --check                       also print the horizontal irradiance of the sky alone (no scene),
                                by rtrace -I -ab 1 -ad 65536 -aa 0 at the origin facing up, for both
                                sky functions: `check fn=<fn> E_h=<value>`

FACES:   one triangle per line, as the benches write them for Mitsuba (write_mitsuba_faces in
         xtask/src/bench/field.rs): x y z ×3, ρ_r ρ_g ρ_b, emitted radiance r g b (Y up).
POINTS:  one point per line, `x y z nx ny nz` (Y up).
SETTING: `ab,ad,as,aa,lw[,ar[,lr]]` — rtrace's -ab -ad -as -aa -lw [-ar (0: not given)] [-lr]
         (aa 0: no ambient cache, pure Monte Carlo; rtrace's other options at their defaults).
OUT:     for the k-th SETTING (from 0), OUT.<k> gets one line `E_r E_g E_b` per point, and the
         script prints `setting=<k> oconv=<s> rtrace=<s>` per SETTING to stdout.

Scene: every triangle a `polygon` of its own `plastic` (ρ as colour, 0 specularity, 0 roughness:
Lambertian), emitting faces a `glow` of their radiance; coordinates turned from Y up to Radiance's
Z up by (x, y, z) -> (x, -z, y), so that our north (-Z) is Radiance's north (+Y), east +X in both.

Sky: gensky gives the sky function's arguments (`gensky -ang EL AZ_WEST_OF_SOUTH -c|+s|-u -B E -g
RHO`: -B is the horizontal diffuse irradiance, so the sky's radiance is in the units of E and rtrace
-I's output in the units of E too; the sun's azimuth in gensky is degrees west of south, =
bearing - 180). Not taken from gensky: its colours (the sky and ground glows are grey, 1 1 1, where
gensky's documented skyglow is 0.986 0.986 1.205 — luminance 1, RGB mean 1.059), its sun (gensky
sets the solar radiance from its own clear-sky model; here a `light` of radiance EN/Ω with Ω = 2π(1
- cos(0.533°/2)), the solid angle Radiance gives a `source` of 0.533°, so that its normal irradiance
is EN), and so the ground brightness: ρ_g (E + EN sin EL)/π, gensky's formula with this sun (gensky
adds its own sun's horizontal irradiance). The sky is a `glow` (no direct sampling: rtrace reaches
it through its ambient rays only), the sun a `source`.

Exit code 3 when the Radiance binaries (pyradiance's, or gensky/oconv/rtrace on PATH) are missing.
"""
import math
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time

SUN_DEG = 0.533


def binaries():
    """(bin dir or None for PATH, lib dir or None) of Radiance; exits 3 when missing."""
    try:
        import pyradiance

        root = os.path.dirname(pyradiance.__file__)
        b, lib = os.path.join(root, "bin"), os.path.join(root, "lib")
        if all(os.path.exists(os.path.join(b, x)) for x in ("gensky", "oconv", "rtrace")):
            return b, lib
    except ImportError:
        pass
    if all(shutil.which(x) for x in ("gensky", "oconv", "rtrace")):
        return None, os.environ.get("RAYPATH")
    print("Radiance binaries (gensky, oconv, rtrace) not found: pip install pyradiance",
          file=sys.stderr)
    sys.exit(3)


BIN, LIB = binaries()


def exe(name):
    return os.path.join(BIN, name) if BIN else name


def parse_args(argv):
    opts = {"sky": "overcast", "eh": 10000.0, "ground": 0.2, "sun": None, "fn": "cie",
            "threads": 2, "check": False}
    rest = []
    i = 0
    while i < len(argv):
        a = argv[i]
        if a == "--sky":
            opts["sky"] = argv[i + 1]
        elif a == "--eh":
            opts["eh"] = float(argv[i + 1])
        elif a == "--ground":
            opts["ground"] = float(argv[i + 1])
        elif a == "--sun":
            opts["sun"] = [float(x) for x in argv[i + 1].split(",")]
        elif a == "--sky-fn":
            opts["fn"] = argv[i + 1]
        elif a == "--threads":
            opts["threads"] = int(argv[i + 1])
        elif a == "--check":
            opts["check"] = True
            i += 1
            continue
        else:
            rest.append(a)
            i += 1
            continue
        i += 2
    return opts, rest


def zup(x, y, z):
    """Our Y-up coordinates in Radiance's Z-up frame (north -Z -> +Y)."""
    return x, -z, y


def sky_args(opts):
    """skybright.cal's arguments (A1..) from gensky, and the ground radiance."""
    kind = {"overcast": "-c", "clear": "+s", "uniform": "-u"}[opts["sky"]]
    if opts["sun"] is not None:
        az, el, en = opts["sun"]
    elif opts["sky"] == "clear":
        sys.exit("--sky clear needs --sun")
    else:
        az, el, en = 180.0, 45.0, 0.0  # no sun: its position does not enter -c and -u
    west_of_south = (az - 180.0 + 540.0) % 360.0 - 180.0
    cmd = [exe("gensky"), "-ang", repr(el), repr(west_of_south), kind, "-B", repr(opts["eh"]),
           "-g", repr(opts["ground"])]
    text = subprocess.run(cmd, capture_output=True, text=True, check=True).stdout
    m = re.search(r"brightfunc skyfunc\s+2 skybr skybright.cal\s+0\s+(\d+) (.*)", text)
    args = [float(a) for a in m.group(2).split()]
    # the ground glow with this sun (gensky adds its own sun's horizontal irradiance)
    sun_h = en * math.sin(math.radians(el)) if opts["sun"] is not None else 0.0
    args[2] = opts["ground"] * (opts["eh"] + sun_h) / math.pi
    return args, (az, el, en), text


def sky_text(opts, args, sun, fn):
    az, el, en = sun
    lines = []
    if opts["sun"] is not None and en > 0:
        omega = 2 * math.pi * (1 - math.cos(math.radians(SUN_DEG / 2)))
        l_sun = en / omega
        a, e = math.radians(az), math.radians(el)
        d = (math.cos(e) * math.sin(a), math.cos(e) * math.cos(a), math.sin(e))  # east, north, up
        lines += [f"void light solar 0 0 3 {l_sun!r} {l_sun!r} {l_sun!r}",
                  f"solar source sun 0 0 4 {d[0]!r} {d[1]!r} {d[2]!r} {SUN_DEG}"]
    name = "skybr" if fn == "gensky" else "skybr_cie"
    lines += [f"void brightfunc skyfunc 2 {name} skybright_cie.cal 0 {len(args)} "
              + " ".join(repr(a) for a in args),
              "skyfunc glow skyglow 0 0 4 1 1 1 0",
              "skyglow source sky 0 0 4 0 0 1 180",
              "skyfunc glow groundglow 0 0 4 1 1 1 0",
              "groundglow source ground 0 0 4 0 0 -1 180"]
    return "\n".join(lines) + "\n"


CAL = """{ skybright.cal's skybr, and skybr_cie: the same sky above the horizon and the ground below,
  without skybr's blend of the two about the horizon }
skybr_cie = if(Dz, select(A1, sunnysky, cloudysky, unifsky, intersky), A3);
"""


def scene_text(faces_path):
    out = []
    with open(faces_path) as f:
        for k, line in enumerate(f):
            v = [float(x) for x in line.split()]
            if len(v) < 15:
                continue
            rho, em = v[9:12], v[12:15]
            if any(e > 0 for e in em):
                out.append(f"void glow m{k} 0 0 4 {em[0]!r} {em[1]!r} {em[2]!r} 0")
            else:
                out.append(f"void plastic m{k} 0 0 5 {rho[0]!r} {rho[1]!r} {rho[2]!r} 0 0")
            pts = " ".join(" ".join(repr(c) for c in zup(*v[3 * i:3 * i + 3])) for i in range(3))
            out.append(f"m{k} polygon f{k} 0 0 9 {pts}")
    return "\n".join(out) + "\n"


def rays_text(points_path):
    out = []
    with open(points_path) as f:
        for line in f:
            v = [float(x) for x in line.split()]
            if len(v) == 6:
                out.append(" ".join(repr(c) for c in (*zup(*v[:3]), *zup(*v[3:]))))
    return "\n".join(out) + "\n"


def rtrace(octree, rays, setting, threads, env):
    ab, ad, as_, aa, lw = setting[:5]
    ar = ["-ar", str(int(setting[5]))] if len(setting) > 5 and setting[5] > 0 else []
    ar += ["-lr", str(int(setting[6]))] if len(setting) > 6 else []
    cmd = [exe("rtrace"), "-I", "-h", "-ab", str(int(ab)), "-ad", str(int(ad)), "-as",
           str(int(as_)), "-aa", repr(aa), "-lw", repr(lw), *ar, "-n", str(threads), octree]
    t0 = time.perf_counter()
    res = subprocess.run(cmd, input=rays, capture_output=True, text=True, env=env)
    seconds = time.perf_counter() - t0
    if res.returncode != 0:
        sys.exit(f"rtrace failed: {res.stderr}")
    rows = [[float(x) for x in l.split()[:3]] for l in res.stdout.splitlines() if l.strip()]
    return rows, seconds


def main():
    opts, args = parse_args(sys.argv[1:])
    faces, points, out, *settings = args
    settings = [[float(x) for x in s.split(",")] for s in settings]
    with tempfile.TemporaryDirectory() as d:
        with open(os.path.join(d, "skybright_cie.cal"), "w") as f:
            f.write(open(os.path.join(LIB, "skybright.cal")).read() if LIB else "")
            f.write(CAL)
        env = dict(os.environ, RAYPATH=os.pathsep.join([d, LIB or ".", "."]))
        args_, sun, gensky_out = sky_args(opts)
        print("gensky: " + " ".join(l for l in gensky_out.splitlines() if l.startswith("#")))
        print("skybright args: " + " ".join(f"{a:.6g}" for a in args_))
        for fn in ("cie", "gensky") if opts["check"] else ():
            sky = os.path.join(d, f"check-{fn}.rad")
            with open(sky, "w") as f:
                f.write(sky_text(opts, args_, (sun[0], sun[1], 0.0), fn))
            oct_ = os.path.join(d, f"check-{fn}.oct")
            with open(oct_, "wb") as f:
                subprocess.run([exe("oconv"), sky], stdout=f, check=True, env=env, cwd=d)
            rows, _ = rtrace(oct_, "0 0 0 0 0 1\n", (1, 65536, 0, 0, 1e-9), 1, env)
            print(f"check fn={fn} E_h={sum(rows[0]) / 3:.6g}", flush=True)
        rad = os.path.join(d, "scene.rad")
        with open(rad, "w") as f:
            f.write(sky_text(opts, args_, sun, opts["fn"]))
            f.write(scene_text(faces))
        rays = rays_text(points)
        octree = os.path.join(d, "scene.oct")
        t0 = time.perf_counter()
        with open(octree, "wb") as f:
            subprocess.run([exe("oconv"), rad], stdout=f, check=True, env=env, cwd=d)
        t_oconv = time.perf_counter() - t0
        for k, s in enumerate(settings):
            rows, seconds = rtrace(octree, rays, s, opts["threads"], env)
            with open(f"{out}.{k}", "w") as f:
                f.writelines(f"{r[0]:.9g} {r[1]:.9g} {r[2]:.9g}\n" for r in rows)
            print(f"setting={k} oconv={t_oconv:.3f} rtrace={seconds:.3f}", flush=True)


main()
