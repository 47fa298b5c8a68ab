"""Bad input at every public entry point: a clear error naming the parameter, or a flag.

One row per case. An error row names the exception, the parameter the message must
name, and a fragment of the allowed range or choices it must state; a flag row names
the flag bit the result must carry. Built from the parameter tables, so a new
parameter is covered the day it is added.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
from hypothesis import given, settings
from hypothesis import strategies as st

import xbsm
from xbsm import params
from xbsm.flags import has_flag
from xbsm.simulate import reflectance_to_photoelectrons

BAND = dict(wavelength_min=0.55e-6, wavelength_max=0.85e-6)
SENSOR = dict(aperture_diameter=0.275, focal_length=4.0, pixel_pitch_x=8e-6, **BAND,
              integration_time=0.03, max_well=96000.0, max_well_fill=0.6)
SCENARIO = dict(altitude=9000.0, ground_range=20e3, visibility=5.0)
S = xbsm.sensor(**SENSOR)
SC = xbsm.scenario(**SCENARIO)
PYBSM_SENSOR = dict(D=0.275, f=4.0, p_x=8e-6, opt_trans_wavelengths=np.array([0.55e-6, 0.85e-6]))


def _bad_values(spec: params.Spec):
    """Values outside ``spec``: below, at an open end, infinite, NaN, not a real number."""
    out = [math.inf, math.nan, "0.1", 1 + 2j, True]
    if spec.low > -math.inf:
        out.append(spec.low - 1.0)
        if spec.low_open:
            out.append(spec.low)
    if spec.high < math.inf:
        out.append(spec.high + 1.0)
    return out


def _rows(specs, make):
    for name, spec in specs.items():
        for value in _bad_values(spec):
            yield pytest.param(make, name, value, id=f"{name}={value!r}")


SPEC_ROWS = [
    *_rows(params.SENSOR_SPECS, lambda **kw: xbsm.sensor(**{**SENSOR, **kw})),
    *_rows(params.SCENARIO_SPECS, lambda **kw: xbsm.scenario(**{**SCENARIO, **kw})),
]


@pytest.mark.parametrize("make, name, value", SPEC_ROWS)
def test_out_of_range_or_non_numeric_value_names_the_parameter(make, name, value):
    with pytest.raises(ValueError) as err:
        make(**{name: value})
    message = str(err.value)
    assert name in message
    assert ("must lie in" in message or "real number" in message or "must be" in message
            or "smaller than" in message), message
    assert not [part for part in INTERNALS if part in message], message


def test_table_has_at_least_120_rows():
    assert len(SPEC_ROWS) + len(OTHER_ROWS) >= 120


@pytest.mark.parametrize("dim", params.RESERVED_DIMS)
def test_each_reserved_dimension_name_is_refused(dim):
    with pytest.raises(ValueError, match=f"swept on dimension '{dim}'"):
        xbsm.scenario(**{**SCENARIO, "ground_range": xr.DataArray([0.0, 2e4], dims=dim)})


def test_the_guide_lists_each_reserved_dimension_name():
    # docs/guide.md names every reserved dimension; the <parameter>_wavelength ones as a pattern
    guide = (Path(__file__).resolve().parent.parent / "docs" / "guide.md").read_text()
    for dim in params.RESERVED_DIMS:
        shown = "<parameter>_wavelength" if dim.endswith("_wavelength") else dim
        assert f"`{shown}`" in guide, dim


def _edited(**changes):
    return lambda: xbsm.snr(S.assign(**changes), SC)


# a reference image for xbsm.simulate_image: a bright square on a gradient, 4 reference
# pixels per camera pixel (the camera's GSD is 8 um / 4 m x 21.9 km = 4.4 cm)
IMAGE = np.add.outer(np.arange(48.0), np.arange(48.0))
IMAGE[16:32, 16:32] = 200.0
IMAGE_GSD = 0.011


def _simulated(image=IMAGE, **kwargs):
    return lambda: xbsm.simulate_image(image, S, SC, gsd=IMAGE_GSD, noise=False, **kwargs)


def _edge(clip=None):
    """A 64 x 64 edge tilted 5 degrees, a Gaussian blur of 1.5 px (values 0 to 1)."""
    y, x = np.indices((64, 64), dtype=float)
    distance = (x - 31.5 - np.tan(np.radians(5.0)) * (y - 31.5)) * np.cos(np.radians(5.0))
    edge = 0.5 * (1.0 + np.vectorize(math.erf)(distance / (1.5 * math.sqrt(2.0))))
    return edge if clip is None else np.clip(edge, *clip)


EDGE = _edge()


OTHER_ROWS = [
    # (id, call, exception, fragment the message must contain)
    ("sweep_on_another_parameter", lambda: xbsm.scenario(
        **{**SCENARIO, "ground_range": xr.DataArray([0.0, 2e4], dims="altitude")}),
     ValueError, "name of another parameter"),
    ("empty_sweep", lambda: xbsm.sensor(**{**SENSOR, "focal_length": xr.DataArray(
        [], dims="f")}), ValueError, "focal_length is an empty sweep"),
    ("unlabelled_array", lambda: xbsm.sensor(**{**SENSOR, "focal_length": [1.0, 2.0]}),
     ValueError, "focal_length must be a scalar or an xr.DataArray"),
    ("units_unknown", lambda: xbsm.scenario(**{**SCENARIO, "ground_range": xr.DataArray(
        [20.0], dims="g", attrs={"units": "furlong"})}), ValueError, "xbsm expects 'm'"),
    ("units_of_another_kind", lambda: xbsm.sensor(**{**SENSOR, "jitter_x": xr.DataArray(
        1.0, attrs={"units": "m"})}), ValueError, "jitter_x has units 'm'"),
    ("qe_in_micrometres", lambda: xbsm.sensor(**{**SENSOR, "quantum_efficiency": xr.DataArray(
        [0.6, 0.7], dims="wavelength", coords={"wavelength": [0.5, 0.9]})}),
     ValueError, "micrometres"),
    ("qe_zero_over_band", lambda: xbsm.sensor(**{**SENSOR, "quantum_efficiency": 0.0}),
     ValueError, "quantum_efficiency is zero over the whole band"),
    ("transmission_outside_band", lambda: xbsm.sensor(**{
        **SENSOR, "optics_transmission": xr.DataArray(
            [0.5, 0.5], dims="wavelength", coords={"wavelength": [3e-6, 5e-6]})}),
     ValueError, "optics_transmission is given over"),
    ("curve_wavelengths_decrease", lambda: xbsm.sensor(**{
        **SENSOR, "quantum_efficiency": xr.DataArray(
            [0.5, 0.5], dims="wavelength", coords={"wavelength": [0.8e-6, 0.6e-6]})}),
     ValueError, "increase strictly"),
    ("band_reversed", lambda: xbsm.sensor(**{**SENSOR, "wavelength_min": 0.9e-6}),
     ValueError, "wavelength_min must be smaller than wavelength_max"),
    ("band_swept", lambda: xbsm.sensor(**{**SENSOR, "wavelength_min": xr.DataArray(
        [0.5e-6, 0.55e-6], dims="b")}), ValueError, "band edges cannot be swept"),
    ("visibility_not_in_database", lambda: xbsm.scenario(**{**SCENARIO, "visibility": 10.0}),
     ValueError, "visibility must be one of"),
    ("misspelt_sensor_keyword", lambda: xbsm.sensor(**SENSOR, focal_lenght=1.0),
     ValueError, "did you mean 'focal_length'"),
    ("misspelt_scenario_keyword", lambda: xbsm.scenario(**SCENARIO, visibilty=5.0),
     ValueError, "did you mean 'visibility'"),
    ("misspelt_pybsm_keyword", lambda: xbsm.pybsm_compat.sensor(
        D=0.275, f=4.0, p_x=8e-6, opt_trans_wavelengths=np.array([0.55e-6, 0.85e-6]),
        int_tme=0.03), ValueError, "did you mean 'int_time'"),
    ("misspelt_method_knob", lambda: xbsm.method("accurate", nodes_per_pannel=3),
     ValueError, "did you mean 'nodes_per_panel'"),
    ("unknown_preset", lambda: xbsm.method("exact"), ValueError, "method must be one of"),
    ("edited_aperture", _edited(aperture_diameter=-0.1), ValueError,
     "aperture_diameter must lie in (0, inf) m"),
    ("edited_qe", _edited(quantum_efficiency=2.0), ValueError,
     "quantum_efficiency must lie in [0, 1]"),
    ("edited_dims", lambda: xbsm.snr(S.assign(read_noise=xr.DataArray(
        [1.0, 2.0], dims="fx")), SC), ValueError, "swept on dimension 'fx'"),
    ("not_a_sensor", lambda: xbsm.snr(SC, SC), ValueError, "sensor must be the dataset"),
    ("shared_dim_different_length", lambda: xbsm.snr(
        xbsm.sensor(**{**SENSOR, "focal_length": xr.DataArray([3.0, 4.0], dims="case")}),
        xbsm.scenario(**{**SCENARIO, "ground_range": xr.DataArray([0.0, 1e4, 2e4],
                                                                   dims="case")})),
     ValueError, "both sweep dimension 'case'"),
    ("shared_dim_different_coords", lambda: xbsm.snr(
        xbsm.sensor(**{**SENSOR, "focal_length": xr.DataArray(
            [3.0, 4.0], dims="case", coords={"case": [0, 1]})}),
        xbsm.scenario(**{**SCENARIO, "ground_range": xr.DataArray(
            [0.0, 1e4], dims="case", coords={"case": [5, 6]})})),
     ValueError, "different coordinate values"),
    ("targets_unknown", lambda: xbsm.snr(S, SC, targets="tank"), ValueError,
     "targets must be 'giqe' or 'scenario'"),
    ("absurd_grid", lambda: xbsm.niirs(xbsm.sensor(**{**SENSOR, "pixel_pitch_x": 1.0}), SC),
     ValueError, "max_frequency_nodes"),
    ("otf_frequency_nan", lambda: xbsm.system_otf(S, SC, [0.0, np.nan]), ValueError,
     "frequency must lie in"),
    ("otf_frequency_inf", lambda: xbsm.system_otf(S, SC, [0.0, np.inf]), ValueError,
     "frequency must lie in"),
    ("otf_frequency_string", lambda: xbsm.system_otf(S, SC, ["a"]), ValueError,
     "frequency must be a real number"),
    ("otf_too_many_frequencies", lambda: xbsm.system_otf(S, SC, np.zeros(1_000_001)),
     ValueError, "at most 1000000"),
    ("reflectance_negative", lambda: reflectance_to_photoelectrons(S, SC, [-0.1, 0.5]),
     ValueError, "reflectance must lie in [0, 1]"),
    ("reflectance_above_one", lambda: reflectance_to_photoelectrons(S, SC, [0.5, 1.5]),
     ValueError, "reflectance must lie in [0, 1]"),
    ("reflectance_empty", lambda: reflectance_to_photoelectrons(S, SC, []), ValueError,
     "reflectance is an empty sweep"),
    ("reflectance_nan", lambda: reflectance_to_photoelectrons(S, SC, [np.nan]), ValueError,
     "reflectance must lie in [0, 1]"),
    ("temperature_zero", lambda: reflectance_to_photoelectrons(S, SC, temperature=0.0),
     ValueError, "temperature must lie in (0, inf) K"),
    ("sensor_dims_disagree", lambda: xbsm.sensor(**{
        **SENSOR, "focal_length": xr.DataArray([3.0, 4.0], dims="case"),
        "jitter_x": xr.DataArray([1e-6, 2e-6, 3e-6], dims="case")}),
     ValueError, "both sweep dimension 'case'"),
    ("kernel_string", lambda: xbsm.sensor(**SENSOR, filter_kernel="sharpen"), ValueError,
     "filter_kernel must be a 2-D array"),
    ("edited_band", lambda: xbsm.niirs(S.assign(wavelength_min=9e-6), SC), ValueError,
     "wavelength_min < wavelength_max"),
    ("otf_frequency_on_reserved_dim", lambda: xbsm.system_otf(
        S, SC, xr.DataArray([0.0, 1e5], dims="wavelength")), ValueError,
     "swept on dimension 'wavelength'"),
    ("otf_frequency_2d_array", lambda: xbsm.system_otf(S, SC, np.zeros((2, 2))), ValueError,
     "frequency must be 1-D"),
    ("otf_fy_not_labelled", lambda: xbsm.system_otf(
        S, SC, xr.DataArray([0.0, 1e5], dims="fx"), fy=[0.0, 1.0]), ValueError,
     "fy must be an xr.DataArray"),
    ("reflectance_without_its_dim", lambda: reflectance_to_photoelectrons(
        S, SC, xr.DataArray([0.1, 0.2], dims="case")), ValueError,
     "must have a 'reflectance' dimension"),
    ("atmosphere_complex", lambda: xbsm.atmosphere_at(9000.0, 1 + 2j, 23.0), ValueError,
     "ground_range must be a real number"),
    ("atmosphere_unknown_units", lambda: xbsm.atmosphere_at(
        9000.0, xr.DataArray(20.0, attrs={"units": "furlong"}), 23.0), ValueError,
     "ground_range has units 'furlong'"),
    ("pybsm_w_x_zero", lambda: xbsm.pybsm_compat.sensor(
        D=0.275, f=4.0, p_x=8e-6, w_x=0.0, opt_trans_wavelengths=np.array([0.55e-6, 0.85e-6])),
     ValueError, "w_x (detector_width_x) must lie in (0, inf)"),
    ("grd_negative_slant_range", lambda: xbsm.metrics.ground_resolved_distance(
        xr.DataArray([1.0, 0.5], dims="frequency", coords={"frequency": [0.0, 1e5]}),
        50.0, 1e-5, -1.0), ValueError, "slant_range must lie in (0, inf)"),
    ("grd_decreasing_frequency", lambda: xbsm.metrics.ground_resolved_distance(
        xr.DataArray([0.5, 1.0], dims="frequency", coords={"frequency": [1e5, 0.0]}),
        50.0, 1e-5, 1e4), ValueError, "must increase strictly"),
    ("method_not_a_name", lambda: xbsm.niirs(S, SC, method={"edge_rule": "x"}), ValueError,
     "method must be one of"),
    ("otf_fy_nan", lambda: xbsm.system_otf(S, SC, xr.DataArray([0.0, 1e5], dims="fx"),
                                           fy=xr.DataArray([0.0, np.nan], dims="fy")),
     ValueError, "fy must lie in"),
    ("database_not_netcdf", lambda: xbsm.open_atmosphere(__file__), ValueError,
     "is not an xbsm atmosphere database: it cannot be read as a NetCDF file"),
    ("database_chunks_bogus", lambda: xbsm.open_atmosphere(chunks="bogus"), ValueError,
     "chunks must be None, 'auto', a byte size"),
    ("integration_time_negative", lambda: reflectance_to_photoelectrons(
        S, SC, integration_time=-1.0), ValueError, "integration_time must lie in (0, inf) s"),
    ("pybsm_other_noise_negative", lambda: xbsm.pybsm_compat.sensor(
        **PYBSM_SENSOR, other_noise=np.array([3.0, -5.0])), ValueError,
     "other_noise must hold rms noise values in [0, inf) electrons; got -5.0"),
    ("pybsm_qe_wavelengths_in_micrometres", lambda: xbsm.pybsm_compat.sensor(
        **PYBSM_SENSOR, qe=np.array([0.7, 0.7]), qe_wavelengths=np.array([0.55, 0.85])),
     ValueError, "must reach into the band. Are its wavelengths in micrometres"),
    ("pybsm_error_names_the_pybsm_keyword", lambda: xbsm.pybsm_compat.sensor(
        **PYBSM_SENSOR, qe=np.array([0.7, 0.7]), qe_wavelengths=np.array([0.4e-6, 0.5e-6])),
     ValueError, "(pyBSM keyword: qe over qe_wavelengths)"),
    ("pybsm_scenario_error_names_the_pybsm_keyword", lambda: xbsm.pybsm_compat.scenario(
        ihaze=1, altitude=9000.0, ground_range=2e4, aircraft_speed=-1.0), ValueError,
     "platform_speed must lie in [0, inf) m s-1; got -1.0 (pyBSM keyword: aircraft_speed)"),
    ("edited_kernel_nan", lambda: xbsm.niirs(S.drop_vars("filter_kernel").assign(
        filter_kernel=xr.DataArray(np.full((2, 2), np.nan), dims=("kernel_y", "kernel_x"))),
        SC), ValueError, "filter_kernel must be finite"),
    ("edited_kernel_sum", lambda: xbsm.snr(S.assign(filter_kernel=xr.DataArray(
        [[2.0]], dims=("kernel_y", "kernel_x"))), SC), ValueError,
     "filter_kernel must sum to 1"),
    ("qe_without_wavelength_coordinate", lambda: xbsm.sensor(**{
        **SENSOR, "quantum_efficiency": xr.DataArray([0.5, 0.6], dims="wavelength")}),
     ValueError, "has no 'wavelength' coordinate: give the wavelength of each value [m]"),
    ("required_pitch_none", lambda: xbsm.sensor(**{**SENSOR, "pixel_pitch_x": None}),
     ValueError, "pixel_pitch_x must be a real number"),
    ("required_aperture_none", lambda: xbsm.sensor(**{**SENSOR, "aperture_diameter": None}),
     ValueError, "aperture_diameter must be a real number"),
    ("non_numeric_sweep_shown_briefly", lambda: xbsm.sensor(**{
        **SENSOR, "focal_length": xr.DataArray(["4"], dims="f")}), ValueError,
     "got an xr.DataArray of dtype <U1 on dims ('f',)"),
    # issue 20, the review's new input classes
    ("simulate_reflectance_range_none", _simulated(reflectance_range=None), ValueError,
     "reflectance_range must be a (low, high) pair in [0, 1] 1 with low < high; got None"),
    ("simulate_reflectance_range_one_value", _simulated(reflectance_range=(0.5,)), ValueError,
     "reflectance_range must be a (low, high) pair in [0, 1] 1 with low < high; got (0.5,)"),
    ("simulate_empty_image", _simulated(np.zeros((0, 0))), ValueError,
     "image must have at least one pixel along 'y' and 'x'; got 0 x 0"),
    ("simulate_image_without_rows", _simulated(np.zeros((0, 48))), ValueError,
     "image must have at least one pixel along 'y' and 'x'; got 0 x 48"),
    ("simulate_stack_dim_x_input", _simulated(xr.DataArray(
        np.stack([IMAGE, IMAGE]), dims=("x_input", "y", "x"))), ValueError,
     "image has a dimension 'x_input', a name simulate_image uses itself; rename it"),
    ("simulate_stack_dim_psf_y", _simulated(xr.DataArray(
        np.stack([IMAGE, IMAGE]), dims=("psf_y", "y", "x"))), ValueError,
     "image has a dimension 'psf_y', a name simulate_image uses itself; rename it"),
    ("simulate_stack_dim_counts", _simulated(xr.DataArray(
        np.stack([IMAGE, IMAGE]), dims=("counts", "y", "x"))), ValueError,
     "image has a dimension 'counts', a name simulate_image uses itself; rename it"),
    ("resample_spectral_empty_curve", lambda: xbsm.radiometry.resample_spectral(
        xr.DataArray(np.array([]), dims="quantum_efficiency_wavelength",
                     coords={"quantum_efficiency_wavelength": np.array([])}),
        xr.DataArray([0.6e-6], dims="wavelength"), "quantum_efficiency"), ValueError,
     "quantum_efficiency is an empty curve: give at least one sample"),
    ("measure_strided_roi", lambda: xbsm.measure.slanted_edge_mtf(
        EDGE, roi=(slice(None), slice(None, None, 2))), ValueError,
     "roi must select contiguous pixels: slices with step 1; got step 2 along 'x'"),
    ("measure_roi_positions_skip_pixels", lambda: xbsm.measure.flat_noise(
        EDGE, region=(np.arange(0, 40, 3), slice(0, 20))), ValueError,
     "region must select contiguous pixels"),
    ("measure_strided_view", lambda: xbsm.measure.slanted_edge_mtf(xr.DataArray(
        EDGE, dims=("y", "x"), coords={"y": np.arange(64), "x": np.arange(64)})[::2]),
     ValueError, "image's 'y' coordinate steps by 2 pixels"),
]

# Fragments of library internals an error message must never show the user (issue 8):
# raw xarray / numpy reprs and errors, dask's byte-unit parser, netCDF error codes.
INTERNALS = ("<xarray.", "array([", "AlignmentError", "reindex", "unhashable",
             "byte unit", "Errno", "NetCDF:")


@pytest.mark.parametrize("call, error, fragment",
                         [pytest.param(c, e, f, id=i) for i, c, e, f in OTHER_ROWS])
def test_bad_call_raises_a_clear_error(call, error, fragment):
    with pytest.raises(error) as err:
        call()
    assert fragment in str(err.value), str(err.value)
    assert not [part for part in INTERNALS if part in str(err.value)], str(err.value)


# --- issue 20: the review's new inputs that give a result: flagged or documented ----------

def _has_measure_flag(name):
    return lambda result: bool(np.all(result["flags"] & xbsm.measure.flag(name)))


def _rgba():
    rgb = np.stack([IMAGE, 0.5 * IMAGE, 0.25 * IMAGE], axis=-1)
    return np.concatenate([rgb, np.full(IMAGE.shape + (1,), 255.0)], axis=-1)


RESULT_ROWS = [
    # (id, call, check the result must pass, what it is): a flag bit, or the documented
    # handling of a legitimate input (alpha dropped; the geometry's limit or NaN)
    ("simulate_rgba", _simulated(_rgba()),
     lambda r: r.attrs["alpha"] == "dropped" and r.sizes["band"] == 3,
     "alpha dropped, recorded in attrs['alpha'] (docs/simulate.md)"),
    ("measure_clipped_edge", lambda: xbsm.measure.slanted_edge_mtf(_edge(clip=(0.2, 0.8))),
     _has_measure_flag("edge_clipped"), "flag edge_clipped (docs/measure.md)"),
    ("measure_saturated_uint8_edge", lambda: xbsm.measure.slanted_edge_mtf(
        np.clip(np.round(400.0 * EDGE - 100.0), 0, 255).astype(np.uint8)),
     _has_measure_flag("edge_clipped"), "flag edge_clipped (docs/measure.md)"),
    ("flat_noise_edge_in_region", lambda: xbsm.measure.flat_noise(
        EDGE + np.random.default_rng(0).normal(0.0, 0.01, EDGE.shape)),
     _has_measure_flag("region_not_flat"), "flag region_not_flat (docs/measure.md)"),
    ("geometry_zero_slant_range_equal_heights", lambda: (
        xbsm.geometry.nadir_angle(0.0, 9000.0, 9000.0),
        xbsm.geometry.altitude_along_path(0.0, 0.0, 9000.0, 9000.0)),
     lambda r: float(r[0]) == math.pi / 2 and float(r[1]) == 9000.0,
     "the limits pi/2 and the height (docstrings, docs/migration.md)"),
    ("geometry_zero_slant_range_below_sensor", lambda: (
        xbsm.geometry.nadir_angle(0.0, 9000.0),
        xbsm.geometry.altitude_along_path(0.0, 0.0, 9000.0)),
     lambda r: bool(np.isnan(r[0])) and bool(np.isnan(r[1])),
     "NaN: no line of sight is shorter than the height difference (docstrings)"),
]


@pytest.mark.parametrize("call, check",
                         [pytest.param(c, k, id=i) for i, c, k, _ in RESULT_ROWS])
def test_odd_input_gives_a_flagged_or_documented_result(call, check):
    assert check(call())


# --- inputs that are legitimate but odd: converted, promoted or flagged, never silent ------


def test_atmosphere_at_reads_the_units_attribute():
    km = xbsm.atmosphere_at(9000.0, xr.DataArray(20.0, attrs={"units": "km"}), 23.0)
    xr.testing.assert_identical(km.transmission, xbsm.atmosphere_at(9000.0, 20e3,
                                                                     23.0).transmission)


def test_cli_refuses_an_output_that_is_a_file(tmp_path, capsys):
    from xbsm.cli import main
    target = tmp_path / "file.txt"
    target.write_text("x")
    with pytest.raises(SystemExit) as exit_:
        main(["olson", "--out", str(target)])
    assert exit_.value.code == 2
    assert "exists and is not a directory" in capsys.readouterr().err


def test_units_attribute_is_converted():
    km = xbsm.scenario(**{**SCENARIO, "ground_range": xr.DataArray(
        [20.0], dims="g", attrs={"units": "km"})})
    assert float(km.ground_range[0]) == 20e3
    mm = xbsm.sensor(**{**SENSOR, "aperture_diameter": xr.DataArray(275.0,
                                                                     attrs={"units": "mm"})})
    assert float(mm.aperture_diameter) == pytest.approx(0.275, rel=1e-15)
    urad = xbsm.sensor(**{**SENSOR, "jitter_x": xr.DataArray(0.5, attrs={"units": "urad"})})
    assert float(urad.jitter_x) == pytest.approx(0.5e-6, rel=1e-15)


@pytest.mark.parametrize("dtype", [np.float16, np.float32, np.int64])
def test_low_precision_and_integer_inputs_are_promoted(dtype):
    altitude = xr.DataArray(np.array([9000], dtype=dtype), dims="case")
    sc = xbsm.scenario(**{**SCENARIO, "altitude": altitude, "ground_range": 0.0})
    assert sc.altitude.dtype == np.float64
    # the slant range at nadir is the altitude itself (float32 arithmetic gave 8688.9 m)
    n = xbsm.niirs(S, sc)
    assert float(n.slant_range[0]) == pytest.approx(9000.0, rel=1e-12)


def test_sweep_on_the_parameters_own_name_keeps_every_output():
    times = xr.DataArray([0.01, 0.03], dims="integration_time",
                         coords={"integration_time": [0.01, 0.03]})
    n = xbsm.niirs(xbsm.sensor(**{**SENSOR, "integration_time": times}), SC)
    assert n.sizes["integration_time"] == 2
    assert "effective_integration_time" in n


def test_beyond_the_horizon_is_flagged_not_silent():
    far = xbsm.scenario(**{**SCENARIO, "altitude": 100.0, "ground_range": 150e3})
    n = xbsm.niirs(S, far)
    assert bool(np.isnan(n.niirs).all())
    assert bool(has_flag(n.flags, "beyond_database").all())
    o = xbsm.system_otf(S, far)
    assert bool(has_flag(o.flags, "beyond_database"))


def test_a_system_blurred_over_many_pixels_is_flagged_not_trusted():
    # RER 0.019 from 20 px of jitter: the edge quadrature does not resolve the narrow OTF
    # (recipes/preset_error.py: accurate off by up to 3.6 NIIRS below RER 0.05)
    blurred = xbsm.sensor(**{**SENSOR, "jitter_x": 160e-6, "jitter_y": 160e-6})
    n = xbsm.niirs(blurred, SC)
    assert float(n.rer) < 0.05
    assert bool(xbsm.flags.decode(n.flags).blur_unresolved.all())
    assert bool(xbsm.flags.is_invalid(n.flags).all())
    assert not bool(xbsm.flags.decode(xbsm.niirs(S, SC).flags).blur_unresolved.any())


CURVE_BAND = dict(dims="wavelength")


@pytest.mark.parametrize("name, wavelengths", [
    ("quantum_efficiency", [0.5e-6, 0.6e-6]),      # ends inside the 0.55-0.85 um band
    ("optics_transmission", [0.6e-6, 0.9e-6]),     # starts inside it
    ("stray_irradiance", [0.6e-6, 0.7e-6]),        # inside at both ends
])
def test_a_curve_covering_part_of_the_band_is_flagged(name, wavelengths):
    # docs/flags.md: partial_spectral_coverage (a notice) on snr, niirs and system_otf
    curve = xr.DataArray([0.5, 0.5], coords={"wavelength": wavelengths}, **CURVE_BAND)
    s = xbsm.sensor(**{**SENSOR, name: curve})
    for result in (xbsm.snr(s, SC), xbsm.niirs(s, SC), xbsm.system_otf(s, SC)):
        bits = xbsm.flags.decode(result.flags)
        assert bool(bits.partial_spectral_coverage.all())
        assert not bool(bits.invalid.any())
    assert "partial_spectral_coverage" in xbsm.flags.NOTICE


def test_a_curve_covering_the_band_is_not_flagged():
    # the band edges written another way (0.55 * 1e-6) still cover the band; a curve sampled
    # only outside the band spans it and is non-zero inside (it was refused as zero before)
    curve = xr.DataArray([0.7, 0.6], coords={"wavelength": [0.55 * 1e-6, 0.85 * 1e-6]},
                         **CURVE_BAND)
    wider = xr.DataArray([0.7, 0.6], coords={"wavelength": [0.4e-6, 1.0e-6]}, **CURVE_BAND)
    for s in (xbsm.sensor(**{**SENSOR, "quantum_efficiency": curve}),
              xbsm.sensor(**{**SENSOR, "optics_transmission": wider}), S):
        assert not bool(has_flag(xbsm.niirs(s, SC).flags, "partial_spectral_coverage").any())


def test_a_sensor_without_signal_is_flagged_in_its_own_cells_of_a_sweep():
    # cold_filter_transmission = 0: no wavelength reaches the detector, so no optics cutoff
    # D / lambda_min of the signal; the call must not fail for the whole sweep (it raised
    # "cutoff must be finite"), the zero-signal cell is NaN with snr_nonpositive (flags.md)
    s = xbsm.sensor(**{**SENSOR, "cold_filter_transmission": xr.DataArray([0.0, 1.0],
                                                                          dims="cold_filter")})
    n = xbsm.niirs(s, SC)
    dark, lit = n.isel(cold_filter=0), n.isel(cold_filter=1)
    assert bool(np.isnan(dark.niirs).all()) and bool(has_flag(dark.flags, "snr_nonpositive").all())
    assert bool(np.isfinite(lit.niirs).all())
    single = xbsm.niirs(xbsm.sensor(**SENSOR), SC)
    np.testing.assert_allclose(lit.niirs, single.niirs, rtol=1e-12)


def test_an_even_pybsm_grid_is_a_valid_grid():
    # pyBSM's slice of linspace(-1, 1, N) is arange(0, 1, 2 / (N - 1)): 50 samples up to
    # 0.99 of the cutoff for N = 100 (0.98 for N = 101). The bound: undersampling_threshold
    # flags wherever the uniform rule's NIIRS error may exceed 0.01 (xbsm.methods), so an
    # unflagged even grid must agree with the converged Gauss-Legendre rule within 0.01.
    even = xbsm.niirs(S, SC, xbsm.method("pybsm", frequency_samples=100))
    converged = xbsm.niirs(S, SC, xbsm.method("pybsm", edge_rule="gauss_legendre"))
    assert not bool(has_flag(even.flags, "undersampled_grid").any())
    assert float(abs(even.niirs - converged.niirs).max()) <= 0.01
    assert float(abs(even.rer - converged.rer)) <= 1e-3


def test_method_overrides_are_recorded_in_the_result():
    n = xbsm.niirs(S, SC, xbsm.method("pybsm", frequency_samples=201))
    assert n.attrs["method"] == "pybsm (frequency_samples=201)"
    assert xbsm.snr(S, SC).attrs["method"] == "accurate"


def test_decode_gives_one_boolean_per_flag():
    n = xbsm.niirs(S, SC)
    bits = xbsm.flags.decode(n.flags)
    assert set(xbsm.flags.FLAGS) <= set(bits.data_vars)
    assert bits.invalid.dims == n.flags.dims
    np.testing.assert_array_equal(bits.well_fill_limited, has_flag(n.flags, "well_fill_limited"))


# --- random invalid values: an error naming the parameter, never a silent number ----------

_SENSOR_NAMES = [n for n in params.SENSOR_SPECS if n not in ("wavelength_min", "wavelength_max")]


@settings(max_examples=150, deadline=None)
@given(name=st.sampled_from(_SENSOR_NAMES),
       value=st.one_of(st.just(math.inf), st.just(-math.inf), st.just(math.nan),
                       st.floats(-1e12, -1e-300), st.text(max_size=3),
                       st.complex_numbers(allow_nan=False, allow_infinity=False)
                       .filter(lambda z: z.imag != 0)))
def test_random_invalid_sensor_values_raise_naming_the_parameter(name, value):
    spec = params.SENSOR_SPECS[name]
    try:
        xbsm.sensor(**{**SENSOR, name: value})
    except ValueError as err:
        assert name in str(err)
        return
    # accepted: only a real, finite value inside the allowed interval may pass
    assert isinstance(value, float) and not spec.violated(np.asarray(value)).any()
