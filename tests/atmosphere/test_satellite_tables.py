"""Above 24.5 km the database's tables are inconsistent: an invalid-group flag, measured."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

import xbsm
from xbsm import flags as fl
from xbsm.atmosphere import open_atmosphere
from xbsm.examples import olson_scenario, olson_sensor

BIT = fl.flag("atmosphere_inconsistent")


@pytest.mark.parametrize("method", ["accurate", "pybsm"])
@pytest.mark.parametrize(("altitude", "flagged"), [(20e3, False), (24.5e3, False),
                                                   (100e3, True), (549e3, True),
                                                   (550e3, True)])
def test_satellite_altitudes_carry_the_invalid_flag(altitude, flagged, method):
    sc = olson_scenario(ground_range=0.0, visibility=23.0, altitude=altitude)
    for door in (xbsm.snr, xbsm.niirs):
        flags = door(olson_sensor("nir"), sc, method=method)["flags"]
        assert bool(np.all(fl.has_flag(flags, "atmosphere_inconsistent"))) is flagged
        assert bool(np.all(fl.is_invalid(flags))) is flagged


def test_the_flag_is_in_the_invalid_group_and_the_sweep_door_sets_it_too():
    assert "atmosphere_inconsistent" in fl.INVALID
    assert fl.INVALID_MASK & BIT
    sc = olson_scenario(ground_range=0.0, visibility=23.0,
                        altitude=xr.DataArray([20e3, 100e3, 549e3], dims="altitude"))
    flags = xbsm.snr(olson_sensor("nir"), sc)["flags"].values
    assert [bool(f & BIT) for f in flags] == [False, True, True]


def test_the_inconsistency_is_what_the_flag_says():
    # The database's own 550 km and 24.5 km nadir tables (band means, both visibilities,
    # 0.4-1.7 um): the flag's description quotes GRND_RFLT 1.65-1.88x, SOL_SCAT
    # 1.30-1.61x, TRANS within 1.5 % (recipes/evidence/satellite_tables.py).
    nadir = open_atmosphere()["atmosphere"].sel(ground_range=0.0)
    ratios = {c: [] for c in ("TRANS", "SOL_SCAT", "GRND_RFLT")}
    for lo, hi in ((0.4e-6, 0.7e-6), (0.7e-6, 1.0e-6), (1.0e-6, 1.7e-6)):
        part = nadir.sel(wavelength=slice(lo, hi))
        for comp, found in ratios.items():
            c = part.sel(component=comp)
            found.extend((c.sel(altitude=550e3).mean("wavelength")
                          / c.sel(altitude=24.5e3).mean("wavelength")).values.tolist())
    assert 1.645 < min(ratios["GRND_RFLT"]) and max(ratios["GRND_RFLT"]) < 1.885
    assert 1.30 < min(ratios["SOL_SCAT"]) and max(ratios["SOL_SCAT"]) < 1.61
    assert max(abs(r - 1.0) for r in ratios["TRANS"]) < 0.015
