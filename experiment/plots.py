#!/usr/bin/env python3
"""Plots of an experiment directory written by `scatterlab experiment` (docs/harness.md).

    python3 experiment/plots.py DIR

Reads DIR/results.json and writes DIR/plots/*.png (matplotlib, Agg backend):
  error_vs_samples.png     rel. L2 against the headline reference vs samples (sampled methods)
  time_vs_resolution.png   frame time vs the `resolution` axis, one line per method+backend
  time_vs_lights.png       frame time vs the `lights` axis
  time_vs_image_size.png   frame time vs pixels (the `image_size` axis)
  stage_breakdown.png      stacked per-stage median times of every successful run
A plot is only made when the experiment has the data for it.
"""
import json
import os
import sys
from collections import defaultdict

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def label(run):
    b = run.get("backend", "cpu")
    return run["method"] + ("" if b == "cpu" else f" ({b})")


def series(runs, axis, key):
    """{(sweep, scene, method label, other axes): [(x, y)]} over runs that have `axis`."""
    out = defaultdict(list)
    for r in runs:
        if r.get("status") != "ok" or axis not in r.get("axes", {}):
            continue
        other = tuple(sorted((k, json.dumps(v)) for k, v in r["axes"].items() if k != axis))
        x = r["axes"][axis]
        y = key(r)
        if y is None:
            continue
        out[(r["sweep"], r["scene"], label(r), other)].append((x, y))
    return out


def line_plot(path, data, xlabel, ylabel, title, logx=False, logy=False, xfun=lambda x: x):
    if not data:
        return False
    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    many_scenes = len({k[1] for k in data}) > 1
    many_sweeps = len({k[0] for k in data}) > 1
    for (sweep, scene, meth, other), pts in sorted(data.items()):
        pts = sorted((xfun(x), y) for x, y in pts)
        name = meth
        if many_sweeps:
            name = f"{sweep}: {name}"
        if many_scenes:
            name += f" [{scene}]"
        if other:
            name += " " + ", ".join(f"{k}={json.loads(v)}" for k, v in other)
        ax.plot([p[0] for p in pts], [p[1] for p in pts], marker="o", label=name)
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    if logx:
        ax.set_xscale("log", base=2)
    if logy:
        ax.set_yscale("log")
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return True


def main():
    if len(sys.argv) != 2:
        print(__doc__)
        return 2
    d = sys.argv[1]
    with open(os.path.join(d, "results.json")) as f:
        res = json.load(f)
    runs = res["runs"]
    refs = res.get("references", [])
    ref = refs[0] if refs else None
    os.makedirs(os.path.join(d, "plots"), exist_ok=True)
    p = lambda name: os.path.join(d, "plots", name)  # noqa: E731
    total = lambda r: r["median_ms"].get("total")  # noqa: E731
    made = []

    # Error vs samples: every successful run with a sample count, grouped by everything except
    # the samples axis (so a samples sweep gives a line; fixed-sample runs give points).
    if ref:
        data = defaultdict(list)
        for r in runs:
            if r.get("status") != "ok" or "samples" not in r or ref not in r.get("errors", {}):
                continue
            other = tuple(sorted((k, json.dumps(v)) for k, v in r["axes"].items()
                                 if k not in ("samples", "epsilon")))
            data[(r["sweep"], r["scene"], label(r), other)].append(
                (r["samples"], 100.0 * r["errors"][ref]["rel_l2"]))
        if line_plot(p("error_vs_samples.png"), data, "samples",
                     f"relative L2 error vs {ref} (%)", "Error vs samples", logx=True):
            made.append("error_vs_samples.png")

    def res_x(v):
        return v if isinstance(v, (int, float)) else v[0]

    if line_plot(p("time_vs_resolution.png"), series(runs, "resolution", total),
                 "volume resolution (voxels per axis)", "frame time (ms, median)",
                 "Time vs volume resolution", logx=True, logy=True, xfun=res_x):
        made.append("time_vs_resolution.png")
    if line_plot(p("time_vs_lights.png"), series(runs, "lights", total), "number of lights",
                 "frame time (ms, median)", "Time vs number of lights", logx=True, logy=True):
        made.append("time_vs_lights.png")
    if line_plot(p("time_vs_image_size.png"), series(runs, "image_size", total),
                 "pixels", "frame time (ms, median)", "Time vs image size", logy=True,
                 xfun=lambda v: v[0] * v[1]):
        made.append("time_vs_image_size.png")

    # Per-stage breakdown: stacked horizontal bars.
    ok = [r for r in runs if r.get("status") == "ok"]
    stages = res.get("stages", [])
    if ok and stages:
        ok = ok[:60]
        fig, ax = plt.subplots(figsize=(7.5, 0.28 * len(ok) + 1.6))
        left = [0.0] * len(ok)
        for s in stages:
            vals = [r["median_ms"].get(s, 0.0) for r in ok]
            ax.barh(range(len(ok)), vals, left=left, label=s)
            left = [a + b for a, b in zip(left, vals)]
        ax.set_yticks(range(len(ok)))
        ax.set_yticklabels([r["id"] for r in ok], fontsize=6)
        ax.invert_yaxis()
        ax.set_xscale("symlog", linthresh=1.0)
        ax.set_xlabel("median time per stage (ms, stacked; symlog axis)")
        ax.set_title("Per-stage time breakdown")
        ax.legend(fontsize=7, loc="lower right")
        fig.tight_layout()
        fig.savefig(p("stage_breakdown.png"), dpi=110)
        plt.close(fig)
        made.append("stage_breakdown.png")
    print("plots:", ", ".join(made) if made else "none")
    return 0


if __name__ == "__main__":
    sys.exit(main())
