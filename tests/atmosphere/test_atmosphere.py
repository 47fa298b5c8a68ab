"""Tests of xbsm.atmosphere: the database cube and per-scenario interpolation."""

from __future__ import annotations

import hashlib
import inspect
import json
import zlib
from pathlib import Path

import dask
import dask.array as da
import netCDF4
import numpy as np
import pytest
import xarray as xr
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.integrate import quad

import xbsm
from xbsm import _chain, geometry
from xbsm import atmosphere as atm
from xbsm.atmosphere._cubic import cubic_increment  # the cubic itself, tested here
from xbsm.atmosphere._profile import profile_of  # the profile itself, tested here
from xbsm.examples import olson_scenario, olson_sensor
from xbsm.flags import FLAGS, has_flag

FIXTURES = Path(__file__).resolve().parents[1] / "fixtures"
IHAZE_TO_VISIBILITY = {1: 23.0, 2: 5.0}


@pytest.fixture(scope="module")
def db():
    return atm.load_database()


def test_database_facts_are_the_files_coordinates(db):
    # xbsm.atmosphere.database states the nodes once (paper Appendix A); params, examples
    # and the flag texts use them: they must be the file's
    assert tuple(db.visibility) == atm.VISIBILITIES
    with netCDF4.Dataset(atm.database_path()) as nc:
        assert tuple(nc["ihaze"][:].tolist()) == atm.IHAZE
    assert tuple(db.altitude) == atm.ALTITUDES and tuple(db.ground_range) == atm.GROUND_RANGES
    assert atm.ALTITUDE_RANGE == (db.altitude[0], db.altitude[-1])
    assert atm.GROUND_RANGE_RANGE == (db.ground_range[0], db.ground_range[-1])
    assert atm.ALTITUDE_GAP == tuple(db.altitude[-2:])
    np.testing.assert_allclose([db.wavelength[0], db.wavelength[-1]],
                               [atm.WAVELENGTH_MIN, atm.WAVELENGTH_MAX], rtol=1e-9)
    assert np.isnan(db.cube[:, -1, 1:]).all()  # above the gap: ground range 0 only


def test_interpolate_database_names_the_rule_it_rejects(db):
    with pytest.raises(ValueError, match="interpolation must be one of"):
        atm.interpolate_database(db, 9000.0, 20e3, 5.0, "cubic")


def test_every_rule_is_a_row_of_the_dispatch_table():
    assert atm.INTERPOLATIONS == tuple(atm.RULES)
    assert all(atm.RULES[name].name == name for name in atm.INTERPOLATIONS)
    line_of_sight = [r.name for r in atm.RULES.values() if r.line_of_sight]
    assert line_of_sight == ["same-elevation", "optical-depth-cubic", "extinction-profile"]


@pytest.fixture(scope="module")
def raw_cube():
    with netCDF4.Dataset(atm.database_path()) as nc:
        nc.set_auto_maskandscale(False)
        return nc["atmosphere"][...]


def _raising_scheduler(*args, **kwargs):
    raise RuntimeError("dask computed something")


# --- the file ---------------------------------------------------------------------------


def test_cube_holds_every_database_spectrum_bit_for_bit_and_nothing_else(raw_cube):
    # tests/fixtures/atmosphere_checksums.json: made by recipes/build_atmosphere.py from
    # the raw .bin files of the pyBSM 0.16.1 wheel
    fixture = json.loads((FIXTURES / "atmosphere_checksums.json").read_text())
    with netCDF4.Dataset(atm.database_path()) as nc:
        ihaze = list(nc["ihaze"][:])
        altitude = list(nc["altitude"][:])
    assert raw_cube.dtype == np.float32
    assert raw_cube.shape == (2, 24, 97, 5, 1371)
    n = 0
    for slab in fixture["slabs"]:
        v, a = ihaze.index(slab["ihaze"]), altitude.index(slab["altitude"])
        k = slab["n_ground_range"]
        present = raw_cube[v, a, :k]
        assert hashlib.sha256(present.tobytes()).hexdigest() == slab["sha256"]
        crcs = [f"{zlib.crc32(spectrum.tobytes()):08x}" for spectrum in present]
        assert crcs == slab["crc32"]
        assert not np.isnan(present).any()
        assert np.isnan(raw_cube[v, a, k:]).all()  # beyond the horizon: nothing
        n += k
    assert n == fixture["n_spectra"] == 3430
    assert np.count_nonzero(~np.isnan(raw_cube[..., 0, 0])) == 3430


def test_coverage_matches_the_database_horizon(db):
    # paper Appendix A / fileDecoder.csv: ranges stop at the horizon of each altitude:
    # 8 ground ranges at 2 m, all 97 from 8 km up to 24.5 km, only nadir at 550 km
    counts = db.present.sum(axis=2)  # (visibility, altitude)
    altitude = list(db.altitude)
    for v in range(2):
        assert counts[v, altitude.index(2.0)] == 8
        for a in (8000.0, 12000.0, 20000.0, 24500.0):
            assert counts[v, altitude.index(a)] == 97
        assert counts[v, altitude.index(550e3)] == 1
    assert counts.sum() == 3430


def test_cube_raw_samples_match_the_database_values(raw_cube):
    fixture = json.loads((FIXTURES / "atmosphere_checksums.json").read_text())
    with netCDF4.Dataset(atm.database_path()) as nc:
        ihaze, alt, gr = (list(nc[n][:]) for n in ("ihaze", "altitude", "ground_range"))
    for s in fixture["samples"]:
        value = raw_cube[ihaze.index(s["ihaze"]), alt.index(s["altitude"]),
                         gr.index(s["ground_range"]), atm.COMPONENTS.index(s["component"]),
                         s["wavelength_index"]]
        assert value.tobytes().hex() == s["float32_hex"]


def test_file_coordinates_units_and_provenance():
    with netCDF4.Dataset(atm.database_path()) as nc:
        assert list(nc["visibility"][:]) == [23.0, 5.0]
        assert nc["visibility"].units == "km"
        assert list(nc["ihaze"][:]) == [1, 2]
        altitude = nc["altitude"][:]
        expected = np.concatenate([[2, 32.5, 75, 150, 225, 500], np.arange(1000, 12001, 1000),
                                   np.arange(14000, 20001, 2000), [24500, 550000]])
        np.testing.assert_array_equal(altitude, expected)  # 32.5 m as in the decoder
        ground_range = nc["ground_range"][:]
        assert ground_range.size == 97 and ground_range[0] == 0 and ground_range[-1] == 3e5
        wavelength = nc["wavelength"][:]
        assert wavelength.dtype == np.float64
        assert np.array_equal(wavelength, 1e-6 * np.linspace(0.3, 14.0, 1371))
        assert all(nc[c].units == "m" for c in ("altitude", "ground_range", "wavelength"))
        assert list(nc["component"][:]) == list(atm.COMPONENTS)
        assert list(nc["component_units"][:]) == ["1"] + ["W sr-1 cm-2 um-1"] * 4
        var = nc["atmosphere"]
        assert var.filters()["zlib"] and var.filters()["shuffle"]
        assert "long_name" in var.ncattrs()
        attrs = nc.__dict__
    assert attrs["Conventions"].startswith("CF-")
    assert "Apache-2.0" in attrs["license"]
    assert "pyBSM 0.16.1" in attrs["source"]
    assert attrs["modtran_version"] == "5.2.1"
    assert attrs["modtran_IDAY"].startswith("236")
    assert attrs["modtran_PARM2"].startswith("50")


def test_atmosphere_at_names_the_database_it_read(tmp_path):
    # its ``source`` attribute comes from the file read (its title and name); it said
    # MODTRAN whatever the file was. A copy retitled as a 6S file says so
    import shutil

    shipped = atm.atmosphere_at(9000.0, 1000.0, 23.0)
    assert shipped.attrs["source"].startswith("MODTRAN 5.2.1 radiative-transfer database of "
                                              "pyBSM 0.16.1")
    assert shipped.attrs["source"].endswith("(atmosphere.nc)")
    copy = tmp_path / "other.nc"
    shutil.copy(atm.database_path(), copy)
    with netCDF4.Dataset(copy, "a") as nc:
        nc.title = "6S tables of a user"
    assert atm.atmosphere_at(9000.0, 1000.0, 23.0, path=copy).attrs["source"] == \
        "6S tables of a user (other.nc)"


# --- open_atmosphere ---------------------------------------------------------------------


def test_open_atmosphere_is_lazy_and_in_si_units_by_pybsms_float32_rule(raw_cube):
    with dask.config.set(scheduler=_raising_scheduler):
        ds = atm.open_atmosphere()
        assert isinstance(ds["atmosphere"].data, da.Array)
        assert list(ds["component_units"].values) == ["1"] + ["W m-2 sr-1 m-1"] * 4
        assert list(ds["ihaze"].values) == [1, 2]
    si = ds["atmosphere"].isel(visibility=1, altitude=6).compute(scheduler="sync").values
    raw = raw_cube[1, 6]
    assert si.dtype == np.float32
    assert np.array_equal(si[:, 0], raw[:, 0], equal_nan=True)  # transmission as stored
    # pyBSM 0.16.1: float32 array / 1e-10 (NumPy 2 keeps float32)
    expected = raw[:, 1:] / np.float32(1e-10)
    assert np.array_equal(si[:, 1:], expected, equal_nan=True)


def test_database_path_reports_where_it_looked(tmp_path):
    with pytest.raises(FileNotFoundError, match="atmosphere database not found"):
        atm.database_path(tmp_path / "missing.nc")


# --- atmosphere_at: nodes, parity, accuracy -------------------------------------------------


@pytest.mark.parametrize("interpolation", atm.INTERPOLATIONS)
def test_every_interpolation_returns_database_nodes_exactly(db, interpolation):
    v, a, g = np.nonzero(db.present)  # all 3430 tables at once
    dim = "table"
    result = atm.atmosphere_at(
        xr.DataArray(db.altitude[a], dims=dim), xr.DataArray(db.ground_range[g], dims=dim),
        xr.DataArray(db.visibility[v], dims=dim), interpolation=interpolation)
    expected = db.cube[v, a, g].astype(np.float64)  # (table, component, wavelength)
    for c, name in enumerate(atm.VARIABLES):
        assert np.array_equal(result[name].transpose(dim, "wavelength").values,
                              expected[:, c])
    # only the 550 km tables are flagged: inconsistent with the 24.5 km ones
    inconsistent = np.where(db.altitude[a] > 24.5e3, FLAGS["atmosphere_inconsistent"][0], 0)
    assert np.array_equal(result["flags"].values, inconsistent)


def test_linear_reproduces_pybsm_load_database_atmosphere_bit_for_bit():
    # tests/fixtures/atmosphere_pybsm_linear.json: pybsm.utils.load_database_atmosphere
    # of pyBSM 0.16.1 (NumPy 2.3.5), made by recipes/fixtures/pybsm_reference_atmosphere.py
    fixture = json.loads((FIXTURES / "atmosphere_pybsm_linear.json").read_text())
    rows = fixture["wavelength_index"]
    for p in fixture["points"]:
        out = atm.atmosphere_at(p["altitude"], p["ground_range"],
                                IHAZE_TO_VISIBILITY[p["ihaze"]], interpolation="linear")
        ours = np.stack([out[name].values[rows] for name in atm.VARIABLES], axis=1)
        ref = np.array([[float.fromhex(x) for x in row] for row in p["values_hex"]])
        assert np.array_equal(ours, ref), p


def _leave_one_out(db, v, a, g, axis, rule, log_coordinate=False):
    """Rebuild table (v, a, g) from its two neighbours along ``axis``."""
    nodes = db.ground_range if axis == "ground_range" else db.altitude
    i = g if axis == "ground_range" else a
    lo, hi = ((v, a, g - 1), (v, a, g + 1)) if axis == "ground_range" else \
        ((v, a - 1, g), (v, a + 1, g))
    x = np.log(nodes[i - 1:i + 2]) if log_coordinate else nodes[i - 1:i + 2]
    w = np.array([(x[1] - x[0]) / (x[2] - x[0])])
    low, high = db.cube[lo].astype(float)[None], db.cube[hi].astype(float)[None]
    return atm.rules.interpolate(low, high, w, rule)[0]


def _window(wavelength, lo, hi):
    """Slice of the database wavelengths in [lo, hi]."""
    index = np.flatnonzero((wavelength >= lo) & (wavelength <= hi))
    return slice(int(index[0]), int(index[-1]) + 1)


def _index(nodes, value):
    return int(np.flatnonzero(nodes == value)[0])


def test_leave_one_out_ground_range_log_beats_linear_as_documented(db):
    # docs/atmosphere.md (recipes/evidence/atmosphere_leave_one_out.py); pyBSM notes 2.1:
    # ihaze 2, altitude 1 km, 11 km rebuilt from the 10 and 12 km tables
    v, a, g = 1, _index(db.altitude, 1000.0), _index(db.ground_range, 11000.0)
    w045, w060 = 15, 30  # 0.45 um, 0.60 um
    cols = [w045, w060]
    comps = [0, 4]  # TRANS, GRND_RFLT (the path radiances are 0 at 0.45 um)
    true = db.cube[v, a, g][np.ix_(comps, cols)].astype(float)
    lin = _leave_one_out(db, v, a, g, "ground_range", "linear")[np.ix_(comps, cols)] / true - 1
    log = _leave_one_out(db, v, a, g, "ground_range", "log")[np.ix_(comps, cols)] / true - 1
    w045, w060 = 0, 1
    assert db.wavelength[cols[0]] == pytest.approx(0.45e-6)
    assert db.wavelength[cols[1]] == pytest.approx(0.6e-6)
    assert lin[0, w045] == pytest.approx(0.4829, abs=5e-4)  # T(0.45 um) +48 %
    assert lin[0, w060] == pytest.approx(0.2536, abs=5e-4)  # T(0.6 um) +25 %
    assert lin[1, w060] == pytest.approx(0.2534, abs=5e-4)  # GRND_RFLT +25 %
    assert np.all(np.abs(log) < 2e-3)  # log-linear: within 0.2 %


def test_leave_one_out_altitude_log_value_log_altitude_beats_linear(db):
    # TRANS at 0.6 um over every interior altitude table (<= 18 km) and ground range,
    # both visibilities; values below 1e-3 of the spectrum maximum are not scored
    errors = {"linear": [], "log-linear": []}
    for v in range(2):
        for a in range(1, 21):
            for g in range(97):
                if not (db.present[v, a - 1, g] and db.present[v, a + 1, g]
                        and db.present[v, a, g]):
                    continue
                true = db.cube[v, a, g, 0].astype(float)
                if true[30] < 1e-3 * true.max():
                    continue
                lin = _leave_one_out(db, v, a, g, "altitude", "linear")[0, 30]
                log = _leave_one_out(db, v, a, g, "altitude", "log", True)[0, 30]
                errors["linear"].append(abs(lin / true[30] - 1))
                errors["log-linear"].append(abs(log / true[30] - 1))
    lin, log = (np.array(errors[k]) for k in ("linear", "log-linear"))
    assert np.percentile(log, 95) < 0.5 * np.percentile(lin, 95)
    assert np.median(log) < 2.0 * np.median(lin)


def test_log_linear_between_nodes_is_bounded_by_the_bracketing_tables(db):
    out = atm.atmosphere_at(1500.0, 10500.0, 5.0, interpolation="log-linear")
    corners = np.stack([db.cube[1, a, g].astype(float) for a in (6, 7) for g in (12, 13)])
    values = np.stack([out[n].values for n in atm.VARIABLES])
    # low * exp(w * log(high / low)) may round one ulp past a bracketing value
    low, high = corners.min(axis=0), corners.max(axis=0)
    assert np.all(values >= low * (1 - 1e-12)) and np.all(values <= high * (1 + 1e-12))


# --- same-elevation -------------------------------------------------------------------


def test_ground_range_at_elevation_inverts_the_curved_earth_geometry():
    # closed form: xbsm.geometry gives the target elevation of (ground range, altitude);
    # the inverse must return the ground range
    ground_range = np.array([0.0, 100.0, 5e3, 60e3, 150e3, 290e3])
    for altitude in (2.0, 500.0, 3000.0, 20000.0):
        g = ground_range[ground_range < 0.95 * np.sqrt(2 * 6378.164e3 * altitude)]
        e = geometry.target_elevation_angle(geometry.slant_range(g, altitude), altitude)
        back = geometry.ground_range_at_elevation_kernel(np.sin(e), np.cos(e), altitude)
        np.testing.assert_allclose(back, g, rtol=1e-9, atol=1e-6)


def _altitude_leave_one_out(db, rule, wavelength_index, components=(0, 4)):
    """|rebuilt / true - 1| of ``components`` (default TRANS and GRND_RFLT, pooled): each
    interior table up to 18 km rebuilt by the package's kernel from a database without it."""
    errors = []
    for a in range(1, 21):
        keep = db.present[:, a] & db.present[:, a - 1] & db.present[:, a + 1]
        v, g = np.nonzero(keep)
        thin = atm.Database(
            visibility=db.visibility, altitude=np.delete(db.altitude, a),
            ground_range=db.ground_range, wavelength=db.wavelength[wavelength_index],
            cube=np.delete(db.cube[..., wavelength_index], a, axis=1),
            present=np.delete(db.present, a, axis=1))
        est = atm.interpolate_database(thin, np.full(v.size, db.altitude[a]),
                                        db.ground_range[g], db.visibility[v], rule, slice(None))
        true = db.cube[v, a, g].astype(float)
        for c in components:
            t = true[:, c, wavelength_index]
            scored = t >= 1e-3 * true[:, c].max(axis=1, keepdims=True)
            errors.append(np.abs(est[:, c][scored] / t[scored] - 1))
    return np.concatenate(errors)


@pytest.mark.parametrize(("old_rule", "new_rule", "bound"), [
    # recipes/evidence/atmosphere_leave_one_out.py (docs/atmosphere.md), 6 wavelengths, both
    # visibilities, TRANS and GRND_RFLT: same-elevation median 0.36 % against log-linear's
    # 0.90 %, 95th percentile 6.6 % against 13.0 %; optical-depth-cubic 0.08 % and 2.8 %
    ("log-linear", "same-elevation", 0.07),
    ("same-elevation", "optical-depth-cubic", 0.035),
])
def test_each_line_of_sight_rule_beats_the_one_before_in_the_altitude_leave_one_out(
        db, old_rule, new_rule, bound):
    wavelengths = [int(np.argmin(np.abs(db.wavelength - w * 1e-6)))
                   for w in (0.45, 0.6, 1.0, 2.2, 4.0, 10.0)]
    old = _altitude_leave_one_out(db, old_rule, wavelengths)
    new = _altitude_leave_one_out(db, new_rule, wavelengths)
    assert old.size == new.size
    assert np.median(new) < 0.5 * np.median(old)
    assert np.percentile(new, 95) < 0.6 * np.percentile(old, 95)
    assert np.percentile(new, 95) < bound


@pytest.mark.parametrize("component", ["TRANS", "SURF_EMIS", "GRND_RFLT"])
def test_extinction_profile_meets_three_percent_in_the_altitude_leave_one_out(db, component):
    # issue 12's target: each interior table rebuilt from the others (neighbours twice the
    # real spacing apart), 95th percentile of |relative error| at most 3 % for each
    # attenuated component, medians no worse than optical-depth-cubic's. Measured
    # (recipes/evidence/atmosphere_leave_one_out.py): TRANS 1.9 %, SURF_EMIS 2.7 %, GRND_RFLT 2.0 %
    # (optical-depth-cubic 2.8 %, 4.0 %, 3.1 %); medians 0.06-0.09 % (0.08-0.12 %)
    wavelengths = [int(np.argmin(np.abs(db.wavelength - w * 1e-6)))
                   for w in (0.45, 0.6, 1.0, 2.2, 4.0, 10.0)]
    c = atm.COMPONENTS.index(component)
    cubic = _altitude_leave_one_out(db, "optical-depth-cubic", wavelengths, (c,))
    profile = _altitude_leave_one_out(db, "extinction-profile", wavelengths, (c,))
    assert profile.size == cubic.size > 5000
    assert np.percentile(profile, 95) <= 0.03
    assert np.median(profile) <= np.median(cubic)


@pytest.mark.parametrize(("altitude", "visibility", "wavelength"), [
    (1500.0, 5.0, 0.6e-6), (700.0, 23.0, 1.0e-6), (12500.0, 23.0, 10.0e-6)])
def test_extinction_profile_at_nadir_is_the_profile_integral(db, altitude, visibility,
                                                            wavelength):
    # straight down, the rule's optical depth above the lower table is the integral of the
    # interval's extinction profile (here by scipy's adaptive quad, not the kernel's
    # Gauss-Legendre rule), and the profile's mean over the interval is the one the two
    # tables' nadir transmittances give
    profile = profile_of(db)
    w = int(np.argmin(np.abs(db.wavelength - wavelength)))
    v = int(np.flatnonzero(db.visibility == visibility)[0])
    lower = int(np.searchsorted(db.altitude, altitude)) - 1
    interval = lower + 1  # the profile's intervals start at the ground
    assert profile.heights[interval] == db.altitude[lower]
    slope, bulge, mean, exists = (getattr(profile, f)[v, interval, w]
                                  for f in ("slope", "bulge", "mean", "exists"))
    assert exists

    def shape(s):
        return np.exp(slope * s + bulge * s * (1.0 - s))

    whole = quad(shape, 0.0, 1.0, epsabs=0, epsrel=1e-13)[0]
    np.testing.assert_allclose(whole, mean, rtol=1e-12)
    s = (altitude - db.altitude[lower]) / (db.altitude[lower + 1] - db.altitude[lower])
    fraction = quad(shape, 0.0, s, epsabs=0, epsrel=1e-13)[0] / whole
    depth = -np.log(db.cube[v, [lower, lower + 1], 0, 0, w].astype(np.float64))
    out = atm.atmosphere_at(altitude, 0.0, visibility, interpolation="extinction-profile",
                            wavelength_bounds=(db.wavelength[w], db.wavelength[w]))
    np.testing.assert_allclose(out["transmission"].values,
                               [np.exp(-(depth[0] + fraction * (depth[1] - depth[0])))],
                               rtol=1e-12)


def test_cubic_increment_where_every_outer_node_is_usable_is_the_general_rule():
    # with every outer node usable the cubic takes the interior slopes alone; the general
    # rule (a choice per entry, here with one entry's outer nodes unusable) gives every
    # other entry the same bits, and the unusable entry its secant slopes
    rng = np.random.default_rng(11)
    x = np.cumsum(rng.uniform(0.1, 1.0, (4, 50)), axis=0)
    y = np.cumsum(rng.uniform(-0.3, 1.0, (4, 50)), axis=0)  # some secants change sign
    t = rng.uniform(0.0, 1.0, 50)
    usable = np.ones(50, dtype=bool)
    some = usable.copy()
    some[0] = False
    shortcut = cubic_increment(y, x, t, usable, usable)
    general = cubic_increment(y, x, t, some, some)
    np.testing.assert_array_equal(shortcut[1:], general[1:])
    # closed form of the secant-slope Hermite step: linear in t, (y2 - y1) t
    np.testing.assert_allclose(general[0], (y[2, 0] - y[1, 0]) * t[0], rtol=1e-14)
    assert shortcut[0] != general[0]


def test_extinction_profile_factor_shared_across_ground_ranges_equals_each_its_own(db):
    # the nadir factor depends on (visibility, altitude) only and is computed once per
    # distinct pair: a sweep over ground range gives what each scenario gives alone
    rng = np.random.default_rng(5)
    altitude = np.repeat([150.0, 1500.0, 2500.0, 7300.0], 25)
    ground_range = rng.uniform(0.0, 60e3, altitude.size)
    visibility = np.tile([5.0, 23.0], altitude.size // 2)
    window = _window(db.wavelength, 0.4e-6, 2.5e-6)
    together = atm.interpolate_database(db, altitude, ground_range, visibility,
                                         "extinction-profile", window)
    alone = np.stack([atm.interpolate_database(db, altitude[i:i + 1], ground_range[i:i + 1],
                                                visibility[i:i + 1], "extinction-profile",
                                                window)[0] for i in range(altitude.size)])
    np.testing.assert_allclose(together, alone, rtol=1e-13, atol=0)
    cubic = atm.interpolate_database(db, altitude, ground_range, visibility,
                                      "optical-depth-cubic", window)
    assert not np.allclose(together, cubic, rtol=1e-3)  # the factor is not 1


def test_same_elevation_equals_log_linear_at_database_altitudes(db):
    # on an altitude node the altitude weight is 0 and the node's own ground range is
    # used, so both rules interpolate the same table in ground range, bit for bit
    ground_range = xr.DataArray(np.linspace(0.0, 150e3, 61), dims="s")
    for altitude in (2.0, 1000.0, 5000.0):
        old = atm.atmosphere_at(altitude, ground_range, 5.0, interpolation="log-linear")
        new = atm.atmosphere_at(altitude, ground_range, 5.0, interpolation="same-elevation")
        # identical but for the rule's name (xarray 2023.12, the floor, has no drop_attrs)
        xr.testing.assert_identical(old, new.assign_attrs(interpolation="log-linear"))


def test_same_elevation_falls_back_to_log_linear_beyond_a_tables_coverage_and_flags_it():
    # at 7.5 km and 295 km the 8 km table would be needed at the same elevation beyond
    # 300 km, the end of the database
    old = atm.atmosphere_at(7500.0, 295e3, 23.0, interpolation="log-linear")
    new = atm.atmosphere_at(7500.0, 295e3, 23.0, interpolation="same-elevation")
    assert int(new["flags"]) == FLAGS["atmosphere_fallback"][0] and int(old["flags"]) == 0
    for name in atm.VARIABLES:
        assert np.isfinite(new[name]).all()
        np.testing.assert_array_equal(new[name].values, old[name].values)
    inside = atm.atmosphere_at(7500.0, 200e3, 23.0, interpolation="same-elevation")
    assert int(inside["flags"]) == 0


# --- optical-depth-cubic ---------------------------------------------------------------


@pytest.mark.parametrize(("removed", "visibility", "ground_range"), [
    (4, 5.0, 0.0), (8, 23.0, 20e3), (12, 5.0, 60e3), (16, 23.0, 100e3)])
def test_optical_depth_cubic_rebuilds_a_left_out_table_better_than_same_elevation(
        db, removed, visibility, ground_range):
    # one table left out: its TRANS rebuilt from the others over 0.4-2.5 um
    window = _window(db.wavelength, 0.4e-6, 2.5e-6)
    thin = atm.Database(
        visibility=db.visibility, altitude=np.delete(db.altitude, removed),
        ground_range=db.ground_range, wavelength=db.wavelength[window],
        cube=np.delete(db.cube[..., window], removed, axis=1),
        present=np.delete(db.present, removed, axis=1))
    altitude = np.array([db.altitude[removed]])
    v = int(np.flatnonzero(db.visibility == visibility)[0])
    g = int(np.flatnonzero(db.ground_range == ground_range)[0])
    assert db.present[v, removed, g]
    true = db.cube[v, removed, g, 0, window].astype(float)

    def error(rule):
        est = atm.interpolate_database(thin, altitude, np.array([ground_range]),
                                        np.array([visibility]), rule, slice(None))[0, 0]
        keep = true > 1e-3
        return np.abs(est[keep] / true[keep] - 1)

    old, new = error("same-elevation"), error("optical-depth-cubic")
    assert np.all(np.isfinite(new))
    assert np.median(new) < np.median(old) and new.max() < old.max()


@pytest.mark.parametrize("rule", ["optical-depth-cubic", "extinction-profile"])
def test_cubic_rules_equal_log_linear_at_database_altitudes(rule):
    ground_range = xr.DataArray(np.linspace(0.0, 150e3, 61), dims="s")
    for altitude in (2.0, 32.5, 1000.0, 5000.0, 20000.0, 24500.0):
        old = atm.atmosphere_at(altitude, ground_range, 5.0, interpolation="log-linear")
        new = atm.atmosphere_at(altitude, ground_range, 5.0, interpolation=rule)
        xr.testing.assert_identical(old, new.assign_attrs(interpolation="log-linear"))


@pytest.mark.parametrize("rule", ["optical-depth-cubic", "extinction-profile"])
def test_cubic_rules_fall_back_as_same_elevation_does_and_flag_it(rule):
    # at 7.5 km and 295 km the 8 km table would be needed beyond 300 km: log-linear
    old = atm.atmosphere_at(7500.0, 295e3, 23.0, interpolation="log-linear")
    new = atm.atmosphere_at(7500.0, 295e3, 23.0, interpolation=rule)
    assert int(new["flags"]) == FLAGS["atmosphere_fallback"][0]
    for name in atm.VARIABLES:
        assert np.isfinite(new[name]).all()
        np.testing.assert_array_equal(new[name].values, old[name].values)
    # the flags are same-elevation's everywhere, and so are the path radiances
    rng = np.random.default_rng(12)
    altitude = xr.DataArray(np.exp(rng.uniform(np.log(2.0), np.log(40e3), 400)), dims="s")
    ground_range = xr.DataArray(rng.uniform(0.0, 300e3, 400), dims="s")
    bounds = (0.4e-6, 1e-6)
    cubic = atm.atmosphere_at(altitude, ground_range, 5.0, interpolation=rule,
                              wavelength_bounds=bounds)
    same = atm.atmosphere_at(altitude, ground_range, 5.0, interpolation="same-elevation",
                             wavelength_bounds=bounds)
    assert has_flag(cubic["flags"], "atmosphere_fallback").any()
    np.testing.assert_array_equal(cubic["flags"], same["flags"])
    for name in ("path_thermal", "solar_scatter"):
        np.testing.assert_array_equal(cubic[name], same[name])
    beyond = has_flag(cubic["flags"], "beyond_database").values
    for name in atm.VARIABLES:
        assert np.isfinite(cubic[name].values[~beyond]).all()


@pytest.mark.parametrize("rule", ["optical-depth-cubic", "extinction-profile"])
@pytest.mark.parametrize("visibility", [23.0, 5.0])
def test_cubic_rules_are_monotone_along_a_long_low_line_of_sight(db, rule, visibility):
    # sensors along one line of sight at 2 degrees elevation, 2 m to 8 km (slant up to
    # 220 km): the transmittance falls with altitude between nodes and stays between
    # the values at the nodes. extinction-profile scales the monotone cubic's increment by
    # a factor that varies with altitude, which can reverse a step by a little: measured
    # at most 1.2e-3 of the interval's largest value, in absorption bands where TRANS is
    # 1e-7 to 1e-2 (0.84-2.48 um); 2e-3 allowed
    slack = 1e-12 if rule == "optical-depth-cubic" else 2e-3
    elevation = np.radians(2.0)
    nodes = db.altitude[db.altitude <= 8000.0]
    altitude = np.unique(np.concatenate(
        [nodes, *(np.linspace(a, b, 41) for a, b in zip(nodes[:-1], nodes[1:], strict=True))]))
    ground_range = geometry.ground_range_at_elevation_kernel(np.sin(elevation), np.cos(elevation),
                                                  altitude)
    out = atm.atmosphere_at(xr.DataArray(altitude, dims="s"),
                            xr.DataArray(ground_range, dims="s"), visibility,
                            interpolation=rule, wavelength_bounds=(0.4e-6, 2.5e-6))
    assert not out["flags"].any()
    trans = out["transmission"].transpose("s", "wavelength").values
    for a, b in zip(nodes[:-1], nodes[1:], strict=True):
        inside = trans[(altitude >= a) & (altitude <= b)]
        ends = inside[[0, -1]]
        steps = np.diff(inside, axis=0)
        rising = ends[1] >= ends[0]
        tol = slack * inside.max(axis=0)
        assert np.all(np.where(rising, steps >= -tol, steps <= tol))
        assert np.all(inside >= ends.min(axis=0) - tol)
        assert np.all(inside <= ends.max(axis=0) + tol)


# --- atmosphere_at: low altitudes, horizon, gap ---------------------------------------------


@pytest.mark.parametrize("altitude", [2.5, 10.0, 32.55, 50.0, 74.9])
def test_altitudes_between_2_and_75_m_interpolate(db, altitude):
    out = atm.atmosphere_at(altitude, 1000.0, 23.0, interpolation="linear")
    assert np.isfinite(out["transmission"]).all() and int(out["flags"]) == 0
    nodes = db.altitude
    a = int(np.searchsorted(nodes, altitude)) - 1
    w = (altitude - nodes[a]) / (nodes[a + 1] - nodes[a])
    g = _index(db.ground_range, 1000.0)
    low, high = (db.cube[0, i, g, 0].astype(np.float64) for i in (a, a + 1))
    # pyBSM's expression in float64 (both sides cast first: numpy 1.x value-based casting
    # would keep w * float32 in float32); exact because the operations and order are the same
    np.testing.assert_array_equal(out["transmission"].values, (1 - w) * low + w * high)


def test_beyond_the_horizon_is_nan_and_flagged():
    # no 1000 m table at 150 km ground range (pyBSM 0.16.1 raises IndexError here)
    out = atm.atmosphere_at(1500.0, 150e3, 23.0)
    assert np.isnan(out["transmission"]).all() and np.isnan(out["path_thermal"]).all()
    assert bool(has_flag(out["flags"], "beyond_database"))
    assert out["flags"].attrs["flag_meanings"].split()[0] == "beyond_database"


def test_altitudes_above_24_5_km_interpolate_only_at_ground_range_zero(db):
    out = atm.atmosphere_at(xr.DataArray([100e3, 100e3, 550e3, 550e3], dims="s"),
                            xr.DataArray([0.0, 1000.0, 0.0, 1000.0], dims="s"), 23.0)
    t = out["transmission"].transpose("s", "wavelength").values
    flags = out["flags"].values
    assert np.isfinite(t[0]).all() and np.isnan(t[1]).all()
    assert np.array_equal(t[2], db.cube[0, -1, 0, 0].astype(float))  # 550 km node
    assert np.isnan(t[3]).all()
    sparse, beyond = FLAGS["atmosphere_sparse"][0], FLAGS["beyond_database"][0]
    bad = FLAGS["atmosphere_inconsistent"][0]  # every altitude above 24.5 km
    assert list(flags) == [sparse | bad, sparse | beyond | bad, bad, beyond | bad]


# --- atmosphere_at: errors -------------------------------------------------------------


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"altitude": 1.0}, r"altitude must be within \[2, 550000\] m"),
        ({"altitude": 600e3}, r"altitude must be within \[2, 550000\] m"),
        ({"altitude": np.nan}, r"altitude must be within"),
        ({"ground_range": -1.0}, r"ground_range must be within \[0, 300000\] m"),
        ({"ground_range": 301e3}, r"ground_range must be within \[0, 300000\] m"),
        ({"visibility": 2.0}, r"visibility must be within \[5, 23\] km: the atmosphere "
                              r"database holds 23, 5 km"),
        ({"visibility": 50.0}, r"visibility must be within \[5, 23\] km"),
        ({"interpolation": "cubic"}, r"interpolation must be one of"),
        ({"altitude": 1500.0, "interpolation": "exact"},
         r"altitude=1500.0 m is not a database node .* nearest nodes: 1000 and 2000 m"),
        ({"ground_range": 10500.0, "interpolation": "exact"},
         r"ground_range=10500.0 m is not a database node .* 10000 and 11000 m"),
        ({"wavelength_bounds": (20e-6, 30e-6)}, r"wavelength_bounds must contain"),
    ],
)
def test_invalid_input_raises_value_error_naming_the_parameter(kwargs, message):
    args = {"altitude": 1000.0, "ground_range": 10000.0, "visibility": 23.0, **kwargs}
    with pytest.raises(ValueError, match=message):
        atm.atmosphere_at(**args)


# --- atmosphere_at: the default rule is the model's -----------------------------------------

# off-node in altitude and ground range, both visibilities, inside every horizon
_OFF_NODE = {"altitude": [1234.5, 7321.0, 15500.0], "ground_range": [3456.7, 41234.0, 88765.0],
             "visibility": [23.0, 5.0, 23.0]}


def _chain_atmosphere(scenario):
    """The band atmosphere ``xbsm.snr`` uses by default on the Olson sensor, by wavelength."""
    m = xbsm.method(inspect.signature(xbsm.snr).parameters["method"].default)
    ap = _chain.applier(olson_sensor(), scenario)
    with ap.errors():
        out = ap.atmosphere(m)
    if isinstance(out, xr.Dataset):  # the labelled applier: scenario dims first
        out = out.transpose(..., "wavelength")
    return {name: np.asarray(out[name]) for name in ("wavelength", *atm.VARIABLES)}


def _default_at_chain_wavelengths(chain, altitude, ground_range, visibility):
    """``atmosphere_at`` with its default rule at the chain's interior database wavelengths."""
    wl = chain["wavelength"]
    out = atm.atmosphere_at(altitude, ground_range, visibility, wavelength_bounds=(wl[1], wl[-2]))
    np.testing.assert_array_equal(out["wavelength"].values, wl[1:-1])  # database samples
    return out


def test_default_rule_is_the_one_snr_uses_on_single_off_node_scenarios():
    # issue 22: atmosphere_at defaulted to "log-linear" while xbsm.snr used the
    # "extinction-profile" of its default preset, so radiometry built from atmosphere_at
    # did not match xbsm.snr; the chain's direct applier runs one scenario
    for altitude, ground_range, visibility in zip(*_OFF_NODE.values(), strict=True):
        scenario = olson_scenario(altitude=altitude, ground_range=ground_range,
                                  visibility=visibility)
        assert isinstance(_chain.applier(olson_sensor(), scenario), _chain.Direct)
        chain = _chain_atmosphere(scenario)
        out = _default_at_chain_wavelengths(chain, altitude, ground_range, visibility)
        old = atm.atmosphere_at(altitude, ground_range, visibility, interpolation="log-linear",
                                wavelength_bounds=(chain["wavelength"][1],
                                                   chain["wavelength"][-2]))
        for name in atm.VARIABLES:
            np.testing.assert_allclose(out[name].values, chain[name][1:-1], rtol=1e-13, atol=0,
                                       err_msg=name)
        # the scenarios tell the rules apart: the old default would fail here
        assert not np.allclose(old["transmission"].values, chain["transmission"][1:-1],
                               rtol=1e-6, atol=0)
        assert out.attrs["interpolation"] == xbsm.method().atmosphere_interpolation


def test_default_rule_is_the_one_snr_uses_on_a_sweep():
    # the labelled applier (a sweep over dim "case") reads the same rule
    case = {name: xr.DataArray(values, dims="case") for name, values in _OFF_NODE.items()}
    scenario = olson_scenario(**case)
    assert isinstance(_chain.applier(olson_sensor(), scenario), _chain.Labelled)
    chain = _chain_atmosphere(scenario)
    out = _default_at_chain_wavelengths(chain, *case.values())
    for name in atm.VARIABLES:
        np.testing.assert_allclose(out[name].transpose("case", "wavelength").values,
                                   chain[name][:, 1:-1], rtol=1e-13, atol=0, err_msg=name)


# --- atmosphere_at: broadcasting, band selection, laziness -------------------------------------


def test_sweep_dimensions_named_like_the_cube_dimensions():
    ground_range = xr.DataArray(np.linspace(0.0, 20e3, 1000), dims="ground_range")
    visibility = xr.DataArray([5.0, 23.0], dims="visibility")
    out = atm.atmosphere_at(5000.0, ground_range.assign_coords(ground_range=ground_range),
                            visibility, wavelength_bounds=(0.4e-6, 0.7e-6))
    t = out["transmission"]
    assert set(t.dims) == {"ground_range", "visibility", "wavelength"}
    assert t.sizes == {"ground_range": 1000, "visibility": 2, "wavelength": 31}
    np.testing.assert_array_equal(t["ground_range"].values, ground_range.values)
    assert out["flags"].dims == ("ground_range", "visibility")
    single = atm.atmosphere_at(5000.0, float(ground_range[123]), 23.0,
                               wavelength_bounds=(0.4e-6, 0.7e-6))
    np.testing.assert_array_equal(t.isel(ground_range=123, visibility=1).values,
                                  single["transmission"].values)
    assert t.attrs == {"units": "1", "long_name": "atmospheric transmittance along the path"}
    assert out["path_thermal"].attrs["units"] == "W m-2 sr-1 m-1"
    assert out["wavelength"].attrs["units"] == "m"


def test_altitude_sweep_named_altitude():
    altitude = xr.DataArray([2.0, 50.0, 1234.5, 24500.0], dims="altitude")
    out = atm.atmosphere_at(altitude, 0.0, 5.0)
    assert out["solar_scatter"].dims == ("altitude", "wavelength")
    assert np.isfinite(out["solar_scatter"]).all()


def test_wavelength_bounds_select_by_exact_float_comparison_like_pybsm(db):
    full = atm.atmosphere_at(3000.0, 7000.0, 23.0)
    # 0.503 um snaps up to the 0.51 um sample; the float 0.6e-6 equals the sample
    band = atm.atmosphere_at(3000.0, 7000.0, 23.0, wavelength_bounds=(0.503e-6, 0.6e-6))
    keep = (db.wavelength >= 0.503e-6) & (db.wavelength <= 0.6e-6)
    np.testing.assert_array_equal(band["wavelength"].values, db.wavelength[keep])
    assert band.sizes["wavelength"] == 10
    for name in atm.VARIABLES:
        np.testing.assert_array_equal(band[name].values, full[name].values[keep])


def test_dask_inputs_stay_lazy_and_equal_eager():
    rng = np.random.default_rng(1)
    altitude = xr.DataArray(rng.uniform(2.0, 20e3, 40), dims="scenario")
    ground_range = xr.DataArray(rng.uniform(0.0, 40e3, 40), dims="scenario")
    visibility = xr.DataArray([23.0, 5.0], dims="visibility")
    bounds = (3e-6, 5e-6)
    eager = atm.atmosphere_at(altitude, ground_range, visibility, wavelength_bounds=bounds)
    with dask.config.set(scheduler=_raising_scheduler):
        lazy = atm.atmosphere_at(altitude.chunk(scenario=7), ground_range.chunk(scenario=7),
                                 visibility, wavelength_bounds=bounds)
        assert all(isinstance(lazy[name].data, da.Array) for name in lazy.data_vars)
    computed = lazy.compute(scheduler="sync")
    # the same kernel on other block shapes: equal to rounding (numpy's SIMD exp/log may
    # take another path on a different array length), with identical labels and metadata
    xr.testing.assert_allclose(computed, eager, rtol=1e-14, atol=0)
    xr.testing.assert_identical(computed.drop_vars(list(computed.data_vars)),
                                eager.drop_vars(list(eager.data_vars)))
    for name in eager.data_vars:
        np.testing.assert_equal(computed[name].attrs, eager[name].attrs)


def test_dask_inputs_outside_the_domain_raise_when_computed():
    altitude = xr.DataArray([1000.0, 1.0], dims="s").chunk(s=1)
    with dask.config.set(scheduler=_raising_scheduler):
        out = atm.atmosphere_at(altitude, 0.0, 23.0)
    with pytest.raises(ValueError, match="altitude must be within"):
        out["transmission"].compute(scheduler="sync")


# --- properties ------------------------------------------------------------------------


@settings(max_examples=60, deadline=None)
@given(
    altitude=st.floats(2.0, 24500.0),
    ground_range=st.floats(0.0, 300e3),
    visibility=st.sampled_from([5.0, 23.0]),
    interpolation=st.sampled_from(["linear", "log-linear", "same-elevation",
                                   "optical-depth-cubic", "extinction-profile"]),
)
def test_values_finite_where_unflagged_and_nan_where_flagged(
        altitude, ground_range, visibility, interpolation):
    out = atm.atmosphere_at(altitude, ground_range, visibility, interpolation=interpolation,
                            wavelength_bounds=(0.4e-6, 1e-6))
    beyond = bool(has_flag(out["flags"], "beyond_database"))
    for name in atm.VARIABLES:
        values = out[name].values
        if beyond:
            assert np.isnan(values).all()
        else:
            # exact: both rules combine non-negative tables with non-negative weights
            assert np.isfinite(values).all() and (values >= 0).all()
    if not beyond:
        assert (out["transmission"] <= 1).all()
