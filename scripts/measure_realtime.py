#!/usr/bin/env python3
"""Frame times and errors of the real-time methods (light-space-march, radial-blur) against
`exact` on demo scenes, through the command-line tool: for every scene and size, `exact` is
rendered once (the reference), then each method on the CPU and, for scenes without objects,
on the GPU backend (llvmpipe where there is no GPU: the device is printed); the relative L2
comes from `scatterlab compare`, also with the pixels next to each light masked (`--scene`,
docs/metrics.md: a point light in view makes a few pixels dominate the plain relative L2), the
time from the stats' timings_ms.total (whole frame: density build included). Prints a Markdown table and the load average. Speed is measured
here, never asserted in tests.

    python3 scripts/measure_realtime.py [--sizes 320x240,800x600] [--scenes glow,shaft,...]
"""
import argparse
import json
import os
import re
import subprocess
import sys
import tempfile

METHODS = [
    ("light-space-march", []),
    ("light-space-march", ["render.light_transmittance=traced"]),
    ("radial-blur", []),
]


def run(cli, args):
    return subprocess.run([cli] + args, capture_output=True, text=True)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--cli", default="build/bin/scatterlab")
    ap.add_argument("--sizes", default="320x240,800x600")
    ap.add_argument("--scenes", default="glow,shaft,smoke,cloud,dusty_room,window")
    ap.add_argument("--gpu", action="store_true", help="also the GPU backend (llvmpipe here)")
    a = ap.parse_args()
    tmp = tempfile.mkdtemp(prefix="realtime_")
    print("load average before:", os.getloadavg())
    print("| scene | size | method | backend | frame ms | rel. L2 vs exact | masked rel. L2 |")
    print("|---|---|---|---|---|---|---|")
    for size in a.sizes.split(","):
        w, h = size.split("x")
        for scene in a.scenes.split(","):
            path = f"data/scenes/{scene}.json"
            sets = ["--set", f"camera.width={w}", "--set", f"camera.height={h}"]
            ref = f"{tmp}/{scene}_{size}_exact.exr"
            r = run(a.cli, ["render", path, "-o", ref, "--method", "exact", "--backend", "cpu",
                            "--stats", ref + ".json"] + sets)
            if r.returncode:
                print(f"| {scene} | {size} | exact | cpu | error: {r.stderr.strip()} | |")
                continue
            t = json.load(open(ref + ".json"))["timings_ms"]["total"]
            print(f"| {scene} | {size} | exact | cpu | {t:.0f} | 0 | 0 |", flush=True)
            backends = ["cpu", "gpu"] if a.gpu else ["cpu"]
            for method, extra in METHODS:
                label = method + ("".join(f" ({e.split('=')[1]})" for e in extra))
                for b in backends:
                    tag = "".join("_" + e.split("=")[1] for e in extra)
                    out = f"{tmp}/{scene}_{size}_{method}{tag}_{b}.exr"
                    args = ["render", path, "-o", out, "--method", method, "--backend", b,
                            "--stats", out + ".json"] + sets
                    for e in extra:
                        args += ["--set", e]
                    r = run(a.cli, args)
                    if r.returncode:
                        msg = r.stderr.strip().splitlines()[-1].replace("scatterlab: error: ", "")
                        print(f"| {scene} | {size} | {label} | {b} | refused: {msg} | | |",
                              flush=True)
                        continue
                    st = json.load(open(out + ".json"))
                    c = run(a.cli, ["compare", out, ref, "--scene", path] + sets)
                    m = re.search(r"relative L2 error: ([0-9.e+-]+)", c.stdout)
                    k = re.search(r"masked rel. L2: +([0-9.e+-]+)", c.stdout)
                    dev = st.get("device", "")
                    bl = b if b == "cpu" else f"gpu ({dev.split(' (')[0]})"
                    print(f"| {scene} | {size} | {label} | {bl} | {st['timings_ms']['total']:.0f} "
                          f"| {float(m.group(1)):.3f} | {float(k.group(1)):.3f} |", flush=True)
    print("load average after:", os.getloadavg())


if __name__ == "__main__":
    sys.exit(main())
