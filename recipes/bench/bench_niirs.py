"""Benchmark: xbsm.niirs against pyBSM 0.16.1 niirs + niirs5, side by side in one run.

The paper's Olson camera (Table 2) at 9 km, both bands, both visibilities and
every database ground range (2 x 2 x 97 = 388 scenarios). pyBSM
(NUMBA_NUM_THREADS=1, its own environment via ``recipes/_pybsm_runner.py``)
runs each scenario once with ``niirs`` and ``niirs5`` (GIQE 3/4 and 5). xbsm
runs the same scenarios with a 25-value focal-length sweep on top (9,700
scenarios, GIQE 3, 4 and 5 at once) per method; medians of repeated runs.
The per-scenario ratio is pyBSM's median time per scenario over xbsm's time
per scenario. Then the sweep (both bands, one ``xbsm.niirs`` call each) runs
once more per method under cProfile, its time grouped by xbsm stage/module
(``atmosphere``, ``radiometry``, ``noise``, ``quadrature``, ``otf.*``,
``metrics.*``, ``model``, ``params``, ``geometry``, ``_kernels``,
``_metadata``, ``flags``) with "xarray overhead" split out, by the rule of
``recipes/bench/_profile.py`` (shared with ``bench_single.py``); the microseconds
per scenario of each stage are its share times the unprofiled median. Writes
``docs/benchmarks/bench_niirs.json`` and ``docs/figures/bench_niirs.png``;
``docs/benchmarks.md`` quotes them.

Run from the repository root with the project environment; pyBSM's own
environment is made on first use (see ``recipes/README.md``)::

    .venv/bin/python recipes/bench/bench_niirs.py [--repeats 3]
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

import numpy as np
import xarray as xr
from _profile import print_by_module, profile_call, stack_shares
from _provenance import commit
from _pybsm_runner import run_pybsm

import xbsm
from xbsm.examples import DATABASE_GROUND_RANGES, OLSON_BANDS, olson_scenario, olson_sensor

ROOT = Path(__file__).resolve().parents[2]
DOCS = ROOT / "docs"
FOCAL_LENGTHS = np.linspace(2.0, 6.0, 25)
METHODS = ("pybsm", "fast", "accurate")


def pybsm_cases():
    """Every (band, visibility, ground range) of the Olson example, as pyBSM keywords."""
    cases = []
    for band, (lo, hi, qe) in OLSON_BANDS.items():
        for ihaze in (1, 2):
            for gr in DATABASE_GROUND_RANGES:
                cases.append({
                    "band": band,
                    "sensor": {
                        "name": "olson", "D": 0.275, "f": 4.0, "p_x": 8e-6, "eta": 0.4,
                        "int_time": 0.03, "read_noise": 25.0, "max_n": 96000.0,
                        "bit_depth": 11.9, "max_well_fill": 0.6, "s_x": 5e-7, "s_y": 5e-7,
                        "da_x": 1e-4, "da_y": 1e-4,
                        "dark_current": float(xbsm.radiometry.dark_current_from_density(
                            1e-5, 8e-6, 8e-6, xbsm.constants.PYBSM_CODATA_2014)),
                        "opt_trans_wavelengths": [lo, hi], "qe": [qe, qe],
                        "qe_wavelengths": [lo, hi], "post": {"optics_transmission": [0.5, 0.5]},
                    },
                    "scenario": {"name": "s", "ihaze": ihaze, "altitude": 9000.0,
                                 "ground_range": float(gr), "aircraft_speed": 100.0},
                })
    return cases


def time_xbsm(method, repeats):
    """Median wall time of xbsm.niirs over both bands with the focal-length sweep."""
    f = xr.DataArray(FOCAL_LENGTHS, dims="focal_length")
    sensors = [olson_sensor(band, focal_length=f) for band in OLSON_BANDS]
    scenario = olson_scenario()
    for s in sensors:  # warm-up (database read, imports)
        xbsm.niirs(s, scenario, method=method)
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        for s in sensors:
            xbsm.niirs(s, scenario, method=method)["niirs"].values  # noqa: B018
        times.append(time.perf_counter() - t0)
    n = len(sensors) * FOCAL_LENGTHS.size * DATABASE_GROUND_RANGES.size * 2
    return statistics.median(times), n


def profile_sweep(method, per_scenario_s):
    """The timed sweep once under cProfile, grouped by xbsm module (recipes/bench/_profile.py)."""
    f = xr.DataArray(FOCAL_LENGTHS, dims="focal_length")
    sensors = [olson_sensor(band, focal_length=f) for band in OLSON_BANDS]
    scenario = olson_scenario()

    def sweep():
        for s in sensors:
            xbsm.niirs(s, scenario, method=method)["niirs"].values  # noqa: B018

    sweep()  # warm
    result = profile_call(sweep)
    for row in result["by_module"].values():
        row["us_per_scenario"] = 1e6 * per_scenario_s * row["share"]
    result["xarray_overhead_us_per_scenario"] = (
        1e6 * per_scenario_s * result["xarray_overhead_share"])
    result["unprofiled_per_scenario_us"] = 1e6 * per_scenario_s
    result["stack_check"] = stack_shares(sweep)
    return result


def print_profile(profiles):
    def cell(profile, row):
        k = profile["unprofiled_per_scenario_us"] / profile["profiled_total_ms"]
        return f"{k * row['own_ms']:6.1f} / {k * row['xarray_ms']:6.1f} ({row['share']:4.0%})"

    methods, modules = print_by_module(
        profiles, "\nprofile of the Olson sweep (both bands, 9,700 scenarios; cProfile), per "
        "stage: us per scenario (own code + numpy / xarray below it), share", cell, width=28,
        label="stage")
    for label, fmt in (("xarray overhead", lambda p: f"{p['xarray_overhead_us_per_scenario']:.1f} "
                        f"us ({p['xarray_overhead_share']:.0%})"),
                       ("unprofiled", lambda p: f"{p['unprofiled_per_scenario_us']:.1f} us"),
                       ("profiled total", lambda p: f"{p['profiled_total_ms']:.0f} ms"),
                       ("function calls", lambda p: f"{p['function_calls']}")):
        print(f"{label:22s}" + "".join(f"{fmt(profiles[m]):>28s}" for m in methods))
    print("check: shares from the exact call stack (sys.setprofile)")
    for module in modules:
        print(f"{module:22s}" + "".join(
            f"{profiles[m]['stack_check']['by_module_share'].get(module, 0.0):28.0%}"
            for m in methods))
    print(f"{'xarray overhead':22s}" + "".join(
        f"{profiles[m]['stack_check']['xarray_overhead_share']:28.0%}" for m in methods))


def agreement(cases, values):
    """Largest |NIIRS difference| between xbsm method="pybsm" and pyBSM on every case."""
    worst = 0.0
    results = {}
    for case, (g3, g4, g5) in zip(cases, values, strict=True):
        band = case["band"]
        if band not in results:
            s = xbsm.pybsm_compat.sensor(
                **{k: v for k, v in case["sensor"].items() if k != "post"},
                **case["sensor"]["post"])
            sc = xbsm.pybsm_compat.scenario(
                ihaze=xr.DataArray([1, 2], dims="visibility"), altitude=9000.0,
                ground_range=xr.DataArray(DATABASE_GROUND_RANGES, dims="ground_range"),
                aircraft_speed=100.0)
            results[band] = xbsm.niirs(s, sc, method="pybsm")
        sc = case["scenario"]
        point = results[band].niirs.sel(
            ground_range=sc["ground_range"], visibility=23.0 if sc["ihaze"] == 1 else 5.0)
        for ours, theirs in zip(point.values, (g3, g4, g5), strict=True):
            if np.isfinite(theirs):
                worst = max(worst, abs(float(ours) - theirs))
    return worst


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3, help="xbsm repeats (median)")
    args = parser.parse_args()

    load_start = os.getloadavg()
    cases = pybsm_cases()
    pybsm = run_pybsm("niirs", cases)
    pybsm_per = statistics.median(pybsm["times"])
    print(f"pyBSM 0.16.1: {len(cases)} scenarios, median {1e3 * pybsm_per:.1f} ms per scenario "
          "(niirs + niirs5, NUMBA_NUM_THREADS=1)")

    rows = {}
    for method in METHODS:
        total, n = time_xbsm(method, args.repeats)
        per = total / n
        rows[method] = {"total_s": total, "scenarios": n, "per_scenario_s": per,
                        "speedup": pybsm_per / per}
        print(f"xbsm method={method:9s} {n} scenarios in {total:.2f} s = "
              f"{1e6 * per:.0f} us/scenario: {pybsm_per / per:.0f}x pyBSM per scenario")
    worst = agreement(cases, pybsm["values"])
    print(f"largest |NIIRS difference| between xbsm method='pybsm' and pyBSM over the "
          f"{len(cases)} scenarios (GIQE 3, 4, 5): {worst:.1e}")

    profiles = {m: profile_sweep(m, rows[m]["per_scenario_s"]) for m in METHODS}
    print_profile(profiles)
    load_end = os.getloadavg()
    print(f"load average (1, 5, 15 min) at start {load_start}, at end {load_end}")

    record = {
        "pybsm_scenarios": len(cases), "pybsm_per_scenario_s": pybsm_per, "xbsm": rows,
        "max_abs_niirs_difference": worst,
        "machine": f"{platform.machine()} python {platform.python_version()}",
        "cpu_count": os.cpu_count(), "repeats": args.repeats,
        "date": time.strftime("%Y-%m-%d"), **commit(),
        "load_average_at_start": load_start, "load_average_at_end": load_end,
        "versions": {"xbsm": xbsm.__version__, "xarray": xr.__version__,
                     "numpy": np.__version__},
        "profile": profiles,
    }
    (DOCS / "benchmarks").mkdir(parents=True, exist_ok=True)
    (DOCS / "benchmarks" / "bench_niirs.json").write_text(json.dumps(record, indent=1))
    plot(record)


def plot(record):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    labels = ["pyBSM 0.16.1"] + [f'xbsm\nmethod="{m}"' for m in METHODS]
    values = [record["pybsm_per_scenario_s"] * 1e6] + [
        record["xbsm"][m]["per_scenario_s"] * 1e6 for m in METHODS]
    fig, ax = plt.subplots(figsize=(7, 3.8))
    bars = ax.bar(labels, values, color=["0.6", "tab:blue", "tab:orange", "tab:green"])
    ax.set_yscale("log")
    ax.set_ylabel("time per scenario [us] (median)")
    ax.set_title("NIIRS (GIQE 3, 4, 5), Olson camera, 9 km, every database range")
    for bar, value in zip(bars, values, strict=True):
        ax.annotate(f"{value:.3g} us", (bar.get_x() + bar.get_width() / 2, value),
                    ha="center", va="bottom")
    fig.tight_layout()
    (DOCS / "figures").mkdir(parents=True, exist_ok=True)
    fig.savefig(DOCS / "figures" / "bench_niirs.png", dpi=120)


if __name__ == "__main__":
    main()
