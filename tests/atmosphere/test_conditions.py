"""Conditions as dimensions: visibility interpolated in extinction, other conditions selected.

The interpolation rule is checked on synthetic cubes built with ``from_tables`` whose
optical depth is exactly linear in 1/visibility (Beer-Lambert with an extinction that
follows Koschmieder's ``3.912 / V``): transmittances are powers of two, so the expected
value at any visibility is a closed form, independent of the code. Radiances are stored
as powers of two times float32(1e-10), so the reader's SI values are exact powers of two.
"""

import numpy as np
import pytest
import xarray as xr

import xbsm
import xbsm.atmosphere as atm
from xbsm import study
from xbsm.examples import olson_scenario, olson_sensor
from xbsm.flags import flag

VISIBILITIES = np.array([20.0, 10.0, 5.0])  # km: 1/V = 0.05, 0.1, 0.2
ALTITUDES = np.array([1000.0, 2000.0, 5000.0])
GROUND_RANGES = np.array([0.0, 1000.0, 2000.0, 5000.0])
WAVELENGTHS = np.arange(0.5e-6, 0.9001e-6, 0.05e-6)
_D = np.float32(1e-10)  # the reader's divisor: raw W sr-1 cm-2 um-1 -> W m-2 sr-1 m-1
_SURFACE, _GROUND = 2.0**20, 2.0**24  # SI scale of SURF_EMIS and GRND_RFLT over TRANS


def _depth_factor(visibility):
    """Optical depth over ln 2 per unit k: 1 + 20 / V, linear in 1/V (2, 3, 5 at the nodes)."""
    return 1.0 + 20.0 / np.asarray(visibility, dtype=float)


def _k(model=1):
    """Integer depth scale k per (altitude, ground range, wavelength): 1..3 (+1 for model 4)."""
    a, g, w = np.meshgrid(np.arange(ALTITUDES.size), np.arange(GROUND_RANGES.size),
                          np.arange(WAVELENGTHS.size), indexing="ij")
    return 1 + (a + g + w) % 3 + (model == 4)


def _path_exponents(v):
    """SI path radiances at visibility index ``v``: 2**(18 + v) (thermal), 2**(22 + v + w % 2)."""
    w = np.arange(WAVELENGTHS.size)
    return np.full(w.shape, 18.0 + v), 22.0 + v + w % 2


def _tables(model=1):
    """(visibility, altitude, ground_range, component, wavelength) raw float32 tables."""
    k = _k(model)
    shape = (VISIBILITIES.size, *k.shape[:2], 5, WAVELENGTHS.size)
    raw = np.empty(shape, dtype=np.float32)
    for v, vis in enumerate(VISIBILITIES):
        trans = 2.0 ** -(k * _depth_factor(vis))  # exact in float32: exponents <= 24
        thermal, scatter = _path_exponents(v)
        raw[v, :, :, 0] = trans
        raw[v, :, :, 1] = _D * np.float32(2.0) ** thermal
        raw[v, :, :, 2] = _D * (np.float32(_SURFACE) * trans.astype(np.float32))
        raw[v, :, :, 3] = _D * np.float32(2.0) ** scatter
        raw[v, :, :, 4] = _D * (np.float32(_GROUND) * trans.astype(np.float32))
    return raw


def _cube(conditions=None):
    """The synthetic database, with an ``aerosol_model`` dim (codes 1, 4) if asked."""
    if conditions:
        tables = np.stack([_tables(model) for model in conditions["aerosol_model"]])
    else:
        tables = _tables()
    return atm.from_tables(
        tables, visibility=VISIBILITIES, altitude=ALTITUDES, ground_range=GROUND_RANGES,
        wavelength=WAVELENGTHS, conditions=conditions,
        coordinate_attrs={"aerosol_model": {"flag_values": np.array([1, 4], dtype=np.int32),
                                            "flag_meanings": "rural maritime"}}
        if conditions else None,
        attrs={"title": "synthetic Beer-Lambert tables", "source": "tests/atmosphere/"
               "test_conditions.py", "surface_reflectance_of_database": 0.15})


@pytest.fixture(scope="module")
def synthetic(tmp_path_factory):
    return atm.write_database(_cube(), tmp_path_factory.mktemp("db") / "synthetic.nc")


@pytest.fixture(scope="module")
def two_models(tmp_path_factory):
    cube = _cube({"aerosol_model": [1, 4]})
    return atm.write_database(cube, tmp_path_factory.mktemp("db") / "two_models.nc")


def _expected(visibility, a, g, model=1):
    """Closed-form spectra at node (a, g) for a visibility between two nodes (SI)."""
    k = _k(model)[a, g]
    trans = 2.0 ** -(k * _depth_factor(visibility))
    upper = int(np.searchsorted(-VISIBILITIES, -visibility))  # the node below visibility
    lower = upper - 1
    t0, t1 = (2.0 ** -(k * _depth_factor(VISIBILITIES[i])) for i in (lower, upper))
    lost = (t0 - trans) / (t0 - t1)  # path radiance affine in the transmittance
    paths = [(2.0 ** _path_exponents(lower)[c], 2.0 ** _path_exponents(upper)[c])
             for c in (0, 1)]
    thermal, scatter = (p0 + lost * (p1 - p0) for p0, p1 in paths)
    return {"transmission": trans, "path_thermal": thermal,
            "surface_emission": _SURFACE * trans, "solar_scatter": scatter,
            "ground_reflected": _GROUND * trans}


@pytest.mark.parametrize("interpolation", ["extinction-profile", "linear", "log-linear"])
@pytest.mark.parametrize("visibility", [17.0, 12.5, 10.0 + 1e-9, 7.0, 5.5])
def test_visibility_is_interpolated_in_extinction_exactly(synthetic, visibility,
                                                          interpolation):
    # at table nodes every rule returns the stored spectra, so the visibility rule alone
    # acts: ln T linear in 1/V (Beer-Lambert), path radiances affine in T
    with atm.use_database(synthetic):
        for a, g in ((0, 0), (1, 2), (2, 3)):
            out = atm.atmosphere_at(ALTITUDES[a], GROUND_RANGES[g], visibility,
                                    interpolation=interpolation)
            for name, expected in _expected(visibility, a, g).items():
                np.testing.assert_allclose(out[name].values, expected, rtol=1e-12, atol=0,
                                           err_msg=name)
            assert int(out["flags"]) == flag("visibility_interpolated")


def test_visibility_interpolation_commutes_with_the_log_linear_altitude_step(synthetic):
    # ln T = -ln 2 k(altitude) (1 + 20 / V) is separable: log-linear in log(altitude), then
    # linear in 1/V, gives 2 ** -(k-weighted (1 + 20 / V)) in closed form
    altitude, visibility = 1500.0, 8.0
    weight = np.log(altitude / ALTITUDES[0]) / np.log(ALTITUDES[1] / ALTITUDES[0])
    k = (1 - weight) * _k()[0, 1] + weight * _k()[1, 1]
    with atm.use_database(synthetic):
        out = atm.atmosphere_at(altitude, GROUND_RANGES[1], visibility,
                                interpolation="log-linear")
    np.testing.assert_allclose(out["transmission"].values, 2.0 ** -(k * _depth_factor(8.0)),
                               rtol=1e-12, atol=0)


def test_on_a_generated_visibility_the_stored_tables_come_back_unflagged(synthetic):
    with atm.use_database(synthetic):
        out = atm.atmosphere_at(ALTITUDES[1], GROUND_RANGES[2],
                                xr.DataArray(VISIBILITIES, dims="visibility"))
    raw = _tables()[:, 1, 2]
    np.testing.assert_array_equal(out["transmission"].values, raw[:, 0])
    np.testing.assert_array_equal(out["ground_reflected"].values, raw[:, 4] / _D)
    assert not out["flags"].values.any()


def test_exact_interpolation_refuses_a_visibility_between_nodes(synthetic):
    with atm.use_database(synthetic), pytest.raises(
            ValueError, match=r"visibility=7.0 km is not a database node \(interpolation="
                              r"'exact'\); the database holds 20, 10, 5 km"):
        atm.atmosphere_at(ALTITUDES[1], GROUND_RANGES[2], 7.0, interpolation="exact")


@pytest.mark.parametrize("visibility", [2.0, 4.99, 23.01, 50.0])
def test_a_visibility_outside_the_shipped_range_is_refused_with_what_it_holds(visibility):
    message = (r"visibility must be within \[5, 23\] km: the atmosphere database holds 23, "
               r"5 km \(MODTRAN IHAZE 1, 2\); between them the tables are interpolated in "
               r"extinction; got")
    with pytest.raises(ValueError, match=message):
        xbsm.scenario(altitude=9000.0, ground_range=20e3, visibility=visibility)
    with pytest.raises(ValueError, match=message):
        atm.atmosphere_at(9000.0, 20e3, visibility)


def test_the_shipped_visibilities_are_unchanged_inside_an_interpolated_sweep():
    # 23 and 5 km in a sweep with 10 km: the same numbers as alone, no new flag
    sensor = olson_sensor("nir")
    swept = xbsm.niirs(sensor, olson_scenario(
        visibility=xr.DataArray([23.0, 10.0, 5.0], dims="visibility")))
    for visibility in (23.0, 5.0):
        alone = xbsm.niirs(sensor, olson_scenario(visibility=visibility))
        at = swept.sel(visibility=visibility)
        for name in ("niirs", "snr", "rer"):
            # to the bit, with numpy's AVX-512 kernels on or off (CI runs both): at 854f67e
            # RER differed by 5.2e-16 at 1 of 97 cells with them off, since the edge
            # response's last rows that did not fill a stack of 32 took another matmul
            # kernel (now padded to a whole stack, metrics/edge.py _matmul_in_stacks)
            np.testing.assert_array_equal(at[name].values, alone[name].values)
        np.testing.assert_array_equal(at["flags"].values, alone["flags"].values)
    between = swept["flags"].sel(visibility=10.0)
    assert ((between & flag("visibility_interpolated")) != 0).all()


_FINE = xr.DataArray(np.linspace(23.0, 5.0, 37), dims="visibility")  # every 0.5 km


@pytest.mark.parametrize("band", ["red", "nir"])
def test_niirs_falls_as_visibility_falls_at_every_range_with_a_fixed_exposure(band):
    # shipped database, all 97 ranges, 37 visibilities: with an exposure the well never
    # limits, every GIQE's NIIRS and the SNR fall strictly as the visibility falls
    sensor = olson_sensor(band)
    sensor = sensor.assign(integration_time=sensor["integration_time"] / 30,
                           max_well_fill=sensor["max_well_fill"] * 0 + 1.0)
    out = xbsm.niirs(sensor, olson_scenario(visibility=_FINE))
    assert not (out["flags"] & flag("well_fill_limited")).any()
    _assert_falls(out["niirs"].transpose("giqe", "ground_range", "visibility").values)
    # (the SNR is 0, not falling, where the transmission underflows at long range)
    _assert_falls(out["snr"].transpose("ground_range", "visibility").values, strictly=False)


def _assert_falls(values, strictly=True):
    """Falling along the last axis where finite; NaN (SNR <= 0) only at its end."""
    finite = np.isfinite(values)
    assert (finite[..., :-1] | ~finite[..., 1:]).all()  # once NaN, NaN at lower visibility
    both = finite[..., 1:] & finite[..., :-1]
    step = np.diff(values, axis=-1)[both]
    assert (step < 0).all() if strictly else (step <= 0).all()
    assert both.mean() > 0.5


@pytest.mark.parametrize("band", ["red", "nir"])
def test_giqe5_niirs_falls_as_visibility_falls_with_the_olson_exposure(band):
    # with the paper's well-fill-limited exposure, GIQE 3 and 4 rise by up to 2e-3 NIIRS as
    # visibility falls at short ranges (more path radiance, shorter exposure, less smear:
    # between the database's own 23 and 5 km tables too, docs/atmosphere.md); GIQE 5 and
    # the SNR fall everywhere
    out = xbsm.niirs(olson_sensor(band), olson_scenario(visibility=_FINE))
    _assert_falls(out["niirs"].sel(giqe=5).transpose("ground_range", "visibility").values)
    # (the SNR is 0, not falling, where the transmission underflows at long range)
    _assert_falls(out["snr"].transpose("ground_range", "visibility").values, strictly=False)


# ---- other conditions: dims of the cube, parameters of the scenario, swept in a study

def test_a_condition_dim_is_written_read_and_selected(two_models):
    with atm.use_database(two_models):
        assert atm.database_conditions() == {"aerosol_model": (1.0, 4.0),
                                             "visibility": tuple(VISIBILITIES)}
        db = atm.load_database()
        assert db.conditions[0][0] == "aerosol_model" and db.cube.shape[0] == 6
        model = xr.DataArray([1.0, 4.0], dims="aerosol_model")
        out = atm.atmosphere_at(ALTITUDES[1], GROUND_RANGES[2], 7.0,
                                conditions={"aerosol_model": model})
    for i, m in enumerate((1, 4)):
        np.testing.assert_allclose(out["transmission"].isel(aerosol_model=i).values,
                                   _expected(7.0, 1, 2, model=m)["transmission"],
                                   rtol=1e-12, atol=0)


def test_a_condition_the_file_does_not_hold_is_refused_with_what_it_holds(two_models):
    with atm.use_database(two_models):
        with pytest.raises(ValueError, match=r"aerosol_model must be one of 1, 4 \[1\], the "
                                             r"values of the atmosphere database in use; got 5.0"):
            xbsm.scenario(altitude=2000.0, ground_range=0.0, visibility=10.0, aerosol_model=5)
        with pytest.raises(ValueError, match=r"holds no sun_zenith dimension \(it holds "
                                             r"visibility within \[5, 20\] km: .*; "
                                             r"aerosol_model one of 1, 4 \[1\]\)"):
            xbsm.scenario(altitude=2000.0, ground_range=0.0, visibility=10.0, sun_zenith=0.5)
        with pytest.raises(ValueError, match=r"holds aerosol_model = 1, 4 \[1\]: give the "
                                             r"scenario parameter aerosol_model"):
            atm.atmosphere_at(2000.0, 0.0, 10.0)
    with pytest.raises(ValueError, match="holds no aerosol_model dimension"):
        xbsm.scenario(altitude=2000.0, ground_range=0.0, visibility=10.0, aerosol_model=1)


def test_from_tables_refuses_an_unknown_condition():
    with pytest.raises(ValueError, match="conditions must be among aerosol_model, "):
        atm.from_tables(np.stack([_tables()]), visibility=VISIBILITIES, altitude=ALTITUDES,
                        ground_range=GROUND_RANGES, wavelength=WAVELENGTHS,
                        conditions={"humidity": [50.0]},
                        attrs={"title": "t", "source": "s",
                               "surface_reflectance_of_database": 0.15})


CONDITION_STUDY = """
title = "aerosol model x visibility"
[sensor]
preset = "olson"
band = "nir"
[scenario]
altitude = 2000.0
ground_range = 2000.0
platform_speed = 50.0
[sweep]
aerosol_model = [1, 4]
visibility = [20.0, 12.0, 7.5, 5.0]
"""


def test_a_condition_dim_is_swept_in_a_study_file(two_models, tmp_path):
    with atm.use_database(two_models):
        spec = study.parse(CONDITION_STUDY, "conditions.toml")
        result = study.write(study.run(spec), tmp_path / "conditions.nc")
        direct = xbsm.niirs(olson_sensor("nir"), xbsm.scenario(
            altitude=2000.0, ground_range=2000.0, platform_speed=50.0,
            aerosol_model=xr.DataArray([1.0, 4.0], dims="aerosol_model"),
            visibility=xr.DataArray([20.0, 12.0, 7.5, 5.0], dims="visibility")))
    with xr.open_dataset(result) as written:
        niirs = written["niirs"].transpose(*direct["niirs"].dims)
        xr.testing.assert_allclose(niirs, direct["niirs"], rtol=1e-12, atol=0)
        assert written["aerosol_model"].attrs["units"] == "1"
        interpolated = (written["flags"] & flag("visibility_interpolated")) != 0
        assert interpolated.sel(visibility=[12.0, 7.5]).all()
        assert not interpolated.sel(visibility=[20.0, 5.0]).any()
        snr = written["snr"]
        # the maritime tables (k + 1) attenuate more: lower SNR at every visibility
        assert (snr.sel(aerosol_model=4) < snr.sel(aerosol_model=1)).all()
        assert (snr.diff("visibility") < 0).all()


def test_xbsm_run_takes_the_database_of_a_condition_study(two_models, tmp_path, capsys):
    import hashlib

    import xbsm.cli

    toml = tmp_path / "conditions.toml"
    toml.write_text(CONDITION_STUDY)
    out = tmp_path / "conditions.nc"
    # without the file that holds the aerosol models: refused, listing what is held
    with pytest.raises(SystemExit) as stop:
        xbsm.cli.main(["run", str(toml), "-o", str(out), "--no-figures"])
    assert stop.value.code == 2
    assert "holds no aerosol_model dimension (it holds visibility within [5, 23] km" in \
        capsys.readouterr().err
    assert xbsm.cli.main(["run", str(toml), "-o", str(out), "--no-figures",
                          "--atmosphere", str(two_models)]) == 0
    with xr.open_dataset(out) as written:
        assert written.sizes["aerosol_model"] == 2 and written.sizes["visibility"] == 4
        assert written.attrs["xbsm_atmosphere_sha256"] == hashlib.sha256(
            two_models.read_bytes()).hexdigest()


def test_xbsm_info_lists_the_conditions_a_database_holds(two_models, tmp_path, capsys):
    import xbsm.cli

    assert xbsm.cli.main(["info", "--atmosphere", str(two_models)]) == 0
    out = capsys.readouterr().out
    # the file written by the fixture: aerosol models 1 and 4 at this module's visibilities
    assert f"atmosphere database: {two_models}" in out
    assert "  aerosol_model: 1, 4 [1]" in out
    assert (f"visibility: {VISIBILITIES.size} values from {VISIBILITIES.min():g} to "
            f"{VISIBILITIES.max():g} km") in out
    assert xbsm.cli.main(["info"]) == 0  # the shipped database: no condition besides visibility
    assert "aerosol_model" not in capsys.readouterr().out
    foreign = tmp_path / "foreign.nc"
    foreign.write_bytes(b"not a NetCDF file")
    with pytest.raises(SystemExit) as stop:
        xbsm.cli.main(["info", "--atmosphere", str(foreign)])
    assert stop.value.code == 2 and "xbsm info: " in capsys.readouterr().err


@pytest.mark.parametrize("ground_range", [100.0, 500.0])
def test_the_shipped_tables_follow_koschmieder_where_the_rule_assumes_it(ground_range):
    # the premise of the rule: extinction linear in 1/V. At 2 m above the ground and
    # 0.55 um (the wavelength of the visibility's definition) MODTRAN's tables give the
    # Koschmieder extinction 3.912 / V (Koschmieder 1924; 2 % contrast threshold) within
    # 0.12 % at both visibilities on 100 m and 500 m paths (0.6-0.8 % on 1 km, 2.4-2.6 % on
    # 2 km, where the path leaves the lowest layer)
    db = atm.load_database()
    w = int(np.argmin(np.abs(db.wavelength - 0.55e-6)))
    g = int(np.flatnonzero(db.ground_range == ground_range)[0])
    trans = db.cube[:, 0, g, 0, w].astype(float)
    extinction = -np.log(trans) / (ground_range / 1e3)  # [1/km]
    np.testing.assert_allclose(extinction, 3.912 / db.visibility, rtol=2e-3)


def test_an_interpolated_visibility_sweep_is_lazy_and_equals_eager():
    import dask

    visibility = xr.DataArray([23.0, 14.0, 9.0, 5.0], dims="visibility")
    def refuse(*args, **kwargs):
        raise AssertionError("something was computed")

    with dask.config.set(scheduler=refuse):  # building the result computes nothing
        lazy = atm.atmosphere_at(9000.0, 20e3, visibility.chunk(1),
                                 wavelength_bounds=(0.5e-6, 0.6e-6))
    assert lazy["transmission"].chunks is not None
    eager = atm.atmosphere_at(9000.0, 20e3, visibility, wavelength_bounds=(0.5e-6, 0.6e-6))
    xr.testing.assert_identical(lazy.compute(), eager)
