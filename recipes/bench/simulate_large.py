"""Benchmark: large reference images through ``xbsm.simulate_image``, peak memory and time.

Three measurements, each call in a child process of its own so that its peak
resident memory (``resource.getrusage(RUSAGE_SELF).ru_maxrss``, which includes the
Python interpreter, the imports and the input image: recorded before the call as
``baseline_rss``) is that call's alone:

1. a 12-megapixel image (3000 x 4000, ``uint8``) eagerly and through the lazy
   path (a dask-backed stack of one image, ``.compute()``);
2. a 12,000 x 12,000 image (``uint8``), with every output and with
   ``outputs=("counts",), counts_dtype="uint16"`` (what a dataset keeps);
3. per-image time at 256 x 256 and 512 x 512 (the median of ``--repeats`` warm
   calls, one image, one range), which the tiles do not touch (images up to
   ``tile_size`` = 2048 pixels take the untiled path).

The camera is the visible camera of ``tests/simulate/test_simulate.py`` (D = 0.2 m,
f = 4 m, 10 um pixels) at 3 km altitude, 4 km ground range, 23 km visibility, the
reference at 4 mm GSD (about 3.3 reference pixels per camera pixel); the image is
a synthetic scene (gradient, slanted edge, bars, squares) with noise, seed 0.

``--before PATH`` runs the same children on another checkout (e.g. the commit
before the tiles, ``git worktree add ../xbsm-before cf2fa1d``) and records both;
``--interleaved ROUNDS`` times only the 256 and 512 pixel images, alternating the
two checkouts, and adds the medians to the JSON (a fair before/after on a shared
machine). ``--after PATH`` measures a frozen copy of this checkout's HEAD instead of the
work tree; ``--skip-before-12k`` leaves out the untiled 12,000 x 12,000 run (about 7 GB).
The 1-minute load average is read before and after each child. Writes
``docs/benchmarks/simulate_large.json`` (or ``--out``); ``docs/simulate.md`` quotes it.

Run from the repository root::

    .venv/bin/python recipes/bench/simulate_large.py [--before ../xbsm-before] [--repeats 5]
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

ROOT = Path(__file__).resolve().parents[2]
OUT = ROOT / "docs" / "benchmarks" / "simulate_large.json"

CHILD = r'''
import json, resource, statistics, sys, time
import numpy as np
import xarray as xr
import xbsm

rows, cols, mode, repeats = int(sys.argv[1]), int(sys.argv[2]), sys.argv[3], int(sys.argv[4])
# the scene, built in strips of rows so that making it costs no more than the image
img = np.empty((rows, cols), np.uint8)
rng = np.random.default_rng(0)
x = np.arange(cols, dtype=np.float32)
step = max(1, (1 << 22) // cols)
for start in range(0, rows, step):
    y = np.arange(start, min(rows, start + step), dtype=np.float32)[:, None]
    part = 40.0 + 0.3 * x * (512 / cols) + 0.1 * y * (512 / rows)
    edge = (x - 0.55 * cols) * np.cos(0.087) + (y - 0.5 * rows) * np.sin(0.087)
    part = part + 90.0 * (edge > 0)
    part = part + 30.0 * (np.sin(2 * np.pi * x / 16.0) > 0) * (y < 0.2 * rows)
    part = part + rng.normal(0.0, 4.0, part.shape).astype(np.float32)
    img[start: start + step] = np.clip(part, 0, 255).astype(np.uint8)
del part
sensor = xbsm.sensor(aperture_diameter=0.2, focal_length=4.0, pixel_pitch_x=10e-6,
                     wavelength_min=0.45e-6, wavelength_max=0.7e-6, integration_time=0.004,
                     read_noise=20.0, max_well=60000.0, bit_depth=12.0)
scenario = xbsm.scenario(altitude=3000.0, ground_range=4000.0, visibility=23.0)
kwargs = dict(gsd=0.004, seed=0)
if mode == "counts":
    kwargs.update(outputs=("counts",), counts_dtype="uint16")
image = xr.DataArray(img, dims=("y", "x"), name="scene")
if mode == "lazy":
    image = image.expand_dims(image=1).chunk({"image": 1})
baseline = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024  # imports + the scene
times = []
for _ in range(repeats):
    start = time.perf_counter()
    out = xbsm.simulate_image(image, sensor, scenario, **kwargs)
    counts = out["counts"].values  # computes the lazy path
    times.append(time.perf_counter() - start)
    del out
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024
print(json.dumps({"rows": rows, "cols": cols, "mode": mode, "seconds": times,
                  "median_seconds": statistics.median(times[1:] or times),
                  "peak_rss_bytes": peak, "baseline_rss_bytes": baseline,
                  "counts_shape": list(counts.shape), "counts_sum": float(np.nansum(counts))}))
'''


def load():
    return round(os.getloadavg()[0], 2)


def run(checkout: Path, rows: int, cols: int, mode: str, repeats: int) -> dict:
    env = dict(os.environ, PYTHONPATH=str(checkout), OMP_NUM_THREADS="1")
    before = load()
    proc = subprocess.run([sys.executable, "-c", CHILD, str(rows), str(cols), mode,
                           str(repeats)], capture_output=True, text=True, env=env, cwd=checkout)
    if proc.returncode:
        return {"rows": rows, "cols": cols, "mode": mode, "error":
                (proc.stderr.strip().splitlines() or ["?"])[-1], "load_1min": [before, load()]}
    out = json.loads(proc.stdout.strip().splitlines()[-1])
    out["peak_rss_gib"] = round(out["peak_rss_bytes"] / 2**30, 3)
    out["baseline_rss_gib"] = round(out["baseline_rss_bytes"] / 2**30, 3)
    out["load_1min"] = [before, load()]
    print(f"{checkout.name:>16} {rows:>6} x {cols:<6} {mode:>6}: "
          f"{out['median_seconds']:8.3f} s  peak RSS {out['peak_rss_gib']:.2f} GiB "
          f"(before the call {out['baseline_rss_gib']:.2f})  "
          f"load {out['load_1min']}", flush=True)
    return out


def interleaved(args) -> None:
    """Per-image time at 256 and 512 pixels, before and after in alternation."""
    sides = {"after": args.after, "before": args.before}
    times = {side: {str(n): [] for n in (256, 512)} for side in sides}
    for _ in range(args.interleaved):
        for n in (256, 512):
            for side, checkout in sides.items():
                times[side][str(n)].append(run(checkout, n, n, "eager", args.repeats)
                                           ["median_seconds"])
    result = json.loads(args.out.read_text()) if args.out.exists() else {}
    result["throughput_interleaved"] = {
        "rounds": args.interleaved, "repeats_per_child": args.repeats, "median_seconds": {
            side: {n: statistics.median(v) for n, v in by.items()} for side, by in times.items()},
        "every_child_median_seconds": times}
    args.out.write_text(json.dumps(result, indent=1) + "\n")
    for n in ("256", "512"):
        after, before = (statistics.median(times[s][n]) for s in ("after", "before"))
        print(f"{n} px: after {after:.3f} s, before {before:.3f} s, ratio {after / before:.3f}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--before", type=Path, help="a checkout to compare with")
    parser.add_argument("--after", type=Path, default=ROOT,
                        help="the checkout measured (default this one; a frozen copy of its "
                        "HEAD, `git archive HEAD xbsm`, keeps edits out of a long run)")
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--skip-before-12k", action="store_true")
    parser.add_argument("--out", type=Path, default=OUT)
    parser.add_argument("--interleaved", type=int, default=0, metavar="ROUNDS",
                        help="only the 256 and 512 pixel timings, alternating the two "
                        "checkouts ROUNDS times (the same load for both), added to --out")
    args = parser.parse_args()
    if args.interleaved:
        interleaved(args)
        return
    sides = {"after": args.after, **({"before": args.before} if args.before else {})}
    result = {"machine": machine(), "commit": commit(), "runs": {}}
    if args.before:
        result["before_commit"] = commit(args.before)
    for side, checkout in sides.items():
        runs = [run(checkout, 3000, 4000, "eager", 1), run(checkout, 3000, 4000, "lazy", 1)]
        if not (side == "before" and args.skip_before_12k):
            runs.append(run(checkout, 12000, 12000, "eager", 1))
        runs.append(run(checkout, 12000, 12000, "counts", 1))
        for n in (256, 512):
            runs.append(run(checkout, n, n, "eager", args.repeats))
        result["runs"][side] = runs
    args.out.write_text(json.dumps(result, indent=1) + "\n")
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
