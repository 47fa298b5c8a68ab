"""Benchmark: image simulation, one 512 x 512 image at 20 ranges, xbsm against pyBSM 0.16.1.

The camera is the visible camera of ``recipes/fixtures/pybsm_reference_simulate.py``
(D = 0.2 m, f = 4 m, 10 um pixels, 0.45-0.70 um, 4 ms, 12 bits) at 3 km
altitude, 20 ground ranges from 2 to 22 km (database nodes), 23 km visibility,
turbulence on; the reference image is a fixed synthetic 512 x 512 scene
(gradient, slanted edge, bars, squares) at 4 mm GSD, so the simulated images
go from 227 x 227 to 37 x 37 pixels. Both sides take the same pyBSM keywords (xbsm through
``xbsm.pybsm_compat``) and add noise.

- pyBSM (its own environment, ``NUMBA_NUM_THREADS=1``, a child process through
  ``recipes/_pybsm_runner.py``): 20 calls of ``pybsm.simulation.simulate_image``,
  one per range, after one warm-up call (numba compilation); each call timed.
- xbsm (a child process of the project's Python, so that its peak memory is its
  own, ``resource.getrusage``): one ``xbsm.simulate_image`` call over the 20
  ranges, for each method of ``--methods``; the first call of the process (cold:
  imports, the atmosphere file) and one more (warm) are timed.

Each repeat runs pyBSM, then each xbsm method, so that both see about the same
machine load; the 1-minute load average is read before and after each step.
The time per image is pyBSM's 20-call total over 20, and xbsm's warm call over
20; the medians over the repeats, with their spread, and their ratio are
printed and written to ``docs/benchmarks/bench_simulate.json`` (or ``--out``)
with the machine and the commit; ``docs/benchmarks.md`` quotes them.

Run from the repository root with the project environment; pyBSM's own
environment is made on first use (see ``recipes/README.md``)::

    .venv/bin/python recipes/bench/bench_simulate.py [--repeats 3] [--methods accurate fast]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # recipes/: the shared helpers

from _provenance import commit, machine
from _pybsm_runner import CHILD_PRELUDE, run_child

ROOT = Path(__file__).resolve().parents[2]
OUT = ROOT / "docs" / "benchmarks" / "bench_simulate.json"
IMAGES = 20

# pyBSM Sensor / Scenario keywords (xbsm.pybsm_compat takes the same)
SENSOR = dict(name="visible", D=0.2, f=4.0, p_x=10e-6, eta=0.3, int_time=0.004,
              opt_trans_wavelengths=[0.45e-6, 0.70e-6], qe_wavelengths=[0.45e-6, 0.70e-6],
              qe=[0.7, 0.6], read_noise=20.0, max_n=60000.0, bit_depth=12.0,
              dark_current=200.0)
SCENARIO = dict(name="slant", ihaze=1, altitude=3000.0, ground_range=0.0)
# m: database nodes (pyBSM's simulate_image reads the atmosphere without interpolation)
GROUND_RANGES = [1000.0 * k for k in range(2, 21)] + [22000.0]
GSD, SIZE, SEED = 0.004, 512, 1

SCENE = r'''
import numpy as np

def scene(n):
    """The synthetic reference image: gradient, 5 degree slanted edge, bars, squares."""
    y, x = np.mgrid[0:n, 0:n].astype(float)
    img = 40.0 + 0.3 * x + 0.1 * y
    angle = np.deg2rad(5.0)
    img += 90.0 * ((x - 0.55 * n) * np.cos(angle) + (y - 0.5 * n) * np.sin(angle) > 0)
    img += 30.0 * (np.sin(2 * np.pi * x / 16.0) > 0) * (y < 0.2 * n)
    for k in range(6):
        a = int((0.1 + 0.13 * k) * n)
        img[int(0.7 * n):int(0.7 * n) + 4 + 3 * k, a:a + 4 + 3 * k] = 230.0
    return img
'''

PYBSM_CHILD = CHILD_PRELUDE + SCENE + r'''
import resource
from pybsm.simulation import RefImage, simulate_image

image = scene(job["size"])

def one(ground_range):
    s, sc = build(job["sensor"], dict(job["scenario"], ground_range=ground_range))
    t0 = time.perf_counter()
    _, blurred, noisy = simulate_image(ref_img=RefImage(img=image, gsd=job["gsd"]),
                                       sensor=s, scenario=sc, rng=job["seed"])
    return time.perf_counter() - t0, list(noisy.shape)

one(job["ground_ranges"][0])  # warm-up: numba compilation, file caches
times, shapes = zip(*(one(g) for g in job["ground_ranges"]))
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
json.dump({"times": times, "shapes": shapes, "peak_rss": peak}, sys.stdout)
'''

XBSM_CHILD = SCENE + r'''
import json, resource, sys, time
import xarray as xr
import xbsm
from xbsm import pybsm_compat

job = json.load(sys.stdin)

def rss():
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024  # Linux: kB

image = scene(job["size"])
ranges = xr.DataArray(job["ground_ranges"], dims="case_range")
sensor = pybsm_compat.sensor(**job["sensor"])
scenario = pybsm_compat.scenario(**dict(job["scenario"], ground_range=ranges))
baseline = rss()
times = []
for _ in range(2):  # cold (first call of the process), then warm
    t0 = time.perf_counter()
    result = xbsm.simulate_image(image, sensor, scenario, gsd=job["gsd"], seed=job["seed"],
                                 method=job["method"])
    result["counts"].values  # eager already; make sure nothing is left to compute
    times.append(time.perf_counter() - t0)
shapes = [[int(a), int(b)] for a, b in zip(result["size_y"].values, result["size_x"].values)]
json.dump({"cold": times[0], "warm": times[1], "baseline_rss": baseline, "peak_rss": rss(),
           "shapes": shapes}, sys.stdout)
'''


def load_average() -> float:
    return float(Path("/proc/loadavg").read_text().split()[0])


def run_xbsm(job: dict) -> dict:
    proc = subprocess.run([sys.executable, "-c", XBSM_CHILD], input=json.dumps(job),
                          capture_output=True, text=True, cwd=ROOT, env=dict(os.environ))
    if proc.returncode:
        sys.stderr.write(proc.stderr)
        proc.check_returncode()
    return json.loads(proc.stdout)


def spread(values: list[float]) -> dict:
    return {"median": statistics.median(values), "min": min(values), "max": max(values),
            "n": len(values)}


def summarise(pybsm: list[dict], xbsm: dict[str, list[dict]]) -> dict:
    """Per-image times (medians over the repeats and their spread), ratios, peak memory."""
    per_image = [sum(r["times"]) / IMAGES for r in pybsm]
    out = {"pybsm": {"per_image_s": spread(per_image),
                     "single_call_s": spread([t for r in pybsm for t in r["times"]]),
                     "peak_rss_mb": max(r["peak_rss"] for r in pybsm) / 2**20}}
    for method, runs in xbsm.items():
        warm = [r["warm"] / IMAGES for r in runs]
        out[f"xbsm_{method}"] = {
            "per_image_s": spread(warm), "cold_call_s": spread([r["cold"] for r in runs]),
            "warm_call_s": spread([r["warm"] for r in runs]),
            "ratio_per_image": statistics.median(per_image) / statistics.median(warm),
            "peak_rss_mb": max(r["peak_rss"] for r in runs) / 2**20,
            "baseline_rss_mb": statistics.median(r["baseline_rss"] for r in runs) / 2**20,
            # xbsm's accurate sampling floors the output size, pyBSM rounds it
            "largest_size_difference_from_pybsm_pixels": max(
                abs(a - b) for x, p in zip(runs[0]["shapes"], pybsm[0]["shapes"], strict=True)
                for a, b in zip(x, p, strict=True))}
    return out


def report(summary: dict) -> None:
    p = summary["pybsm"]["per_image_s"]
    print("\n| | time per image, median (min-max) | ratio | peak memory |\n|---|---|---|---|")
    print(f"| pyBSM 0.16.1, 20 calls | {p['median']:.2f} s ({p['min']:.2f}-{p['max']:.2f}) | 1 | "
          f"{summary['pybsm']['peak_rss_mb']:.0f} MB |")
    for key, row in summary.items():
        if key.startswith("xbsm_"):
            t = row["per_image_s"]
            print(f"| xbsm `{key[5:]}`, one call | {1e3 * t['median']:.0f} ms "
                  f"({1e3 * t['min']:.0f}-{1e3 * t['max']:.0f}) | "
                  f"{row['ratio_per_image']:.0f}x | {row['peak_rss_mb']:.0f} MB "
                  f"(baseline {row['baseline_rss_mb']:.0f} MB) |")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--methods", nargs="+", default=["accurate", "fast"],
                        choices=["accurate", "fast", "pybsm"])
    parser.add_argument("--out", type=Path, default=OUT)
    args = parser.parse_args()
    job = {"sensor": SENSOR, "scenario": SCENARIO, "ground_ranges": GROUND_RANGES,
           "gsd": GSD, "size": SIZE, "seed": SEED}
    load, pybsm, xbsm = [("start", load_average())], [], {m: [] for m in args.methods}
    for repeat in range(args.repeats):
        pybsm.append(run_child(PYBSM_CHILD, job))
        load.append((f"repeat {repeat} pybsm", load_average()))
        print(f"repeat {repeat}: pyBSM {sum(pybsm[-1]['times']):.1f} s", flush=True)
        for method in args.methods:
            xbsm[method].append(run_xbsm(dict(job, method=method)))
            load.append((f"repeat {repeat} xbsm {method}", load_average()))
            print(f"repeat {repeat}: xbsm {method} {xbsm[method][-1]['warm']:.2f} s "
                  f"(cold {xbsm[method][-1]['cold']:.2f} s)", flush=True)
    summary = summarise(pybsm, xbsm)
    report(summary)
    print(f"load average (1 min): {', '.join(f'{v:.2f}' for _, v in load)}")
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps({
        "machine": machine(), **commit(), "load_average_1min": load,
        "config": {**job, "images": IMAGES, "repeats": args.repeats, "methods": args.methods,
                   "numba_num_threads": 1},
        "summary": summary, "pybsm_runs": pybsm, "xbsm_runs": xbsm}, indent=1) + "\n")
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
