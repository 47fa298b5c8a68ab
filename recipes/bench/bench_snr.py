"""Benchmark: xbsm.snr over a 10^4-scenario sweep against pyBSM 0.16.1 per scenario.

Both run in this one invocation on the same machine: xbsm in this
interpreter, pyBSM (NUMBA_NUM_THREADS=1) in its own environment through
``recipes/_pybsm_runner.py``. The sweep is the paper's Olson NIR camera
(Table 2) with a 25-value focal-length sweep, at 9 km and 12 km altitude,
over every database ground range (97) and both visibilities:
25 x 2 x 97 x 2 = 9,700 scenarios. pyBSM has no sweep: it is timed per
scenario on a random sample (every altitude, range and visibility is a
database node, so pyBSM reads tables without interpolating). Medians of
repeated runs are quoted. The results are written to
``docs/benchmarks/bench_snr.json`` and ``docs/figures/bench_snr.png`` and the
table in ``docs/benchmarks.md`` quotes them.

Run from the repository root with the project environment; pyBSM's own
environment is made on first use (see ``recipes/README.md``)::

    .venv/bin/python recipes/bench/bench_snr.py [--sample 200] [--repeats 5]
"""

from __future__ import annotations

import argparse
import json
import platform
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # recipes/: the shared helpers

import numpy as np
import xarray as xr
from _pybsm_runner import run_pybsm

import xbsm
from xbsm.atmosphere import VISIBILITIES

DOCS = Path(__file__).resolve().parents[2] / "docs"
GROUND_RANGES = np.array(xbsm.atmosphere.GROUND_RANGES)  # every database ground range
FOCAL_LENGTHS = np.linspace(2.0, 6.0, 25)
ALTITUDES = (9000.0, 12000.0)
OLSON = dict(D=0.275, p_x=8e-6, eta=0.4, int_time=0.03, read_noise=25.0, max_n=96000.0,
             bit_depth=11.9, max_well_fill=0.6, s_x=5e-7, s_y=5e-7, da_x=1e-4, da_y=1e-4,
             dark_current=1e-5 * 64e-12 / 1.60217662e-19,
             opt_trans_wavelengths=[0.55e-6, 0.85e-6], qe=[0.71, 0.71],
             qe_wavelengths=[0.55e-6, 0.85e-6], post={"optics_transmission": [0.5, 0.5]})


def xbsm_inputs():
    kw = {k: v for k, v in OLSON.items() if k != "post"}
    kw["optics_transmission"] = OLSON["post"]["optics_transmission"]
    kw["f"] = xr.DataArray(FOCAL_LENGTHS, dims="focal_length")
    sensor = xbsm.pybsm_compat.sensor(**kw)
    scenario = xbsm.scenario(
        altitude=xr.DataArray(list(ALTITUDES), dims="altitude"),
        ground_range=xr.DataArray(GROUND_RANGES, dims="ground_range"),
        visibility=xr.DataArray(list(VISIBILITIES), dims="visibility"),
        platform_speed=100.0,
    )
    return sensor, scenario


def time_xbsm(method, repeats):
    sensor, scenario = xbsm_inputs()
    result = xbsm.snr(sensor, scenario, method=method)  # warm-up: loads the database
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        result = xbsm.snr(sensor, scenario, method=method)
        result["snr"].values  # noqa: B018 (make sure everything is computed)
        times.append(time.perf_counter() - t0)
    return statistics.median(times), result


def pybsm_sample(n, rng):
    cases = []
    for _ in range(n):
        kw = dict(OLSON, name="olson", f=float(rng.choice(FOCAL_LENGTHS)))
        cases.append({
            "sensor": kw,
            "scenario": {"name": "s", "ihaze": 1 if rng.uniform() < 0.5 else 2,
                         "altitude": float(rng.choice(ALTITUDES)),
                         "ground_range": float(rng.choice(GROUND_RANGES)),
                         "aircraft_speed": 100.0},
        })
    return cases


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sample", type=int, default=200, help="pyBSM scenarios timed")
    parser.add_argument("--repeats", type=int, default=5, help="xbsm repeats (median)")
    args = parser.parse_args()
    rng = np.random.default_rng(1)

    cases = pybsm_sample(args.sample, rng)
    pybsm = run_pybsm("snr", cases)
    pybsm_per = statistics.median(pybsm["times"])

    n_scenarios = len(FOCAL_LENGTHS) * len(ALTITUDES) * len(GROUND_RANGES) * len(VISIBILITIES)
    rows = {}
    for method in ("pybsm", "accurate"):
        total, result = time_xbsm(method, args.repeats)
        rows[method] = {"total_s": total, "per_scenario_s": total / n_scenarios,
                        "speedup": pybsm_per / (total / n_scenarios)}
        print(f"xbsm method={method:9s} {n_scenarios} scenarios in {total:.3f} s "
              f"= {1e6 * total / n_scenarios:.1f} us/scenario; "
              f"pyBSM {1e3 * pybsm_per:.2f} ms/scenario; ratio {rows[method]['speedup']:.0f}x")

    # agreement on the sampled scenarios (method="pybsm" vs pyBSM's own numbers)
    sensor, scenario = xbsm_inputs()
    ours = xbsm.snr(sensor, scenario, method="pybsm")["snr_frame"]
    worst = 0.0
    for case, value in zip(cases, pybsm["values"], strict=False):
        sc = case["scenario"]
        mine = float(ours.sel(focal_length=case["sensor"]["f"], altitude=sc["altitude"],
                              ground_range=sc["ground_range"],
                              visibility=23.0 if sc["ihaze"] == 1 else 5.0))
        # relative to max(SNR, 1): where the contrast is ~1e-14 of the signal (SNR ~ 1e-9
        # at 300 km in haze) both codes are at the mercy of cancellation
        worst = max(worst, abs(mine - value) / max(abs(value), 1.0))
    print(f"largest SNR difference from pyBSM on the sample, relative to max(SNR, 1): "
          f"{worst:.2e}")

    record = {
        "scenarios": n_scenarios, "pybsm_sample": args.sample,
        "pybsm_per_scenario_s": pybsm_per, "xbsm": rows, "max_relative_difference": worst,
        "machine": f"{platform.machine()} {platform.processor() or ''} "
                   f"python {platform.python_version()}",
        "date": time.strftime("%Y-%m-%d"),
    }
    (DOCS / "benchmarks").mkdir(parents=True, exist_ok=True)
    (DOCS / "benchmarks" / "bench_snr.json").write_text(json.dumps(record, indent=1))
    plot(record)


def plot(record):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    labels = ["pyBSM 0.16.1\n(per scenario)", 'xbsm\nmethod="pybsm"', 'xbsm\nmethod="accurate"']
    values = [record["pybsm_per_scenario_s"] * 1e6,
              record["xbsm"]["pybsm"]["per_scenario_s"] * 1e6,
              record["xbsm"]["accurate"]["per_scenario_s"] * 1e6]
    fig, ax = plt.subplots(figsize=(6, 3.5))
    bars = ax.bar(labels, values, color=["0.6", "tab:blue", "tab:green"])
    ax.set_yscale("log")
    ax.set_ylabel("time per scenario [us] (median)")
    ax.set_title(f"contrast SNR, {record['scenarios']} scenarios (Olson NIR camera)")
    for bar, value in zip(bars, values, strict=False):
        ax.annotate(f"{value:.3g} us", (bar.get_x() + bar.get_width() / 2, value),
                    ha="center", va="bottom")
    fig.tight_layout()
    (DOCS / "figures").mkdir(parents=True, exist_ok=True)
    fig.savefig(DOCS / "figures" / "bench_snr.png", dpi=120)


if __name__ == "__main__":
    main()
