"""How much the atmosphere interpolation rule moves NIIRS and SNR over a representative sweep.

The Olson camera (both bands) at 1, 2, 3 and 5 km altitude and halfway between
database altitudes (1.5, 2.5, 3.5, 5.5 km), every database ground range, both
visibilities, ``method="accurate"`` with ``atmosphere_interpolation`` "log-linear"
(fixed ground range) against "same-elevation", "optical-depth-cubic" and
"extinction-profile" (the presets' rule). Cells that are NaN under either rule
(beyond the horizon) are left out, and so are cells where either NIIRS is off the
0-10 rating scale (SNR near zero at long range in 5 km visibility, where NIIRS runs
to minus infinity and any difference is meaningless).
Writes ``docs/benchmarks/atmosphere_rule_effect.json``.

Run from the repository root with the project environment::

    .venv/bin/python recipes/evidence/atmosphere_rule_effect.py
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import xarray as xr

import xbsm

OUT = Path(__file__).resolve().parents[2] / "docs" / "benchmarks" / "atmosphere_rule_effect.json"
ALTITUDES = {"database altitudes": [1000.0, 2000.0, 3000.0, 5000.0],
             "halfway between database altitudes": [1500.0, 2500.0, 3500.0, 5500.0]}
RULES = ("log-linear", "same-elevation", "optical-depth-cubic",
         "extinction-profile")  # the first is the reference


def _summary(values):
    values = np.abs(values[np.isfinite(values)])
    return {"n": int(values.size), "median": float(np.median(values)),
            "p95": float(np.percentile(values, 95)), "max": float(values.max())}


def differences(band: str, altitudes) -> dict:
    """NIIRS (each GIQE) and relative SNR differences, each rule minus log-linear."""
    sensor = xbsm.examples.olson_sensor(band)
    scenario = xbsm.examples.olson_scenario(
        altitude=xr.DataArray(altitudes, dims="altitude", coords={"altitude": altitudes}))
    results = [xbsm.niirs(sensor, scenario, xbsm.method("accurate", atmosphere_interpolation=r))
               for r in RULES]
    old = results[0]
    on_scale = ((old.niirs >= 0) & (old.niirs <= 10)).all("giqe")
    for new in results[1:]:  # the same cells for every rule
        on_scale &= ((new.niirs >= 0) & (new.niirs <= 10)).all("giqe")
    by_rule = {}
    for rule, new in zip(RULES[1:], results[1:], strict=True):
        out = {f"niirs_giqe{int(g)}": _summary((new.niirs - old.niirs).where(on_scale)
                                               .sel(giqe=g).values)
               for g in old["giqe"].values}
        out["snr_relative"] = _summary((new.snr / old.snr - 1.0).where(on_scale).values)
        out["cells_off_scale"] = int((~on_scale & np.isfinite(old.snr)).sum())
        fallback = xbsm.flags.has_flag(new.flags, "atmosphere_fallback")
        out["fallback_cells"] = int(fallback.sum())
        by_rule[f"{rule} minus {RULES[0]}"] = out
    return by_rule


def main() -> int:
    report = {"method": "accurate", "rules": list(RULES), "by_band": {}}
    for band in ("red", "nir"):
        report["by_band"][band] = {label: {"altitudes_m": alts, **differences(band, alts)}
                                   for label, alts in ALTITUDES.items()}
    OUT.write_text(json.dumps(report, indent=1) + "\n")
    print(json.dumps(report, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
