"""Benchmark: 10^6-scenario studies computed and written to NetCDF, 1 and 2 workers.

Runs ``recipes/studies/million.toml`` (the Olson NIR camera over ground range x
altitude x focal length x visibility x drift) and
``recipes/studies/optics_million.toml`` (500 focal lengths x altitude x ground
range x visibility: every focal length its own optics), or the ``--study`` files,
through ``xbsm.study``: build the lazy result, then compute it chunk by chunk and
write the NetCDF, with 1 thread, 2 threads and a 2-process ``dask.distributed``
LocalCluster, each configuration in a fresh child process so its peak memory is
its own. Prints and saves (``docs/benchmarks/bench_study.json``) for each: the
time to build the lazy result, the wall time to compute and write, scenarios per
second, peak resident memory and the load; per study, the parallel efficiency
T1 / (2 T2) of each 2-worker configuration.

Where the time goes: ``compute_s`` is the phase that computes and saves the
chunks, ``assemble_s`` the one that streams them into the NetCDF file (the rest of
``write_s`` is the fingerprint, the lock and a LocalCluster's start and stop);
with threads ``model_s`` is the time spent in the chunks' model calls, summed
over threads, so with 1 thread ``write_s - model_s`` is the study machinery's
own time (graph, chunk files, assembly, progress).

Peak memory is given two ways: ``getrusage`` in the child (its own peak, and the
largest of the processes it reaped, e.g. one cluster worker), and the peak of the
whole process tree's summed RSS (the child, the LocalCluster's nanny and worker
processes), which the parent samples every 50 ms with ``psutil`` (a peak shorter
than that can be missed). The load average (``os.getloadavg``) is read before and
after each run, and the CPU the rest of the machine used during it (``/proc/stat``
busy time minus the reaped child tree's own) is recorded in cores.

``--checkout PATH`` (repeatable) times another checkout's xbsm in the same run: its
child runs in ``PATH`` with ``PYTHONPATH=PATH``; the checkouts alternate
configuration by configuration (a before/after pair on one machine state).

It also measures the cost of one more chunk: the same 10^5 scenarios cut
into 2 and into 100 chunks; the difference in wall time over the difference
in chunk count. Dask's own scheduling is a few milliseconds of it; the rest
is the fixed cost of one model call and of one chunk file.

Run from the repository root with the project environment (see ``recipes/README.md``)::

    .venv/bin/python recipes/bench/bench_study.py [--scenarios-scale 1.0] [--repeats 3]
        [--study FILE ...] [--checkout PATH ...] [--no-chunk-overhead] [--out PATH]
"""

from __future__ import annotations

import argparse
import json
import os
import re
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # recipes/: the shared helpers

import psutil
from _provenance import commit, machine

ROOT = Path(__file__).resolve().parents[2]
STUDY = ROOT / "recipes" / "studies" / "million.toml"
STUDIES = (STUDY, ROOT / "recipes" / "studies" / "optics_million.toml")
#: the sweep --scenarios-scale shortens in each shipped study (else the longest one)
SCALED_AXIS = {"million.toml": "drift_rate_x", "optics_million.toml": "focal_length"}
CONFIGURATIONS = (("threads", 1), ("threads", 2), ("local-cluster", 2))

CHILD = r"""
import functools, json, resource, sys, threading, time
t0 = time.perf_counter()
import xbsm.study as st
import xbsm.study.build as build
import xbsm.study.store as store
spec = st.parse(sys.argv[1], "bench")
t1 = time.perf_counter()
result = st.run(spec)
t2 = time.perf_counter()
phases, lock = {"model_s": 0.0, "compute_s": 0.0, "assemble_s": 0.0}, threading.Lock()
def timed(key, function):  # time spent in a function, summed over threads
    @functools.wraps(function)
    def wrapper(*args, **kwargs):
        start = time.perf_counter()
        try:
            return function(*args, **kwargs)
        finally:
            with lock:
                phases[key] += time.perf_counter() - start
    return wrapper
build._outputs = timed("model_s", build._outputs)  # the model calls (threads only)
store._compute_missing = timed("compute_s", store._compute_missing)
store._assemble = timed("assemble_s", store._assemble)
st.write(result, sys.argv[2], overwrite=True, scheduler=sys.argv[3], workers=int(sys.argv[4]))
t3 = time.perf_counter()
if sys.argv[3] != "threads":
    phases["model_s"] = None  # computed in the workers' processes
self_rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1e3
child_rss = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1e3
print(json.dumps({"xbsm_file": st.__file__, "scenarios": spec.scenarios,
                  "chunks": int(result.niirs.data.npartitions),
                  "import_s": t1 - t0, "build_s": t2 - t1, "write_s": t3 - t2,
                  "peak_rss_mb": self_rss, "peak_worker_rss_mb": child_rss, **phases}))
"""


def busy_seconds() -> float:
    """CPU time the whole machine has spent busy (all cores), from /proc/stat."""
    fields = [int(x) for x in Path("/proc/stat").read_text().split("\n", 1)[0].split()[1:]]
    return (sum(fields[:8]) - fields[3] - fields[4]) / os.sysconf("SC_CLK_TCK")


def tree_rss(proc: psutil.Process) -> float:
    """Summed resident memory of a process and all its descendants. [MB]"""
    total = 0
    try:
        for p in [proc, *proc.children(recursive=True)]:
            try:
                total += p.memory_info().rss
            except psutil.Error:
                pass
    except psutil.Error:
        pass
    return total / 1e6


def run_once(text: str, scheduler: str, workers: int, checkout: Path = ROOT) -> dict:
    """One configuration in a fresh child process (xbsm from ``checkout``)."""
    env = {**os.environ, "PYTHONPATH": str(checkout)}
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "out.nc"
        load_before = [round(x, 2) for x in os.getloadavg()]
        busy0, t0 = busy_seconds(), time.perf_counter()
        cpu0 = resource.getrusage(resource.RUSAGE_CHILDREN)
        proc = subprocess.Popen([sys.executable, "-c", CHILD, text, str(out), scheduler,
                                 str(workers)], cwd=checkout, env=env, text=True,
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE)
        watched, peak = psutil.Process(proc.pid), 0.0
        while proc.poll() is None:
            peak = max(peak, tree_rss(watched))
            time.sleep(0.05)
        stdout, stderr = proc.communicate()
        if proc.returncode:
            raise SystemExit(f"study child failed ({scheduler}, {workers}):\n{stderr}")
        wall = time.perf_counter() - t0
        cpu1 = resource.getrusage(resource.RUSAGE_CHILDREN)
        own = (cpu1.ru_utime + cpu1.ru_stime) - (cpu0.ru_utime + cpu0.ru_stime)
        row = json.loads(stdout.strip().splitlines()[-1])
        if not Path(row.pop("xbsm_file")).resolve().is_relative_to(checkout.resolve()):
            raise SystemExit(f"the study child did not import {checkout}'s xbsm")
        row["file_mb"] = out.stat().st_size / 1e6
        row["peak_tree_rss_mb"] = peak
        row["load_before"] = load_before
        row["load_after"] = [round(x, 2) for x in os.getloadavg()]
        row["other_cpu_cores"] = max(0.0, (busy_seconds() - busy0 - own) / wall)
    return row


def median_of(rows: list[dict]) -> dict:
    """Median of every number over repeats, with the spread of the wall time."""
    out = {key: statistics.median(row[key] for row in rows) for key in rows[0]
           if isinstance(rows[0][key], (int, float))}
    out["peak_tree_rss_mb_max"] = max(row.get("peak_tree_rss_mb", 0.0) for row in rows)
    out["load_before"] = [row.get("load_before") for row in rows]
    out["load_after"] = [row.get("load_after") for row in rows]
    out["write_s_all"] = [row["write_s"] for row in rows]
    out["write_s_min"] = min(row["write_s"] for row in rows)
    out["write_s_max"] = max(row["write_s"] for row in rows)
    out["us_per_scenario"] = 1e6 * out["write_s"] / out["scenarios"]
    out["scenarios_per_s"] = out["scenarios"] / out["write_s"]
    return out


def scaled(text: str, factor: float, axis: str = "drift_rate_x") -> str:
    """The study with one sweep (``axis``, else the longest) shortened by ``factor``."""
    pattern = re.compile(r"^(?P<name>\w+) = \{(?P<body>[^}]*)num = (?P<num>\d+) \}", re.M)
    ranges = {m["name"]: m for m in pattern.finditer(text)}
    match = ranges.get(axis) or max(ranges.values(), key=lambda m: int(m["num"]))
    num = max(1, round(int(match["num"]) * factor))
    start, end = match.span("num")
    return text[:start] + str(num) + text[end:]


def chunk_overhead(text: str, repeats: int) -> dict:
    """Cost of one more chunk: 10^5 scenarios in 2 and in 100 chunks (threads, 2 workers)."""
    small = scaled(text, 0.1)
    rows = {}
    for chunk in (50_000, 1_000):
        study = small.replace("chunk_scenarios = 50000", f"chunk_scenarios = {chunk}")
        rows[chunk] = median_of([run_once(study, "threads", 2) for _ in range(repeats)])
    few, many = rows[50_000], rows[1_000]
    per_chunk = (many["write_s"] - few["write_s"]) / (many["chunks"] - few["chunks"])
    return {"few_chunks": few, "many_chunks": many, "seconds_per_extra_chunk": per_chunk}


def print_row(name, label, scheduler, workers, row):
    model = (f" of which the model {row['model_s']:.1f} s summed over threads"
             if "model_s" in row else "")
    print(f"{name} [{label}] {scheduler:13s} {workers} worker(s): {row['scenarios']:.0f} "
          f"scenarios in {row['chunks']:.0f} chunks; build {row['build_s']:.2f} s; "
          f"compute+write {row['write_s']:.1f} s (min {row['write_s_min']:.1f}, max "
          f"{row['write_s_max']:.1f}) = {row['us_per_scenario']:.1f} us/scenario "
          f"[computing {row['compute_s']:.1f} s{model}, then assembling {row['assemble_s']:.1f}"
          f" s], "
          f"{row['scenarios_per_s']:.0f} scenarios/s; peak RSS {row['peak_rss_mb']:.0f} MB"
          f" (+ largest reaped child {row['peak_worker_rss_mb']:.0f} MB; whole tree "
          f"{row['peak_tree_rss_mb_max']:.0f} MB); file {row['file_mb']:.0f} MB; load "
          f"{row['load_before']} -> {row['load_after']}, other CPU "
          f"{row['other_cpu_cores']:.2f} cores", flush=True)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenarios-scale", type=float, default=1.0,
                        help="shrink each study (0.1 = 10^5 scenarios) for a quick look")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--study", action="append", type=Path,
                        help="a study file (repeatable; default: the two 10^6 studies)")
    parser.add_argument("--checkout", action="append", type=Path,
                        help="a checkout whose xbsm to time (repeatable; default: this one)")
    parser.add_argument("--no-chunk-overhead", action="store_true",
                        help="skip the cost-of-one-more-chunk measurement")
    parser.add_argument("--out", type=Path, default=ROOT / "docs/benchmarks/bench_study.json")
    args = parser.parse_args()
    checkouts = [Path(p).resolve() for p in (args.checkout or [ROOT])]
    labels = [commit(c)["commit"] or str(c) for c in checkouts]
    labels = [f"{lab}@{c.name}" if labels.count(lab) > 1 else lab
              for lab, c in zip(labels, checkouts, strict=True)]
    studies = args.study or list(STUDIES)
    results = {"machine": machine(), "load_start": [round(x, 2) for x in os.getloadavg()],
               "checkouts": [{"path": str(c), "label": lab, **commit(c)}
                             for c, lab in zip(checkouts, labels, strict=True)],
               "studies": {}}
    if len(checkouts) == 1:
        results["commit"] = commit(checkouts[0])
    print(f"load average (1, 5, 15 min) at start: {results['load_start']}; "
          f"{os.cpu_count()} cores", flush=True)
    for study in studies:
        text = scaled(study.read_text(), args.scenarios_scale, SCALED_AXIS.get(study.name, ""))
        runs = {(lab, sch, w): [] for lab in labels for sch, w in CONFIGURATIONS}
        for _ in range(args.repeats):
            for scheduler, workers in CONFIGURATIONS:
                for checkout, label in zip(checkouts, labels, strict=True):
                    runs[label, scheduler, workers].append(
                        run_once(text, scheduler, workers, checkout))
        per_study = results["studies"][study.name] = {}
        for label in labels:
            configurations = {}
            for scheduler, workers in CONFIGURATIONS:
                row = median_of(runs[label, scheduler, workers])
                configurations[f"{scheduler}-{workers}"] = row
                print_row(study.name, label, scheduler, workers, row)
            t1 = configurations["threads-1"]["write_s"]
            efficiency = {name: t1 / (2 * row["write_s"]) for name, row in
                          configurations.items() if name != "threads-1"}
            print(f"{study.name} [{label}] parallel efficiency T1 / (2 T2): "
                  + ", ".join(f"{k} {v:.2f}" for k, v in efficiency.items()), flush=True)
            per_study[label] = {"configurations": configurations,
                                "parallel_efficiency": efficiency}
    if len(checkouts) == 1 and len(studies) == 1:  # the layout of earlier runs
        results["configurations"] = results["studies"][studies[0].name][labels[0]][
            "configurations"]
    if not args.no_chunk_overhead:
        overhead = chunk_overhead(STUDY.read_text(), args.repeats)
        results["chunk_overhead"] = overhead
        print(f"cost of one more chunk: {1e3 * overhead['seconds_per_extra_chunk']:.1f} ms"
              f" (10^5 scenarios in {overhead['few_chunks']['chunks']:.0f} and "
              f"{overhead['many_chunks']['chunks']:.0f} chunks)")
    results["load_end"] = [round(x, 2) for x in os.getloadavg()]
    print(f"load average at end: {results['load_end']}")
    args.out.write_text(json.dumps(results, indent=1))
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
