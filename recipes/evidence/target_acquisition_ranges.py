"""P(task) against range of the MWIR and LWIR example cameras, next to their NIIRS.

The cameras of docs/infrared.md (MWIR f/4 15 um, LWIR f/2 17 um) on a 100 m tower,
23 km visibility, looking at a 2.5 m vehicle 2 K warmer than a 290 K background:
``xbsm.target_acquisition`` (TTP metric, default observer and display) and
``xbsm.niirs`` (same target, GIQE 5) over 120 ground ranges; the ranges at which
P(task) falls to 0.5, 0.8 and 0.9 from ``xbsm.study.max_range`` for the TTP metric and
the Johnson criteria; the figure ``docs/figures/target_acquisition_ranges.png`` and the
numbers ``docs/benchmarks/target_acquisition_ranges.json`` that
docs/target_acquisition.md quotes.

Run from the repository root::

    .venv/bin/python recipes/evidence/target_acquisition_ranges.py
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import xarray as xr

import xbsm
from xbsm.examples import INFRARED_CAMERAS

ROOT = Path(__file__).resolve().parents[2]
MWIR = dict(INFRARED_CAMERAS["mwir"])  # xbsm.examples
LWIR = dict(INFRARED_CAMERAS["lwir"])  # xbsm.examples
RANGES = xr.DataArray(np.linspace(200.0, 12000.0, 120), dims="ground_range")
TARGET = xbsm.radiometry.target_set(2.5, thermal_contrast=2.0, names=["vehicle"])


def camera_ranges(name, camera):
    sensor = xbsm.sensor(**camera)
    scenario = xbsm.scenario(altitude=100.0, ground_range=RANGES, visibility=23.0,
                             background_temperature=290.0)
    out = {}
    results = {}
    for criterion in ("ttp", "johnson"):
        r = xbsm.target_acquisition(sensor, scenario, TARGET, criterion=criterion)
        results[criterion] = r
        rows = {}
        for task in r.task.values:
            p = r.probability.sel(task=task, target="vehicle")
            rows[str(task)] = {
                str(level): float(xbsm.study.max_range(
                    p, level, flags=r.flags.sel(target="vehicle")).max_range)
                for level in (0.5, 0.8, 0.9)}
        out[criterion] = rows
    n = xbsm.niirs(sensor, scenario, targets=TARGET).niirs.sel(giqe=5, target="vehicle")
    ttp_identify = out["ttp"]["identify"]["0.5"]
    niirs_there = float(n.interp(ground_range=ttp_identify))
    print(f"\n{name}: range [km] at which P(task) falls to 0.5 / 0.8 / 0.9")
    for criterion, rows in out.items():
        for task, levels in rows.items():
            print(f"  {criterion:8s} {task:10s} " + " / ".join(
                f"{levels[k] / 1e3:6.2f}" for k in ("0.5", "0.8", "0.9")))
    print(f"  NIIRS (GIQE 5, this target) at the TTP P(identify) = 0.5 range: "
          f"{niirs_there:.2f}")
    return out, niirs_there, results["ttp"], n


def main():
    record, curves = {}, {}
    for name, camera in (("MWIR", MWIR), ("LWIR", LWIR)):
        ranges, niirs_there, result, niirs = camera_ranges(name, camera)
        record[name] = {"ranges_m": ranges, "niirs_at_identify_p50": niirs_there}
        curves[name] = (result, niirs)
    (ROOT / "docs" / "benchmarks" / "target_acquisition_ranges.json").write_text(
        json.dumps(record, indent=1))
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(10, 4), layout="constrained")
    for ax, (name, (result, niirs)) in zip(axes, curves.items(), strict=True):
        xbsm.plot.probability_against_range(result, ax=ax)
        twin = ax.twinx()
        twin.plot(niirs.ground_range / 1e3, niirs, "k:", label="NIIRS (GIQE 5)")
        twin.set_ylabel("NIIRS (GIQE 5)")
        twin.legend(loc="center right", fontsize="small")
        ax.set_title(f"{name} camera, 2.5 m vehicle, 2 K")
    fig.savefig(ROOT / "docs" / "figures" / "target_acquisition_ranges.png", dpi=100)


if __name__ == "__main__":
    main()
