#!/usr/bin/env python3
"""Cost of running debris-runout from Python over running the app, on the getting-started case
(the Alplehner DTM and release polygon, --h0 1; docs/getting-started.md).

    PYTHONPATH=build/python /usr/bin/python3 bench/python_overhead.py [--runs 3] [--threads 1]

Runs, alternately, `debris-runout avaAlr.tif --release relAlr.shp --h0 1 --quiet --out DIR` and a
fresh `python3 -c` that imports geohaz and calls geohaz.runout.run(avaAlr.tif, release=relAlr.shp,
h0=1, out=DIR) (both write every output), and prints per run the wall time and the CPU time
(user + system) of the whole process, interpreter start and imports included, then the medians.
Alternating spreads the load of a shared machine over both; on a loaded machine the CPU time is
the steadier figure.
"""
import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

root = Path(__file__).resolve().parents[1]
p = argparse.ArgumentParser()
p.add_argument("--runs", type=int, default=3)
p.add_argument("--threads", type=int, default=1)
p.add_argument("--app", default=str(root / "build/apps/debris-runout/debris-runout"))
a = p.parse_args()
dsm, rel = root / "data/terrain/alr/avaAlr.tif", root / "data/terrain/alr/relAlr.shp"

snippet = ("import sys, geohaz; geohaz.runout.run(sys.argv[1], release=sys.argv[2], h0=1, out=sys.argv[3], "
           "threads=int(sys.argv[4]), particles=False)")


def cpu():
    u = resource.getrusage(resource.RUSAGE_CHILDREN)
    return u.ru_utime + u.ru_stime


wall = {"app": [], "python": []}
cpus = {"app": [], "python": []}
steps = {}
with tempfile.TemporaryDirectory() as tmp:
    for k in range(a.runs):
        for kind in ("app", "python"):
            out = Path(tmp) / f"{kind}{k}"
            if kind == "app":
                cmd = [a.app, str(dsm), "--release", str(rel), "--h0", "1", "--quiet", "--threads", str(a.threads),
                       "--out", str(out)]
            else:
                cmd = [sys.executable, "-c", snippet, str(dsm), str(rel), str(out), str(a.threads)]
            c0, t0 = cpu(), time.perf_counter()
            subprocess.run(cmd, check=True, env=dict(os.environ))
            wall[kind].append(time.perf_counter() - t0)
            cpus[kind].append(cpu() - c0)
            steps[kind] = json.loads((out / "summary.json").read_text())["steps"]
            print(f"run {k + 1} {kind:6s} wall {wall[kind][-1]:7.2f} s  cpu {cpus[kind][-1]:7.2f} s  "
                  f"({steps[kind]} steps)", flush=True)
assert steps["app"] == steps["python"], steps
for name, d in (("wall", wall), ("cpu", cpus)):
    ap, py = statistics.median(d["app"]), statistics.median(d["python"])
    print(f"median {name}: app {ap:.2f} s, python {py:.2f} s: {100 * (py / ap - 1):+.2f} %")
