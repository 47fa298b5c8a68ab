"""How inconsistent the database's tables above 24.5 km are, and what it does to SNR.

The only table above 24.5 km is 550 km at ground range 0 (nadir). Above 24.5 km lies
about 3 % of the air mass (27 hPa of 1013, US Standard Atmosphere 1976), so the 550 km
nadir tables should differ from the 24.5 km ones by a few percent at most (TRANS does:
below 1.5 %). This recipe measures

1. the band means of TRANS, SOL_SCAT and GRND_RFLT at 550 km relative to 24.5 km
   (ground range 0, both visibilities, 0.4-0.7, 0.7-1.0 and 1.0-1.7 um);
2. the contrast SNR (``xbsm.snr``, ``method="accurate"``) of a camera looking at nadir
   from 100 km and 549 km, with the database as it is against the same camera whose
   atmosphere is the 24.5 km nadir table (the consistent reference: the path above
   24.5 km adds almost nothing). The reference is made by calling the atmosphere
   lookup at min(altitude, 24.5 km) (a patch of ``xbsm._chain.band_atmosphere`` here,
   for this measurement only); everything else (geometry, optics) stays at the
   real altitude. The camera: the paper's Olson camera, both bands (the SNR of an
   extended target does not depend on the altitude but through the atmosphere), and
   its NIR band with a 1 ms exposure: the Olson camera's 30 ms fills the well, its
   integration time is shortened (``well_fill_limited``) and that hides part of the
   brighter radiance.

Writes ``docs/benchmarks/satellite_tables.json``. Run from the repository root::

    .venv/bin/python recipes/evidence/satellite_tables.py
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import xarray as xr

import xbsm
import xbsm._chain as chain
from xbsm.atmosphere import open_atmosphere
from xbsm.examples import olson_scenario, olson_sensor

OUT = Path(__file__).resolve().parents[2] / "docs" / "benchmarks" / "satellite_tables.json"
TOP = 24500.0
BANDS = {"0.4-0.7 um": (0.4e-6, 0.7e-6), "0.7-1.0 um": (0.7e-6, 1.0e-6),
         "1.0-1.7 um": (1.0e-6, 1.7e-6)}


def table_ratios():
    nadir = open_atmosphere()["atmosphere"].sel(ground_range=0.0)
    out = {}
    for band, (lo, hi) in BANDS.items():
        part = nadir.sel(wavelength=slice(lo, hi))
        for vis in (23.0, 5.0):
            for comp in ("TRANS", "SOL_SCAT", "GRND_RFLT"):
                c = part.sel(visibility=vis, component=comp)
                ratio = float(c.sel(altitude=550000.0).mean() / c.sel(altitude=TOP).mean())
                out[f"{comp} {band} {vis:g} km"] = round(ratio, 4)
    return out


def snr_optimism():
    original = chain.band_atmosphere
    altitude = xr.DataArray([20000.0, 100000.0, 549000.0], dims="altitude")
    out = {}
    cameras = {"red": olson_sensor("red"), "nir": olson_sensor("nir"),
               # a short exposure that never fills the well: SNR as the radiance gives it
               "nir 1 ms": olson_sensor("nir", integration_time=0.001)}
    for band, s in cameras.items():
        sc = olson_scenario(ground_range=0.0, visibility=xr.DataArray([23.0, 5.0],
                                                                      dims="visibility"),
                            altitude=altitude)
        as_is = xbsm.snr(s, sc)

        def at_top(alt, *args, **kwargs):
            return original(np.minimum(alt, TOP), *args, **kwargs)

        chain.band_atmosphere = at_top
        try:
            reference = xbsm.snr(s, sc)
        finally:
            chain.band_atmosphere = original
        ratio = (as_is["snr"] / reference["snr"]).transpose("altitude", "visibility")
        for i, alt in enumerate(altitude.values):
            for j, vis in enumerate(ratio["visibility"].values):
                out[f"{band} {alt / 1e3:g} km {vis:g} km vis"] = round(
                    float(ratio.values[i, j]) - 1.0, 4)
        flags = as_is["flags"].transpose("altitude", "visibility").values
        out[f"{band} flags"] = flags.tolist()
    return out


def main():
    result = {"table ratio 550 km / 24.5 km (band mean, nadir)": table_ratios(),
              "SNR relative excess against the 24.5 km table": snr_optimism(),
              "xbsm": xbsm.__version__}
    OUT.write_text(json.dumps(result, indent=1) + "\n")
    print(json.dumps(result, indent=1))


if __name__ == "__main__":
    main()
