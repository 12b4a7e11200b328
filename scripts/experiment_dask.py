#!/usr/bin/env python3
"""Runs a `scatterlab experiment` sweep as shards on a Dask cluster, then merges them.

    python3 scripts/experiment_dask.py CONFIG -o DIR --scheduler tcp://HOST:8786 [--shards N]
    python3 scripts/experiment_dask.py CONFIG -o DIR --local N                   [--shards N]

Each shard K of N is one Dask task that runs

    scatterlab experiment CONFIG -o DIR/shards/K-of-N --shard K/N --no-plots -q --no-progress

on a worker, and when every shard is done this process runs

    scatterlab experiment merge DIR/shards/*-of-N -o DIR

which writes results.csv/json, report.md, the gallery and the plots of the whole sweep into DIR.
CONFIG, DIR and the scatterlab binary must be at the same paths on every worker (a shared file
system, as on a cluster). A worker that dies takes its scatterlab process with it (PR_SET_PDEATHSIG)
and Dask runs the shard again on another worker; the shard resumes, so the runs it had finished
are not rendered again. Running this command again with the same -o DIR resumes the same way.

Needs Dask's distributed (Debian: python3-distributed, installed by scripts/setup.sh). When the
python running this lacks it, the script runs itself again with /usr/bin/python3 if that has it.
Exit status: 0 when every run succeeded, 1 when some run failed or a shard could not be run, 2 for
bad arguments.
"""
import argparse
import ctypes
import glob
import json
import os
import signal
import socket
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
DEFAULT_SCATTERLAB = os.path.join(os.path.dirname(HERE), "build", "bin", "scatterlab")
SYSTEM_PYTHON = "/usr/bin/python3"


def ensure_distributed():
    """Imports distributed, or re-runs this process with the system python that has it."""
    try:
        import distributed  # noqa: F401
        return
    except ImportError:
        pass
    if os.path.realpath(sys.executable) != os.path.realpath(SYSTEM_PYTHON) and \
            os.path.exists(SYSTEM_PYTHON) and subprocess.run(
                [SYSTEM_PYTHON, "-c", "import distributed"], capture_output=True).returncode == 0:
        os.execv(SYSTEM_PYTHON, [SYSTEM_PYTHON] + sys.argv)
    sys.stderr.write("experiment_dask.py: error: no python with Dask's distributed module "
                     "(install python3-distributed, e.g. by scripts/setup.sh)\n")
    sys.exit(2)


def shard_dir(out, k, n):
    return os.path.join(out, "shards", f"{k}-of-{n}")


def _die_with_parent():
    # Linux: SIGKILL this child when the worker thread that started it dies, so that a killed
    # worker leaves no scatterlab process writing into the shard directory behind.
    try:
        ctypes.CDLL("libc.so.6", use_errno=True).prctl(1, signal.SIGKILL)  # PR_SET_PDEATHSIG
    except OSError:
        pass


def run_shard(exe, config, out, k, n, sets):
    """The Dask task: renders (or resumes) shard k of n. Raises when the shard did not finish
    (so that Dask retries it); returns its summary when it did, failed runs included."""
    d = shard_dir(out, k, n)
    os.makedirs(d, exist_ok=True)
    with open(os.path.join(d, "worker.json"), "w") as f:
        json.dump({"pid": os.getpid(), "host": socket.gethostname(), "started": time.time()}, f)
    cmd = [exe, "experiment", config, "-o", d, "--shard", f"{k}/{n}", "--no-plots", "-q",
           "--no-progress"]
    for s in sets:
        cmd += ["--set", s]
    p = subprocess.run(cmd, capture_output=True, text=True, preexec_fn=_die_with_parent)
    manifest = os.path.join(d, f"shard-{k}-of-{n}.json")
    if p.returncode not in (0, 1) or not os.path.exists(manifest):
        raise RuntimeError(f"shard {k}/{n} on {socket.gethostname()}: exit {p.returncode}: "
                           f"{(p.stderr or p.stdout).strip()[-2000:]}")
    with open(manifest) as f:
        m = json.load(f)
    return {"shard": k, "rc": p.returncode, "host": socket.gethostname(),
            "rendered": m["rendered"], "resumed": m["resumed"], "failed": m["failed"],
            "refused": m.get("refused", 0)}


def run_sweep(client, exe, config, out, shards, sets=(), retries=2, log=sys.stderr):
    """Submits the shards to `client`, waits for them and returns their summaries (in shard
    order) and the errors of the shards that could not be run."""
    futures = [client.submit(run_shard, exe, config, out, k, shards, list(sets), retries=retries,
                             pure=False, key=f"scatterlab-shard-{k}-of-{shards}-{time.time_ns()}")
               for k in range(1, shards + 1)]
    from distributed import as_completed
    done, errors = {}, []
    for fut in as_completed(futures):
        try:
            s = fut.result()
            done[s["shard"]] = s
            print(f"shard {s['shard']}/{shards} on {s['host']}: {s['rendered']} rendered, "
                  f"{s['resumed']} resumed, {s['failed']} failed, {s['refused']} refused",
                  file=log, flush=True)
        except Exception as e:  # noqa: BLE001 -- every failure is reported, the others go on
            errors.append(str(e))
            print(f"error: {e}", file=log, flush=True)
    return [done[k] for k in sorted(done)], errors


def merge(exe, out, shards, plots=True):
    dirs = sorted(glob.glob(os.path.join(out, "shards", f"*-of-{shards}")))
    cmd = [exe, "experiment", "merge"] + dirs + ["-o", out, "-q", "--no-progress"]
    if not plots:
        cmd.append("--no-plots")
    return subprocess.run(cmd).returncode


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("config", help="experiment config (JSON), e.g. data/experiments/fig3.json")
    ap.add_argument("-o", "--output", required=True, help="output directory (shared by workers)")
    where = ap.add_mutually_exclusive_group(required=True)
    where.add_argument("--scheduler", help="address of a running Dask scheduler, tcp://HOST:8786")
    where.add_argument("--local", type=int, metavar="N",
                       help="start a LocalCluster of N single-threaded worker processes here")
    ap.add_argument("--shards", type=int, help="number of shards (default: the number of workers)")
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                    help="scene override for every render (repeatable), as scatterlab's --set")
    ap.add_argument("--scatterlab", default=DEFAULT_SCATTERLAB,
                    help=f"the scatterlab binary, same path on every worker "
                         f"(default {DEFAULT_SCATTERLAB})")
    ap.add_argument("--retries", type=int, default=2,
                    help="times Dask reruns a shard that raised (default 2; a shard on a worker "
                         "that died is rerun by the scheduler in any case)")
    ap.add_argument("--no-plots", action="store_true", help="merge without plots and gallery")
    a = ap.parse_args(argv)
    if a.local is not None and a.local < 1:
        ap.error(f"--local {a.local}: need at least 1 worker")
    if a.shards is not None and a.shards < 1:
        ap.error(f"--shards {a.shards}: need at least 1")
    if a.retries < 0:
        ap.error(f"--retries {a.retries}: must be 0 or more")
    if not os.path.isfile(a.config):
        ap.error(f"config '{a.config}' does not exist")
    if not os.access(a.scatterlab, os.X_OK):
        ap.error(f"scatterlab binary '{a.scatterlab}' not found or not executable "
                 "(build it, or pass --scatterlab PATH)")
    # The config is checked here first (scatterlab's own message, exit 1), before any cluster.
    check = subprocess.run([a.scatterlab, "experiment", a.config, "--list"] +
                           [x for s in a.set for x in ("--set", s)], capture_output=True, text=True)
    if check.returncode != 0:
        sys.stderr.write(check.stderr or check.stdout)
        return 1
    ensure_distributed()
    from distributed import Client, LocalCluster

    config, out, exe = (os.path.abspath(p) for p in (a.config, a.output, a.scatterlab))
    cluster = None
    if a.local:
        cluster = LocalCluster(n_workers=a.local, threads_per_worker=1, processes=True,
                               dashboard_address=None)
        client = Client(cluster)
    else:
        try:
            client = Client(a.scheduler, timeout="30s")
        except OSError as e:
            print(f"experiment_dask: error: cannot reach the scheduler {a.scheduler}: {e}",
                  file=sys.stderr)
            return 1
    try:
        try:
            client.wait_for_workers(1, timeout=60)
        except Exception:  # noqa: BLE001 -- distributed raises TimeoutError or its own
            print(f"experiment_dask: error: no worker joined {client.scheduler.address} within "
                  "60 s (start some: dask-worker ADDRESS --nthreads 1)", file=sys.stderr)
            return 1
        workers = len(client.scheduler_info()["workers"])
        shards = a.shards or max(1, workers)
        print(f"experiment_dask: {shards} shard(s) on {workers} worker(s) at "
              f"{client.scheduler.address}; output {out}", file=sys.stderr, flush=True)
        _, errors = run_sweep(client, exe, config, out, shards, a.set, a.retries)
    finally:
        client.close()
        if cluster:
            cluster.close()
    if errors:
        print(f"experiment_dask: {len(errors)} shard(s) could not be run; run the same command "
              "again to resume them", file=sys.stderr)
        return 1
    return merge(exe, out, shards, plots=not a.no_plots)


if __name__ == "__main__":
    sys.exit(main())
