#!/usr/bin/env python3
"""Writes the population of scenes of issue 35 (item 4): 60 random scenes, twelve families x five
seeds, of the kinds users render, so that defaults can be chosen on a population rather than on
the 14 shipped scenes (data/experiments/population.json renders them; docs/fidelity.md,
"Population of scenes (issue 35)").

One generator function per family; scene FAMILY_K.json (K = 0..4) is drawn from
random.Random(1000 * F + K), F the family's number below, so the files are the same on every run
and every machine (python3's random is portable; numbers are rounded to 4 digits). Every scene is
JSON only: procedural densities (gaussians, height, uniform, dusty-room), except that
spot_smoke_1 and spot_smoke_3 use the shipped OpenVDB smoke (data/vdb/smoke1.vdb) and some
occluder scenes the shipped bunny mesh (data/meshes/bun_zipper_res3.obj). Each family varies
the density scale (sigma_t), albedo, phase, light colours and intensities, and the camera.

 1 sheet       thin dense sheets/slabs of Gaussians (1-2 layers, optical depth 3-12 across) with
               holes and/or slits, in thin fog, a point or spot light behind, camera in front
 2 wisp        thin filaments of small Gaussians (1-2 voxels thick) under a spot light
 3 plume       chimney trails / plumes of 200-600 growing Gaussians lit from outside the box
 4 cloud_low   Gaussian-cluster clouds under a low sun (directional, 2-8 deg above the
               horizon, HG g 0.5-0.7), sky background; the box reaches well past the clusters
 5 cloud_high  clouds drawn the same way under a high sun (45-85 deg), HG g 0.4-0.8
 6 fogbank     height fog (or dusty-room noise fog) banks with 8-40 point lamps
 7 spot_smoke  a spot light through smoke: multi-scale Gaussian smoke, or smoke1.vdb (K = 1, 3)
 8 occluder    spheres, boxes or the bunny casting volumetric shadows in uniform/height/noise fog
 9 lamp_in     a light inside the medium: one or two lamps in a puff of Gaussians
10 lamp_out    a light outside the medium: a point or spot lamp beside a box of noise fog or of
               smooth Gaussians
11 fog_shaft   uniform or height fog with a spot shaft
12 dense_puff  1-6 small dense puffs (optical depth 10-60 through the centre) with a point light
               near one of them

Resolutions are 72-144 voxels per axis (48-96 drawn, times RES_SCALE 1.5), cells about cubic in
the wide boxes. Cameras are 320x240 (the experiment renders at 160x120).
Run from anywhere: python3 make_population.py (writes the 60 JSONs next to itself; --list prints
their names instead). python3 make_population.py --holdout writes 120 more from seeds K = 5..14
(the same families and draws, so no VDB file) into holdout/ next to itself: scenes no default
was chosen on, to check a choice made on the first 60 (data/experiments/population_holdout.json;
docs/fidelity.md, "log_space re-checked on the population")."""
import json
import math
import os
import random
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
SEEDS = range(5)
HOLDOUT_SEEDS = range(5, 15)
VDB_SMOKE = "../../vdb/smoke1.vdb"
BUNNY = "../../meshes/bun_zipper_res3.obj"
# bun_zipper_res3.obj's bounding box (min, max), for placing it on the floor
BUNNY_BOX = ([-0.0944, 0.0334, -0.0617], [0.0609, 0.1848, 0.0585])


# ---- output -------------------------------------------------------------------------------

def dumps(obj, ind=0):
    """JSON with short objects and arrays on one line (Gaussians one a line)."""
    flat = json.dumps(obj)
    if not isinstance(obj, (dict, list)) or len(flat) + ind <= 96:
        return flat
    pad = " " * (ind + 1)
    if isinstance(obj, dict):
        items = [pad + json.dumps(k) + ": " + dumps(v, ind + 1) for k, v in obj.items()]
        return "{\n" + ",\n".join(items) + "\n" + " " * ind + "}"
    return "[\n" + ",\n".join(pad + dumps(v, ind + 1) for v in obj) + "\n" + " " * ind + "]"


def write(name, scene, out=HERE):
    with open(os.path.join(out, name + ".json"), "w") as f:
        f.write(dumps(scene))
        f.write("\n")


# ---- helpers ------------------------------------------------------------------------------

def r4(x):
    return round(x, 4)


def v3(v):
    return [round(x, 4) for x in v]


def add(a, b):
    return [x + y for x, y in zip(a, b)]


def sub(a, b):
    return [x - y for x, y in zip(a, b)]


def mul(a, s):
    return [x * s for x in a]


def norm(a):
    n = math.sqrt(sum(x * x for x in a))
    return [x / n for x in a]


def dist(a, b):
    return math.sqrt(sum((x - y) ** 2 for x, y in zip(a, b)))


def clamp(x, lo, hi):
    return max(lo, min(hi, x))


def sphere_dir(rng, elev_lo_deg, elev_hi_deg):
    """A unit vector elev degrees above the horizon, any azimuth."""
    e = math.radians(rng.uniform(elev_lo_deg, elev_hi_deg))
    a = rng.uniform(0, 2 * math.pi)
    return [math.cos(e) * math.sin(a), math.sin(e), math.cos(e) * math.cos(a)]


def tint(rng, lo=-1.0, hi=1.0):
    """A light colour from cool (-1) through white (0) to warm (+1), max channel 1."""
    t = rng.uniform(lo, hi)
    end = (1.0, 0.76, 0.5) if t > 0 else (0.7, 0.82, 1.0)
    return [1 + abs(t) * (c - 1) for c in end]


def colour(rng, intensity, lo=-1.0, hi=1.0):
    return v3(mul(tint(rng, lo, hi), intensity))


def phase(rng, g_lo=-0.1, g_hi=0.8, p_iso=0.3):
    if rng.random() < p_iso:
        return {"type": "isotropic"}
    return {"type": "henyey-greenstein", "g": round(rng.uniform(g_lo, g_hi), 3)}


# Every drawn resolution times RES_SCALE (rounded to a multiple of 8): 72-144 voxels per axis,
# the sizes users render (the held-out scenes were 96-128; at 48-96 per-voxel is so cheap
# that a budget in cost is never tested). The draws themselves do not depend on it.
RES_SCALE = 1.5


def scaled(n):
    return max(8, int(round(n * RES_SCALE / 8)) * 8)


def resolution(rng, lo=48, hi=96):
    return scaled(rng.randrange(lo, hi + 1, 8))


def box_resolution(extent, n_max):
    """Voxels per axis, n_max along the longest axis, cells about cubic."""
    m = max(extent)
    return [max(24, int(round(n_max * e / m))) for e in extent]


def camera(rng, target, dist_lo, dist_hi, yaw=(-35, 35), pitch=(-5, 25), fov=(35, 50)):
    """A pinhole camera on the -z side of target, looking at it."""
    y = math.radians(rng.uniform(*yaw))
    p = math.radians(rng.uniform(*pitch))
    d = rng.uniform(dist_lo, dist_hi)
    pos = add(target, [d * math.sin(y) * math.cos(p), d * math.sin(p),
                       -d * math.cos(y) * math.cos(p)])
    return {"position": v3(pos), "look_at": v3(target), "up": [0, 1, 0],
            "fov_y_deg": round(rng.uniform(*fov), 1), "width": 320, "height": 240}


def background(rng, p_black=0.6):
    if rng.random() < p_black:
        return [0, 0, 0]
    s = rng.uniform(0.005, 0.03)
    return v3([s, s * 1.15, s * 1.6])


def blob(c, r, w):
    return {"center": v3(c), "radius": r4(r), "weight": r4(w)}


def medium(bounds, density, res, sigma_t, albedo, ph):
    m = {}
    if bounds is not None:
        m["bounds"] = {"min": v3(bounds[0]), "max": v3(bounds[1])}
    m.update({"density": density, "resolution": res, "sigma_t": r4(sigma_t),
              "albedo": r4(albedo), "phase": ph})
    return m


def scene(med, lights, cam, bg, objects=None):
    s = {"medium": med, "lights": lights}
    if objects:
        s["objects"] = objects
    s.update({"camera": cam, "background": bg, "render": {"method": "exact"}})
    return s


def point(pos, intensity):
    return {"type": "point", "position": v3(pos), "intensity": intensity}


def spot(pos, target, intensity, outer, inner_share):
    return {"type": "spot", "position": v3(pos), "direction": v3(norm(sub(target, pos))),
            "intensity": intensity, "inner_deg": round(outer * inner_share, 2),
            "outer_deg": round(outer, 2)}


UNIT = ([0, 0, 0], [1, 1, 1])
CENTRE = [0.5, 0.5, 0.5]


def cloud_blobs(rng, centre, size):
    """A cumulus-like cluster: a few big Gaussians, small ones on their upper surfaces, a
    flattened base."""
    blobs = []
    big = []
    base = centre[1] - 0.35 * size
    for _ in range(rng.randint(4, 8)):
        r = size * rng.uniform(0.22, 0.38)
        c = [centre[0] + size * rng.uniform(-0.45, 0.45),
             centre[1] + size * rng.uniform(-0.1, 0.25),
             centre[2] + size * rng.uniform(-0.4, 0.4)]
        c[1] = max(c[1], base + 0.5 * r)
        big.append((c, r))
        blobs.append(blob(c, r, rng.uniform(0.7, 1.0)))
    for _ in range(rng.randint(40, 140)):
        c0, r0 = rng.choice(big)
        d = norm([rng.gauss(0, 1), abs(rng.gauss(0, 1)) + 0.2, rng.gauss(0, 1)])
        r = size * rng.uniform(0.05, 0.13)
        c = add(c0, mul(d, r0 * rng.uniform(0.7, 1.05)))
        c[1] = max(c[1], base + 0.5 * r)
        blobs.append(blob(c, r, rng.uniform(0.4, 0.9)))
    return blobs


# ---- the families -------------------------------------------------------------------------

def sheet(rng, k):
    """1: a thin dense sheet (slab) with holes or slits, fog, a light behind, camera in front."""
    res = resolution(rng, 48, 96)
    sigma_t = rng.uniform(3, 8)
    n = rng.randint(14, 26)                  # Gaussians per side
    s = 0.8 / n                              # their spacing
    r = 0.56 * s                             # flat in the plane
    layers = rng.choice([1, 1, 2])
    tau = rng.uniform(3, 12)                 # optical depth across the sheet
    w = tau / (sigma_t * layers * (math.pi * r * r / (s * s)) * r * math.sqrt(math.pi))
    zc = rng.uniform(0.42, 0.6)
    a, b = math.radians(rng.uniform(-25, 25)), math.radians(rng.uniform(-15, 15))
    u = [math.cos(a), 0, -math.sin(a)]
    nrm = [math.sin(a) * math.cos(b), -math.sin(b), math.cos(a) * math.cos(b)]
    v = [nrm[1] * u[2] - nrm[2] * u[1], nrm[2] * u[0] - nrm[0] * u[2],
         nrm[0] * u[1] - nrm[1] * u[0]]
    removed = set()
    kind = rng.choice(["holes", "slits", "both"])
    if kind in ("holes", "both"):
        p = rng.uniform(0.04, 0.12)
        size = rng.choice([1, 2])
        for i in range(n):
            for j in range(n):
                if rng.random() < p:
                    removed.update((i + di, j + dj) for di in range(size) for dj in range(size))
    if kind in ("slits", "both"):
        for _ in range(rng.randint(1, 3)):
            length = rng.randint(n // 4, n - 4)
            fixed, start = rng.randint(2, n - 3), rng.randint(1, n - length - 1)
            vertical = rng.random() < 0.5
            for t in range(start, start + length):
                removed.add((fixed, t) if vertical else (t, fixed))
    fog_tau = rng.uniform(0.3, 1.2)          # across the box
    blobs = [blob(CENTRE, 1.5, fog_tau / sigma_t)]
    centre = [0.5, 0.5, zc]
    for layer in range(layers):
        off = (layer - 0.5 * (layers - 1)) * 0.9 * r
        for i in range(n):
            for j in range(n):
                if (i, j) in removed:
                    continue
                x, y = (i + 0.5) * s - 0.4, (j + 0.5) * s - 0.4
                blobs.append(blob(add(centre, add(add(mul(u, x), mul(v, y)), mul(nrm, off))), r, w))
    behind = add(centre, [rng.uniform(-0.25, 0.25), rng.uniform(-0.15, 0.3), 0])
    behind[2] = rng.uniform(0.8, 1.3)
    d = dist(behind, centre)
    e = rng.uniform(10, 40)                  # irradiance at the sheet
    if rng.random() < 0.35:
        light = spot(behind, add(centre, [rng.uniform(-0.1, 0.1), rng.uniform(-0.1, 0.1), 0]),
                     colour(rng, e * d * d), rng.uniform(20, 45), rng.uniform(0.4, 0.9))
    else:
        light = point(behind, colour(rng, e * d * d))
    return scene(medium(UNIT, {"type": "gaussians", "blobs": blobs}, res, sigma_t,
                        rng.uniform(0.6, 0.95), phase(rng, -0.2, 0.6)),
                 [light], camera(rng, [0.5, 0.5, 0.5], 1.7, 2.2, pitch=(-10, 20)),
                 background(rng))


def wisp(rng, k):
    """2: wisps: thin filaments of small Gaussians (1-2 voxels across) under a spot light."""
    res = resolution(rng, 64, 96)
    h = 1.0 / res
    r = h * rng.uniform(0.5, 1.0)
    sp = 0.7 * r
    sigma_t = rng.uniform(5, 20)
    blobs = []
    for _ in range(rng.randint(3, 6)):
        tau = rng.uniform(0.3, 2.5)          # optical depth across the filament
        w = tau * sp / (sigma_t * math.pi * r * r)
        p = [rng.uniform(0.2, 0.8), rng.uniform(0.1, 0.4), rng.uniform(0.25, 0.75)]
        d = norm([rng.gauss(0, 0.5), 1.0, rng.gauss(0, 0.5)])
        turn = rng.uniform(0.05, 0.2)
        for _ in range(int(rng.uniform(0.4, 0.9) / sp)):
            blobs.append(blob(p, r, w * rng.uniform(0.7, 1.0)))
            d = norm(add(d, [rng.gauss(0, turn) for _ in range(3)]))
            p = add(p, mul(d, sp))
            if not all(0.06 < x < 0.94 for x in p):
                break
    pos = [rng.uniform(0.25, 0.75), rng.uniform(1.1, 1.5), rng.uniform(0.25, 0.75)]
    target = [rng.uniform(0.4, 0.6), rng.uniform(0.3, 0.5), rng.uniform(0.4, 0.6)]
    e = rng.uniform(6, 16)
    light = spot(pos, target, colour(rng, e * dist(pos, target) ** 2), rng.uniform(15, 35),
                 rng.uniform(0.5, 0.9))
    return scene(medium(UNIT, {"type": "gaussians", "blobs": blobs}, res, sigma_t,
                        rng.uniform(0.6, 0.95), phase(rng)),
                 [light], camera(rng, [0.5, 0.5, 0.5], 1.6, 2.2), background(rng))


def plume(rng, k):
    """3: a plume / chimney trail of growing Gaussians, lit from outside the box."""
    res = resolution(rng, 64, 96)
    n = rng.randint(200, 600)
    x0, z0 = rng.uniform(0.15, 0.35), rng.uniform(0.4, 0.6)
    drift, rise = rng.uniform(0.3, 0.55), rng.uniform(0.65, 0.8)
    wig, freq = rng.uniform(0.02, 0.08), rng.uniform(4, 10)
    r0, r1 = rng.uniform(0.015, 0.03), rng.uniform(0.04, 0.08)
    spread = rng.uniform(0.03, 0.06)
    blobs = []
    for i in range(n):
        t = i / n
        c = [x0 + drift * t + wig * math.sin(freq * t) + rng.gauss(0, 0.015 + spread * t),
             0.1 + rise * t ** 0.8 + rng.gauss(0, 0.015 + 0.8 * spread * t),
             z0 + wig * math.sin(0.6 * freq * t + 1) + rng.gauss(0, 0.015 + spread * t)]
        c = [clamp(x, 0.05, 0.95) for x in c]
        blobs.append(blob(c, r0 + (r1 - r0) * t,
                          max(0.05, 0.9 - 0.6 * t + rng.uniform(-0.1, 0.1))))
    sigma_t = rng.uniform(2, 10)
    if rng.random() < 0.3:
        lights = [{"type": "directional", "direction": v3(mul(sphere_dir(rng, 20, 60), -1)),
                   "irradiance": colour(rng, rng.uniform(5, 12))}]
    else:
        pos = add(CENTRE, mul(sphere_dir(rng, 10, 60), rng.uniform(1.0, 1.5)))
        lights = [point(pos, colour(rng, rng.uniform(5, 12) * dist(pos, CENTRE) ** 2))]
    return scene(medium(UNIT, {"type": "gaussians", "blobs": blobs}, res, sigma_t,
                        rng.uniform(0.5, 0.9), phase(rng)),
                 lights, camera(rng, [0.5, 0.5, 0.5], 2.1, 2.7), background(rng))


def cloud(rng, elev_lo, elev_hi, g_lo, g_hi, warm):
    res = resolution(rng, 80, 96)
    blobs = cloud_blobs(rng, [0.5, 0.45, 0.5], rng.uniform(0.45, 0.55))
    sigma_t = rng.uniform(6, 30)
    sun = sphere_dir(rng, elev_lo, elev_hi)
    lights = [{"type": "directional", "direction": v3(mul(sun, -1)),
               "irradiance": colour(rng, rng.uniform(6, 16), *warm)}]
    sky = rng.uniform(0.6, 1.2)
    bg = v3([0.16 * sky, 0.28 * sky, 0.52 * sky]) if warm[0] <= 0 else \
        v3([0.3 * sky, 0.24 * sky, 0.28 * sky])
    # a box well beyond the Gaussians' tails, which are bright against a low sun
    box = ([-0.3, -0.1, -0.3], [1.3, 1.1, 1.3])
    return scene(medium(box, {"type": "gaussians", "blobs": blobs},
                        box_resolution([1.6, 1.2, 1.6], res), sigma_t, rng.uniform(0.9, 0.99),
                        {"type": "henyey-greenstein", "g": round(rng.uniform(g_lo, g_hi), 3)}),
                 lights, camera(rng, [0.5, 0.5, 0.5], 2.2, 2.8, pitch=(-12, 15)), bg)


def cloud_low(rng, k):
    """4: a cloud under a low sun (2-8 deg above the horizon), warm light, HG g 0.5-0.7."""
    return cloud(rng, 2, 8, 0.5, 0.7, (0.4, 1.0))


def cloud_high(rng, k):
    """5: a cloud under a high sun (45-85 deg), white light, HG g 0.4-0.8."""
    return cloud(rng, 45, 85, 0.4, 0.8, (-0.2, 0.2))


def fogbank(rng, k):
    """6: a fog bank (height fog, or dusty-room noise over it) with 8-40 point lamps."""
    ext = [rng.uniform(1.6, 2.4), rng.uniform(0.6, 1.0), rng.uniform(1.2, 2.0)]
    res = box_resolution(ext, scaled(rng.randrange(64, 81, 8)))
    if rng.random() < 0.4:
        dens = {"type": "dusty-room", "floor": r4(rng.uniform(0.6, 1.2)),
                "ceiling": r4(rng.uniform(0.05, 0.3)), "amplitude": r4(rng.uniform(0.1, 0.3)),
                "frequency": r4(rng.uniform(3, 8)), "octaves": 3, "seed": rng.randint(1, 999)}
    else:
        dens = {"type": "height", "bottom": r4(rng.uniform(0.6, 1.5)),
                "top": r4(rng.uniform(0.0, 0.3))}
    n = rng.randint(8, 40)
    each = rng.uniform(0.02, 0.1) * math.sqrt(32.0 / n)
    lights = []
    street = rng.random() < 0.5
    for i in range(n):
        if street:                           # two rows of street lamps
            x = (i // 2 + 0.5) / ((n + 1) // 2) * ext[0] + rng.uniform(-0.03, 0.03)
            z = ext[2] * (0.3 if i % 2 == 0 else 0.7) + rng.uniform(-0.05, 0.05)
            y = ext[1] * rng.uniform(0.3, 0.45)
        else:
            x, z = rng.uniform(0.05, 0.95) * ext[0], rng.uniform(0.05, 0.95) * ext[2]
            y = ext[1] * rng.uniform(0.08, 0.7)
        lights.append(point([x, y, z], colour(rng, each * rng.uniform(0.5, 1.5), -0.3, 1.0)))
    target = [ext[0] / 2, ext[1] * 0.35, ext[2] / 2]
    cam = camera(rng, target, 1.9, 2.6, yaw=(-30, 30), pitch=(5, 25), fov=(50, 60))
    return scene(medium(([0, 0, 0], ext), dens, res, rng.uniform(0.8, 2.5),
                        rng.uniform(0.7, 0.9), phase(rng, 0.0, 0.5, 0.4)),
                 lights, cam, background(rng, 0.8))


def spot_smoke(rng, k):
    """7: a spot light through smoke: smoke1.vdb (K = 1, 3) or multi-scale Gaussian smoke."""
    if k in (1, 3):
        centre = [-7, 40, 0]
        target = [rng.uniform(-20, 8), rng.uniform(15, 75), rng.uniform(-12, 12)]
        pos = add(target, mul(sphere_dir(rng, -10, 50), rng.uniform(60, 90)))
        e = rng.uniform(12, 30)
        light = spot(pos, target, colour(rng, e * dist(pos, target) ** 2),
                     rng.uniform(8, 20), rng.uniform(0.5, 0.85))
        return scene(medium(None, {"type": "vdb", "file": VDB_SMOKE, "grid": "density"},
                            resolution(rng, 64, 96), rng.uniform(0.4, 1.6),
                            rng.uniform(0.8, 0.95), phase(rng, 0.1, 0.5, 0.2)),
                     [light], camera(rng, centre, 140, 170, yaw=(-40, 40), pitch=(-8, 15),
                                     fov=(40, 48)),
                     v3([0.01, 0.012, 0.02]))
    res = resolution(rng, 64, 96)
    blobs = []
    p = [rng.uniform(0.35, 0.65), 0.08, rng.uniform(0.35, 0.65)]
    d = [0, 1, 0]
    for i in range(rng.randint(60, 120)):
        t = i / 120
        d = norm(add(d, [rng.gauss(0, 0.35), rng.gauss(0.15, 0.2), rng.gauss(0, 0.35)]))
        p = [clamp(x, 0.15, 0.85) for x in add(p, mul(d, rng.uniform(0.01, 0.02)))]
        big = rng.uniform(0.04, 0.07) + 0.06 * t
        blobs.append(blob(p, big, rng.uniform(0.3, 0.8)))
        for _ in range(rng.randint(1, 3)):   # small eddies around it
            q = add(p, [rng.gauss(0, big) for _ in range(3)])
            blobs.append(blob(q, big * rng.uniform(0.2, 0.5), rng.uniform(0.3, 1.2)))
    pos = add(CENTRE, mul(sphere_dir(rng, 15, 70), rng.uniform(0.9, 1.4)))
    target = add(CENTRE, [rng.uniform(-0.15, 0.15) for _ in range(3)])
    e = rng.uniform(4, 10)
    light = spot(pos, target, colour(rng, e * dist(pos, target) ** 2), rng.uniform(8, 20),
                 rng.uniform(0.5, 0.85))
    return scene(medium(UNIT, {"type": "gaussians", "blobs": blobs}, res, rng.uniform(2, 8),
                        rng.uniform(0.7, 0.95), phase(rng, 0.0, 0.6)),
                 [light], camera(rng, [0.5, 0.5, 0.5], 2.1, 2.7), background(rng))


def occluder(rng, k):
    """8: objects (spheres, boxes, the bunny) casting volumetric shadows in fog."""
    res = resolution(rng, 48, 96)
    kind = rng.choice(["uniform", "height", "dusty-room"])
    if kind == "uniform":
        dens = {"type": "uniform", "value": 1.0}
    elif kind == "height":
        dens = {"type": "height", "bottom": r4(rng.uniform(0.8, 1.4)),
                "top": r4(rng.uniform(0.1, 0.6))}
    else:
        dens = {"type": "dusty-room", "floor": r4(rng.uniform(0.7, 1.1)),
                "ceiling": r4(rng.uniform(0.3, 0.6)), "amplitude": r4(rng.uniform(0.1, 0.35)),
                "frequency": r4(rng.uniform(3, 7)), "octaves": 3, "seed": rng.randint(1, 999)}
    objects = []
    if rng.random() < 0.6:
        objects.append({"type": "box", "min": [-0.5, -0.05, -0.5], "max": [1.5, 0, 1.5],
                        "albedo": r4(rng.uniform(0.3, 0.7))})
    for _ in range(rng.randint(1, 3)):
        c = [rng.uniform(0.25, 0.75), rng.uniform(0.25, 0.6), rng.uniform(0.3, 0.7)]
        alb = colour(rng, rng.uniform(0.4, 0.85), -0.4, 0.4)
        shape = rng.choice(["sphere", "box", "box", "mesh"])
        if shape == "sphere":
            objects.append({"type": "sphere", "center": v3(c),
                            "radius": r4(rng.uniform(0.06, 0.15)), "albedo": alb})
        elif shape == "box":
            half = [rng.uniform(0.03, 0.15) for _ in range(3)]
            objects.append({"type": "box", "min": v3(sub(c, half)), "max": v3(add(c, half)),
                            "albedo": alb})
        else:
            sc = rng.uniform(2.5, 4.0)
            lo, hi = BUNNY_BOX
            mid = [(a + b) / 2 for a, b in zip(lo, hi)]
            objects.append({"type": "mesh", "file": BUNNY,
                            "transform": {"translate": v3([c[0] - sc * mid[0], -sc * lo[1],
                                                           c[2] - sc * mid[2]]),
                                          "rotate_deg": [0, round(rng.uniform(0, 360), 1), 0],
                                          "scale": r4(sc)},
                            "albedo": alb})
    how = rng.choice(["spot", "point", "directional"])
    e = rng.uniform(2, 6)
    if how == "directional":
        lights = [{"type": "directional", "direction": v3(mul(sphere_dir(rng, 25, 65), -1)),
                   "irradiance": colour(rng, e)}]
    else:
        # above and behind the objects, so their shadows fall through the fog towards the camera
        pos = [rng.uniform(0.1, 0.9), rng.uniform(0.85, 1.3), rng.uniform(0.75, 1.2)]
        target = [rng.uniform(0.35, 0.65), rng.uniform(0.1, 0.4), rng.uniform(0.2, 0.5)]
        intensity = colour(rng, e * dist(pos, target) ** 2)
        lights = [spot(pos, target, intensity, rng.uniform(25, 45), rng.uniform(0.6, 0.9))
                  if how == "spot" else point(pos, intensity)]
    return scene(medium(UNIT, dens, res, rng.uniform(0.5, 2.0), rng.uniform(0.6, 0.9),
                        phase(rng, 0.0, 0.5)),
                 lights, camera(rng, [0.5, 0.45, 0.5], 2.0, 2.6, pitch=(0, 20)),
                 [0, 0, 0], objects)


def lamp_in(rng, k):
    """9: a light inside the medium: one or two lamps in a puff of Gaussians."""
    res = resolution(rng, 48, 96)
    c0 = [rng.uniform(0.4, 0.6) for _ in range(3)]
    r0 = rng.uniform(0.15, 0.25)
    blobs = [blob(c0, r0, 1.0)]
    for _ in range(rng.randint(10, 40)):
        c = add(c0, [rng.uniform(-0.9, 0.9) * r0 for _ in range(3)])
        blobs.append(blob(c, rng.uniform(0.04, 0.1), rng.uniform(0.2, 0.8)))
    lights = []
    for _ in range(1 if rng.random() < 0.7 else 2):
        pos = add(c0, [rng.uniform(-0.35, 0.35) * r0 for _ in range(3)])
        lights.append(point(pos, colour(rng, rng.uniform(0.5, 3.0), -0.3, 1.0)))
    return scene(medium(UNIT, {"type": "gaussians", "blobs": blobs}, res, rng.uniform(1, 8),
                        rng.uniform(0.5, 0.95), phase(rng)),
                 lights, camera(rng, c0, 2.0, 2.6), background(rng))


def lamp_out(rng, k):
    """10: a light outside the medium: a lamp beside a box of noise fog or of smooth Gaussians."""
    res = resolution(rng, 48, 96)
    if rng.random() < 0.5:
        dens = {"type": "dusty-room", "floor": r4(rng.uniform(0.4, 1.0)),
                "ceiling": r4(rng.uniform(0.1, 0.5)), "amplitude": r4(rng.uniform(0.2, 0.5)),
                "frequency": r4(rng.uniform(3, 9)), "octaves": rng.randint(2, 4),
                "seed": rng.randint(1, 999)}
        sigma_t = rng.uniform(0.8, 2.5)
    else:
        blobs = [blob([rng.uniform(0.25, 0.75) for _ in range(3)], rng.uniform(0.1, 0.25),
                      rng.uniform(0.4, 1.0)) for _ in range(rng.randint(3, 12))]
        dens = {"type": "gaussians", "blobs": blobs}
        sigma_t = rng.uniform(2, 8)
    # a point beyond one face of the box, 0.15-0.7 outside it
    axis = rng.choice([0, 1, 2, 0, 1])
    pos = [rng.uniform(0.1, 0.9) for _ in range(3)]
    pos[axis] = 1 + rng.uniform(0.15, 0.7) if rng.random() < 0.7 or axis == 2 else \
        -rng.uniform(0.15, 0.7)
    e = rng.uniform(4, 12)
    intensity = colour(rng, e * dist(pos, CENTRE) ** 2)
    if rng.random() < 0.35:
        light = spot(pos, add(CENTRE, [rng.uniform(-0.2, 0.2) for _ in range(3)]), intensity,
                     rng.uniform(20, 40), rng.uniform(0.5, 0.9))
    else:
        light = point(pos, intensity)
    return scene(medium(UNIT, dens, res, sigma_t, rng.uniform(0.6, 0.95), phase(rng)),
                 [light], camera(rng, [0.5, 0.5, 0.5], 2.0, 2.6), background(rng))


def fog_shaft(rng, k):
    """11: uniform or height fog with a spot shaft."""
    ext = [rng.uniform(1, 1.6), rng.uniform(0.8, 1.2), rng.uniform(1, 1.6)]
    res = box_resolution(ext, scaled(rng.randrange(72, 97, 8)))
    if rng.random() < 0.5:
        dens = {"type": "uniform", "value": 1.0}
    else:
        dens = {"type": "height", "bottom": r4(rng.uniform(0.8, 1.5)),
                "top": r4(rng.uniform(0.1, 0.8))}
    centre = mul(ext, 0.5)
    inside = rng.random() < 0.3
    pos = [rng.uniform(0.2, 0.8) * ext[0], ext[1] * (rng.uniform(0.85, 0.95) if inside else
                                                     rng.uniform(1.05, 1.4)),
           rng.uniform(0.2, 0.8) * ext[2]]
    target = [rng.uniform(0.2, 0.8) * ext[0], 0, rng.uniform(0.2, 0.8) * ext[2]]
    d = dist(pos, centre)
    light = spot(pos, target, colour(rng, rng.uniform(4, 14) * d * d), rng.uniform(8, 25),
                 rng.uniform(0.5, 0.9))
    return scene(medium(([0, 0, 0], ext), dens, res, rng.uniform(0.5, 2.5), rng.uniform(0.5, 0.9),
                        phase(rng, 0.0, 0.7)),
                 [light], camera(rng, centre, 1.5 * max(ext), 1.9 * max(ext)), background(rng))


def dense_puff(rng, k):
    """12: 1-6 small dense puffs (optical depth 10-60 through the centre), a point light near."""
    res = resolution(rng, 48, 96)
    sigma_t = rng.uniform(10, 40)
    blobs = []
    puffs = []
    for _ in range(rng.randint(1, 6)):
        c = [rng.uniform(0.3, 0.7) for _ in range(3)]
        r = rng.uniform(0.04, 0.1)
        tau = rng.uniform(10, 60)
        w = tau / (sigma_t * r * math.sqrt(math.pi))
        puffs.append((c, r))
        blobs.append(blob(c, r, w))
        for _ in range(rng.randint(0, 4)):   # lumps
            blobs.append(blob(add(c, [rng.gauss(0, 0.5 * r) for _ in range(3)]),
                              r * rng.uniform(0.3, 0.6), w * rng.uniform(0.3, 0.8)))
    mid = [sum(p[0][i] for p in puffs) / len(puffs) for i in range(3)]
    c, r = rng.choice(puffs)
    # beside the puff, on the camera's side of it more often than not
    side = norm([rng.gauss(0, 1), rng.gauss(0, 1), -abs(rng.gauss(0, 1)) + 0.3])
    pos = add(c, mul(side, r * rng.uniform(1.6, 3.5)))
    lights = [point(pos, colour(rng, rng.uniform(0.05, 0.4)))]
    return scene(medium(UNIT, {"type": "gaussians", "blobs": blobs}, res, sigma_t,
                        rng.uniform(0.5, 0.95), phase(rng)),
                 lights, camera(rng, mid, 1.3, 1.8), background(rng))


FAMILIES = [sheet, wisp, plume, cloud_low, cloud_high, fogbank, spot_smoke, occluder, lamp_in,
            lamp_out, fog_shaft, dense_puff]


def names():
    return [f"{fam.__name__}_{k}" for fam in FAMILIES for k in SEEDS]


def main():
    global VDB_SMOKE, BUNNY
    args = sys.argv[1:]
    if args == ["--list"]:
        print("\n".join(names()))
        return
    out, seeds = HERE, SEEDS
    if args == ["--holdout"]:
        out, seeds = os.path.join(HERE, "holdout"), HOLDOUT_SEEDS
        os.makedirs(out, exist_ok=True)
        VDB_SMOKE, BUNNY = "../" + VDB_SMOKE, "../" + BUNNY  # one directory deeper
    elif args:
        print("usage: make_population.py [--list | --holdout]", file=sys.stderr)
        sys.exit(2)
    for f, fam in enumerate(FAMILIES, 1):
        for k in seeds:
            write(f"{fam.__name__}_{k}", fam(random.Random(1000 * f + k), k), out)


if __name__ == "__main__":
    main()
