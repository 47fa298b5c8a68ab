"""Tests of xbsm.atmosphere's public builder (from_tables, write_database, validate_database)
and of another database file in use (use_database)."""

from __future__ import annotations

import hashlib
from pathlib import Path

import netCDF4
import numpy as np
import pytest
import xarray as xr

import xbsm
from xbsm import atmosphere as atm
from xbsm.examples import olson_scenario, olson_sensor
from xbsm.study import store

#: A subset of the shipped tables for small synthetic files: altitudes around the Olson
#: scenario's 9 km (database nodes) and the first 30 ground ranges (0-27 km, inside the
#: horizon of 1 km and up).
SUBSET = {"altitude": [1000.0, 5000.0, 9000.0, 12000.0, 24500.0], "ground_range": slice(0, 30)}


def sha256(path):
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


@pytest.fixture(scope="module")
def shipped():
    with xr.open_dataset(atm.database_path(), engine="netcdf4", chunks=None) as ds:
        return ds.load()


@pytest.fixture(scope="module")
def small(shipped):
    return shipped.sel(altitude=SUBSET["altitude"]).isel(ground_range=SUBSET["ground_range"])


def _variables_and_attributes(path):
    """Every variable's raw bytes and every attribute of a NetCDF file, in file order."""
    with netCDF4.Dataset(path) as nc:
        nc.set_auto_maskandscale(False)
        out = {"": [(k, repr(nc.getncattr(k))) for k in nc.ncattrs()],
               "dims": [(d, len(nc.dimensions[d])) for d in nc.dimensions]}
        for name, var in nc.variables.items():
            data = var[...]
            raw = data.tobytes() if data.dtype != object else repr(list(data)).encode()
            out[name] = (var.dtype if var.dtype is str else var.dtype.str, var.dimensions,
                         [(k, repr(var.getncattr(k))) for k in var.ncattrs()],
                         var.chunking(), var.filters(), hashlib.sha256(raw).hexdigest())
        return out, nc.getncattr("_NCProperties")


def test_shipped_database_rewritten_through_write_database_is_byte_identical(shipped, tmp_path):
    # the shipped atmosphere.nc (recipes/build_atmosphere.py, now also through
    # write_database) read back by xarray and written again by the public builder
    out = atm.write_database(shipped, tmp_path / "again.nc")
    mine, my_libraries = _variables_and_attributes(out)
    theirs, their_libraries = _variables_and_attributes(atm.database_path())
    assert mine == theirs  # every variable's bytes, dtype, dims, chunks, filters, attributes
    if my_libraries == their_libraries:  # same netCDF-C and HDF5: the same file
        assert sha256(out) == sha256(atm.database_path())


def test_from_tables_rebuilds_the_shipped_cube_from_plain_arrays(shipped, small, tmp_path):
    values = small["atmosphere"].values
    cube = atm.from_tables(
        values, visibility=small["visibility"].values, altitude=small["altitude"].values,
        ground_range=small["ground_range"].values, wavelength=small["wavelength"].values,
        ihaze=small["ihaze"].values, attrs=shipped.attrs)
    assert cube["atmosphere"].dims == atm.DIMS
    assert cube["atmosphere"].dtype == np.float32
    np.testing.assert_array_equal(cube["atmosphere"].values, values)  # NaN where NaN
    assert list(cube["component_units"].values) == list(atm.FILE_UNITS)
    path = atm.write_database(cube, tmp_path / "small.nc")
    db = atm.load_database(path)
    np.testing.assert_array_equal(db.altitude, SUBSET["altitude"])
    # in memory: the file's SI conversion, as for the shipped file
    full = atm.load_database()
    a = [list(full.altitude).index(x) for x in SUBSET["altitude"]]
    np.testing.assert_array_equal(db.cube, full.cube[:, a, SUBSET["ground_range"]])


def test_from_tables_takes_a_data_array_with_its_coordinates_and_conditions(small):
    tables = small["atmosphere"].assign_attrs(small.attrs)
    cube = atm.from_tables(tables)
    assert cube.attrs["modtran_IDAY"].startswith("236")
    np.testing.assert_array_equal(cube["altitude"].values, SUBSET["altitude"])


def _without_source(ds):
    ds.attrs.pop("source")
    return ds


def _coordinate(ds, name, values):
    return ds.assign_coords({name: (ds[name].dims, values, ds[name].attrs)})


def _cell(ds, index, value):
    ds = ds.copy(deep=True)
    ds["atmosphere"].values[index] = value
    return ds


def _units(ds, name, units):
    ds = ds.copy(deep=True)
    ds[name].attrs["units"] = units
    return ds


# ground ranges of the small cube: 0, 100, 500, 1000, 2000, 3000... m
BROKEN = {
    "altitude not increasing": (
        lambda ds: _coordinate(ds, "altitude", [1e3, 5e3, 4e3, 12e3, 24.5e3]),
        "altitude must be strictly increasing; altitude[1] = 5000.0 then altitude[2] = 4000.0"),
    "visibility increasing": (
        lambda ds: _coordinate(ds, "visibility", [23.0, 30.0]),
        "visibility must be strictly decreasing; visibility[0] = 23.0 then visibility[1] = 30.0"),
    "wavelength in micrometres": (
        lambda ds: _coordinate(ds, "wavelength", ds["wavelength"].values * 1e6),
        "wavelength must be in metres"),
    "altitude in km": (
        lambda ds: _units(ds, "altitude", "km"),
        "coordinate altitude must have units 'm'; got 'km'"),
    "TRANS above 1": (
        lambda ds: _cell(ds, (1, 2, 3, 0, 100), 1.5),
        "TRANS must be within [0, 1]; 1.5 at (visibility=5.0, altitude=9000.0, "
        "ground_range=1000.0, component=TRANS, wavelength=1.3e-06)"),
    "negative radiance": (
        lambda ds: _cell(ds, (0, 0, 0, 3, 7), -0.5),
        "radiances must be >= 0; -0.5 at (visibility=23.0, altitude=1000.0, "
        "ground_range=0.0, component=SOL_SCAT, wavelength=3.7e-07)"),
    "NaN inside a table": (
        lambda ds: _cell(ds, (0, 1, 5, 2, 9), np.nan),
        "the cell (visibility=23.0, altitude=5000.0, ground_range=3000.0, "
        "component=SURF_EMIS, wavelength=3.9e-07) is NaN"),
    "a hole in the ground ranges": (
        lambda ds: _cell(ds, (0, 1, 5), np.nan),
        "at (visibility=23.0, altitude=5000.0) ground_range=3000.0 is missing but "
        "ground_range=4000.0 is present"),
    "SI radiance units": (
        lambda ds: _coordinate(ds, "component_units", ["1"] + ["W m-2 sr-1 m-1"] * 4),
        "component_units must be"),
    # (not Dataset.drop_attrs: xarray 2023.12, the floor, lacks it)
    "no source": (lambda ds: ds.copy().assign_attrs(source=None).pipe(_without_source),
        "lacks the global attribute(s) source"),
}


@pytest.mark.parametrize("case", list(BROKEN))
def test_validate_database_names_what_is_wrong_and_where(small, case, tmp_path):
    change, message = BROKEN[case]
    broken = change(small)
    with pytest.raises(ValueError) as err:
        atm.write_database(broken, tmp_path / "broken.nc")
    assert message in str(err.value)
    assert not (tmp_path / "broken.nc").exists()  # nothing written


def test_the_shipped_tables_stop_at_the_geometric_horizon(shipped):
    # a fact of pyBSM's fileDecoder.csv that the horizon check rests on: below the 550 km
    # table, each altitude holds exactly the grid's ground ranges inside the spherical-Earth
    # horizon (radius 6378.164 km, the paper's Sec. 2.6), from 8 at 2 m to all 97 at 8 km
    db = atm.load_database()
    for a, altitude in enumerate(db.altitude[:-1]):
        inside = np.count_nonzero(db.ground_range <= atm.horizon(altitude))
        assert (db.present[:, a].sum(axis=1) == inside).all(), altitude


def test_a_table_beyond_the_horizon_is_refused(shipped):
    # 2 m sees 5.05 km geometrically, 5.83 km with standard refraction (Earth radius x 4/3);
    # fill 6 km (missing at 2 m in the shipped file) with the 5 km spectrum: refused
    two = shipped.sel(altitude=[2.0, 1000.0]).isel(ground_range=slice(0, 12)).copy(deep=True)
    assert np.isnan(two["atmosphere"].values[:, 0, 8]).all()  # 6 km: missing at 2 m
    radius = xbsm.constants.EARTH_RADIUS
    assert atm.horizon(2.0) == pytest.approx(np.sqrt(2 * 2.0 * radius), rel=1e-6)
    assert atm.horizon(2.0, 4 / 3) == pytest.approx(np.sqrt(2 * 2.0 * radius * 4 / 3), rel=1e-6)
    two["atmosphere"].values[:, 0, 8] = two["atmosphere"].values[:, 0, 7]
    with pytest.raises(ValueError, match=r"ground_range=6000.0 m is beyond the horizon"):
        atm.validate_database(two)


def test_from_tables_rejects_a_shape_that_does_not_match_the_coordinates(small):
    with pytest.raises(ValueError, match=r"the coordinates give \(2, 4, 30, 5, 1371\)"):
        atm.from_tables(small["atmosphere"].values, visibility=[23.0, 5.0],
                        altitude=SUBSET["altitude"][:4],
                        ground_range=small["ground_range"].values,
                        wavelength=small["wavelength"].values, attrs=small.attrs)


# ---- another database in use ------------------------------------------------------------


def _halved(small, tmp_path):
    """The small cube with every component x 0.5 (exact in float32), written."""
    half = small.copy(deep=True)
    half["atmosphere"] = half["atmosphere"] * np.float32(0.5)
    half.attrs["history"] = "test: the shipped tables x 0.5"
    return atm.write_database(half, tmp_path / "half.nc")


def test_use_database_changes_what_snr_reads_by_the_closed_form(small, tmp_path):
    # The aperture radiance L = L_pt + (1 - r) L_bb tau + L_ss + L_tr r / 0.15
    # (xbsm.radiometry.total_radiance, paper eq. for L_ap) is linear in the four database
    # components it uses: with all of them halved, every photoelectron rate halves exactly
    # in exact arithmetic. At a database node (9 km, 5 km) every interpolation rule returns
    # the stored value, so the halved file's spectra are exactly half.
    sensor, scenario = olson_sensor("nir"), olson_scenario(ground_range=5000.0, visibility=23.0)
    assert float(scenario["altitude"]) == 9000.0
    before = xbsm.snr(sensor, scenario)
    path = _halved(small, tmp_path)
    with atm.use_database(path) as active:
        assert atm.database_path() == active == path.resolve()
        spectra = atm.atmosphere_at(9000.0, 5000.0, 23.0)
        after = xbsm.snr(sensor, scenario)
        assert store.atmosphere_checksum() == sha256(path)  # the study provenance follows
    assert atm.database_path() != path.resolve()  # only inside the block
    shipped = atm.atmosphere_at(9000.0, 5000.0, 23.0)
    # x 0.5 is exact in float32 except on subnormal raw values (< 1.18e-38 in the file's
    # units, 1.18e-28 W m-2 sr-1 m-1 in SI): there it loses the last bit
    tiny = np.finfo(np.float32).tiny * 1e10
    for name in atm.VARIABLES:
        half, full = spectra[name].values, 0.5 * shipped[name].values
        normal = np.abs(full) >= tiny
        np.testing.assert_array_equal(half[normal], full[normal])
        np.testing.assert_allclose(half[~normal], full[~normal], rtol=0, atol=tiny)
    # photoelectron rates: the scene's halves, the dark current (in the target and background
    # counts, cancelled in the contrast) does not; the integration time differs (the
    # halved scene fills the well more slowly), so compare rates
    dark = float(sensor["dark_current"])
    for name, offset in (("target_photoelectrons", dark), ("background_photoelectrons", dark),
                         ("contrast_photoelectrons", 0.0)):
        rate_before = float(before[name] / before["effective_integration_time"])
        rate_after = float(after[name] / after["effective_integration_time"])
        np.testing.assert_allclose(rate_after - offset, 0.5 * (rate_before - offset),
                                   rtol=1e-12)
    assert float(after["snr"]) < float(before["snr"])


def test_use_database_reaches_a_sweep_through_the_labelled_chain(small, tmp_path):
    # a sweep takes the labelled path (band_atmosphere -> atmosphere_at), not the
    # single-scenario one: the contrast rate halves there too, at database nodes
    sensor = olson_sensor("nir")
    scenario = olson_scenario(ground_range=xr.DataArray([0.0, 5000.0, 20000.0],
                                                        dims="ground_range"), visibility=23.0)
    before = xbsm.snr(sensor, scenario)
    with atm.use_database(_halved(small, tmp_path)):
        after = xbsm.snr(sensor, scenario)
    rate = [r["contrast_photoelectrons"] / r["effective_integration_time"]
            for r in (after, before)]
    np.testing.assert_allclose(rate[0].values, 0.5 * rate[1].values, rtol=1e-12)


def test_use_database_is_seen_by_a_lazy_sweep_built_inside_the_block(small, tmp_path):
    path = _halved(small, tmp_path)
    ground_range = xr.DataArray([0.0, 5000.0], dims="ground_range").chunk(1)
    with atm.use_database(path):
        lazy = atm.atmosphere_at(9000.0, ground_range, 23.0)
    computed = lazy.compute()  # outside the block: the graph carries the file
    eager = atm.atmosphere_at(9000.0, ground_range.compute(), 23.0)
    np.testing.assert_array_equal(computed["transmission"].values,  # no subnormal TRANS
                                  0.5 * eager["transmission"].values)


def test_scenario_accepts_the_visibilities_of_the_database_in_use(small, tmp_path):
    # the 5 km tables relabelled 10 km: a plumbing test of the visibility coordinate
    relabelled = small.assign_coords(visibility=("visibility", [23.0, 10.0],
                                                 small["visibility"].attrs))
    path = atm.write_database(relabelled, tmp_path / "ten.nc")
    with pytest.raises(ValueError, match=r"visibility must be within \[5, 23\] km"):
        xbsm.scenario(altitude=9000.0, ground_range=5000.0, visibility=4.0)
    with atm.use_database(path):
        assert atm.database_visibilities() == (23.0, 10.0)
        scenario = olson_scenario(ground_range=5000.0, visibility=10.0)
        result = xbsm.snr(olson_sensor("nir"), scenario)
        with pytest.raises(ValueError, match=r"within \[10, 23\] km: the atmosphere database "
                                             r"holds 23, 10 km; between them"):
            xbsm.scenario(altitude=9000.0, ground_range=5000.0, visibility=5.0)
        with pytest.raises(ValueError, match=r"visibility must be within \[10, 23\] km.*; "
                                             r"got 5.0"):
            atm.atmosphere_at(9000.0, 5000.0, 5.0)
    shipped = xbsm.snr(olson_sensor("nir"), olson_scenario(ground_range=5000.0, visibility=5.0))
    np.testing.assert_array_equal(result["snr"].values, shipped["snr"].values)


UNSUPPORTED = {
    "a table inside the 24.5-550 km gap": (
        lambda ds: ds.assign_coords(altitude=("altitude", [1e3, 5e3, 9e3, 12e3, 30e3],
                                              ds["altitude"].attrs)),
        "altitude 30000 m lies between 24500 m and 550000 m"),
    "ground ranges beyond 300 km": (
        lambda ds: ds.sel(altitude=[24500.0]).isel(ground_range=[0, 1]).assign_coords(
            ground_range=("ground_range", [0.0, 301e3], ds["ground_range"].attrs)),
        "ground_range spans [0, 301000] m; xbsm supports only [0, 300000] m"),
    "an altitude above the database's highest (550 km)": (
        lambda ds: ds.assign_coords(altitude=("altitude", [1e3, 5e3, 9e3, 12e3, 600e3],
                                              ds["altitude"].attrs)),
        "coordinate altitude spans [1000, 600000] m; xbsm supports only [2, 550000] m"),
    "a wavelength beyond 14 um": (
        lambda ds: ds.assign_coords(wavelength=("wavelength", np.r_[
            ds["wavelength"].values[:-1], 14.5e-6], ds["wavelength"].attrs)),
        "coordinate wavelength spans [3e-07, 1.45e-05] m; xbsm supports only "
        "[3e-07, 1.4e-05] m"),
    "a single wavelength": (
        lambda ds: ds.isel(wavelength=[100]),
        "coordinate wavelength has 1 value(s); a band needs at least two"),
    "another reflectance of GRND_RFLT": (
        lambda ds: ds.assign_attrs(surface_reflectance_of_database=0.2),
        "surface_reflectance_of_database is 0.2"),
}


def test_use_database_takes_visibilities_beyond_the_shipped_ones(small, tmp_path):
    # the 23 km tables relabelled 50 km and the 5 km ones 23 km: a file's own visibility
    # range is the scenario's (the shipped 5-23 km limits were lifted)
    relabelled = small.assign_coords(visibility=("visibility", [50.0, 23.0],
                                                 small["visibility"].attrs))
    path = atm.write_database(relabelled, tmp_path / "fifty.nc")
    with atm.use_database(path):
        scenario = xbsm.scenario(altitude=9000.0, ground_range=5000.0, visibility=30.0)
        out = atm.atmosphere_at(9000.0, 5000.0, scenario["visibility"])
        assert int(out["flags"]) == xbsm.flags.flag("visibility_interpolated")
        with pytest.raises(ValueError, match=r"within \[23, 50\] km"):
            xbsm.scenario(altitude=9000.0, ground_range=5000.0, visibility=10.0)


@pytest.mark.parametrize("case", list(UNSUPPORTED))
def test_use_database_refuses_what_the_code_does_not_support_yet(small, case, tmp_path):
    change, message = UNSUPPORTED[case]
    path = atm.write_database(change(small), tmp_path / "other.nc")
    with pytest.raises(ValueError) as err, atm.use_database(path):
        pass
    assert message in str(err.value)
    assert atm.database_path() != path.resolve()


def test_the_supported_reflectance_is_the_radiometrys_and_the_shipped_files(shipped):
    assert atm.SURFACE_REFLECTANCE == xbsm.radiometry.DATABASE_REFLECTANCE
    assert shipped.attrs["surface_reflectance_of_database"] == atm.SURFACE_REFLECTANCE


def test_use_database_refuses_a_missing_file_and_a_non_database(tmp_path):
    with pytest.raises(FileNotFoundError, match="atmosphere database not found"), \
            atm.use_database(tmp_path / "nothing.nc"):
        pass
    bad = tmp_path / "bad.nc"
    bad.write_text("not netcdf")
    with pytest.raises(ValueError, match="is not an xbsm atmosphere database"), \
            atm.use_database(bad):
        pass
