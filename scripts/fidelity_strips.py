#!/usr/bin/env python3
"""The per-scene strips of docs/fidelity.md from a fidelity experiment's output directory:
the reference, then each method's image (top row) over its signed difference from the
reference (bottom row, mean over the channels of the PNG previews, full colour at +-0.1),
labelled with method, samples and masked relative L2.

    python3 scripts/fidelity_strips.py out/fidelity -o docs/images \
        --scenes glow lamp_puff lamps32 shaft shaft_smoke perforated_sheet chimney

Needs Debian's python3-matplotlib (scripts/setup.sh installs it)."""
import argparse
import json
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.image as mpimg  # noqa: E402
import matplotlib.pyplot as plt  # noqa: E402

METHODS = ["per-voxel", "gradient", "gradient-paper", "rbf", "nearest", "adaptive",
           "adaptive-log", "adaptive-occlusion", "adaptive-paper"]
DIFF_FULL = 0.1


def rgb(path):
    img = mpimg.imread(path)
    return img[..., :3] if img.ndim == 3 else img


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("dir", help="fidelity experiment output directory (results.json)")
    ap.add_argument("-o", "--out", required=True, help="directory for fidelity_<scene>.png")
    ap.add_argument("--scenes", nargs="+", required=True)
    a = ap.parse_args()
    path = os.path.join(a.dir, "results.json")
    if not os.path.exists(path):
        sys.exit(f"fidelity_strips: error: no results.json in '{a.dir}'")
    res = json.load(open(path))
    runs = {(r["scene"], r["method"]): r for r in res["runs"] if r.get("status") == "ok"}
    os.makedirs(a.out, exist_ok=True)
    for scene in a.scenes:
        cols = [runs[(scene, m)] for m in METHODS if (scene, m) in runs]
        if not cols:
            sys.exit(f"fidelity_strips: error: no runs of scene '{scene}' in '{path}'")
        ref = rgb(os.path.join(a.dir, cols[0]["reference_images"]["exact"]))
        n = len(cols) + 1
        aspect = ref.shape[0] / ref.shape[1]
        fig, ax = plt.subplots(2, n, figsize=(2.0 * n, 2.0 * 2 * aspect + 0.9), squeeze=False)
        for axis in ax.flat:
            axis.set_xticks([])
            axis.set_yticks([])
        ax[0][0].imshow(ref)
        ax[0][0].set_title(f"{scene}\nexact (reference)", fontsize=7)
        ax[1][0].axis("off")
        im = None
        for c, r in enumerate(cols, start=1):
            img = rgb(os.path.join(a.dir, r["image"]))
            ax[0][c].imshow(img)
            e = r.get("errors", {}).get("exact", {}).get("masked_rel_l2")
            samples = r.get("samples", "—")
            ax[0][c].set_title(f"{r['method']}\n{samples} samples, "
                               f"{'—' if e is None else f'{100 * e:.2f} %'}", fontsize=7)
            im = ax[1][c].imshow((img - ref).mean(axis=2), cmap="RdBu_r", vmin=-DIFF_FULL,
                                 vmax=DIFF_FULL)
        fig.tight_layout(rect=(0, 0.08, 1, 1))
        cax = fig.add_axes([0.3, 0.03, 0.4, 0.025])
        cb = fig.colorbar(im, cax=cax, orientation="horizontal")
        cb.set_label("image − exact (PNG values; red brighter); masked relative L2 in the titles",
                     fontsize=7)
        cb.ax.tick_params(labelsize=6)
        out = os.path.join(a.out, f"fidelity_{scene}.png")
        fig.savefig(out, dpi=80)
        plt.close(fig)
        print(out)


if __name__ == "__main__":
    main()
