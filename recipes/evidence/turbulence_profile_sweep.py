"""A Cn2 profile sweep: the whole-profile multiplier 0.3-10x moves r0 and NIIRS.

The paper's Olson camera (NIR band) on its Sec. 3 flight (9 km altitude, 100 m/s),
23 km visibility, ground ranges 5, 15 and 30 km, the Hufnagel-Valley 5/7 profile
scaled by ``cn2_multiplier`` = 0.3, 0.5, 1, 2, 3, 5, 10 (a sweep dimension like any
scenario parameter), ``method="accurate"``. Also the zenith plane-wave r0 and
isoplanatic angle of the unscaled profile at 0.5 um (adaptive quadrature of
``xbsm.otf.turbulence.hufnagel_valley``), against the published HV 5/7 values.
Writes ``docs/benchmarks/turbulence_profile_sweep.json``. Run from the repository root::

    .venv/bin/python recipes/evidence/turbulence_profile_sweep.py
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import xarray as xr
from scipy.integrate import quad

import xbsm
from xbsm.examples import olson_scenario, olson_sensor
from xbsm.otf.turbulence import hufnagel_valley

OUT = (Path(__file__).resolve().parents[2] / "docs" / "benchmarks"
       / "turbulence_profile_sweep.json")
MULTIPLIERS = [0.3, 0.5, 1.0, 2.0, 3.0, 5.0, 10.0]
RANGES = [5000.0, 15000.0, 30000.0]


def zenith_hv57(wavelength=0.5e-6):
    k = 2 * np.pi / wavelength
    pieces = [(0, 1000), (1000, 5000), (5000, 30000), (30000, 200000)]

    def cn2(h):
        return float(hufnagel_valley(h))

    m0 = sum(quad(cn2, a, b, epsrel=1e-12, limit=400)[0] for a, b in pieces)
    m53 = sum(quad(lambda h: cn2(h) * h ** (5 / 3), a, b, epsrel=1e-12, limit=400)[0]
              for a, b in pieces)
    return {"r0 [cm]": round(100 * (0.423 * k**2 * m0) ** (-3 / 5), 3),
            "isoplanatic angle [urad]": round(1e6 * (2.914 * k**2 * m53) ** (-3 / 5), 3),
            "published (HV 5/7)": "r0 5 cm, isoplanatic angle 7 urad at 0.5 um"}


def sweep():
    m = xr.DataArray(MULTIPLIERS, dims="cn2_multiplier")
    sc = olson_scenario(ground_range=xr.DataArray(RANGES, dims="ground_range"),
                        visibility=23.0, cn2_multiplier=m)
    out = xbsm.niirs(olson_sensor("nir"), sc)
    table = {}
    for gr in RANGES:
        cell = out.sel(ground_range=gr)
        table[f"{gr / 1e3:g} km"] = {
            "r0 band [cm]": [round(100 * float(v), 3) for v in cell["coherence_diameter"].values],
            "NIIRS (GIQE 5)": [round(float(v), 3)
                               for v in cell["niirs"].sel(giqe=5).values],
            "RER": [round(float(v), 4) for v in cell["rer"].values],
        }
    return {"cn2_multiplier": MULTIPLIERS, "by ground range": table}


def main():
    result = {"zenith HV 5/7": zenith_hv57(), "Olson NIR, 9 km, 23 km visibility": sweep(),
              "xbsm": xbsm.__version__}
    OUT.write_text(json.dumps(result, indent=1) + "\n")
    print(json.dumps(result, indent=1))


if __name__ == "__main__":
    main()
