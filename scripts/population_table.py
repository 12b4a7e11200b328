#!/usr/bin/env python3
"""The population table of an experiment directory (issue 35, docs/fidelity.md "Population of
scenes"): per method, over every scene it rendered, the median and the worst scene's error
against the headline reference (masked relative L2, visibly wrong) and its time as a ratio to
per-voxel's on the same scene (both measured in the same run), how many scenes the whole-scene
fallback rendered as per-voxel renders them (`gradient` and `adaptive` runs without samples,
render.voxel_switch), with how many scenes miss the
issue's targets, and how many of those miss on error alone (times within ±20 % of per-voxel's
vary between runs of the same work on a small machine; errors do not):
  adaptive-like methods: masked rel L2 <= max(1 %, 1.2 x per-voxel's), visibly wrong <=
  max(0.5 %, per-voxel's), time <= per-voxel's;
  gradient-like methods: masked rel L2 <= max(2 %, 2 x per-voxel's), time <= per-voxel's.
A method is adaptive-like when its registered method is `adaptive`, gradient-like for `gradient`.
Usage: scripts/population_table.py OUT_DIR [--baseline per-voxel] [--worst N]
Prints a Markdown table; --worst N also lists each method's N worst scenes."""
import argparse
import csv
import math
import os
import statistics
import sys


def number(row, key):
    v = row.get(key, "")
    try:
        x = float(v)
    except ValueError:
        return None
    return x if math.isfinite(x) else None


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("dir")
    ap.add_argument("--baseline", default="per-voxel")
    ap.add_argument("--worst", type=int, default=0)
    a = ap.parse_args()
    path = os.path.join(a.dir, "results.csv")
    try:
        with open(path, newline="") as f:
            rows = list(csv.DictReader(f))
    except OSError as e:
        sys.exit(f"population_table: cannot read '{path}': {e.strerror}")
    if not rows:
        sys.exit(f"population_table: '{path}' has no runs")
    ref = next((k[len("masked_rel_l2_vs_"):] for k in rows[0] if k.startswith("masked_rel_l2_vs_")),
               None)
    if ref is None:
        sys.exit(f"population_table: '{path}' has no masked_rel_l2_vs_<reference> column")
    err, vis = f"masked_rel_l2_vs_{ref}", f"visibly_wrong_vs_{ref}"
    ok = [r for r in rows if r.get("status") == "ok" and number(r, err) is not None]
    base = {r["scene"]: r for r in ok if r["method"] == a.baseline}
    if not base:
        sys.exit(f"population_table: no successful '{a.baseline}' runs in '{path}'")
    methods = []
    for r in ok:
        if r["method"] not in methods:
            methods.append(r["method"])
    failed = [r for r in rows if r.get("status") != "ok"]
    print(f"{len(base)} scenes; errors against `{ref}` (masked relative L2, %; visibly wrong, % "
          f"of pixels); time as a ratio to {a.baseline}'s on the same scene (same run)\n")
    print("| method | scenes | masked rel L2 median | worst | worst / per-voxel's | visibly wrong "
          "median | worst | time / per-voxel median | worst | samples median | per-voxel instead | "
          "misses target | of them on error |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    worst_lists = {}
    for m in methods:
        rs = [r for r in ok if r["method"] == m and r["scene"] in base]
        if not rs:
            continue
        kind = rs[0].get("registered_method", m)
        e = [100 * number(r, err) for r in rs]
        v = [100 * (number(r, vis) or 0.0) for r in rs]
        ratio = [number(r, "total_ms") / number(base[r["scene"]], "total_ms") for r in rs]
        erel = [number(r, err) / max(number(base[r["scene"]], err), 1e-12) for r in rs]
        samples = [number(r, "samples") for r in rs if number(r, "samples")]
        # The whole-scene fallback leaves a sampled method without samples.
        instead = (str(sum(1 for r in rs if not number(r, "samples")))
                   if kind in ("adaptive", "gradient") else "—")
        misses = error_misses = 0
        for r, ei, vi, ti in zip(rs, e, v, ratio):
            be = 100 * number(base[r["scene"]], err)
            bv = 100 * (number(base[r["scene"]], vis) or 0.0)
            if kind == "adaptive":
                wrong = ei > max(1.0, 1.2 * be) or vi > max(0.5, bv)
            elif kind == "gradient":
                wrong = ei > max(2.0, 2.0 * be)
            else:
                wrong = False
            misses += wrong or (kind in ("adaptive", "gradient") and ti > 1.0)
            error_misses += wrong
        worst_lists[m] = sorted(zip(e, v, ratio, [r["scene"] for r in rs]), reverse=True)
        target = (f"{misses} | {error_misses}" if kind in ("adaptive", "gradient") else "— | —")
        print(f"| {m} | {len(rs)} | {statistics.median(e):.2f} | {max(e):.2f} | "
              f"{max(erel):.2f} | {statistics.median(v):.2f} | {max(v):.2f} | "
              f"{statistics.median(ratio):.2f} | {max(ratio):.2f} | "
              f"{statistics.median(samples) if samples else 0:.0f} | {instead} | {target} |")
    if failed:
        print(f"\n{len(failed)} runs failed: " +
              ", ".join(f"{r['scene']}/{r['method']}" for r in failed))
    if a.worst:
        for m, lst in worst_lists.items():
            print(f"\n{m}, worst {a.worst} by masked rel L2: " + "; ".join(
                f"{s} {e:.2f} % ({v:.2f} % visibly wrong, {t:.2f}x time)"
                for e, v, t, s in lst[:a.worst]))


if __name__ == "__main__":
    main()
