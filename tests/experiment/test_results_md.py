#!/usr/bin/env python3
"""ctest ResultsMd.*: scripts/results_md.py merges into an existing RESULTS.md.

A fake fig3 results.json (one run, a machine record) and an old RESULTS.md with Fig. 3, Table 2
and Fidelity sections: after the script, Fig. 3 holds the new run and the machine from the
results, Table 2 (no new results) keeps its old body under a note, Fidelity is untouched, and a
second run changes nothing. A fake GPU Table 2 (table2_gpu.json's shape: a baseline and a method
with steady frames, one switched to per-voxel) gives its cold and steady columns, the speed-up
from the steady GPU times, the device's name and, on llvmpipe, the warning that its times are
CPU times.
"""
import json
import os
import shutil
import subprocess
import sys
import tempfile

from script_checks import Checks

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
OLD = """# Results beside the paper's

Old header with a fixed sentence about shared machines.

## Fig. 3: interpolation schemes (relative L2 against per-voxel)

| old fig3 row |

## Table 2: frame rate (fps) and speed-up over per-voxel

### resolution

| old table2 row |

## Fidelity (issue 11): every method against `exact` where users look

| old fidelity row |
"""
MACHINE = {"cpu_model": "Test CPU 9000", "cores_used": 3, "logical_cpus": 8,
           "load_avg_start": [1.5, 1.25, 1.0], "hostname": "testhost", "commit": "abc123",
           "gpu_renderers": [], "runs": 1}


def main():
    tmp = tempfile.mkdtemp(prefix="scatterlab-resultsmd-")
    check = Checks()

    try:
        fig3 = os.path.join(tmp, "fig3")
        os.makedirs(fig3)
        run = {"id": "gradient", "status": "ok", "registered_method": "gradient", "samples": 800,
               "errors": {"per-voxel": {"rel_l2": 0.0222}}, "paper": {"rel_error": 0.043},
               "median_ms": {"total": 313.0}}
        with open(os.path.join(fig3, "results.json"), "w") as f:
            json.dump({"references": ["per-voxel"], "runs": [run], "machine": MACHINE,
                       "machines": [MACHINE]}, f)
        out = os.path.join(tmp, "RESULTS.md")
        with open(out, "w") as f:
            f.write(OLD)
        cmd = [sys.executable, os.path.join(ROOT, "scripts", "results_md.py"), "--fig3", fig3,
               "--fig45", os.path.join(tmp, "none45"), "--table2", os.path.join(tmp, "none2"),
               "--table2-gpu", os.path.join(tmp, "none2gpu"), "-o", out]
        check(subprocess.run(cmd).returncode == 0, "results_md.py exits 0")
        text = open(out).read()
        check("| gradient | gradient | 800 | 2.22% | 4.30% | 313 |" in text, "new Fig. 3 row")
        check("old fig3 row" not in text, "old Fig. 3 row replaced")
        check("Machine: Test CPU 9000, 3 of 8 CPUs used, load average 1.50 / 1.25 / 1.00" in text
              and "commit `abc123`" in text, "machine of the Fig. 3 results")
        check("shared machines" not in text, "no fixed sentence about the machine")
        t2 = text.split("## Table 2")[1].split("\n## ")[0]
        check("### resolution" in t2 and "| old table2 row |" in t2 and "kept from the previous" in t2,
              "Table 2 without new results keeps its body")
        check("## Fidelity (issue 11)" in text and "| old fidelity row |" in text, "Fidelity kept")
        check("Not run (no " in text.split("## Fig. 4/5")[1].split("\n## ")[0],
              "Fig. 4/5 with neither results nor a previous section: Not run")
        check(subprocess.run(cmd).returncode == 0 and open(out).read() == text,
              "a second run changes nothing")

        # Fig. 4/5: the paper's 2705 samples beside the runs at its ε only.
        fig45 = os.path.join(tmp, "fig45")
        os.makedirs(fig45)
        runs45 = [{"id": f"epsilon__adaptive__epsilon-{e}", "status": "ok", "samples": n,
                   "axes": {"epsilon": e}, "paper": {"samples": 2705},
                   "errors": {"exact": {"rel_l2": 0.2}}, "median_ms": {"total": 100.0}}
                  for e, n in ((0.001, 889), (0.0001, 2748))]
        with open(os.path.join(fig45, "results.json"), "w") as f:
            json.dump({"references": ["exact"], "runs": runs45, "machine": MACHINE,
                       "machines": [MACHINE]}, f)
        cmd45 = cmd[:cmd.index("--fig45") + 1] + [fig45] + cmd[cmd.index("--fig45") + 2:]
        check(subprocess.run(cmd45).returncode == 0, "results_md.py with Fig. 4/5 exits 0")
        f45 = open(out).read().split("## Fig. 4/5")[1].split("\n## ")[0]
        check("| epsilon__adaptive__epsilon-0.001 | 889 | — |" in f45 and
              "| epsilon__adaptive__epsilon-0.0001 | 2748 | 2705 |" in f45,
              "Fig. 4/5: the paper's count at ε = 1e-4 only")

        # GPU Table 2: cold and steady columns, the speed-up from the steady GPU times.
        t2g = os.path.join(tmp, "table2_gpu")
        os.makedirs(t2g)

        def gpu_run(method, ms, steady, samples=512, stats=None):
            return {"id": f"resolution__plume__{method}__resolution-128", "status": "ok",
                    "sweep": "resolution", "method": method, "axes": {"resolution": 128},
                    "point": 2, "samples": samples, "median_ms": {"total": ms},
                    "steady": steady, "stats": stats or {}, "paper": {},
                    "errors": {"per-voxel": {"rel_l2": 0.025}, "exact": {"rel_l2": 0.03}}}
        gpu_runs = [gpu_run("per-voxel-gpu", 8.0, {"frames": 10, "wall_ms": 1.25, "gpu_ms": 1.0,
                                                   "host_waits": 0.0}, samples=None),
                    gpu_run("gradient-gpu", 12.0, {"frames": 10, "wall_ms": 0.8, "gpu_ms": 0.5,
                                                   "host_waits": 0.0}),
                    gpu_run("gradient-gpu-defaults", 9.0,
                            {"frames": 10, "wall_ms": 1.3, "gpu_ms": 1.1, "host_waits": 0.0},
                            samples=0, stats={"voxels_instead": True, "traced_voxels": 4321})]
        for renderer, warned in (("NVIDIA H200/PCIe/SSE2", False),
                                 ("llvmpipe (LLVM 15.0.6, 256 bits)", True)):
            m = dict(MACHINE, gpu_renderers=[renderer])
            with open(os.path.join(t2g, "results.json"), "w") as f:
                json.dump({"references": [{"name": "per-voxel"}, {"name": "exact"}],
                           "runs": gpu_runs, "machine": m, "machines": [m]}, f)
            cmdg = cmd[:cmd.index("--table2-gpu") + 1] + [t2g] + cmd[cmd.index("--table2-gpu") + 2:]
            check(subprocess.run(cmdg).returncode == 0, f"results_md.py with GPU Table 2 ({renderer})")
            g = open(out).read().split("## GPU Table 2")[1].split("\n## ")[0]
            check(f"GPU: {renderer}" in g, "GPU Table 2 names the device")
            check("| 128 | gradient-gpu | 512 | 12.000 (83) | 0.800 (1250) | 0.500 (2000) | 0 | — "
                  "| 2.00× | 2.50% | 3.00% |" in g, "GPU Table 2: cold, steady, speed-up, errors")
            check("| 128 | gradient-gpu-defaults | per-voxel: 4321 voxels |" in g,
                  "GPU Table 2: a switched run's voxels")
            check(("its times are CPU times" in g) == warned,
                  "GPU Table 2: the llvmpipe warning " + ("given" if warned else "absent"))
    finally:
        if not check.failures:
            shutil.rmtree(tmp, ignore_errors=True)
    return check.summary()


if __name__ == "__main__":
    sys.exit(main())
