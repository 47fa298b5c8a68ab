import dask.array as dsa
import numpy as np
import pytest
import xarray as xr

import xbsm
from xbsm import params
from xbsm import pybsm_compat as compat

BASE = dict(aperture_diameter=0.275, focal_length=4.0, pixel_pitch_x=8e-6,
            wavelength_min=0.5e-6, wavelength_max=0.66e-6)


def test_sensor_defaults_follow_pybsm():
    s = xbsm.sensor(**BASE)
    # pyBSM 0.16.1 Sensor defaults (simulation/sensor.py): int_time 1, max_n 1e8, bit_depth 100
    assert float(s.integration_time) == 1.0
    assert float(s.max_well) == 1e8
    assert float(s.bit_depth) == 100.0
    assert float(s.detector_width_y) == 8e-6
    assert float(s.wavefront_correlation_length_x) == 0.275
    assert s.aperture_diameter.attrs["units"] == "m"
    assert s.filter_kernel.shape == (1, 1)


def test_detector_height_default_keeps_the_fill_factor():
    s = xbsm.sensor(**BASE, pixel_pitch_y=10e-6, detector_width_x=6e-6)
    assert float(s.detector_width_y) == pytest.approx(6e-6 / 8e-6 * 10e-6)
    # pyBSM derives w_y = p_x / w_x * p_y; pybsm_compat reproduces it
    c = compat.sensor(D=0.275, f=4.0, p_x=8e-6, p_y=10e-6, w_x=6e-6,
                      opt_trans_wavelengths=np.array([0.5e-6, 0.66e-6]))
    assert float(c.detector_width_y) == pytest.approx(8e-6 / 6e-6 * 10e-6)


@pytest.mark.parametrize(
    "kw, name, allowed",
    [
        ({"aperture_diameter": -0.1}, "aperture_diameter", "(0, inf) m"),
        ({"wavelength_min": 0.2e-6}, "wavelength_min", "[3e-07, 1.4e-05) m"),
        ({"wavelength_max": 15e-6}, "wavelength_max", "(3e-07, 1.4e-05] m"),
        ({"max_well_fill": 1.2}, "max_well_fill", "(0, 1] 1"),
        ({"obscuration_ratio": 1.0}, "obscuration_ratio", "[0, 1) 1"),
        ({"quantum_efficiency": -0.1}, "quantum_efficiency", "[0, 1] 1"),
    ],
)
def test_sensor_rejects_bad_input_naming_parameter_and_range(kw, name, allowed):
    with pytest.raises(ValueError) as err:
        xbsm.sensor(**{**BASE, **kw})
    assert name in str(err.value)
    assert allowed in str(err.value)


def test_band_must_be_ordered():
    with pytest.raises(ValueError, match="wavelength_min must be smaller"):
        xbsm.sensor(**{**BASE, "wavelength_min": 0.7e-6})


def test_kernel_must_sum_to_one_within_rounding():
    xbsm.sensor(**BASE, filter_kernel=[[0.7, 0.2, 0.1]])  # float sum 0.9999999999999999
    with pytest.raises(ValueError, match="filter_kernel must sum to 1"):
        xbsm.sensor(**BASE, filter_kernel=[[0.5, 0.4]])


@pytest.mark.parametrize(
    "kw, name",
    [
        ({"altitude": 600e3}, "altitude"),
        ({"altitude": 1.0}, "altitude"),
        ({"ground_range": -1.0}, "ground_range"),
        ({"ground_range": 301e3}, "ground_range"),
        ({"visibility": 2.0}, "visibility"),
        ({"visibility": 50.0}, "visibility"),
    ],
)
def test_scenario_rejects_bad_input(kw, name):
    with pytest.raises(ValueError, match=name):
        xbsm.scenario(**{"altitude": 9000.0, "ground_range": 0.0, "visibility": 23.0, **kw})


def test_compat_rejects_mismatched_spectral_arrays():
    with pytest.raises(ValueError, match="qe must have one value per entry of qe_wavelengths"):
        compat.sensor(D=0.2, f=2.0, p_x=1e-5, opt_trans_wavelengths=np.array([0.5e-6, 0.7e-6]),
                      qe=np.array([0.5, 0.6, 0.7]), qe_wavelengths=np.array([0.5e-6, 0.7e-6]))


def test_compat_rejects_unknown_ihaze_and_keywords():
    with pytest.raises(ValueError, match="ihaze must be 1"):
        compat.scenario(ihaze=3, altitude=9000.0, ground_range=0.0)
    with pytest.raises(ValueError, match="unknown pyBSM Sensor keyword"):
        compat.sensor(D=0.2, f=2.0, p_x=1e-5, opt_trans_wavelengths=[0.5e-6, 0.7e-6], bogus=1)


def test_compat_maps_every_pybsm_keyword():
    # every pyBSM 0.16.1 Sensor.__init__ keyword plus post-construction attributes
    pybsm_sensor = {
        "name", "D", "f", "p_x", "opt_trans_wavelengths", "eta", "p_y", "w_x", "w_y",
        "int_time", "qe", "qe_wavelengths", "dark_current", "other_irradiance", "read_noise",
        "max_n", "max_well_fill", "bit_depth", "n_tdi", "cold_shield_temperature",
        "optics_temperature", "optics_emissivity", "cold_filter_transmission",
        "cold_filter_temperature", "cold_filter_emissivity", "s_x", "s_y", "da_x", "da_y",
        "pv", "pv_wavelength", "filter_kernel", "frame_stacks",
        "optics_transmission", "other_noise", "L_x", "L_y",
    }
    assert pybsm_sensor == set(compat.SENSOR_NAMES)
    pybsm_scenario = {
        "name", "ihaze", "altitude", "ground_range", "aircraft_speed", "target_reflectance",
        "target_temperature", "background_reflectance", "background_temperature",
        "ha_wind_speed", "cn2_at_1m", "interp",
    }
    assert pybsm_scenario == set(compat.SCENARIO_NAMES)


def test_inputs_are_not_modified():
    qe = xr.DataArray([0.8, 0.8], dims="wavelength", coords={"wavelength": [0.5e-6, 0.66e-6]})
    before = qe.copy(deep=True)
    gr = xr.DataArray(np.linspace(0, 5e4, 3), dims="case")
    gr_before = gr.copy(deep=True)
    s = xbsm.sensor(**BASE, quantum_efficiency=qe)
    sc = xbsm.scenario(altitude=9000.0, ground_range=gr, visibility=23.0)
    xbsm.snr(s, sc)
    xr.testing.assert_identical(qe, before)
    xr.testing.assert_identical(gr, gr_before)


def test_sweep_parameter_keeps_its_dimension():
    d = xr.DataArray([0.1, 0.2, 0.3], dims="diameter")
    s = xbsm.sensor(**{**BASE, "aperture_diameter": d})
    assert s.aperture_diameter.dims == ("diameter",)


def test_dask_inputs_are_checked_lazily(no_compute):
    gr = xr.DataArray(dsa.from_array(np.array([0.0, 400e3]), chunks=1), dims="case")
    sc = xbsm.scenario(altitude=9000.0, ground_range=gr, visibility=23.0)
    assert sc.ground_range.chunks is not None


def test_dask_inputs_raise_when_computed():
    gr = xr.DataArray(dsa.from_array(np.array([0.0, 400e3]), chunks=1), dims="case")
    sc = xbsm.scenario(altitude=9000.0, ground_range=gr, visibility=23.0)
    with pytest.raises(ValueError, match="ground_range"):
        sc.ground_range.compute()


def test_sweeps_of_parameters_other_defaults_derive_from():
    # pixel_pitch_y, detector widths and the wavefront correlation lengths default to a swept
    # parameter and carry its dimension; every point equals the scalar call (to rounding:
    # the swept call broadcasts in another order)
    from xbsm.examples import olson_scenario, olson_sensor
    sweep = olson_sensor("nir",
                         aperture_diameter=xr.DataArray([0.2, 0.3], dims="aperture_diameter"),
                         pixel_pitch_x=xr.DataArray([5e-6, 8e-6], dims="pixel_pitch_x"))
    assert sweep.wavefront_correlation_length_x.dims == ("aperture_diameter",)
    assert sweep.detector_width_y.dims == ("pixel_pitch_x",)
    scenario = olson_scenario(ground_range=20e3, visibility=5.0)
    swept = xbsm.niirs(sweep, scenario).niirs
    one = xbsm.niirs(olson_sensor("nir", aperture_diameter=0.3, pixel_pitch_x=5e-6),
                     scenario).niirs
    xr.testing.assert_allclose(swept.sel(aperture_diameter=0.3, pixel_pitch_x=5e-6, drop=True),
                               one, rtol=1e-12, atol=0)


@pytest.mark.parametrize("dim", ["snr", "niirs", "gsd", "system"])
def test_a_sweep_dimension_named_like_a_result_variable_is_refused(dim):
    # the result would replace that variable by the sweep's coordinate, silently
    with pytest.raises(ValueError, match=f"dimension '{dim}', the name of a result variable"):
        xbsm.scenario(altitude=9000.0, ground_range=xr.DataArray([1e3, 2e4], dims=dim),
                      visibility=23.0)


def test_result_names_cover_every_result_variable():
    from xbsm.examples import olson_scenario, olson_sensor
    from xbsm.params import RESERVED_DIMS, RESULT_NAMES
    s, sc = olson_sensor("nir"), olson_scenario(ground_range=1e3, visibility=23.0)
    results = (xbsm.snr(s, sc), xbsm.niirs(s, sc), xbsm.system_otf(s, sc))
    names = set().union(*(set(r.variables) for r in results)) - set(RESERVED_DIMS)
    assert names <= set(RESULT_NAMES), names - set(RESULT_NAMES)
    # a parameter echoed under its own name may still sweep on its own dimension
    echoed = olson_sensor("nir", read_noise=xr.DataArray([10.0, 25.0], dims="read_noise"))
    np.testing.assert_array_equal(xbsm.niirs(echoed, sc).read_noise, [10.0, 25.0])


# ---- declared contracts (params.contract) ----------------------------------------------------

def test_contract_checks_positional_keyword_and_default_arguments():
    from xbsm._metadata import Output

    @params.contract(Output("out", "m", "an output"), form=params.Choice(("a", "b")),
                     count=params.Spec("1", "a count", low=1.0, whole=True))
    def f(x, form="a", *, count=2):
        return xr.DataArray(x, attrs={"units": "s", "other": 1})

    out = f(1.0, "b", count=3)
    assert out.attrs == {"units": "m", "long_name": "an output"}  # exactly the declared ones
    with pytest.raises(ValueError, match=r"^form must be one of 'a', 'b'; got 'c'$"):
        f(1.0, "c")
    with pytest.raises(ValueError, match=r"^form must be one of 'a', 'b'; got 'c'$"):
        f(1.0, form="c")
    with pytest.raises(ValueError, match=r"^count must be a whole number in \[1, inf\); got 0$"):
        f(1.0, count=0)
    with pytest.raises(ValueError, match="count must be a whole number"):
        f(1.0, count=2.5)
    assert set(f.__contract__.rules) == {"form", "count"}
    assert f.__contract__.returns.units == "m"


def test_contract_hands_the_function_what_the_rule_returns():
    @params.contract(outputs=params.Selection(("a", "b")),
                     span=params.Pair(params.Spec("1", "fraction", **params.FRACTION)))
    def f(outputs=None, span=(0.1, 0.9)):
        return outputs, span

    assert f() == (("a", "b"), (0.1, 0.9))
    assert f("b", [0, 1]) == (("b",), (0.0, 1.0))
    with pytest.raises(ValueError, match=r"^outputs must be a non-empty selection of"):
        f(())
    with pytest.raises(ValueError, match=r"^span must be a \(low, high\) pair in \[0, 1\] 1 "
                                         r"with low < high; got \(0.5, 0.5\)$"):
        f(span=(0.5, 0.5))
    with pytest.raises(ValueError, match="span must be a"):
        f(span=(0.5,))


def test_pair_may_reach_an_unbounded_end_and_be_optional():
    rule = params.Pair(params.Spec("1", "snr", low=0.0), equal=True, optional=True)
    assert rule.check("snr", (4.1, np.inf)) == (4.1, np.inf)
    assert rule.check("snr", None) is None
    assert rule.check("snr", (2.0, 2.0)) == (2.0, 2.0)
    for bad in [(-1.0, 2.0), (3.0, 2.0), (np.nan, 2.0), 0.3]:
        with pytest.raises(ValueError, match=r"^snr must be None or a \(low, high\) pair in "
                                             r"\[0, inf\) 1 with low <= high; got"):
            rule.check("snr", bad)


def test_instance_names_the_type_it_got():
    rule = params.Instance(dict, "a mapping (e.g. {})")
    with pytest.raises(ValueError, match=r"^table must be a mapping \(e.g. \{\}\); got list$"):
        rule.check("table", [])


def test_values_rule_checks_every_value_of_an_array_argument():
    rule = params.Values(params.Spec("m", "slant range", **params.POSITIVE))
    ok = xr.DataArray([1.0, 2.0], dims="r")
    assert rule.check("slant_range", ok) is ok
    with pytest.raises(ValueError, match=r"^slant_range must lie in \(0, inf\) m; got -1.0$"):
        rule.check("slant_range", np.array([1.0, -1.0]))
    with pytest.raises(ValueError, match="slant_range must lie in"):
        rule.check("slant_range", np.nan)
    lazy = xr.DataArray(dsa.from_array(np.array([-1.0])), dims="r")
    assert rule.check("slant_range", lazy) is lazy  # dask values are not computed here


def test_table_and_either_rules_for_a_choice_or_a_lookup_table():
    table = params.Table("pixel_values", "reflectance_values",
                         params.Spec("1", "reflectance", **params.FRACTION))
    rule = params.Either(params.Choice(("minmax", "identity")), table)
    assert rule.check("reflectance", "minmax") == "minmax"
    xs, ys = rule.check("reflectance", ([255, 0], [0.9, 0.1]))  # sorted by pixel value
    assert list(xs) == [0.0, 255.0] and list(ys) == [0.1, 0.9]
    for bad, message in [
            ("stretch", r"^reflectance must be one of 'minmax', 'identity' or a table"),
            (3, r"^reflectance must be a pair \(pixel_values, reflectance_values\)"),
            (([0], [0.5]), "table needs at least 2 pixel_values and as many"),
            (([0, 0], [0.1, 0.2]), "pixel_values must be finite and distinct"),
            (([0, 1], [0.1, 1.5]), r"reflectance_values must lie in \[0, 1\] 1")]:
        with pytest.raises(ValueError, match=message):
            rule.check("reflectance", bad)
