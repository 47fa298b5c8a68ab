"""Benchmark: what the edge-response rule costs per scenario, before and after, in one run.

Issue 23 replaced the `accurate` and `fast` edge rule (composite Gauss-Legendre on uniform
panels) by composite Gauss-Kronrod on panels that follow the system OTF (graded toward
f = 0, one per drift-sinc lobe) with an error estimate. This times, for each checkout
given (``--checkout PATH``, repeatable; default: this one alone), the same cells with
``accurate`` and ``fast``:

- ``olson``: the paper's Olson example over ground range -- both bands (one
  ``xbsm.niirs`` call each), 9 km, visibility 23 and 5 km, the 97 database ground ranges
  (388 scenarios);
- ``ground_range``: Olson NIR, 2,000 ground ranges 0-100 km on one dimension;
- ``focal_length``: 20 focal lengths 2-6 m x 100 ground ranges (0.25-99.25 km);
- ``drift``: 20 drift rates 0-500 urad/s (0-7.5 px over the 30 ms exposure) x 100
  ground ranges;
- ``drift_alone``: 1,000 drift rates 0-500 urad/s, one per scenario (each its own rule).

The timed part runs in one child process per checkout (``PYTHONPATH=PATH``, it prints
``xbsm.__file__``), kept alive for the run; the parent sends every child the same cell,
one repeat at a time, checkouts alternating (their order rotated each repeat), so that
a load change on the shared machine falls on all. Each cell: one warm-up call, then
``--repeats`` (3) timed eager calls with ``.niirs.values`` read; the median per scenario
is reported (wall time and the child's CPU time, which a busy shared machine disturbs
less), every repeat kept. The load average is printed before every cell.

Writes ``docs/benchmarks/bench_edge_cost.json`` (``--out``). Run from the repository
root; the docs' before/after run compared this checkout with one of 3b99eb9 (the commit
before issue 23's rule)::

    git worktree add ../xbsm-before 3b99eb9
    .venv/bin/python recipes/bench/bench_edge_cost.py --checkout . --checkout ../xbsm-before \
        [--repeats 5]
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
CELLS = ("olson", "ground_range", "focal_length", "drift", "drift_alone")
METHODS = ("accurate", "fast")


def _inputs(cell):
    """(sensor, scenario) pairs of a cell (child side: imports the child's xbsm)."""
    import numpy as np
    import xarray as xr

    import xbsm
    from xbsm.examples import DATABASE_GROUND_RANGES, olson_sensor

    ranges = xr.DataArray([250.0 + 1000.0 * i for i in range(100)], dims="ground_range")
    base = dict(altitude=9000.0, visibility=23.0, platform_speed=100.0)
    if cell == "olson":
        sc = xbsm.scenario(altitude=9000.0, platform_speed=100.0,
                           visibility=xr.DataArray([23.0, 5.0], dims="visibility"),
                           ground_range=xr.DataArray(np.asarray(DATABASE_GROUND_RANGES),
                                                     dims="ground_range"))
        return [(olson_sensor(band), sc) for band in ("nir", "red")]
    if cell == "ground_range":
        gr = xr.DataArray(np.linspace(0.0, 100e3, 2000), dims="ground_range")
        return [(olson_sensor("nir"), xbsm.scenario(**base, ground_range=gr))]
    if cell == "focal_length":
        f = xr.DataArray(np.linspace(2.0, 6.0, 20), dims="focal_length")
        return [(olson_sensor("nir", focal_length=f), xbsm.scenario(**base, ground_range=ranges))]
    if cell == "drift":
        d = xr.DataArray(np.linspace(0.0, 500e-6, 20), dims="drift_step")
        return [(olson_sensor("nir", drift_rate_x=d),
                 xbsm.scenario(**base, ground_range=ranges))]
    if cell == "drift_alone":
        d = xr.DataArray(np.linspace(0.0, 500e-6, 1000), dims="drift_step")
        return [(olson_sensor("nir", drift_rate_x=d),
                 xbsm.scenario(**base, ground_range=20_250.0))]
    raise ValueError(cell)


def child():
    """Serve timing requests on stdin: one JSON line per (cell, method); warm-up once."""
    import xbsm

    print(json.dumps({"xbsm": xbsm.__file__}), flush=True)
    prepared = {}
    for line in sys.stdin:
        request = json.loads(line)
        key = (request["cell"], request["method"])
        if key not in prepared:
            pairs = _inputs(request["cell"])
            for s, sc in pairs:  # warm-up
                _ = xbsm.niirs(s, sc, method=request["method"]).niirs.values
            prepared[key] = pairs
        pairs = prepared[key]
        start, cpu = time.perf_counter(), time.process_time()
        count = 0
        for s, sc in pairs:
            out = xbsm.niirs(s, sc, method=request["method"])
            count += out.niirs.size // out.sizes["giqe"]
        seconds, cpu = time.perf_counter() - start, time.process_time() - cpu
        print(json.dumps({"seconds": seconds, "cpu": cpu, "scenarios": count}), flush=True)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--checkout", action="append", default=None)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--cells", nargs="*", default=list(CELLS))
    parser.add_argument("--out", default=str(ROOT / "docs/benchmarks/bench_edge_cost.json"))
    parser.add_argument("--child", action="store_true", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.child:
        return child()
    checkouts = [str(Path(c).resolve()) for c in args.checkout or [ROOT]]
    children = {}
    for path in checkouts:
        env = {**os.environ, "PYTHONPATH": path, "OMP_NUM_THREADS": "1",
               "OPENBLAS_NUM_THREADS": "1", "MKL_NUM_THREADS": "1"}
        proc = subprocess.Popen([sys.executable, __file__, "--child"], cwd=path, env=env,
                                stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
        hello = json.loads(proc.stdout.readline())
        print(f"checkout {path}: xbsm from {hello['xbsm']}", flush=True)
        assert hello["xbsm"].startswith(str(Path(path).resolve())), hello
        children[path] = proc
    record = {"machine": {"platform": platform.platform(), "python": platform.python_version(),
                          "cpus": os.cpu_count()},
              "load_start": os.getloadavg(), "repeats": args.repeats, "cells": {}}
    print(f"load average at start: {os.getloadavg()}", flush=True)
    for cell in args.cells:
        for method in METHODS:
            load = os.getloadavg()
            times = {path: [] for path in checkouts}
            cpus = {path: [] for path in checkouts}
            scenarios = {}
            for r in range(args.repeats):
                order = checkouts[r % len(checkouts):] + checkouts[:r % len(checkouts)]
                for path in order:
                    proc = children[path]
                    proc.stdin.write(json.dumps({"cell": cell, "method": method}) + "\n")
                    proc.stdin.flush()
                    answer = json.loads(proc.stdout.readline())
                    times[path].append(answer["seconds"])
                    cpus[path].append(answer["cpu"])
                    scenarios[path] = answer["scenarios"]
            row = {path: {"seconds": times[path], "cpu_seconds": cpus[path],
                          "scenarios": scenarios[path],
                          "us_per_scenario": 1e6 * statistics.median(times[path])
                          / scenarios[path],
                          "cpu_us_per_scenario": 1e6 * statistics.median(cpus[path])
                          / scenarios[path]} for path in checkouts}
            for key in ("us_per_scenario", "cpu_us_per_scenario"):
                base = row[checkouts[-1]][key]
                for path in checkouts:
                    row[path][key.replace("us_per_scenario", "ratio_to_last")] = (
                        row[path][key] / base)
            record["cells"][f"{cell}/{method}"] = {"load": load, **row}
            text = "  ".join(f"{Path(p).name}: {row[p]['us_per_scenario']:7.1f} us wall "
                             f"{row[p]['cpu_us_per_scenario']:7.1f} us cpu" for p in checkouts)
            print(f"{cell:13s} {method:8s} load {load[0]:4.2f}  {text}  ratio wall "
                  f"{row[checkouts[0]]['ratio_to_last']:.3f} cpu "
                  f"{row[checkouts[0]]['cpu_ratio_to_last']:.3f}", flush=True)
    record["load_end"] = os.getloadavg()
    print(f"load average at end: {record['load_end']}", flush=True)
    for proc in children.values():
        proc.stdin.close()
        proc.wait()
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    Path(args.out).write_text(json.dumps(record, indent=1) + "\n")
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
