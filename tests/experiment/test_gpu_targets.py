#!/usr/bin/env python3
"""ctest GpuTargets.*: scripts/gpu-targets.py judges issues 33 and 34's targets from a report.

A fake frames.json (google benchmark's JSON, the report's counters) with frames chosen on both
sides of each bound, a test_gpu.txt and a fake GPU Table 2 (the harness's results.json): on a
GPU's name every target gets met or MISSED as its figure says; on llvmpipe's the times are "CPU
time" and only the counts and waits are judged; a missing input is exit 2.
"""
import json
import os
import shutil
import subprocess
import sys
import tempfile

from script_checks import Checks

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
SCRIPT = os.path.join(ROOT, "scripts", "gpu-targets.py")


def frame(kind, case, res, lights, wall, gpu, waits=0, **counters):
    names = ["fig3 gradient paper", "fig3 gradient defaults", "fig3 per-voxel defaults",
             "shaft adaptive paper", "shaft adaptive defaults"]
    return dict({"name": f"BM_Gpu{kind}Frame/{case}/{res}/{lights}/0/iterations:30/real_time",
                 "real_time": wall, "time_unit": "ms", "gpu_ms": gpu, "host_waits": waits,
                 "label": f"{kind.lower()}: {names[case]}, {lights} lights, compute, DEVICE"},
                **counters)


def benchmarks(device):
    rows = [
        # gradient paper: 128³ 0.5 ms GPU / 0.8 wall (met), 256³ 2.5 ms GPU (400 fps: missed)
        frame("Steady", 0, 128, 1, 0.8, 0.5, skipped_pct=56.0, samples=512, tracer_inv=3584),
        frame("Steady", 0, 256, 1, 2.8, 2.5),
        frame("Steady", 0, 128, 64, 1.2, 1.0, samples=512, tracer_inv=30000),  # < 512·64
        frame("Steady", 0, 256, 64, 2.4, 2.0),
        frame("Steady", 1, 128, 1, 1.7, 1.5),  # 2.1× the paper's wall: missed
        frame("Steady", 2, 128, 1, 1.2, 1.0),  # per-voxel 1000 fps: met
        frame("Steady", 2, 256, 1, 11.0, 10.0),
        frame("Steady", 2, 128, 64, 46.0, 45.0),  # 45× the gradient: met
        frame("Steady", 2, 256, 64, 80.0, 79.0),  # 39.5×: missed
        frame("Steady", 3, 128, 1, 2.2, 1.9, waits=2),  # 526 fps GPU: met; 2 waits
        frame("Steady", 4, 128, 1, 1.3, 1.1),
        {"name": "BM_GpuSteadyFrame/5/256/1/0/iterations:30/real_time", "error_occurred": True,
         "error_message": "'far field': a storage buffer of 260 MiB is above ..."},
    ]
    for r in rows:
        if "label" in r:
            r["label"] = r["label"].replace("DEVICE", device)
    return {"context": {}, "benchmarks": rows}


def table2(device):
    def run(sweep, method, x, wall, gpu, exact):
        return {"id": f"{sweep}__{method}__{x}", "status": "ok", "sweep": sweep, "method": method,
                "registered_method": method.split("-gpu")[0], "axes": {"a": x},
                "steady": {"frames": 10, "wall_ms": wall, "gpu_ms": gpu, "host_waits": 0.0},
                "errors": {"per-voxel": {"rel_l2": 0.01}, "exact": {"rel_l2": exact}}}
    runs = [run("resolution", "per-voxel-gpu", 128, 1.3, 1.0, 0.004),     # 1.08×: met
            run("resolution", "gradient-gpu", 128, 1.3, 0.4, 0.03),       # 1.63×: missed
            run("resolution", "gradient-gpu-defaults", 128, 1.1, 0.9, 0.005),  # on the front
            run("resolution", "jittered-march-gpu", 128, 0.5, 0.3, 0.02),  # beats gradient-gpu
            run("resolution", "froxel-gpu", 128, 0.5, 0.35, 0.05),
            run("spot_lights", "adaptive-gpu", 1, 2.0, 1.8, 0.2),
            # 64 lights, the same ring as the report's frames: 60 / 46 ms (met), 2.0 / 1.2 (missed)
            run("point_lights", "per-voxel-gpu", 64, 60.0, 58.0, 0.004),
            run("point_lights", "gradient-gpu", 64, 2.0, 1.1, 0.03)]
    m = {"gpu_renderers": [device]}
    return {"references": ["per-voxel", "exact"], "runs": runs, "machine": m, "machines": [m]}


def main():
    tmp = tempfile.mkdtemp(prefix="scatterlab-gputargets-")
    check = Checks()

    try:
        for device, hardware in (("NVIDIA H200/PCIe/SSE2", True),
                                 ("llvmpipe (LLVM 15.0.6, 256 bits)", False)):
            rep, t2 = os.path.join(tmp, "report"), os.path.join(tmp, "report", "table2_gpu")
            os.makedirs(t2, exist_ok=True)
            with open(os.path.join(rep, "frames.json"), "w") as f:
                json.dump(benchmarks(device), f)
            with open(os.path.join(rep, "test_gpu.txt"), "w") as f:
                f.write("[==========] 137 tests ran.\n[  PASSED  ] 136 tests.\n"
                        "[  FAILED  ] 1 test, listed below:\n")
            with open(os.path.join(t2, "results.json"), "w") as f:
                json.dump(table2(device), f)
            p = subprocess.run([sys.executable, SCRIPT, "--report", rep, "--table2", t2],
                               capture_output=True, text=True)
            check(p.returncode == 0, f"{device}: exit 0")
            lines = p.stdout.splitlines()

            def verdict(start):
                hit = [x for x in lines if x.startswith(start)]
                return hit[0].rsplit("  ", 1)[1].strip() if len(hit) == 1 else f"{len(hit)} lines"
            timed = (lambda v: v) if hardware else (lambda v: "CPU time")
            expect = {
                "#33  gradient paper 128³ ≥ 1000 fps GPU": timed("met"),
                "#33  gradient paper 128³ ≥ 500 fps wall": timed("met"),
                "#34  gradient paper 256³ ≥ 500 fps GPU": timed("MISSED"),
                "#33  gradient defaults within 2× of paper": timed("MISSED"),
                "#33  adaptive paper (shaft) 128³ ≥ 500 fps GPU": timed("met"),
                "#34  per-voxel 128³ ≥ 500 fps GPU": timed("met"),
                "#34  gradient paper / per-voxel 128³ 64 lights ≥ 44×": timed("met"),
                "#34  gradient paper / per-voxel 256³ 64 lights ≥ 44×": timed("MISSED"),
                "#34  gradient paper / per-voxel 128³ 1 lights ≥ 1×": timed("met"),
                # judged on any device: waits, counts, tests
                "#33  steady frames wait for nothing": "MISSED",
                "#34  plume: march steps skipped ≥ 50 %": "met",
                "#34  tracer invocations ≥ samples × lights": "MISSED",
                "#33  test_gpu: 0 failures": "MISSED",
                "#33  harness steady per-voxel-gpu (1 light) within": timed("met"),
                "#33  harness steady gradient-gpu (1 light) within": timed("MISSED"),
                "#33  harness steady per-voxel-gpu (64 lights) within": timed("met"),
                "#33  harness steady gradient-gpu (64 lights) within": timed("MISSED"),
                "#33  harness steady adaptive-gpu (64 lights) within": "not measured",
                "#34  gradient-gpu 128³ on the Pareto front (vs exact)": timed("MISSED"),
                "#34  gradient-gpu-defaults 128³ on the Pareto front": timed("met"),
            }
            for start, v in expect.items():
                got = verdict(start)
                check(got == v, f"{device}: {start.strip()} -> {v} (got {got})")
            check("beaten by jittered-march-gpu" in p.stdout, f"{device}: names who beats it")
            check("adaptive-gpu spot_lights" not in p.stdout,
                  f"{device}: no front where nothing else was run")
            check(lines[0].startswith(f"device: {device}"), f"{device}: names the device")
            check("frame failed: steady gradient defaults + far field (plume) 256³ 1 lights: 'far field'"
                  in p.stdout and lines[-1].endswith(", 1 frames failed"),
                  f"{device}: a frame that failed is listed")
        # A frames.json the report's timeout cut after its third record (Google Benchmark's
        # own layout: a record per benchmark as it ends): the frames it holds are judged, the
        # others are not measured, and the output says it was cut.
        cut = os.path.join(tmp, "cut")
        os.makedirs(cut, exist_ok=True)
        whole = json.dumps(benchmarks("NVIDIA H100 80GB HBM3/PCIe/SSE2"), indent=2)
        third = whole.index("\n    }", whole.index("\n    }", whole.index("\n    }") + 1) + 1)
        with open(os.path.join(cut, "frames.json"), "w") as f:
            f.write(whole[:third + 6])
        with open(os.path.join(cut, "test_gpu.txt"), "w") as f:
            # --gtest_brief=1, as the report runs it: no FAILED count, a line per failed test.
            f.write("/work/tests/gpu/test_validate.cpp:171: Failure\n"
                    "[  FAILED  ] GpuValidate.ATexelFetchOutsideItsTextureNamesThePass (0 ms)\n"
                    "[==========] 138 tests from 47 test suites ran. (67525 ms total)\n"
                    "[  PASSED  ] 137 tests.\n")
        p = subprocess.run([sys.executable, SCRIPT, "--report", cut], capture_output=True,
                           text=True)
        lines = p.stdout.splitlines()
        check(p.returncode == 0, f"a cut frames.json: exit 0 ({p.stderr.strip()})")
        check("frames.json was cut short" in p.stdout and "3 frames read" in p.stdout,
              "a cut frames.json: says so, with the frames read")
        got = [x for x in lines if x.startswith("#33  gradient paper 128³ ≥ 1000 fps GPU")]
        check(len(got) == 1 and got[0].endswith("met"), f"a cut frames.json: judged ({got})")
        got = [x for x in lines if x.startswith("#33  test_gpu: 0 failures")]
        check(len(got) == 1 and "137 passed, 1 failed" in got[0] and got[0].endswith("MISSED"),
              f"a brief test_gpu.txt: its failed test counted ({got})")
        got = [x for x in lines if x.startswith("#33  adaptive paper (shaft) 128³ ≥ 500 fps GPU")]
        check(len(got) == 1 and got[0].endswith("not measured"),
              f"a cut frames.json: the frames after the cut not measured ({got})")
        p = subprocess.run([sys.executable, SCRIPT, "--report", os.path.join(tmp, "none")],
                           capture_output=True, text=True)
        check(p.returncode == 2 and "frames.json" in p.stderr, "a missing report: exit 2")
    finally:
        if not check.failures:
            shutil.rmtree(tmp, ignore_errors=True)
    return check.summary()


if __name__ == "__main__":
    sys.exit(main())
