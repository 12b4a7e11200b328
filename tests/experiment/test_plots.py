#!/usr/bin/env python3
"""ctest Plots.*: experiment/plots.py on a fake results.json (issue 25's plot items).

- Stage bars add up to 100 %: a run whose per-stage medians add up to more than its median total
  is drawn from `median_run_ms` (the repetition whose total is the median), and, in results
  without it, from the medians scaled down to the total; the caption says which.
- Pareto points carry labels of what the sweep varies (ε here), placed without overlapping.
- The reference tile's difference slot in the gallery holds the colour scale (recorded in
  gallery/index.json), not a blank.
"""
import importlib.util
import json
import os
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
SCRIPT = os.path.join(ROOT, "experiment", "plots.py")


def load_plots():
    spec = importlib.util.spec_from_file_location("plots", SCRIPT)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def fail(msg):
    print("FAIL:", msg)
    sys.exit(1)


def run(i, eps, total, rel, with_median_run=True):
    # Medians of the stages: 60 + 50 = 110 % of the median total (each from another repetition).
    r = {"id": f"eps__adaptive__epsilon-{eps}", "status": "ok", "sweep": "eps", "scene": "shaft",
         "method": "adaptive", "backend": "cpu", "axes": {"epsilon": eps},
         "median_ms": {"sampling": 0.6 * total, "march": 0.5 * total, "total": total},
         "errors": {"exact": {"rel_l2": rel}}, "samples": 1000 * (i + 1),
         "image": "images/run.png", "reference_images": {"exact": "references/exact.png"}}
    if with_median_run:
        r["median_run_ms"] = {"sampling": 0.55 * total, "march": 0.4 * total, "total": total}
    return r


def main():
    try:
        import matplotlib  # noqa: F401
        import numpy  # noqa: F401
    except ImportError:
        print("skipped: no matplotlib/numpy in", sys.executable)
        return 77
    plots = load_plots()
    stages = ["sampling", "march"]

    # Stage times: one repetition where recorded, else the medians scaled to the total.
    times, tot, how = plots.stage_times(run(0, 1e-3, 20.0, 0.1), stages)
    if how != "median run" or abs(sum(times.values()) - 19.0) > 1e-9 or tot != 20.0:
        fail(f"median run: {times} {tot} {how}")
    times, tot, how = plots.stage_times(run(0, 1e-3, 20.0, 0.1, with_median_run=False), stages)
    if how != "scaled" or abs(sum(times.values()) - 20.0) > 1e-9:
        fail(f"scaled: {times} {tot} {how}")
    if abs(times["sampling"] / times["march"] - 1.2) > 1e-9:
        fail(f"scaling must keep the ratios: {times}")

    # Labels: what varies, and none overlapping for a cluster of nearby points.
    if plots.point_label(run(0, 1e-4, 20.0, 0.1), ["epsilon"]) != "ε=0.0001":
        fail(plots.point_label(run(0, 1e-4, 20.0, 0.1), ["epsilon"]))
    if plots.point_label({"samples": 2748, "axes": {}}, []) != "2748 samples":
        fail("no axis: samples used")
    fig, ax = plots.plt.subplots(figsize=(5, 3.5))
    pts = [(28, 0.47, "ε=0.01"), (44, 0.47, "ε=0.0001"), (52, 0.471, "ε=0.001"),
           (50, 0.46, "ε=3e-05"), (30, 0.48, "ε=0.003")]
    for x, y, _ in pts:
        ax.scatter([x], [y])
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlim(15, 90)
    ax.set_ylim(0.3, 0.7)
    texts = plots.place_labels(ax, [(x, y, t, "k") for x, y, t in pts])
    if sorted(t.get_text() for t in texts) != sorted(p[2] for p in pts):
        fail("every point gets its label")
    rend = fig.canvas.get_renderer()
    boxes = [t.get_window_extent(rend) for t in texts]
    for i in range(len(boxes)):
        for j in range(i + 1, len(boxes)):
            if plots._overlap(boxes[i], boxes[j], pad=0):
                fail(f"labels overlap: {texts[i].get_text()} and {texts[j].get_text()}")
    plots.plt.close(fig)

    # The whole script on a fake experiment.
    d = tempfile.mkdtemp()
    os.makedirs(os.path.join(d, "images"))
    os.makedirs(os.path.join(d, "references"))
    import numpy as np
    img = np.zeros((12, 16, 3))
    img[4:8, 6:10] = 0.8
    plots.plt.imsave(os.path.join(d, "images", "run.png"), img)
    plots.plt.imsave(os.path.join(d, "references", "exact.png"), img * 0.9)
    res = {"title": "fake", "references": ["exact"], "stages": stages,
           "runs": [run(0, 1e-2, 20.0, 0.02), run(1, 1e-3, 40.0, 0.01),
                    run(2, 1e-4, 80.0, 0.005)]}
    with open(os.path.join(d, "results.json"), "w") as f:
        json.dump(res, f)
    subprocess.run([sys.executable, SCRIPT, d], check=True)
    with open(os.path.join(d, "plots", "index.json")) as f:
        index = {p["file"]: p for p in json.load(f)}
    cap = index["stages__eps.png"]["caption"]
    if "one repetition, the one whose frame time is the median" not in cap or "100 %" not in cap:
        fail("stage caption: " + cap)
    if "labelled with its value of `epsilon`" not in index["pareto__eps.png"]["caption"]:
        fail("pareto caption: " + index["pareto__eps.png"]["caption"])
    with open(os.path.join(d, "plots", "pareto__eps.svg")) as f:
        svg = f.read()
    for label in ("ε=0.01", "ε=0.001", "ε=0.0001"):
        if f"<!-- {label} -->" not in svg:
            fail(f"pareto__eps.svg has no label {label}")
    # A light in view: the scene's Pareto panel plots the masked error, and the caption says so.
    lit = [run(i, e, t, rel) for i, (e, t, rel) in enumerate([(1e-2, 20.0, 0.74), (1e-3, 40.0, 0.78)])]
    for r, masked in zip(lit, (0.02, 0.01)):
        r["errors"]["exact"].update({"masked_rel_l2": masked, "masked_lights": 1,
                                     "mask_radius_px": 2.0})
    if plots.lights_in_view(lit, "exact") != 2.0 or plots.lights_in_view(res["runs"], "exact"):
        fail("lights_in_view")
    d2 = tempfile.mkdtemp()
    os.makedirs(os.path.join(d2, "images"))
    os.makedirs(os.path.join(d2, "references"))
    plots.plt.imsave(os.path.join(d2, "images", "run.png"), img)
    plots.plt.imsave(os.path.join(d2, "references", "exact.png"), img * 0.9)
    with open(os.path.join(d2, "results.json"), "w") as f:
        json.dump(dict(res, runs=lit), f)
    subprocess.run([sys.executable, SCRIPT, d2], check=True)
    with open(os.path.join(d2, "plots", "index.json")) as f:
        cap = {p["file"]: p for p in json.load(f)}["pareto__eps.png"]["caption"]
    if "Where a light is in view (shaft) the error is the masked relative L2" not in cap:
        fail("masked pareto caption: " + cap)
    with open(os.path.join(d2, "plots", "pareto__eps.svg")) as f:
        svg = f.read()
    if "masked relative L2 vs exact" not in svg or "masked: 2 px around each light" not in svg:
        fail("masked pareto: axis label or panel title missing")
    with open(os.path.join(d, "gallery", "index.json")) as f:
        slots = json.load(f)["difference_slots"][0]
    if slots[0] != {"tile": "reference", "image": "references/exact.png",
                    "difference": "colour scale"}:
        fail(f"reference slot: {slots[0]}")
    if [s["difference"] for s in slots[1:]] != ["signed"] * 3:
        fail(f"run slots: {slots}")
    print("ok")
    return 0


if __name__ == "__main__":
    sys.exit(main())
