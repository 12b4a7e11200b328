#!/usr/bin/env python3
"""Issues 33 and 34's targets, judged from what a GPU report wrote (docs/gpu.md, "Running on a
real GPU"):

    python3 scripts/gpu-targets.py --report gpu-report [--table2 gpu-report/table2_gpu]

--report: the directory of `scripts/gpu-report.sh` (frames.json, test_gpu.txt); --table2: a
`scatterlab experiment data/experiments/table2_gpu.json` output (its results.json), what
`scripts/gpu-report.sh --table2` writes. Prints one line a target: the figure measured, the bound,
and `met`, `MISSED`, `not measured` (its input absent or the benchmark failed) or, for a time on
llvmpipe, `CPU time` (llvmpipe's times are the CPU's: only its counts, waits and errors are
judged). Exit 0 when it could read what it was given (missed targets included), 2 otherwise.
Plain python3, no third-party modules.
"""
import argparse
import json
import os
import re
import sys

# BM_GpuSteadyFrame / BM_GpuColdFrame's cases (bench/bench_gpu.cpp kFrameCases).
GRADIENT_PAPER, GRADIENT_DEFAULTS, PER_VOXEL, ADAPTIVE_PAPER, ADAPTIVE_DEFAULTS = range(5)
CASE_NAMES = ["gradient paper (plume)", "gradient defaults (plume)", "per-voxel (plume)",
              "adaptive paper (shaft)", "adaptive defaults (shaft)",
              "gradient defaults + far field (plume)"]

# The harness's steady rows and the Renderer frames that are the same work (since 2026-12-07 the
# report's frames put their lights on the harness's ring, experiment::ringOfLights, so every
# light count compares): (sweep, method, axis value) of data/experiments/table2_gpu.json -> the
# frame case at 128³ and its lights.
SAME_WORK = [
    (("resolution", "gradient-gpu", 128), GRADIENT_PAPER, 1),
    (("resolution", "gradient-gpu-defaults", 128), GRADIENT_DEFAULTS, 1),
    (("resolution", "per-voxel-gpu", 128), PER_VOXEL, 1),
    (("point_lights", "gradient-gpu", 64), GRADIENT_PAPER, 64),
    (("point_lights", "per-voxel-gpu", 64), PER_VOXEL, 64),
    (("spot_lights", "adaptive-gpu", 1), ADAPTIVE_PAPER, 1),
    (("spot_lights", "adaptive-gpu-defaults", 1), ADAPTIVE_DEFAULTS, 1),
    (("spot_lights", "adaptive-gpu", 64), ADAPTIVE_PAPER, 64),
    (("spot_lights", "adaptive-gpu-defaults", 64), ADAPTIVE_DEFAULTS, 64),
]


class Frames:
    """frames.json of the report: steady and cold frames by (kind, case, res, lights, raster)."""

    def __init__(self, path):
        with open(path) as f:
            text = f.read()
        self.cut = False
        try:
            doc = json.loads(text)
        except ValueError:
            # Google Benchmark writes a record as each benchmark ends: a file the report's
            # timeout cut (a slower device) ends after its last whole record, "    }", at the
            # records' indent. Judge what it holds, and say that it was cut.
            end = text.rfind("\n    }")
            if end < 0:
                raise
            doc = json.loads(text[:end + 6] + "\n  ]\n}")
            self.cut = True
        self.rows = {}
        self.device = ""
        for b in doc.get("benchmarks", []):
            m = re.match(r"BM_Gpu(Steady|Cold)Frame/(\d+)/(\d+)/(\d+)/(\d+)", b.get("name", ""))
            if not m:
                continue
            key = (m.group(1).lower(),) + tuple(int(x) for x in m.groups()[1:])
            if b.get("error_occurred"):
                self.rows[key] = {"error": b.get("error_message", "failed")}
                continue
            assert b.get("time_unit", "ms") == "ms", b["name"]
            self.rows[key] = b
            # "steady: fig3 gradient paper, 1 lights, compute, RENDERER" (frameLabel)
            parts = b.get("label", "").split(", ", 3)
            if not self.device and len(parts) == 4:
                self.device = parts[3]

    def get(self, kind, case, res, lights=1, raster=0):
        r = self.rows.get((kind, case, res, lights, raster))
        return None if r is None or "error" in r else r


class Verdicts:
    def __init__(self, hardware):
        self.hardware = hardware
        self.lines = []
        self.missed = 0

    def add(self, issue, target, figure, ok, timed=True):
        """ok: True, False or None (not measured); a time on llvmpipe is not judged."""
        if ok is None:
            v = "not measured"
        elif timed and not self.hardware:
            v = "CPU time"
        else:
            v = "met" if ok else "MISSED"
            self.missed += not ok
        self.lines.append((issue, target, figure, v))

    def print(self):
        wt = max(len(t) for _, t, _, _ in self.lines)
        wf = max(len(f) for _, _, f, _ in self.lines)
        for issue, t, f, v in self.lines:
            print(f"#{issue}  {t:<{wt}}  {f:<{wf}}  {v}")


def fps(ms):
    return 1000.0 / ms if ms and ms > 0 else float("inf")


def frame_targets(fr, v):
    steady = lambda case, res, lights=1: fr.get("steady", case, res, lights)
    # Issue 33: host waits of steady frames, every method, compute pipeline.
    waits, seen = [], 0
    for case in range(len(CASE_NAMES)):
        for res in (128, 256):
            for lights in (1, 64):
                r = steady(case, res, lights)
                if r is None:
                    continue
                seen += 1
                if r.get("host_waits", 0) != 0:
                    waits.append(f"{CASE_NAMES[case]} {res}³ {lights} lights: "
                                 f"{r['host_waits']:.0f}")
    v.add(33, "steady frames wait for nothing (host_waits 0)",
          f"{seen} frames, " + ("; ".join(waits) if waits else "all 0"),
          None if not seen else not waits, timed=False)

    # Gradient with the paper's samples: 1000 fps GPU / 500 wall at 128³; 500 GPU at 256³.
    for res, gpu_fps, wall_fps, issue in ((128, 1000, 500, 33), (256, 500, None, 34)):
        r = steady(GRADIENT_PAPER, res)
        if r is None:
            v.add(issue, f"gradient paper {res}³ ≥ {gpu_fps} fps GPU", "—", None)
            continue
        g, w = fps(r["gpu_ms"]), fps(r["real_time"])
        v.add(issue, f"gradient paper {res}³ ≥ {gpu_fps} fps GPU",
              f"{g:.0f} fps ({r['gpu_ms']:.3f} ms)", g >= gpu_fps)
        if wall_fps:
            v.add(issue, f"gradient paper {res}³ ≥ {wall_fps} fps wall",
                  f"{w:.0f} fps ({r['real_time']:.3f} ms)", w >= wall_fps)

    # The defaults within 2× of the paper's variant (wall, 128³, one light).
    p, d = steady(GRADIENT_PAPER, 128), steady(GRADIENT_DEFAULTS, 128)
    v.add(33, "gradient defaults within 2× of paper (128³ wall)",
          f"{d['real_time'] / p['real_time']:.2f}×" if p and d else "—",
          None if not (p and d) else d["real_time"] <= 2 * p["real_time"])

    # Adaptive on the shaft: 500 fps (GPU time; wall beside it).
    for case in (ADAPTIVE_PAPER, ADAPTIVE_DEFAULTS):
        r = steady(case, 128)
        name = f"{CASE_NAMES[case]} 128³ ≥ 500 fps GPU"
        if r is None:
            v.add(33, name, "—", None)
            continue
        v.add(33, name, f"{fps(r['gpu_ms']):.0f} fps GPU, {fps(r['real_time']):.0f} wall",
              fps(r["gpu_ms"]) >= 500)

    # Issue 34: per-voxel ≥ 500 fps GPU at 128³.
    r = steady(PER_VOXEL, 128)
    v.add(34, "per-voxel 128³ ≥ 500 fps GPU",
          f"{fps(r['gpu_ms']):.0f} fps ({r['gpu_ms']:.3f} ms)" if r else "—",
          None if r is None else fps(r["gpu_ms"]) >= 500)

    # gradient / per-voxel: ≥ 44× at 64 point lights, ≥ 1× at one (GPU time, both sizes).
    for lights, bound in ((64, 44.0), (1, 1.0)):
        for res in (128, 256):
            g, pv = steady(GRADIENT_PAPER, res, lights), steady(PER_VOXEL, res, lights)
            name = f"gradient paper / per-voxel {res}³ {lights} lights ≥ {bound:g}×"
            if not (g and pv):
                v.add(34, name, "—", None)
                continue
            ratio = pv["gpu_ms"] / g["gpu_ms"]
            v.add(34, name, f"{ratio:.1f}× ({pv['gpu_ms']:.3f} / {g['gpu_ms']:.3f} ms)",
                  ratio >= bound)

    # Issue 34's counts, judged on any device: the march skips half its steps on the plume, the
    # tracer runs an invocation per sample and light at least.
    r = steady(GRADIENT_PAPER, 128)
    v.add(34, "plume: march steps skipped ≥ 50 %",
          f"{r['skipped_pct']:.1f} %" if r else "—",
          None if r is None else r["skipped_pct"] >= 50, timed=False)
    r = steady(GRADIENT_PAPER, 128, 64)
    if r is None or not r.get("samples"):
        v.add(34, "tracer invocations ≥ samples × lights (64 lights)", "—", None, timed=False)
    else:
        need = r["samples"] * 64
        v.add(34, "tracer invocations ≥ samples × lights (64 lights)",
              f"{r['tracer_inv']:.0f} ≥ {need:.0f}", r["tracer_inv"] >= need, timed=False)


def test_gpu_target(path, v):
    if not os.path.exists(path):
        v.add(33, "test_gpu: 0 failures", "—", None, timed=False)
        return
    text = open(path, errors="replace").read()
    passed = re.search(r"\[  PASSED  \] (\d+) test", text)
    failed = re.search(r"\[  FAILED  \] (\d+) test", text)
    skipped = re.search(r"\[  SKIPPED \] (\d+) test", text)
    if not passed and not failed:
        v.add(33, "test_gpu: 0 failures", "no summary (cut off?)", False, timed=False)
        return
    # The report runs test_gpu with --gtest_brief=1, whose summary has no FAILED count: each
    # failed test has its own "[  FAILED  ] Suite.Name (N ms)" line.
    names = set(re.findall(r"^\[  FAILED  \] ([\w/]+\.[\w/]+)", text, re.M))
    n_fail = max(int(failed.group(1)) if failed else 0, len(names))
    fig = f"{passed.group(1) if passed else 0} passed, {n_fail} failed" + \
          (f", {skipped.group(1)} skipped" if skipped else "")
    v.add(33, "test_gpu: 0 failures", fig, n_fail == 0, timed=False)


def harness_targets(res, fr, v):
    runs = [r for r in res.get("runs", []) if r.get("status") == "ok"]
    by = {(r["sweep"], r["method"], next(iter(r["axes"].values()), None)): r for r in runs}
    # The harness's steady rows within 1.5× of the Renderer frames of the same work.
    for (sweep, method, x), case, lights in SAME_WORK:
        h = by.get((sweep, method, x))
        b = fr.get("steady", case, 128, lights) if fr else None
        name = (f"harness steady {method} ({lights} light{'s' if lights > 1 else ''}) "
                "within 1.5× of the Renderer frame")
        if not (h and h.get("steady") and b):
            v.add(33, name, "—", None)
            continue
        a, c = h["steady"]["wall_ms"], b["real_time"]
        v.add(33, name, f"{a:.3f} / {c:.3f} ms", max(a / c, c / a) <= 1.5)
    # The error-versus-frame-time plane (issue 34): gradient and adaptive on the Pareto front
    # beside froxel and jittered-march, steady GPU time against `exact` (the config's reference
    # when it has none), at every point of every sweep (the plume's resolutions, the shaft's
    # spot lights). Ours are judged against
    # the others (the competitors, per-voxel unless it is the reference itself), not against
    # each other's variants.
    refs = [x if isinstance(x, str) else x.get("name") for x in res.get("references", [])]
    ref = "exact" if "exact" in refs else (res.get("default_reference") or (refs or [None])[0])
    ours = ("gradient-gpu", "gradient-gpu-defaults", "adaptive-gpu", "adaptive-gpu-defaults")
    plane = {}
    for (sweep, method, x), r in by.items():
        e = r.get("errors", {}).get(ref, {}).get("rel_l2")
        t = (r.get("steady") or {}).get("gpu_ms")
        if e is None or not t or "raster" in method:
            continue
        if method not in ours and r.get("registered_method") == ref:
            continue  # the reference's own method: 0 error by construction
        plane.setdefault((sweep, x), {})[method] = (t, e)
    for (sweep, x) in sorted(plane):
        pts = plane[(sweep, x)]
        if not any(o not in ours for o in pts):
            continue  # nothing to be beaten by (the point_lights sweep: per-voxel and gradient)
        for m in (m for m in ours if m in pts):
            t, e = pts[m]
            over = [o for o, (to, eo) in pts.items()
                    if o not in ours and to <= t and eo <= e and (to < t or eo < e)]
            where = f"{x}³" if sweep == "resolution" else f"{sweep} {x}"
            v.add(34, f"{m} {where} on the Pareto front (vs {ref})",
                  f"{t:.3f} ms, {100 * e:.2f} %" + (f"; beaten by {', '.join(over)}" if over
                                                    else ""), not over)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--report", help="scripts/gpu-report.sh's output directory")
    ap.add_argument("--table2", help="the harness's output of data/experiments/table2_gpu.json")
    a = ap.parse_args()
    if not a.report and not a.table2:
        ap.error("give --report, --table2 or both")
    fr, res = None, None
    try:
        if a.report:
            fr = Frames(os.path.join(a.report, "frames.json"))
        if a.table2:
            with open(os.path.join(a.table2, "results.json")) as f:
                res = json.load(f)
    except (OSError, ValueError) as e:
        print(f"gpu-targets: {e}", file=sys.stderr)
        return 2
    device = fr.device if fr else ", ".join(
        m.get("gpu_renderers", [""])[0] for m in res.get("machines", []) if m.get("gpu_renderers"))
    hardware = bool(device) and "llvmpipe" not in device.lower()
    print(f"device: {device or 'unknown'}" +
          ("" if hardware else "  (not a GPU: times are CPU times, not judged)"))
    if fr and fr.cut:
        print(f"frames.json was cut short (the report's timeout for the frames?): "
              f"{len(fr.rows)} frames read; the targets of the others are not measured")
    v = Verdicts(hardware)
    if fr:
        frame_targets(fr, v)
        test_gpu_target(os.path.join(a.report, "test_gpu.txt"), v)
    if res:
        harness_targets(res, fr, v)
    v.print()
    failed = sorted((k, r["error"]) for k, r in (fr.rows.items() if fr else []) if "error" in r)
    for (kind, case, res, lights, raster), why in failed:
        name = CASE_NAMES[case] if case < len(CASE_NAMES) else f"case {case}"  # a newer bench
        print(f"frame failed: {kind} {name} {res}³ {lights} lights"
              f"{' raster' if raster else ''}: {why}")
    print(f"{v.missed} missed" + (f", {len(failed)} frames failed" if failed else ""))
    return 0


if __name__ == "__main__":
    sys.exit(main())
