#!/usr/bin/env python3
"""Plots and gallery of an experiment directory written by `scatterlab experiment` (docs/harness.md).

    python3 experiment/plots.py DIR [--per-page N]

Reads DIR/results.json (and the PNGs under DIR/images/ and DIR/references/) and writes, with
matplotlib (Agg backend):

  plots/<question>__<sweep>.png and .svg, one figure per question and sweep, one panel per scene:
    error_vs_samples   rel. L2 vs samples used (sweeps with a `samples` or `epsilon` axis)
    time_vs_<axis>     frame time vs `resolution`, `lights` or `image_size` (with the paper's
                       frame times, dashed, where the config gives `paper_fps`)
    pareto             error against frame time, every run a point labelled with what the sweep
                       varies (ε=…, n=…, or the samples used), the Pareto front as a line
    stages             each run's frame split into its stages (share of the frame, linear
                       axis): the stages of its median repetition (median_run_ms), so that the
                       bar adds up to 100 %; that frame time at the end of each bar
  plots/index.json     the figures in order with a one-line caption each (report.md uses it)
  gallery/page-NN.png  every successful run as a labelled tile (method, samples, error, time)
                       beside its signed difference from the headline reference, each reference
                       as a tile beside the colour scale of those differences; N tiles a page
  gallery/index.json   the pages, how many runs they hold and what each difference slot shows

One colour per method (its config name) in every figure of the experiment; stages have their own
palette. Every figure's title names the experiment, its sweep and the machine and backends.
"""
import argparse
import json
import math
import os
import sys
import textwrap
from collections import OrderedDict

import matplotlib

matplotlib.use("Agg")
import matplotlib.cm  # noqa: E402
import matplotlib.colors  # noqa: E402
import matplotlib.image as mpimg  # noqa: E402
import matplotlib.patches  # noqa: E402
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.lines import Line2D  # noqa: E402
from matplotlib.ticker import (FixedLocator, FuncFormatter, MaxNLocator, NullFormatter,  # noqa: E402
                               NullLocator)

# Display-space difference shown at full colour in the gallery's difference images (the same
# scale as report.md's signed error maps; "visibly wrong" starts at 0.05).
DIFF_FULL = 0.1

# Axes the sweep's time plots know how to put on x: value -> (x, x label, log base or None).
TIME_AXES = {
    "resolution": (lambda v: v if isinstance(v, (int, float)) else v[0],
                   "volume resolution (voxels per axis)", 2),
    "lights": (lambda v: v, "number of lights", 2),
    "image_size": (lambda v: v[0] * v[1] / 1e6, "image size (megapixels)", 2),
}


# ---- What the figures share ----------------------------------------------------------------

class Style:
    """Fixed colours: one per method over the whole experiment, one per stage."""

    # The registered methods keep these tab10 colours in every experiment's figures (a method
    # entry named like one, e.g. `gradient`, gets its colour); other names take the free ones.
    FIXED = {"per-voxel": 0, "gradient": 1, "adaptive": 2, "rbf": 3, "nearest": 4, "exact": 7}

    def __init__(self, runs, stages):
        methods = list(OrderedDict.fromkeys(r["method"] for r in runs))
        unknown = [m for m in methods if m not in self.FIXED]
        fixed = len(unknown) <= 10 - len(self.FIXED)
        cmap = plt.get_cmap("tab10" if fixed or len(methods) <= 10 else "tab20")
        self.method_colour = {m: cmap(self.FIXED[m]) for m in methods if fixed and m in self.FIXED}
        free = [i for i in range(cmap.N) if not fixed or i not in self.FIXED.values()]
        for m in methods:
            if m not in self.method_colour:
                self.method_colour[m] = cmap(free.pop(0) if free else len(self.method_colour) % cmap.N)
        scmap = plt.get_cmap("Set2" if len(stages) <= 8 else "tab20b")
        self.stage_colour = {s: scmap(i % scmap.N) for i, s in enumerate(stages)}
        self.markers = ["o", "s", "^", "D", "v", "P", "X", "*"]

    def method_handles(self, methods):
        return [Line2D([], [], color=self.method_colour[m], marker="o", label=m) for m in methods]


def machine_text(res, runs):
    """"AMD EPYC, 2 cores; cpu backend" for the figure titles, from the results' machines."""
    machines = res.get("machines") or ([res["machine"]] if res.get("machine") else [])
    backends = sorted({r.get("backend", "cpu") for r in runs})
    parts = []
    for m in machines[:2]:
        if "cpu_model" not in m:
            continue
        s = f"{m['cpu_model']}, {m.get('cores_used', '?')} cores"
        if m.get("load_avg_start"):
            s += f" (load {m['load_avg_start'][0]:.1f} at the start)"
        gpus = m.get("gpu_renderers") or []
        if gpus and any(b != "cpu" for b in backends):
            s += ", " + "; ".join(gpus)
        parts.append(s)
    if len(machines) > 2:
        parts.append(f"+{len(machines) - 2} more machines")
    text = " | ".join(parts) if parts else "machine unknown"
    return f"{text}; backend {'/'.join(backends)}"


def short_title(res):
    t = res.get("title", "experiment")
    return t if len(t) <= 110 else t[:107].rstrip() + "..."


def panel_grid(n, width=4.2, height=3.3, max_cols=4):
    cols = min(n, max_cols)
    rows = math.ceil(n / cols)
    # At least 9 in wide, so that one panel still has room for the title and the legend.
    fig, axes = plt.subplots(rows, cols, figsize=(max(9.0, width * cols + 0.4), height * rows + 1.5),
                             squeeze=False)
    for ax in axes.flat[n:]:
        ax.set_visible(False)
    return fig, list(axes.flat[:n])


def finish(fig, path_base, title, subtitle, handles=None, made=None, caption="", after_layout=None):
    """Suptitle, one legend below the panels, PNG + SVG; records the figure in `made`.
    `after_layout()` runs once the panels have their final size (point labels are placed then)."""
    wrap = max(40, int(fig.get_figwidth() * 11))
    lines = textwrap.wrap(title, wrap) + textwrap.wrap(subtitle, wrap)
    fig.suptitle("\n".join(lines), fontsize=10)
    h = fig.get_figheight()  # margins in inches, whatever the figure's height
    top = 1  # tight_layout makes room for the suptitle itself
    if handles:
        ncol = min(len(handles), 5)
        fig.legend(handles=handles, loc="lower center", ncol=ncol, fontsize=8, frameon=False)
        rows = math.ceil(len(handles) / ncol)
        fig.tight_layout(rect=(0, (0.1 + 0.2 * rows) / h, 1, top))
    else:
        fig.tight_layout(rect=(0, 0, 1, top))
    if after_layout:
        after_layout()
    for ext in ("png", "svg"):
        fig.savefig(f"{path_base}.{ext}", dpi=100)
    plt.close(fig)
    if made is not None:
        made.append({"file": os.path.basename(path_base) + ".png",
                     "svg": os.path.basename(path_base) + ".svg", "caption": caption})


def plain_log_ticks(ax, x=True, y=True):
    """Log axes labelled 20, 50, 0.5 rather than 2x10^1; an axis spanning fewer than three
    decades gets ticks at 1, 2 and 5 times powers of ten, or, within one decade, evenly spaced
    round values, instead of the decades it does not reach."""
    fmt = FuncFormatter(lambda v, _: f"{v:g}")
    for on, axis, lim in ((x, ax.xaxis, ax.get_xlim), (y, ax.yaxis, ax.get_ylim)):
        if not on or axis.get_scale() != "log":
            continue
        lo, hi = lim()
        axis.set_major_formatter(fmt)
        axis.set_minor_formatter(NullFormatter())
        if lo <= 0:
            continue
        k0, k1 = math.floor(math.log10(lo)), math.ceil(math.log10(hi))
        decades = [10.0 ** k for k in range(k0, k1 + 1) if lo <= 10.0 ** k <= hi]
        if len(decades) >= 3:
            continue  # the default decades read well
        ticks = [m * 10.0 ** k for k in range(k0, k1 + 1) for m in (1, 2, 5)
                 if lo <= m * 10.0 ** k <= hi]
        if len(ticks) < 3:  # less than a decade: evenly spaced round values
            ticks = [t for t in MaxNLocator(nbins=6).tick_values(lo, hi) if lo <= t <= hi and t > 0]
        if len(ticks) >= 2:
            axis.set_major_locator(FixedLocator(ticks))
            axis.set_minor_locator(NullLocator())


def ok_runs(res):
    return [r for r in res["runs"] if r.get("status") == "ok"]


def by(runs, key):
    out = OrderedDict()
    for r in runs:
        out.setdefault(key(r), []).append(r)
    return out


def other_axes(r, axis_names):
    return tuple((k, json.dumps(v)) for k, v in sorted(r.get("axes", {}).items())
                 if k not in axis_names)


def other_label(other):
    return ", ".join(f"{k}={json.loads(v)}" for k, v in other)


def rel_l2_pct(r, ref, masked=False):
    e = r.get("errors", {}).get(ref)
    key = "masked_rel_l2" if masked else "rel_l2"
    return None if not e or e.get(key) is None else 100.0 * e[key]


def lights_in_view(runs, ref):
    """The mask radius (px) where a light is in view of these runs' images, else None: their
    unmasked error is then dominated by the pixels around the light."""
    for r in runs:
        e = r.get("errors", {}).get(ref) or {}
        if (e.get("masked_lights") or 0) > 0 and e.get("masked_rel_l2") is not None:
            return e.get("mask_radius_px")
    return None


# ---- Figures ---------------------------------------------------------------------------------

def line_figure(res, style, runs, sweep, scenes, xkey, ykey, xlabel, ylabel, logx, logy, name,
                question, d, made, caption, paper_y=None):
    """One panel per scene, one line per method (markers tell apart the other axes' values)."""
    fig, axes = panel_grid(len(scenes))
    methods_seen = []
    extra = OrderedDict()
    for ax, scene in zip(axes, scenes):
        srun = [r for r in runs if r["scene"] == scene]
        for (meth, other), pts in by(srun, lambda r: (r["method"], other_axes(r, xkey.axes))).items():
            xy = sorted((xkey(r), ykey(r)) for r in pts if ykey(r) is not None)
            if not xy:
                continue
            if meth not in methods_seen:
                methods_seen.append(meth)
            mk = extra.setdefault(other, style.markers[len(extra) % len(style.markers)])
            ax.plot([p[0] for p in xy], [p[1] for p in xy], color=style.method_colour[meth],
                    marker=mk, ms=4, lw=1.4)
            if paper_y:
                pxy = sorted((xkey(r), paper_y(r)) for r in pts if paper_y(r) is not None)
                if pxy:
                    ax.plot([p[0] for p in pxy], [p[1] for p in pxy], color=style.method_colour[meth],
                            ls="--", lw=1.0, marker=mk, ms=3, mfc="none")
        ax.set_title(scene, fontsize=9)
        ax.set_xlabel(xlabel, fontsize=8)
        ax.set_ylabel(ylabel, fontsize=8)
        if logx:
            ax.set_xscale("log", base=logx)
        if logy:
            ax.set_yscale("log")
        plain_log_ticks(ax)
        if xkey.axes[0] in TIME_AXES:  # a swept axis: ticks at the swept values (32, 64, ...)
            xs = sorted({xkey(r) for r in srun})
            if xs:
                ax.xaxis.set_major_locator(FixedLocator(xs))
                ax.xaxis.set_minor_locator(NullLocator())
                ax.xaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
        ax.tick_params(which="both", labelsize=7)
        ax.grid(True, which="both", alpha=0.25)
    if not methods_seen:
        plt.close(fig)
        return
    handles = style.method_handles(methods_seen)
    if len(extra) > 1:
        handles += [Line2D([], [], color="0.3", marker=mk, ls="", label=other_label(o) or "—")
                    for o, mk in extra.items()]
    if paper_y:
        handles.append(Line2D([], [], color="0.3", ls="--", label="paper (from its fps)"))
    finish(fig, os.path.join(d, "plots", f"{name}__{sweep}"),
           f"{short_title(res)} — sweep '{sweep}': {question}", machine_text(res, runs), handles,
           made, caption)


class XKey:
    """x of a run for a line figure, with the axis names it consumes."""

    def __init__(self, fn, axes):
        self.fn, self.axes = fn, axes

    def __call__(self, r):
        return self.fn(r)


# Short names of the swept axes in point labels.
AXIS_SHORT = {"epsilon": "ε", "samples": "n", "resolution": "res", "lights": "lights",
              "image_size": "px"}


def point_label(r, vary):
    """What tells run `r` apart from the others of its method in a sweep: the values of the axes
    in `vary` ("ε=1e-4", "n=2000", "res=64"), else the samples it used ("2748 samples")."""
    parts = []
    for a in vary:
        v = r.get("axes", {}).get(a)
        if v is None:
            continue
        text = "x".join(map(str, v)) if isinstance(v, list) else f"{v:g}" if isinstance(
            v, float) else str(v)
        parts.append(f"{AXIS_SHORT.get(a, a)}={text}")
    if not parts and isinstance(r.get("samples"), (int, float)):
        parts.append(f"{r['samples']:g} samples")
    return ", ".join(parts)


def _overlap(a, b, pad=1.0):
    return not (a.x1 + pad <= b.x0 or b.x1 + pad <= a.x0 or a.y1 + pad <= b.y0 or b.y1 + pad <= a.y0)


def place_labels(ax, items, fontsize=6.5, lines=()):
    """Labels `items` = [(x, y, text, colour)] beside their points, each at the first of eight
    offsets (right, left, above, below, diagonals) that overlaps no label placed before it, no
    other point, none of the polylines `lines` ([(x, y), ...] in data units) and stays inside the
    axes; the least-overlapping offset where none is free. Returns the Text objects. Call it once
    the axes have their final size."""
    fig = ax.figure
    renderer = fig.canvas.get_renderer()
    frame = ax.get_window_extent(renderer)
    dpi = fig.dpi / 72.0
    pts = [ax.transData.transform((x, y)) for x, y, _, _ in items]
    dot = 4.0 * dpi  # the marker's radius in pixels, and a little room
    # The lines as points every few pixels.
    along = []
    for line in lines:
        disp = [ax.transData.transform(p) for p in line]
        for (x0, y0), (x1, y1) in zip(disp, disp[1:]):
            n = max(1, int(math.hypot(x1 - x0, y1 - y0) / 3))
            along += [(x0 + (x1 - x0) * k / n, y0 + (y1 - y0) * k / n) for k in range(n + 1)]
    offsets = [(5, 0, "left", "center"), (-5, 0, "right", "center"), (0, 5, "center", "bottom"),
               (0, -5, "center", "top"), (4, 4, "left", "bottom"), (-4, 4, "right", "bottom"),
               (4, -4, "left", "top"), (-4, -4, "right", "top")]
    placed, texts = [], []
    order = sorted(range(len(items)), key=lambda i: (pts[i][0], pts[i][1]))
    for i in order:
        x, y, text, colour = items[i]
        if not text:
            continue
        best = None
        for dx, dy, ha, va in offsets:
            t = ax.annotate(text, (x, y), xytext=(dx, dy), textcoords="offset points", ha=ha,
                            va=va, fontsize=fontsize, color=colour, zorder=4,
                            annotation_clip=False)
            bb = t.get_window_extent(renderer)
            cost = sum(_overlap(bb, p) for p in placed) * 10
            cost += sum(1 for j, (px, py) in enumerate(pts) if j != i and
                        bb.x0 - dot < px < bb.x1 + dot and bb.y0 - dot < py < bb.y1 + dot) * 3
            cost += 2 * any(bb.x0 - 1 < px < bb.x1 + 1 and bb.y0 - 1 < py < bb.y1 + 1
                            for px, py in along)
            if bb.x0 < frame.x0 or bb.x1 > frame.x1 or bb.y0 < frame.y0 or bb.y1 > frame.y1:
                cost += 5
            if best is None or cost < best[0]:
                if best is not None:
                    best[1].remove()
                best = (cost, t, bb)
            else:
                t.remove()
            if cost == 0:
                break
        placed.append(best[2])
        texts.append(best[1])
    return texts


def pareto_figure(res, style, runs, sweep, scenes, ref, d, made):
    """Error against frame time, one point per run; the non-dominated runs joined by a line."""
    fig, axes = panel_grid(len(scenes))
    methods_seen = []
    vary = list(OrderedDict.fromkeys(a for r in runs for a in r.get("axes", {})))
    labels = []  # (axes, [(x, y, text, colour)]), placed after the layout
    masked_scenes = []
    for ax, scene in zip(axes, scenes):
        # A light in view dominates the unmasked error (every method, exact's own check included,
        # at tens of %): the scene's panel plots the masked figure, and says so.
        radius = lights_in_view([r for r in runs if r["scene"] == scene], ref)
        masked = radius is not None
        if masked:
            masked_scenes.append(scene)
        pts = [(r["median_ms"]["total"], rel_l2_pct(r, ref, masked), r) for r in runs
               if r["scene"] == scene and rel_l2_pct(r, ref, masked) is not None]
        pts = [p for p in pts if p[0] > 0 and p[1] > 0]
        labels.append((ax, [(t, e, point_label(r, vary), style.method_colour[r["method"]])
                            for t, e, r in pts], []))
        for t, e, r in pts:
            if r["method"] not in methods_seen:
                methods_seen.append(r["method"])
            ax.scatter([t], [e], color=style.method_colour[r["method"]], s=22, zorder=3)
        front, best = [], math.inf
        for t, e, _ in sorted(pts, key=lambda p: (p[0], p[1])):
            if e < best:
                front.append((t, e))
                best = e
        if len(front) > 1:
            ax.step([p[0] for p in front], [p[1] for p in front], where="post", color="0.4",
                    lw=1, zorder=2)
            # The step line's corners, for place_labels to keep the labels off it.
            steps = [front[0]]
            for (t0, e0), (t1, e1) in zip(front, front[1:]):
                steps += [(t1, e0), (t1, e1)]
            labels[-1] = (ax, labels[-1][1], [steps])
        ax.set_title(scene + (f" (masked: {radius:g} px around each light)" if masked else ""),
                     fontsize=9)
        ax.set_xscale("log")
        ax.set_yscale("log")
        if pts:  # room for the labels beside the outermost points
            ts, es = [p[0] for p in pts], [p[1] for p in pts]
            ax.set_xlim(min(ts) / 1.6, max(ts) * 1.6)
            ax.set_ylim(min(es) / 1.4, max(es) * 1.4)
        ax.set_xlabel("frame time (ms, median)", fontsize=8)
        ax.set_ylabel(f"{'masked ' if masked else ''}relative L2 vs {ref} (%)", fontsize=8)
        plain_log_ticks(ax)
        ax.tick_params(which="both", labelsize=7)
        ax.grid(True, which="both", alpha=0.25)
    if not methods_seen:
        plt.close(fig)
        return
    handles = style.method_handles(methods_seen) + [
        Line2D([], [], color="0.4", label="Pareto front (no run both faster and more accurate)")]
    finish(fig, os.path.join(d, "plots", f"pareto__{sweep}"),
           f"{short_title(res)} — sweep '{sweep}': which runs are fast and accurate?",
           machine_text(res, runs), handles, made,
           f"Sweep `{sweep}`: error against frame time per scene; lower left is better, the grey "
           "line joins the runs no other run beats in both. "
           + (f"Where a light is in view ({', '.join(masked_scenes)}) the error is the masked "
              "relative L2 (the pixels around each light left out, as report.md's masked "
              "column): unmasked, the light's few pixels dominate every method. "
              if masked_scenes else "")
           + "Each point is labelled with "
           + (f"its value of {', '.join('`' + a + '`' for a in vary)}" if vary
              else "the samples it used (where the method reports them)"),
           after_layout=lambda: [place_labels(ax, items, lines=lines)
                                 for ax, items, lines in labels])


def run_label(r, axis_names):
    s = r["method"]
    ax = [f"{k}={v if not isinstance(v, list) else 'x'.join(map(str, v))}"
          for k, v in r.get("axes", {}).items()]
    return s + (" " + ", ".join(ax) if ax else "")


def stage_times(r, stages):
    """(per-stage ms, total ms, how) of run `r` for its stage bar, the stages adding up to at most
    the total. From `median_run_ms` (the one repetition whose frame time is the median) where the
    results have it: how = "median run". Older results only have per-stage medians, which need not
    add up to the median total: they are scaled down to it where they pass it (how = "scaled")."""
    run = r.get("median_run_ms")
    if run and run.get("total"):
        return {s: run.get(s, 0.0) for s in stages}, run["total"], "median run"
    med = r.get("median_ms", {})
    tot = med.get("total") or 0.0
    times = {s: med.get(s, 0.0) for s in stages}
    summed = sum(times.values())
    if tot > 0 and summed > tot:
        times = {s: v * tot / summed for s, v in times.items()}
        return times, tot, "scaled"
    return times, tot, "medians"


def stage_figure(res, style, runs, sweep, scenes, stages, d, made):
    """Each run's frame as 100% split into its stages (linear axis), total time at the bar end:
    the stages of its median repetition (stage_times)."""
    rows = [len([r for r in runs if r["scene"] == s]) for s in scenes]
    cols = min(len(scenes), 2)
    nrow = math.ceil(len(scenes) / cols)
    height = [max(rows[i:i + cols]) for i in range(0, len(rows), cols)]
    fig, axes = plt.subplots(nrow, cols, figsize=(max(9.0, 7.2 * cols), 0.26 * sum(height) + 1.3 * nrow + 1.6),
                             squeeze=False, gridspec_kw={"height_ratios": [h + 3 for h in height]})
    for ax in axes.flat[len(scenes):]:
        ax.set_visible(False)
    used = []
    hows = set()
    for ax, scene in zip(axes.flat, scenes):
        srun = [r for r in runs if r["scene"] == scene]
        labels = [run_label(r, None) for r in srun]
        timed = [stage_times(r, stages) for r in srun]
        hows.update(t[2] for t in timed)
        left = [0.0] * len(srun)
        for s in stages:
            share = []
            for times, tot, _ in timed:
                share.append(100.0 * times[s] / tot if tot > 0 else 0.0)
            if any(v > 0 for v in share):
                if s not in used:
                    used.append(s)
                ax.barh(range(len(srun)), share, left=left, color=style.stage_colour[s], height=0.7)
            left = [a + b for a, b in zip(left, share)]
        # What no stage timer covers (set-up, copies): the rest of the frame, in grey.
        rest = [max(0.0, 100.0 - v) for v in left]
        if any(v > 0.5 for v in rest):
            if "other (untimed)" not in used:
                used.append("other (untimed)")
            ax.barh(range(len(srun)), rest, left=left, color="0.85", height=0.7)
        for i, (_, tot, _) in enumerate(timed):
            ax.text(101, i, f"{tot:.0f} ms", va="center", fontsize=7)
        ax.set_yticks(range(len(srun)))
        ax.set_yticklabels(labels, fontsize=7)
        ax.invert_yaxis()
        ax.set_xlim(0, 118)
        ax.set_xticks([0, 25, 50, 75, 100])
        ax.set_xlabel("share of the frame time (%, the median repetition's stages); its frame time "
                      "at the right", fontsize=8)
        ax.set_title(scene, fontsize=9)
        ax.tick_params(axis="x", labelsize=7)
    handles = [matplotlib.patches.Patch(color=style.stage_colour.get(s, "0.85"), label=s)
               for s in used]
    finish(fig, os.path.join(d, "plots", f"stages__{sweep}"),
           f"{short_title(res)} — sweep '{sweep}': where does the frame time go?",
           machine_text(res, runs), handles, made,
           f"Sweep `{sweep}`: each run's frame split into its stages, linear axis: "
           + stage_caption(hows) + "; grey: time no stage timer covers; that frame time at the "
           "right. The bars add up to 100 %")


def stage_caption(hows):
    """What the stage bars show, for the caption (`hows` from stage_times)."""
    parts = []
    if "median run" in hows:
        parts.append("the stage times of one repetition, the one whose frame time is the median "
                     "(medians of stages need not add up to the median frame)")
    if "scaled" in hows:
        parts.append("where only per-stage medians were recorded and they add up to more than the "
                     "median frame time, those medians scaled down to it")
    if "medians" in hows:
        parts.append("where only per-stage medians were recorded and they fit in the median frame "
                     "time, those medians")
    return "; ".join(parts) or "no stage times"


def sweep_figures(res, style, d, made):
    runs = ok_runs(res)
    refs = res.get("references", [])
    ref = refs[0] if refs else None
    stages = res.get("stages", [])
    for sweep, sruns in by(runs, lambda r: r["sweep"]).items():
        scenes = list(OrderedDict.fromkeys(r["scene"] for r in sruns))
        axes = list(OrderedDict.fromkeys(a for r in sruns for a in r.get("axes", {})))
        if ref and ("samples" in axes or "epsilon" in axes):
            line_figure(res, style, [r for r in sruns if "samples" in r], sweep, scenes,
                        XKey(lambda r: r["samples"], ("samples", "epsilon")),
                        lambda r: rel_l2_pct(r, ref), "samples used", f"relative L2 vs {ref} (%)",
                        10, True, "error_vs_samples", "how does the error fall with samples?",
                        d, made,
                        f"Sweep `{sweep}`: relative L2 against `{ref}` over the samples each run "
                        "used, one panel per scene")
        for axis, (fx, xlabel, base) in TIME_AXES.items():
            if axis not in axes:
                continue
            line_figure(res, style, [r for r in sruns if axis in r.get("axes", {})], sweep, scenes,
                        XKey(lambda r, fx=fx, axis=axis: fx(r["axes"][axis]), (axis,)),
                        lambda r: r["median_ms"].get("total"), xlabel, "frame time (ms, median)",
                        base, True, f"time_vs_{axis}", f"how does the frame time grow with {axis}?",
                        d, made,
                        f"Sweep `{sweep}`: frame time over `{axis}`, one panel per scene; dashed: "
                        "the paper's frame time (1000 / its fps) where the config gives it",
                        paper_y=lambda r: (1000.0 / r["paper"]["fps"]
                                           if isinstance(r.get("paper", {}).get("fps"), (int, float))
                                           and r["paper"]["fps"] > 0 else None))
        if ref:
            pareto_figure(res, style, sruns, sweep, scenes, ref, d, made)
        if stages:
            stage_figure(res, style, sruns, sweep, scenes, stages, d, made)


# ---- Gallery -----------------------------------------------------------------------------------

def load_rgb(path):
    img = mpimg.imread(path)
    return img[..., :3] if img.ndim == 3 else img


def axes_text(r):
    return ", ".join(f"{a}={v if not isinstance(v, list) else 'x'.join(map(str, v))}"
                     for a, v in r.get("axes", {}).items())


def reference_scale(ax, ref):
    """The difference slot of a reference tile: the colour scale of the difference images that
    follow (the reference's own difference is 0 everywhere, a blank map), with what its ends
    mean."""
    ax.axis("off")
    ax.set_title(f"{ref} is the reference: colour scale of the differences", fontsize=8)
    cax = ax.inset_axes([0.08, 0.42, 0.84, 0.14])
    sm = matplotlib.cm.ScalarMappable(norm=matplotlib.colors.Normalize(-DIFF_FULL, DIFF_FULL),
                                      cmap="RdBu_r")
    cb = ax.figure.colorbar(sm, cax=cax, orientation="horizontal")
    cb.set_ticks([-DIFF_FULL, -DIFF_FULL / 2, 0, DIFF_FULL / 2, DIFF_FULL])
    cb.ax.tick_params(labelsize=7)
    cax.set_xlabel(f"image − {ref} (mean over channels of the PNGs)", fontsize=7)
    ax.text(0.08, 0.66, "darker than the reference", ha="left", va="bottom", fontsize=7,
            color=matplotlib.cm.RdBu_r(0.0), transform=ax.transAxes)
    ax.text(0.92, 0.66, "brighter", ha="right", va="bottom", fontsize=7,
            color=matplotlib.cm.RdBu_r(1.0), transform=ax.transAxes)
    ax.text(0.5, 0.08, f"its own difference is 0 everywhere; full colour at ±{DIFF_FULL:g}",
            ha="center", va="bottom", fontsize=7, transform=ax.transAxes)


def gallery(res, d, per_page):
    """Labelled tiles (image + signed difference from the headline reference), `per_page` a
    page; each run's reference image as a tile of its own before the first run that uses it."""
    runs = ok_runs(res)
    refs = res.get("references", [])
    ref = refs[0] if refs else None
    os.makedirs(os.path.join(d, "gallery"), exist_ok=True)
    for f in os.listdir(os.path.join(d, "gallery")):
        if f.startswith("page-") and f.endswith(".png"):
            os.remove(os.path.join(d, "gallery", f))
    shown = [r for r in runs if os.path.exists(os.path.join(d, r.get("image", "")))]
    tiles, last_ref = [], None
    for n, r in enumerate(shown):
        rp = r.get("reference_images", {}).get(ref) if ref else None
        if rp and os.path.exists(os.path.join(d, rp)) and rp != last_ref:
            tiles.append({"ref": rp, "run": r})
            last_ref = rp
        tiles.append({"run": r, "n": n + 1, "ref_image": rp})
    pages = [tiles[i:i + per_page] for i in range(0, len(tiles), per_page)]
    cols = 2  # tiles per row, each an image and its difference
    files, tiles_of = [], []
    for p, page in enumerate(pages):
        nrow = math.ceil(len(page) / cols)
        first = load_rgb(os.path.join(d, page[0]["run"]["image"]))
        aspect = first.shape[0] / first.shape[1]
        # 4 in per tile half, plus room for two title lines a row, the header and the colour bar.
        fig, axes = plt.subplots(nrow, 2 * cols,
                                 figsize=(4 * 2 * cols, (4 * aspect + 0.6) * nrow + 2.0),
                                 squeeze=False)
        diff_im = None
        slots = []  # what each tile's difference slot shows, for gallery/index.json
        for i, ax in enumerate(axes.flat):
            ax.set_xticks([])
            ax.set_yticks([])
            k = i // 2
            if k >= len(page):
                ax.set_visible(False)
                continue
            t, r = page[k], page[k]["run"]
            if "ref" in t:
                if i % 2 == 0:
                    ax.imshow(load_rgb(os.path.join(d, t["ref"])))
                    ax.set_title(f"{r['scene']}: reference {ref}"
                                 f"{' · ' + axes_text(r) if axes_text(r) else ''}", fontsize=8)
                else:
                    reference_scale(ax, ref)
                    slots.append({"tile": "reference", "image": t["ref"],
                                  "difference": "colour scale"})
                continue
            img = load_rgb(os.path.join(d, r["image"]))
            if i % 2 == 0:
                ax.imshow(img)
                e = rel_l2_pct(r, ref)
                ax.set_title(f"{r['scene']}: {r['method']} ({r.get('backend', 'cpu')})"
                             f"{' · ' + axes_text(r) if axes_text(r) else ''}\n"
                             f"{r['samples'] if 'samples' in r else '—'} samples · "
                             f"rel L2 {'—' if e is None else f'{e:.2f}%'} · "
                             f"{r['median_ms'].get('total', 0):.0f} ms", fontsize=8)
                continue
            rp = t["ref_image"]
            if rp and os.path.exists(os.path.join(d, rp)):
                refimg = load_rgb(os.path.join(d, rp))
                if refimg.shape == img.shape:
                    diff = (img - refimg).mean(axis=2) if img.ndim == 3 else img - refimg
                    diff_im = ax.imshow(diff, cmap="RdBu_r", vmin=-DIFF_FULL, vmax=DIFF_FULL)
                    ax.set_title(f"minus {ref} (signed)", fontsize=8)
                    slots.append({"tile": r.get("id", ""), "difference": "signed"})
                    continue
            ax.text(0.5, 0.5, "no reference image", ha="center", va="center", fontsize=8,
                    transform=ax.transAxes)
            slots.append({"tile": r.get("id", ""), "difference": "none"})
        numbers = [t["n"] for t in page if "n" in t]
        span = f"runs {numbers[0]}–{numbers[-1]} of {len(shown)}" if numbers else "references"
        title = f"{short_title(res)} — gallery page {p + 1}/{len(pages)} ({span})"
        lines = textwrap.wrap(title, 100) + [machine_text(res, [t["run"] for t in page])]
        fig.suptitle("\n".join(lines), fontsize=10)
        h = fig.get_figheight()
        fig.tight_layout(rect=(0, 1.0 / h, 1, 1 - (0.1 + 0.2 * len(lines)) / h))
        if diff_im is not None:
            cax = fig.add_axes([0.3, 0.55 / h, 0.4, 0.12 / h])
            cb = fig.colorbar(diff_im, cax=cax, orientation="horizontal")
            cb.set_label(f"image − {ref}, mean over channels of the PNGs (red: brighter); "
                         f"full colour at ±{DIFF_FULL}", fontsize=8)
            cb.ax.tick_params(labelsize=7)
        name = f"page-{p + 1:02d}.png"
        fig.savefig(os.path.join(d, "gallery", name), dpi=90)
        plt.close(fig)
        files.append(name)
        tiles_of.append(slots)
    index = {"pages": files, "runs": len(shown), "per_page": per_page, "reference": ref,
             "diff_full": DIFF_FULL, "difference_slots": tiles_of}
    with open(os.path.join(d, "gallery", "index.json"), "w") as f:
        json.dump(index, f, indent=2)
    return index


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("dir")
    ap.add_argument("--per-page", type=int, default=12, help="gallery tiles per page (default 12)")
    ap.add_argument("--no-gallery", action="store_true", help="plots only")
    a = ap.parse_args()
    if a.per_page < 1:
        ap.error(f"--per-page {a.per_page}: must be at least 1")
    path = os.path.join(a.dir, "results.json")
    if not os.path.exists(path):
        ap.error(f"'{path}' does not exist (run `scatterlab experiment CONFIG -o {a.dir}` first)")
    with open(path) as f:
        res = json.load(f)
    os.makedirs(os.path.join(a.dir, "plots"), exist_ok=True)
    for f in os.listdir(os.path.join(a.dir, "plots")):
        if f.endswith((".png", ".svg")):
            os.remove(os.path.join(a.dir, "plots", f))
    style = Style(res["runs"], res.get("stages", []))
    made = []
    sweep_figures(res, style, a.dir, made)
    with open(os.path.join(a.dir, "plots", "index.json"), "w") as f:
        json.dump(made, f, indent=2)
    print("plots:", ", ".join(m["file"] for m in made) if made else "none")
    if not a.no_gallery and res.get("gallery") != "off":
        g = gallery(res, a.dir, a.per_page)
        print(f"gallery: {g['runs']} runs on {len(g['pages'])} pages")
    return 0


if __name__ == "__main__":
    sys.exit(main())
