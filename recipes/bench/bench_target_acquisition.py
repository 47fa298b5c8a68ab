"""Cost of P(task) (the TTP metric) and of NIIRS over one lazy sweep of 10^5 scenarios.

The MWIR camera of docs/infrared.md, swept over 100 ground ranges x 100 aperture
diameters x 10 targets (2.5 m, 0.5-5 K) = 10^5 scenarios, dask-chunked on
the aperture; ``xbsm.target_acquisition`` and ``xbsm.niirs`` (same targets) are built
lazily and computed in the same run, each timed as a whole (median of ``--repeats``).
Writes ``docs/benchmarks/bench_target_acquisition.json``.

    python recipes/bench/bench_target_acquisition.py [--repeats 1] [--scale 1.0]
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # recipes/: the shared helpers

import dask
import numpy as np
import xarray as xr
from _provenance import commit

import xbsm

ROOT = Path(__file__).resolve().parents[2]


def inputs(scale: float):
    """The lazy sweep: 100 x 100 x 10 scenarios at scale 1 (each axis times scale^(1/3))."""
    n = max(2, round(100 * scale ** (1 / 3)))
    m = max(2, round(10 * scale ** (1 / 3)))
    aperture = xr.DataArray(np.linspace(0.03, 0.1, n), dims="aperture_diameter")
    sensor = xbsm.sensor(
        aperture_diameter=aperture.chunk({"aperture_diameter": max(1, n // 10)}),
        focal_length=0.2, pixel_pitch_x=15e-6, wavelength_min=3e-6, wavelength_max=5e-6,
        quantum_efficiency=0.8, optics_transmission=0.8, integration_time=2e-3,
        read_noise=100.0, max_well=1.1e7, bit_depth=14.0, dark_current=1e4,
        cold_shield_temperature=77.0, cold_filter_temperature=77.0)
    scenario = xbsm.scenario(
        altitude=10.0, background_temperature=290.0,
        ground_range=xr.DataArray(np.linspace(300.0, 10000.0, n), dims="ground_range"),
        visibility=23.0)
    targets = xbsm.radiometry.target_set(2.5, thermal_contrast=np.linspace(0.5, 5.0, m))
    return sensor, scenario, targets, n * n * m


def timed(build, repeats: int) -> tuple[float, xr.Dataset]:
    times, out = [], None
    for _ in range(repeats):
        start = time.perf_counter()
        out = build().compute()
        times.append(time.perf_counter() - start)
    return statistics.median(times), out


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=1)
    parser.add_argument("--scale", type=float, default=1.0, help="fraction of 10^5")
    args = parser.parse_args()
    load_start = os.getloadavg()
    sensor, scenario, targets, count = inputs(args.scale)
    with dask.config.set(scheduler="threads", num_workers=1):
        lazy = xbsm.target_acquisition(sensor, scenario, targets)
        assert lazy.probability.chunks is not None  # nothing computed yet
        ttp_s, ttp = timed(lambda: xbsm.target_acquisition(sensor, scenario, targets)
                           [["probability", "flags"]], args.repeats)
        niirs_s, _ = timed(lambda: xbsm.niirs(sensor, scenario, targets=targets)
                           [["niirs", "flags"]], args.repeats)
    rows = {"target_acquisition": {"total_s": ttp_s, "per_scenario_s": ttp_s / count},
            "niirs": {"total_s": niirs_s, "per_scenario_s": niirs_s / count}}
    for name, row in rows.items():
        print(f"{name:20s} {count} scenarios in {row['total_s']:.1f} s = "
              f"{1e6 * row['per_scenario_s']:.0f} us/scenario")
    p = ttp.probability
    finite = p.notnull()
    within = bool(((p >= 0) & (p <= 1)).where(finite, True).all())
    nan_flagged = bool(xbsm.flags.is_invalid(ttp.flags).where(~finite, True).all())
    print(f"P(task) in [0, 1] wherever finite: {within}; NaN cells "
          f"{int((~finite).sum())}, each flagged invalid: {nan_flagged}")
    load_end = os.getloadavg()
    print(f"load average (1, 5, 15 min) at start {load_start}, at end {load_end}")
    record = {"scenarios": count, **rows, "probability_within_0_1": within,
              "nan_cells_all_flagged_invalid": nan_flagged, "scheduler": "dask threads, 1 worker",
              "machine": f"{platform.machine()} python {platform.python_version()}",
              "cpu_count": os.cpu_count(), "repeats": args.repeats,
              "date": time.strftime("%Y-%m-%d"), **commit(),
              "load_average_at_start": load_start, "load_average_at_end": load_end,
              "versions": {"xbsm": xbsm.__version__, "xarray": xr.__version__,
                           "numpy": np.__version__, "dask": dask.__version__}}
    name = "bench_target_acquisition.json" if args.scale == 1.0 else \
        f"bench_target_acquisition_scale{args.scale:g}.json"
    (ROOT / "docs" / "benchmarks" / name).write_text(json.dumps(record, indent=1))


if __name__ == "__main__":
    main()
