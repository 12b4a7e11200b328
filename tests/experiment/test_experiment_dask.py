#!/usr/bin/env python3
"""ctest ExperimentDask.*: scripts/experiment_dask.py on a LocalCluster of 2 workers.

    python3 tests/experiment/test_experiment_dask.py --scatterlab build/bin/scatterlab

A tiny sweep (12 runs, 2 reference groups, 64x48) run three ways: by one process; as 2 shards on
the cluster; and as 2 shards where the worker of shard 1 is killed (SIGKILL) once its first run
is recorded. Checks: the cluster's merged results equal the single process's (run ids, status,
sample counts and every error figure, to the last bit: renders are deterministic); after the kill
the sweep still completes, shard 1's rerun resumes the runs recorded before the kill and renders
only the rest, and its scatterlab process died with the worker. Exit 77 (ctest: skipped) without
a python that has Dask's distributed.
"""
import argparse
import glob
import json
import os
import shutil
import subprocess
import sys
import tempfile
import threading
import time

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(ROOT, "scripts"))


def have_distributed():
    try:
        import distributed  # noqa: F401
        return True
    except ImportError:
        return False


if not have_distributed():
    if os.path.exists("/usr/bin/python3") and \
            os.path.realpath(sys.executable) != os.path.realpath("/usr/bin/python3") and \
            subprocess.run(["/usr/bin/python3", "-c", "import distributed"],
                           capture_output=True).returncode == 0:
        os.execv("/usr/bin/python3", ["/usr/bin/python3"] + sys.argv)
    print("SKIPPED: no python with Dask's distributed (python3-distributed)")
    sys.exit(77)

import experiment_dask  # noqa: E402
from distributed import Client, LocalCluster  # noqa: E402
from script_checks import Checks  # noqa: E402

check = Checks()


def alive(pid):
    """True while `pid` runs (a zombie waiting to be reaped counts as dead)."""
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


def children(pid):
    """The child processes of `pid` (all its threads'), from /proc."""
    out = []
    for f in glob.glob(f"/proc/{pid}/task/*/children"):
        try:
            with open(f) as fh:
                out += fh.read().split()
        except OSError:
            pass
    return out


def tiny_config(d):
    scene = os.path.join(ROOT, "data", "scenes", "glow.json")
    cfg = {
        "title": "dask test",
        "scenes": [{"name": "glow", "file": scene,
                    "set": ["camera.width=64", "camera.height=48"]}],
        "references": ["per-voxel"],
        "repetitions": 1, "warmup": 0,
        "methods": [{"name": "gradient", "method": "gradient",
                     "set": ["render.sampler={\"type\": \"jittered\", \"seed\": 1}"]},
                    {"name": "nearest", "method": "nearest",
                     "set": ["render.sampler={\"type\": \"jittered\", \"seed\": 1}"]}],
        "sweeps": [{"name": "s", "axes": {"resolution": [16, 24],
                                          "samples": [16, 32, 64]}}],
    }
    path = os.path.join(d, "exp.json")
    with open(path, "w") as f:
        json.dump(cfg, f)
    return path


def summary(out):
    with open(os.path.join(out, "results.json")) as f:
        res = json.load(f)
    return {r["id"]: (r["status"], r.get("samples"), r.get("errors")) for r in res["runs"]}


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--scatterlab", required=True)
    a = ap.parse_args()
    exe = os.path.abspath(a.scatterlab)
    tmp = tempfile.mkdtemp(prefix="scatterlab-dask-")
    try:
        cfg = tiny_config(tmp)
        single = os.path.join(tmp, "single")
        p = subprocess.run([exe, "experiment", cfg, "-o", single, "--no-plots", "-q"],
                           capture_output=True, text=True)
        check(p.returncode == 0, f"single-process run exits 0 ({p.stderr.strip()[-300:]})")
        want = summary(single)
        check(len(want) == 12 and all(v[0] == "ok" for v in want.values()), "12 runs, all ok")

        cluster = LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                               dashboard_address=None)
        client = Client(cluster)
        try:
            # 1. Two shards on two workers, merged: the single process's results.
            out = os.path.join(tmp, "dask")
            shards, errors = experiment_dask.run_sweep(client, exe, cfg, out, 2)
            check(not errors, f"both shards ran ({errors})")
            check(sum(s["rendered"] for s in shards) == 12, "the shards rendered 12 runs together")
            check(experiment_dask.merge(exe, out, 2, plots=False) == 0, "merge exits 0")
            check(summary(out) == want, "merged results (status, samples, errors) == single run")

            # 2. Kill shard 1's worker after its first record: Dask reruns the shard, which
            # resumes. The watcher kills the worker process named in the shard's worker.json.
            out2 = os.path.join(tmp, "killed")
            d1 = experiment_dask.shard_dir(out2, 1, 2)
            killed = {}

            def watch():
                deadline = time.time() + 120
                while time.time() < deadline:
                    recs = glob.glob(os.path.join(d1, "runs", "*.json"))
                    if recs:
                        with open(os.path.join(d1, "worker.json")) as f:
                            pid = json.load(f)["pid"]
                        child = children(pid)
                        killed.update(pid=pid, records=len(recs), child=child)
                        os.kill(pid, 9)
                        # The scatterlab child dies with its worker (PR_SET_PDEATHSIG).
                        end = time.time() + 5
                        while time.time() < end and any(alive(c) for c in child):
                            time.sleep(0.05)
                        killed["child_alive"] = [c for c in child if alive(c)]
                        return
                    time.sleep(0.01)

            t = threading.Thread(target=watch)
            t.start()
            shards, errors = experiment_dask.run_sweep(client, exe, cfg, out2, 2)
            t.join()
            check("pid" in killed and killed["records"] < 6,
                  f"a worker was killed mid-shard ({killed})")
            check(not errors, f"the sweep completed after the kill ({errors})")
            s1 = [s for s in shards if s["shard"] == 1]
            check(bool(s1) and s1[0]["resumed"] >= killed.get("records", 99) and
                  s1[0]["rendered"] + s1[0]["resumed"] == 6,
                  f"shard 1's rerun resumed the runs recorded before the kill and rendered the "
                  f"rest ({s1}, {killed.get('records')} recorded at the kill)")
            check(bool(killed.get("child")) and not killed.get("child_alive"),
                  f"the killed worker's scatterlab process {killed.get('child')} died with it")
            check(experiment_dask.merge(exe, out2, 2, plots=False) == 0, "merge exits 0")
            check(summary(out2) == want, "results after the kill == single run")

            # 3. The whole driver once more on the finished directory: everything resumes.
            p = subprocess.run([sys.executable, os.path.join(ROOT, "scripts", "experiment_dask.py"),
                                cfg, "-o", out2, "--scheduler", cluster.scheduler_address,
                                "--shards", "2", "--scatterlab", exe, "--no-plots"],
                               capture_output=True, text=True)
            check(p.returncode == 0 and "0 rendered, 6 resumed" in p.stderr,
                  f"driver rerun: every run resumed ({p.stderr.strip()[-400:]})")
        finally:
            client.close()
            cluster.close()
    finally:
        if not check.failures:
            shutil.rmtree(tmp, ignore_errors=True)
        else:
            print("kept", tmp)
    return check.summary()


if __name__ == "__main__":
    sys.exit(main())
