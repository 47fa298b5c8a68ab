"""The must-show study of issue 24 on engine-generated tables, and the cheaper generation.

``tests/data/sixs_visibility_aerosol.nc`` was generated with 6S by
``recipes/evidence/engine_visibility_study.py`` (the Olson red band's 17 default-grid
wavelengths, 9 km, ground ranges 0-40 km, visibility 50/23/10/5/2 km, 6S continental and
maritime aerosols). One of its tables is regenerated here with the engine (so the file is
what 6S gives, not a hand-made cube), and the study file
``recipes/studies/visibility_aerosol.toml`` runs on it through the public study path.
In CI (``CI`` set) a missing engine is a failure, never a skip (as in test_sixs.py).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import xarray as xr

import xbsm
from xbsm import atmosphere as atm
from xbsm import study
from xbsm.atmosphere import sixs
from xbsm.examples import OLSON_BANDS, olson_scenario, olson_sensor

ROOT = Path(__file__).resolve().parents[2]
CUBE = ROOT / "tests" / "data" / "sixs_visibility_aerosol.nc"
STUDY = ROOT / "recipes" / "studies" / "visibility_aerosol.toml"


# test_sixs.py's check that 6S runs (in CI a missing engine fails the import, never skips)
from test_sixs import needs_engine  # noqa: E402  (a sibling module: pytest puts its folder on the path)


@pytest.fixture(scope="module")
def result():
    with atm.use_database(CUBE):
        spec = study.parse(STUDY.read_text(), STUDY.name)
        return study.run(spec).compute()


def test_the_committed_cube_is_valid_supported_and_holds_the_study_conditions():
    atm.check_supported(CUBE)
    with xr.open_dataset(CUBE, engine="netcdf4") as ds:
        assert ds["aerosol_model"].values.tolist() == [1, 2]
        assert ds["visibility"].values.tolist() == [50.0, 23.0, 10.0, 5.0, 2.0]
        assert ds.sizes["ground_range"] == 8
        assert "6SV1.1" in ds.attrs["sixs_engine"]


@pytest.mark.parametrize("model", [1, 2])
def test_niirs_falls_monotonically_as_visibility_falls_at_every_range(result, model):
    niirs = result["niirs"]
    if "giqe" in niirs.dims:
        niirs = niirs.sel(giqe=5)
    niirs = niirs.sel(aerosol_model=model).transpose("ground_range", "visibility")
    assert niirs["visibility"].values.tolist() == [50.0, 23.0, 10.0, 5.0, 2.0]
    assert np.isfinite(niirs).all()
    assert (niirs.diff("visibility") < 0).all(), niirs.values
    snr = result["snr"].sel(aerosol_model=model).transpose("ground_range", "visibility")
    assert (snr.diff("visibility") < 0).all()
    # and with range at every visibility (the farther, the worse)
    assert (niirs.diff("ground_range") < 0).all()
    # the file's own visibilities: nothing interpolated
    assert not (result["flags"] & xbsm.flags.flag("visibility_interpolated")).any()


def test_maritime_and_continental_tables_differ(result):
    snr = result["snr"]
    ratio = snr.sel(aerosol_model=2) / snr.sel(aerosol_model=1)
    assert float(abs(np.log(ratio)).max()) > 0.05  # the aerosol model is not ignored


@needs_engine
def test_the_committed_cube_is_what_6s_gives():
    # one table regenerated with the engine: 9 km, 10 km range, 5 km visibility, maritime
    lo, hi, _ = OLSON_BANDS["red"]
    wavelength = sixs.band_wavelengths(lo, hi)
    direct = sixs.sixs_table(9000.0, 10000.0, 5.0, wavelength=wavelength, workers=2,
                             settings=sixs.SixSSettings(aerosol_model="Maritime"))
    with xr.open_dataset(CUBE, engine="netcdf4") as ds:
        stored = ds["atmosphere"].sel(aerosol_model=2, visibility=5.0, altitude=9000.0,
                                      ground_range=10000.0).transpose(
                                          "component", "wavelength").values
        np.testing.assert_allclose(ds["wavelength"].values, wavelength, rtol=1e-12)
    np.testing.assert_array_equal(stored, direct.astype(stored.dtype))


def test_a_sensor_band_outside_the_band_only_cube_is_refused():
    # the cube covers 0.50-0.66 um only; the Olson NIR band (0.55-0.85 um) reaches past it
    refused = r"reaches outside the atmosphere database.s wavelengths \[5e-07, 6.6e-07\] m"
    with atm.use_database(CUBE), pytest.raises(ValueError, match=refused):
        xbsm.niirs(olson_sensor("nir"), olson_scenario(
            ground_range=xr.DataArray([0.0], dims="ground_range"), visibility=23.0,
            aerosol_model=1))


# ---- the cheaper generation: the same runs, shared among processes; a band-only grid

@needs_engine
def test_workers_share_the_wavelengths_and_give_the_same_table_bit_for_bit():
    wavelength = 1e-6 * np.array([0.45, 0.55, 0.65, 0.85, 1.6])
    one = sixs.sixs_table(150.0, 500.0, 10.0, wavelength=wavelength)  # reference-plane path
    two = sixs.sixs_table(150.0, 500.0, 10.0, wavelength=wavelength, workers=2)
    three = sixs.sixs_table(150.0, 500.0, 10.0, wavelength=wavelength, workers=3)
    np.testing.assert_array_equal(one, two)
    np.testing.assert_array_equal(one, three)


@pytest.mark.parametrize("workers", [0, 1.5, -1])
def test_sixs_table_refuses_bad_workers_naming_the_parameter(workers):
    with pytest.raises(ValueError, match="workers must be an integer >= 1"):
        sixs.sixs_table(1000.0, 0.0, 23.0, wavelength=[0.55e-6], workers=workers)


@pytest.mark.parametrize("lo, hi, first, last", [
    (0.50e-6, 0.66e-6, 0.50e-6, 0.66e-6),     # on the grid: the edges themselves
    (0.505e-6, 0.655e-6, 0.50e-6, 0.66e-6),   # between samples: the next ones out
    (0.3e-6, 2.5e-6, 0.3e-6, 2.5e-6),         # the whole default grid
])
def test_band_wavelengths_are_the_default_samples_covering_the_band(lo, hi, first, last):
    w = sixs.band_wavelengths(lo, hi)
    assert np.isin(w, sixs.DEFAULT_WAVELENGTHS).all()  # the same samples, not a new grid
    assert w[0] == pytest.approx(first, rel=1e-12) and w[-1] == pytest.approx(last, rel=1e-12)
    i = np.searchsorted(sixs.DEFAULT_WAVELENGTHS, w[0])
    np.testing.assert_array_equal(w, sixs.DEFAULT_WAVELENGTHS[i:i + w.size])  # contiguous


@pytest.mark.parametrize("lo, hi", [(0.2e-6, 0.6e-6), (0.6e-6, 0.5e-6), (0.5e-6, 3.0e-6)])
def test_band_wavelengths_refuse_a_band_off_the_grid(lo, hi):
    with pytest.raises(ValueError, match=r"wavelength_min < wavelength_max must lie within"):
        sixs.band_wavelengths(lo, hi)
