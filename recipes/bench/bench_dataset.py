"""Benchmark: an image dataset over a sweep (`xbsm simulate`) against pyBSM's simulate_image.

The camera is the visible camera of ``recipes/bench/bench_simulate.py`` (D = 0.2 m,
f = 4 m, 10 um pixels, 0.45-0.70 um, 4 ms, 12 bits, pyBSM keywords through
``xbsm.pybsm_compat``'s names) at 3 km altitude and 5 ground ranges (2, 4, 6, 8 and
10 km, database nodes), 23 km visibility (pyBSM ``ihaze=1``). The images are the
synthetic scene of ``bench_simulate.py`` (gradient, slanted edge, bars, squares),
each shifted and scaled by its index so that no two are equal, at 4 mm GSD, as
8-bit PNG files; the same pixel values are given to pyBSM.

- xbsm: the image-dataset study (``xbsm.study.simulate``: the folder in, 16-bit PNG
  counts and a COCO file per range out, the default 8 images per chunk) in a child
  process of the project's Python, for each image size, with ``--images`` images
  (and ``--images / 10`` to show that memory does not grow with the dataset), on
  each of ``--workers`` threads; wall time and the child's peak RSS
  (``resource.getrusage``).
- pyBSM 0.16.1 (its own environment, ``NUMBA_NUM_THREADS=1``, through
  ``recipes/_pybsm_runner.py``): ``pybsm.simulation.simulate_image`` on
  ``--pybsm-images`` of the same images at the 5 ranges (one call per image and
  range, each timed, after a warm-up call); pyBSM takes seconds per call, so it
  runs on a subset of the images (different ones each round).

The machine is shared, so the two are measured interleaved: ``--rounds`` rounds per
size, each an xbsm run at both dataset sizes then a pyBSM run, with the 1-minute
load printed after each. Per output image (one image at one range): pyBSM's median
call time over every round, xbsm's median over the rounds of its wall time per
output, and their ratio (also per round, from that round's pyBSM median), to
``docs/benchmarks/bench_dataset.json`` (with the machine, its load and the
commit); ``docs/datasets.md`` quotes them.
Run from the repository root with an environment that has the ``datasets`` extra::

    PYBSM_PYTHON=.../pybsm-venv/bin/python python recipes/bench/bench_dataset.py \\
        [--sizes 256 512] [--images 100] [--pybsm-images 2] [--rounds 3] [--workers 1]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # recipes/: the shared helpers

from _provenance import commit, machine
from _pybsm_runner import CHILD_PRELUDE, run_child

ROOT = Path(__file__).resolve().parents[2]
OUT = ROOT / "docs" / "benchmarks" / "bench_dataset.json"

SENSOR = dict(name="visible", D=0.2, f=4.0, p_x=10e-6, eta=0.3, int_time=0.004,
              opt_trans_wavelengths=[0.45e-6, 0.70e-6], qe_wavelengths=[0.45e-6, 0.70e-6],
              qe=[0.7, 0.6], read_noise=20.0, max_n=60000.0, bit_depth=12.0,
              dark_current=200.0)
SCENARIO = dict(name="slant", ihaze=1, altitude=3000.0, ground_range=0.0)
GROUND_RANGES = [2000.0, 4000.0, 6000.0, 8000.0, 10000.0]
GSD = 0.004

SCENE = r'''
import numpy as np

def scene(n, k):
    """Image k of the dataset: bench_simulate's scene, shifted and scaled by k, 8 bits."""
    y, x = np.mgrid[0:n, 0:n].astype(float)
    img = 40.0 + 0.3 * x * 512 / n + 0.1 * y * 512 / n
    angle = np.deg2rad(5.0 + k % 7)
    img += 90.0 * ((x - 0.55 * n) * np.cos(angle) + (y - 0.5 * n) * np.sin(angle) > 0)
    img += 30.0 * (np.sin(2 * np.pi * x / 16.0) > 0) * (y < 0.2 * n)
    for j in range(6):
        a = int((0.1 + 0.13 * j) * n)
        img[int(0.7 * n):int(0.7 * n) + 4 + 3 * j, a:a + 4 + 3 * j] = 230.0
    img = np.roll(img, (3 * k) % n, axis=1) * (0.8 + 0.2 * ((k * 37) % 11) / 10)
    return np.clip(img, 0, 255).astype(np.uint8)
'''

PYBSM_CHILD = CHILD_PRELUDE + SCENE + r'''
import resource
from pybsm.simulation import RefImage, simulate_image

def one(image, ground_range):
    s, sc = build(job["sensor"], dict(job["scenario"], ground_range=ground_range))
    t0 = time.perf_counter()
    simulate_image(ref_img=RefImage(img=image.astype(float), gsd=job["gsd"]), sensor=s,
                   scenario=sc, rng=1)
    return time.perf_counter() - t0

one(scene(job["size"], 0), job["ground_ranges"][0])  # warm-up: numba, file caches
times = [one(scene(job["size"], k), g) for k in job["indices"] for g in job["ground_ranges"]]
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
json.dump({"times": times, "peak_rss": peak}, sys.stdout)
'''

XBSM_CHILD = SCENE + r'''
import json, resource, sys, time
from pathlib import Path

job = json.load(sys.stdin)
from PIL import Image

folder = Path(job["folder"])
images = folder / "images"
images.mkdir(parents=True, exist_ok=True)
for k in range(job["images"]):
    Image.fromarray(scene(job["size"], k)).save(images / f"{k:05d}.png")
from xbsm import study
from xbsm.atmosphere import load_database

load_database()
(folder / "study.toml").write_text(job["study"])
spec = study.load(folder / "study.toml")
baseline = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
t0 = time.perf_counter()
study.simulate(spec, folder / "out", workers=job["workers"], progress=False)
wall = time.perf_counter() - t0
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
written = sum(1 for _ in (folder / "out").rglob("*.png"))
json.dump({"wall": wall, "baseline_rss": baseline, "peak_rss": peak, "written": written},
          sys.stdout)
'''


def study_text(names: dict) -> str:
    """The study file: pyBSM's camera in xbsm's names, the 5 ranges, the image folder."""
    sensor = {names[k]: v for k, v in SENSOR.items()
              if k not in ("name", "opt_trans_wavelengths", "qe", "qe_wavelengths")}
    lines = ["title = \"dataset benchmark\"", "[sensor]",
             "wavelength_min = 0.45e-6", "wavelength_max = 0.70e-6",
             "quantum_efficiency = { wavelength = [0.45e-6, 0.70e-6], values = [0.7, 0.6] }"]
    lines += [f"{k} = {v!r}" for k, v in sensor.items()]
    lines += ["[scenario]", "altitude = 3000.0", "visibility = 23.0", "[sweep]",
              f"ground_range = {GROUND_RANGES!r}", "[dataset]", "input = \"images\"",
              f"gsd = {GSD}", "output = \"out\""]
    return "\n".join(lines) + "\n"


def load_average() -> float:
    return float(Path("/proc/loadavg").read_text().split()[0])


def run_xbsm(job: dict) -> dict:
    proc = subprocess.run([sys.executable, "-c", XBSM_CHILD], input=json.dumps(job),
                          capture_output=True, text=True, cwd=ROOT, env=dict(os.environ))
    if proc.returncode:
        sys.stderr.write(proc.stderr)
        proc.check_returncode()
    return json.loads(proc.stdout)


def _xbsm_runs(size, images, workers, text, load) -> list:
    runs = []
    for n in (max(1, images // 10), images):
        for threads in workers:
            with tempfile.TemporaryDirectory() as folder:
                run = run_xbsm({"folder": folder, "images": n, "size": size, "study": text,
                                "workers": threads})
            outputs = n * len(GROUND_RANGES)
            assert run["written"] == outputs, run
            run.update(images=n, workers=threads, outputs=outputs,
                       per_output_s=run["wall"] / outputs, images_per_s=outputs / run["wall"])
            runs.append(run)
            load.append((f"xbsm {size} {n} images {threads} threads", load_average()))
            print(f"{size}: xbsm {n} images x 5 ranges, {threads} thread(s): "
                  f"{run['wall']:.1f} s, {run['images_per_s']:.1f} images/s, peak "
                  f"{run['peak_rss'] / 2**20:.0f} MB (load {load[-1][1]:.2f})", flush=True)
    return runs


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[256, 512])
    parser.add_argument("--images", type=int, default=100)
    parser.add_argument("--pybsm-images", type=int, default=2)
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--workers", type=int, nargs="+", default=[1])
    parser.add_argument("--out", type=Path, default=OUT)
    args = parser.parse_args()
    from xbsm.pybsm_compat import SENSOR_NAMES

    text = study_text(dict(SENSOR_NAMES))
    load, results = [("start", load_average())], {}
    print(f"load average (1 min) at the start: {load[0][1]:.2f}", flush=True)
    for size in args.sizes:
        rounds = []
        for r in range(args.rounds):
            runs = _xbsm_runs(size, args.images, args.workers, text, load)
            indices = list(range(r * args.pybsm_images, (r + 1) * args.pybsm_images))
            pybsm = run_child(PYBSM_CHILD, {"sensor": SENSOR, "scenario": SCENARIO,
                                            "ground_ranges": GROUND_RANGES, "gsd": GSD,
                                            "size": size, "indices": indices})
            load.append((f"pybsm {size} round {r}", load_average()))
            median = statistics.median(pybsm["times"])
            print(f"{size}: pyBSM round {r}: {len(pybsm['times'])} calls, median "
                  f"{median:.2f} s, peak {pybsm['peak_rss'] / 2**20:.0f} MB "
                  f"(load {load[-1][1]:.2f})", flush=True)
            for run in runs:
                run["round"], run["ratio_to_round_pybsm"] = r, median / run["per_output_s"]
            rounds.append({"xbsm": runs, "pybsm": pybsm, "pybsm_median_s": median})
        times = [t for rnd in rounds for t in rnd["pybsm"]["times"]]
        pybsm_s = statistics.median(times)
        summary = []
        for n in (max(1, args.images // 10), args.images):
            for threads in args.workers:
                same = [run for rnd in rounds for run in rnd["xbsm"]
                        if run["images"] == n and run["workers"] == threads]
                per = statistics.median(run["per_output_s"] for run in same)
                summary.append({
                    "images": n, "workers": threads, "per_output_s": per,
                    "images_per_s": 1 / per, "ratio_to_pybsm": pybsm_s / per,
                    "ratios_per_round": [run["ratio_to_round_pybsm"] for run in same],
                    "peak_rss": max(run["peak_rss"] for run in same),
                    "baseline_rss": max(run["baseline_rss"] for run in same)})
        results[str(size)] = {"rounds": rounds, "xbsm": summary, "pybsm": {
            "calls": len(times), "per_output_s": pybsm_s,
            "peak_rss": max(rnd["pybsm"]["peak_rss"] for rnd in rounds)}}
    print("\n| size | images x ranges | threads | xbsm images/s | x pyBSM (per round) | "
          "peak RSS |")
    print("|---|---|---|---|---|---|")
    for size, row in results.items():
        for run in row["xbsm"]:
            rounds = ", ".join(f"{x:.0f}" for x in run["ratios_per_round"])
            print(f"| {size} | {run['images']} x 5 | {run['workers']} | "
                  f"{run['images_per_s']:.1f} | {run['ratio_to_pybsm']:.0f} ({rounds}) | "
                  f"{run['peak_rss'] / 2**20:.0f} MB |")
        p = row["pybsm"]
        print(f"| {size} | pyBSM {p['calls']} calls | 1 | {1 / p['per_output_s']:.3f} | 1 "
              f"| {p['peak_rss'] / 2**20:.0f} MB |")
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps({
        "machine": machine(), **commit(), "load_average_1min": load,
        "config": {"sensor": SENSOR, "scenario": SCENARIO, "ground_ranges": GROUND_RANGES,
                   "gsd": GSD, "sizes": args.sizes, "images": args.images,
                   "pybsm_images_per_round": args.pybsm_images, "rounds": args.rounds,
                   "numba_num_threads": 1, "study": text},
        "results": results}, indent=1) + "\n")
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
