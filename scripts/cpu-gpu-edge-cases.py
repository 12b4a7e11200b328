#!/usr/bin/env python3
"""CPU = GPU on scenes made by hand, not drawn at random (docs/gpu.md, "Edge cases"): variants of
data/scenes/glow.json at 32^3 voxels and 64 x 48 pixels that sit on the edges where the two
backends may round apart (a camera down the box's axis, zoomed; tiny and flat volumes; a lamp on
a face, a corner, a voxel vertex; extreme extinction, albedo, phase and fields of view; scaled
and moved worlds; odd image sizes), each rendered by per-voxel, gradient and adaptive on both
backends and the GPU image compared with the CPU's (relative L2, `scatterlab compare`; issue 33's
bound 1e-4). Both images black (nothing reaches the camera) counts as equal.
Usage: scripts/cpu-gpu-edge-cases.py [OUT_DIR]   (default cpu-gpu-edge-cases/; after
  scripts/setup.sh, or through the GPU bundle like scripts/gpu-report.sh). Writes
  OUT_DIR/edge_cases.txt (one line per case) and the scenes and images; exit 1 when a render
  fails or a pair differs by more than the bound. About 5 minutes on llvmpipe (2 cores)."""
import copy
import json
import os
import shutil
import subprocess
import sys

BOUND = 1e-4
METHODS = ("per-voxel", "gradient", "adaptive")
ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def cli():
    local = os.path.join(ROOT, "build", "bin", "scatterlab")
    found = local if os.access(local, os.X_OK) else shutil.which("scatterlab")
    if not found:
        sys.exit("cpu-gpu-edge-cases: build first (scripts/setup.sh)")
    return found


def cases(base):
    """(name, scene) for every variant of `base`."""

    def variant(name, *edits):
        d = copy.deepcopy(base)
        for e in edits:
            e(d)
        return name, d

    def put(path, value):
        def edit(d):
            o = d
            for k in path[:-1]:
                o = o[k]
            o[path[-1]] = value

        return edit

    def world(k, offset):
        """The whole scene scaled by k about the origin and moved by offset: the same image."""

        def edit(d):
            at = lambda p: [c * k + o for c, o in zip(p, offset)]
            m = d["medium"]
            m["bounds"] = {"min": at(m["bounds"]["min"]), "max": at(m["bounds"]["max"])}
            m["sigma_t"] /= k
            for b in m["density"]["blobs"]:
                b["center"], b["radius"] = at(b["center"]), b["radius"] * k
            for l in d["lights"]:
                l["position"] = at(l["position"])
                l["intensity"] = [i * k * k for i in l["intensity"]]
            d["camera"]["position"] = at(d["camera"]["position"])
            d["camera"]["look_at"] = at(d["camera"]["look_at"])

        return edit

    lamp = base["lights"][0]
    spot = lambda outer, inner: {"type": "spot", "position": [0.5, 1.3, 0.5],
                                 "direction": [0, -1, 0], "intensity": [8, 6, 4],
                                 "outer_deg": outer, "inner_deg": inner}
    return [
        variant("base"),
        variant("voxels_2", put(["medium", "resolution"], 2)),
        variant("voxels_3x5x7", put(["medium", "resolution"], [3, 5, 7])),
        variant("voxels_64x2x40", put(["medium", "resolution"], [64, 2, 40])),
        variant("sigma_t_1000", put(["medium", "sigma_t"], 1000.0)),
        variant("sigma_t_1e-6", put(["medium", "sigma_t"], 1e-6)),
        variant("albedo_0", put(["medium", "albedo"], 0.0)),
        variant("camera_inside", put(["camera", "position"], [0.3, 0.4, 0.45])),
        variant("lamp_on_face", put(["lights", 0, "position"], [0.52, 0.5, 0.0])),
        variant("lamp_on_corner", put(["lights", 0, "position"], [1.0, 1.0, 1.0])),
        variant("lamp_on_voxel_vertex", put(["lights", 0, "position"], [0.5, 0.5, 0.5])),
        variant("lamp_zero", put(["lights", 0, "intensity"], [0, 0, 0])),
        variant("hg_0.99", put(["medium", "phase"], {"type": "henyey-greenstein", "g": 0.99})),
        variant("hg_-0.99", put(["medium", "phase"], {"type": "henyey-greenstein", "g": -0.99})),
        variant("looking_away", put(["camera", "look_at"], [0.5, 0.5, -5])),
        variant("fov_170", put(["camera", "fov_y_deg"], 170)),
        variant("fov_0.5_down_the_axis", put(["camera", "fov_y_deg"], 0.5)),
        variant("world_x1000", world(1000.0, [0, 0, 0])),
        variant("world_x0.001", world(0.001, [0, 0, 0])),
        variant("world_moved", world(1.0, [-100.5, 20, 7])),
        variant("spot_1deg", put(["lights", 0], spot(1.0, 0.0))),
        variant("spot_89deg", put(["lights", 0], spot(89.0, 80.0))),
        variant("sun_along_x", put(["lights", 0], {"type": "directional", "direction": [1, 0, 0],
                                                   "irradiance": [2, 2, 2]})),
        variant("two_coincident_lamps", lambda d: d["lights"].append(copy.deepcopy(lamp))),
        variant("lamps_40", lambda d: d["lights"].extend(
            {"type": "point", "position": [0.1 + 0.02 * i, 0.8, 0.3 + 0.01 * i],
             "intensity": [0.1, 0.1, 0.1]} for i in range(39))),
        variant("image_1x1", put(["camera", "width"], 1), put(["camera", "height"], 1)),
        variant("image_37x3", put(["camera", "width"], 37), put(["camera", "height"], 3)),
    ]


def main():
    out = os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else "cpu-gpu-edge-cases")
    os.makedirs(out, exist_ok=True)
    scatterlab = cli()
    with open(os.path.join(ROOT, "data", "scenes", "glow.json")) as f:
        base = json.load(f)
    base["medium"]["resolution"] = 32
    base["camera"].update(width=64, height=48)
    lines, failed, over, worst = [], 0, 0, 0.0
    for name, scene in cases(base):
        path = os.path.join(out, name + ".json")
        with open(path, "w") as f:
            json.dump(scene, f)
        row = [f"{name:24s}"]
        for method in METHODS:
            images, errors = {}, []
            for backend in ("cpu", "gpu"):
                image = os.path.join(out, f"{name}__{method}__{backend}.exr")
                p = subprocess.run([scatterlab, "render", path, "--method", method, "--backend",
                                    backend, "-o", image, "-q"], capture_output=True, text=True)
                if p.returncode:
                    errors.append(f"{backend}: {p.stderr.strip().splitlines()[-1:]}")
                images[backend] = image
            if errors:
                failed += 1
                row.append(f"{method} FAILED ({'; '.join(errors)})")
                continue
            p = subprocess.run([scatterlab, "compare", "--json", images["gpu"], images["cpu"]],
                               capture_output=True, text=True)
            c = json.loads(p.stdout)
            rel = c["rel_l2"]
            if not isinstance(rel, float):  # "inf"/"nan": the CPU's image is black
                rel = 0.0 if c["max_abs"] < 1e-9 else float("inf")
                note = " (black)" if rel == 0.0 else ""
            else:
                note = ""
            worst = max(worst, rel)
            over += rel > BOUND
            row.append(f"{method} {rel:.2e}{note}{' OVER' if rel > BOUND else ''}")
        lines.append("  ".join(row))
        print(lines[-1], flush=True)
    summary = (f"{len(lines)} cases x {len(METHODS)} methods; worst {worst:.3e}; above {BOUND:g}: "
               f"{over}; failed: {failed}")
    with open(os.path.join(out, "edge_cases.txt"), "w") as f:
        f.write("CPU vs GPU, relative L2 of the GPU image against the CPU's\n")
        f.write("\n".join(lines) + "\n" + summary + "\n")
    print(summary)
    return 1 if over or failed else 0


if __name__ == "__main__":
    sys.exit(main())
