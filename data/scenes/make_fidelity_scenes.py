#!/usr/bin/env python3
"""Writes the scenes of the fidelity experiment (issue #11) that exercise where the paper's
method fails: a lamp inside a puff, 32 lamps in a fog bank, a perforated dense sheet with a
light behind it, a spot shaft through OpenVDB smoke1, and a chimney trail of ~600 Gaussians lit
from outside. Deterministic (fixed seeds). Run from anywhere: python3 make_fidelity_scenes.py"""
import array
import json
import math
import os
import random
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
CAMERA = {"position": [0.5, 0.5, -2], "look_at": [0.5, 0.5, 0.5], "up": [0, 1, 0],
          "fov_y_deg": 40, "width": 320, "height": 240}


def write(name, scene):
    with open(os.path.join(HERE, name), "w") as f:
        json.dump(scene, f, indent=1)
        f.write("\n")


def r3(v):
    return [round(x, 4) for x in v]


# A lamp inside a puff: one soft Gaussian puff with a warm point light a little off its centre.
rng = random.Random(11)
blobs = [{"center": [0.5, 0.5, 0.5], "radius": 0.22, "weight": 1.0}]
for _ in range(24):
    c = [0.5 + rng.uniform(-0.2, 0.2) for _ in range(3)]
    blobs.append({"center": r3(c), "radius": round(rng.uniform(0.05, 0.1), 4),
                  "weight": round(rng.uniform(0.3, 0.7), 4)})
write("lamp_puff.json", {
    "medium": {"bounds": {"min": [0, 0, 0], "max": [1, 1, 1]},
               "density": {"type": "gaussians", "blobs": blobs},
               "resolution": 96, "sigma_t": 3.0, "albedo": 0.7, "phase": {"type": "isotropic"}},
    "lights": [{"type": "point", "position": [0.53, 0.47, 0.48], "intensity": [3.0, 2.2, 1.4]}],
    "camera": CAMERA, "background": [0, 0, 0], "render": {"method": "exact"}})

# 32 lamps in a fog bank: a height fog over a wide box, lamps on a 8 x 4 grid at two heights.
lights = []
rng = random.Random(32)
for i in range(8):
    for j in range(4):
        x = 0.15 + i * 0.24 + rng.uniform(-0.03, 0.03)
        z = 0.2 + j * 0.4 + rng.uniform(-0.05, 0.05)
        y = 0.18 + 0.22 * ((i + j) % 2)
        col = [rng.uniform(0.6, 1.0), rng.uniform(0.5, 0.9), rng.uniform(0.3, 0.8)]
        s = 0.05
        lights.append({"type": "point", "position": r3([x, y, z]),
                       "intensity": r3([c * s for c in col])})
write("lamps32.json", {
    "medium": {"bounds": {"min": [0, 0, 0], "max": [2, 0.8, 1.6]},
               "density": {"type": "height", "bottom": 1.0, "top": 0.2},
               "resolution": [128, 52, 104], "sigma_t": 1.5, "albedo": 0.8,
               "phase": {"type": "henyey-greenstein", "g": 0.2}},
    "lights": lights,
    "camera": {"position": [1.0, 0.55, -1.3], "look_at": [1.0, 0.3, 0.8], "up": [0, 1, 0],
               "fov_y_deg": 55, "width": 320, "height": 240},
    "background": [0, 0, 0], "render": {"method": "exact"}})

# A perforated dense sheet (about 3 voxels thick at 64^3) in thin fog, a light behind it: the
# camera sees the shadowed front face, with light shafts through the holes.
blobs = [{"center": [0.5, 0.5, 0.5], "radius": 1.5, "weight": 0.08}]  # the thin fog
n = 20
for i in range(n):
    for j in range(n):
        x, y = (i + 0.5) / n, (j + 0.5) / n
        hole = (i % 5 in (1, 2) and j % 5 in (1, 2))
        if hole:
            continue
        blobs.append({"center": r3([x, y, 0.5]), "radius": 0.028, "weight": 12.0})
write("perforated_sheet.json", {
    "medium": {"bounds": {"min": [0, 0, 0], "max": [1, 1, 1]},
               "density": {"type": "gaussians", "blobs": blobs},
               "resolution": 64, "sigma_t": 6.0, "albedo": 0.8, "phase": {"type": "isotropic"}},
    "lights": [{"type": "point", "position": [0.55, 0.6, 0.95], "intensity": [1.5, 1.4, 1.2]}],
    "camera": {"position": [0.9, 0.6, -1.6], "look_at": [0.5, 0.5, 0.5], "up": [0, 1, 0],
               "fov_y_deg": 40, "width": 320, "height": 240},
    "background": [0, 0, 0], "render": {"method": "exact"}})

# A spot shaft through OpenVDB smoke1 (about 100 units wide).
write("shaft_smoke.json", {
    "medium": {"density": {"type": "vdb", "file": "../vdb/smoke1.vdb",
                           "grid": "density"},
               "resolution": 96, "sigma_t": 0.8, "albedo": 0.9,
               "phase": {"type": "henyey-greenstein", "g": 0.3}},
    "lights": [{"type": "spot", "position": [-60, 75, -20], "direction": [53, -35, 20],
                "intensity": [90000, 80000, 65000], "inner_deg": 12, "outer_deg": 16}],
    "camera": {"position": [-7, 40, -150], "look_at": [-7, 40, 0], "up": [0, 1, 0],
               "fov_y_deg": 45, "width": 320, "height": 240},
    "background": [0.01, 0.012, 0.02], "render": {"method": "exact"}})

# A chimney trail: ~600 Gaussians rising and drifting, lit by a light outside the box.
rng = random.Random(600)
blobs = []
for k in range(600):
    t = k / 600.0
    c = [0.2 + 0.6 * t + 0.05 * math.sin(9 * t) + rng.gauss(0, 0.02 + 0.05 * t),
         0.1 + 0.75 * t ** 0.8 + rng.gauss(0, 0.02 + 0.04 * t),
         0.5 + 0.08 * math.sin(5 * t) + rng.gauss(0, 0.02 + 0.05 * t)]
    blobs.append({"center": r3(c), "radius": round(0.025 + 0.05 * t, 4),
                  "weight": round(max(0.05, 0.9 - 0.6 * t + rng.uniform(-0.1, 0.1)), 4)})
write("chimney.json", {
    "medium": {"bounds": {"min": [0, 0, 0], "max": [1, 1, 1]},
               "density": {"type": "gaussians", "blobs": blobs},
               "resolution": 96, "sigma_t": 6.0, "albedo": 0.7, "phase": {"type": "isotropic"}},
    "lights": [{"type": "point", "position": [1.6, 1.3, 0.2], "intensity": [12, 10, 8]}],
    "camera": CAMERA, "background": [0.0, 0.0, 0.0],
    "render": {"method": "gradient", "sampler": {"type": "gaussian-centres"}}})

# Issue 24's held-out kinds, made here so they can be measured.
#
# A thin dense sheet lit from behind, fog in front: 128^3 over the unit box, a sheet 3 voxels
# thick (optical depth 9 across it) covering x, y in [0.12, 0.88], with 2x2-voxel holes every 16
# voxels and a vertical slit 1 voxel wide and 48 long; thin fog everywhere (optical depth 0.6
# across the box). Hard edges: a raw float32 grid (x fastest), written beside the scene.
N = 128
SHEET_Z = range(76, 79)
SIGMA_T = 4.0
SHEET_D = 9.0 / (SIGMA_T * len(SHEET_Z) / N)  # optical depth 9 across the 3 voxels
FOG_D = 0.15


def sheet_value(i, j, k):
    if k not in SHEET_Z or not (15 <= i < 113 and 15 <= j < 113):
        return FOG_D
    if i % 16 in (7, 8) and j % 16 in (7, 8) and not 88 <= i < 100:
        return FOG_D  # a small hole
    if i == 92 and 40 <= j < 88:
        return FOG_D  # the slit
    return SHEET_D


plane = {}
for k in set(SHEET_Z):
    plane[k] = array.array("f", [sheet_value(i, j, k) for j in range(N) for i in range(N)])
fog_plane = array.array("f", [FOG_D] * (N * N))
with open(os.path.join(HERE, "thin_sheet.f32"), "wb") as f:
    for k in range(N):
        p = plane.get(k, fog_plane)
        if sys.byteorder != "little":
            p = array.array("f", p)
            p.byteswap()
        p.tofile(f)
write("thin_sheet.json", {
    "medium": {"bounds": {"min": [0, 0, 0], "max": [1, 1, 1]},
               "density": {"type": "grid", "dims": [N, N, N], "file": "thin_sheet.f32"},
               "resolution": N, "sigma_t": SIGMA_T, "albedo": 0.8,
               "phase": {"type": "isotropic"}},
    "lights": [{"type": "point", "position": [0.56, 0.62, 0.97], "intensity": [1.6, 1.5, 1.3]}],
    "camera": {"position": [0.85, 0.58, -1.5], "look_at": [0.5, 0.5, 0.55], "up": [0, 1, 0],
               "fov_y_deg": 40, "width": 320, "height": 240},
    "background": [0, 0, 0], "render": {"method": "exact"}})

# Optically thick clouds (the Disney cloud at 128^3, twice the density of cloud.json): an HG
# cloud lit from behind-left and an isotropic one, where the linear Taylor step of `gradient`
# undershoots the convex transmittance.
for name, phase in (("thick_cloud", {"type": "henyey-greenstein", "g": 0.5}),
                    ("thick_cloud_iso", {"type": "isotropic"})):
    write(name + ".json", {
        "medium": {"density": {"type": "vdb",
                               "file": "../vdb/wdas_cloud_sixteenth.vdb",
                               "grid": "density"},
                   "resolution": 128, "sigma_t": 0.06, "albedo": 0.95, "phase": phase},
        "lights": [{"type": "directional", "direction": [0.5, -0.6, 0.6],
                    "irradiance": [24, 23, 21]}],
        "camera": {"position": [0, 20, -620], "look_at": [-10, 70, 0], "up": [0, 1, 0],
                   "fov_y_deg": 45, "width": 320, "height": 240},
        "background": [0.16, 0.28, 0.52], "render": {"method": "exact"}})
