#!/usr/bin/env python3
"""Writes data/scenes/fig3.json: the smoke-like sum-of-Gaussians medium of the Fig. 3 experiment.

Deterministic (fixed seed, pure Python): 800 Gaussians along a rising, curling plume in the box
[0,2]^3, weights scaled so that the density's maximum on a 64^3 grid of cell centres is 1.0
(the paper's Fig. 3: "density values range from 0.0 to 1.0"). sigma_t = 1.2, albedo 0.6, 128^3,
one point light close to the plume. FIG3_N, FIG3_RSCALE and FIG3_LIGHT override the count,
radius scale and light position (used while choosing them; docs/interpolation.md lists what was
tried). Run from the repository root:
    python3 data/experiments/make_fig3_scene.py
"""
import json
import math
import os
import random

rng = random.Random(20081)
N = int(os.environ.get("FIG3_N", 800))
RS = float(os.environ.get("FIG3_RSCALE", 0.5))
LIGHT = json.loads(os.environ.get("FIG3_LIGHT", "[1.75, 0.75, 0.8]"))
blobs = []
for n in range(N):
    t = (n + rng.random()) / N  # position along the plume, bottom to top
    # Centre line: rises from y=0.25 to y=1.75, drifts and curls in x/z.
    cx = 1.0 + 0.35 * math.sin(3.0 * t + 0.3) * t
    cy = 0.25 + 1.5 * t
    cz = 1.0 + 0.25 * math.cos(4.0 * t) * t
    spread = 0.08 + 0.22 * t  # the plume widens as it rises
    c = [cx + rng.gauss(0, spread), cy + rng.gauss(0, 0.5 * spread), cz + rng.gauss(0, spread)]
    c = [min(1.9, max(0.1, v)) for v in c]
    r = RS * (0.05 + 0.07 * rng.random()) * (0.7 + 0.8 * t)
    w = 0.3 + 0.7 * rng.random()
    blobs.append({"center": c, "radius": r, "weight": w})

# Maximum of the density on a 64^3 grid of cell centres (each blob culled beyond 3r).
G, lo, ext = 64, 0.0, 2.0
h = ext / G
acc = {}
for b in blobs:
    (x0, y0, z0), r, w = b["center"], b["radius"], b["weight"]
    R = 3 * r
    rng_i = lambda c: range(max(0, int((c - R) / h - 0.5)), min(G - 1, int((c + R) / h - 0.5) + 1) + 1)
    for k in rng_i(z0):
        z = (k + 0.5) * h
        for j in rng_i(y0):
            y = (j + 0.5) * h
            for i in rng_i(x0):
                x = (i + 0.5) * h
                q = (x - x0) ** 2 + (y - y0) ** 2 + (z - z0) ** 2
                if q < R * R:
                    key = (i, j, k)
                    acc[key] = acc.get(key, 0.0) + w * math.exp(-q / (r * r))
peak = max(acc.values())
for b in blobs:
    b["weight"] = round(b["weight"] / peak, 6)
    b["center"] = [round(v, 6) for v in b["center"]]
    b["radius"] = round(b["radius"], 6)

scene = {
    "medium": {
        "bounds": {"min": [0, 0, 0], "max": [2, 2, 2]},
        "density": {"type": "gaussians", "blobs": blobs},
        "resolution": 128,
        "sigma_t": 1.2,
        "albedo": 0.6,
        "phase": {"type": "isotropic"},
    },
    "lights": [{"type": "point", "position": LIGHT, "intensity": [30, 24, 18]}],
    "camera": {"position": [1, 1, -3.2], "look_at": [1, 1, 1], "up": [0, 1, 0],
               "fov_y_deg": 36, "width": 256, "height": 256},
    "background": [0, 0, 0],
    "render": {"method": "gradient", "sampler": {"type": "gaussian-centres"}},
}
with open("data/scenes/fig3.json", "w") as f:
    json.dump(scene, f, indent=1)
print(f"{N} Gaussians, peak density before scaling {peak:.3f}")
