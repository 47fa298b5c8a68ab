"""Benchmark: a 10^6-scenario study computed and written to NetCDF, 1 and 2 workers.

Runs ``recipes/studies/million.toml`` (the Olson NIR camera over ground range x
altitude x focal length x visibility x drift) through ``xbsm.study``: build the
lazy result, then compute it chunk by chunk and write the NetCDF, each
configuration in a fresh child process so its peak memory is its own. Prints
and saves (``docs/benchmarks/bench_study.json``) for each: the time to build
the lazy result, the wall time to compute and write, scenarios per second,
and peak resident memory (the child's, plus its workers' for a LocalCluster).

It also measures the cost of one more chunk: the same 10^5 scenarios cut
into 2 and into 100 chunks; the difference in wall time over the difference
in chunk count. Dask's own scheduling is a few milliseconds of it; the rest
is the fixed cost of one model call and of one chunk file.

Run from the repository root with the project environment (see ``recipes/README.md``)::

    .venv/bin/python recipes/bench_study.py [--scenarios-scale 1.0] [--repeats 3]
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

from _provenance import commit, machine

ROOT = Path(__file__).resolve().parent.parent
STUDY = ROOT / "recipes" / "studies" / "million.toml"

CHILD = r"""
import json, resource, sys, time
t0 = time.perf_counter()
import xbsm.study as st
spec = st.parse(sys.argv[1], "bench")
t1 = time.perf_counter()
result = st.run(spec)
t2 = time.perf_counter()
st.write(result, sys.argv[2], overwrite=True, scheduler=sys.argv[3], workers=int(sys.argv[4]))
t3 = time.perf_counter()
self_rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1e3
child_rss = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1e3
print(json.dumps({"scenarios": spec.scenarios, "chunks": int(result.niirs.data.npartitions),
                  "import_s": t1 - t0, "build_s": t2 - t1, "write_s": t3 - t2,
                  "peak_rss_mb": self_rss, "peak_worker_rss_mb": child_rss}))
"""


def run_once(text: str, scheduler: str, workers: int) -> dict:
    """One configuration in a fresh child process."""
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "out.nc"
        proc = subprocess.run([sys.executable, "-c", CHILD, text, str(out), scheduler,
                               str(workers)], capture_output=True, text=True, check=True)
        row = json.loads(proc.stdout.strip().splitlines()[-1])
        row["file_mb"] = out.stat().st_size / 1e6
    return row


def median_of(rows: list[dict]) -> dict:
    """Median of every number over repeats, with the spread of the wall time."""
    out = {key: statistics.median(row[key] for row in rows) for key in rows[0]}
    out["write_s_min"] = min(row["write_s"] for row in rows)
    out["write_s_max"] = max(row["write_s"] for row in rows)
    out["us_per_scenario"] = 1e6 * out["write_s"] / out["scenarios"]
    out["scenarios_per_s"] = out["scenarios"] / out["write_s"]
    return out


def scaled(text: str, factor: float) -> str:
    """The study with its drift sweep shortened (factor < 1) for a quicker run."""
    num = max(1, round(50 * factor))
    return text.replace("num = 50 }", f"num = {num} }}")


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


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenarios-scale", type=float, default=1.0,
                        help="shrink the study (0.1 = 10^5 scenarios) for a quick look")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--out", type=Path, default=ROOT / "docs/benchmarks/bench_study.json")
    args = parser.parse_args()
    text = scaled(STUDY.read_text(), args.scenarios_scale)
    results = {"machine": machine(), "commit": commit(), "configurations": {}}
    for scheduler, workers in (("threads", 1), ("threads", 2), ("local-cluster", 2)):
        rows = [run_once(text, scheduler, workers) for _ in range(args.repeats)]
        row = median_of(rows)
        results["configurations"][f"{scheduler}-{workers}"] = row
        print(f"{scheduler:13s} {workers} worker(s): {row['scenarios']:.0f} scenarios in "
              f"{row['chunks']:.0f} chunks; build {row['build_s']:.2f} s; compute+write "
              f"{row['write_s']:.1f} s (min {row['write_s_min']:.1f}, max "
              f"{row['write_s_max']:.1f}) = {row['us_per_scenario']:.1f} us/scenario, "
              f"{row['scenarios_per_s']:.0f} scenarios/s; peak RSS {row['peak_rss_mb']:.0f} MB"
              f" (+ workers {row['peak_worker_rss_mb']:.0f} MB); file {row['file_mb']:.0f} MB",
              flush=True)
    overhead = chunk_overhead(STUDY.read_text(), args.repeats)
    results["chunk_overhead"] = overhead
    print(f"cost of one more chunk: {1e3 * overhead['seconds_per_extra_chunk']:.1f} ms"
          f" (10^5 scenarios in {overhead['few_chunks']['chunks']:.0f} and "
          f"{overhead['many_chunks']['chunks']:.0f} chunks)")
    args.out.write_text(json.dumps(results, indent=1))
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
