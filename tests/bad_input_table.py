"""The bad-input table: shared by tests/test_bad_inputs.py and recipes/evidence/bad_input_sweep.py.

One row per bad or odd input at a public entry point. :data:`ERROR_ROWS`: the call must
raise the exception, its message containing the fragment (the parameter's name and its
allowed range, choices or fix), and none of :data:`INTERNALS`. :data:`RESULT_ROWS`: the
call gives a result that passes the check (a flag bit, or the documented handling of a
legitimate input). The test asserts each row; the sweep recipe runs each row in a
memory-capped child and counts it with its own cases (a row's fragment is its oracle).
"""

from __future__ import annotations

import math

import numpy as np
import xarray as xr

import xbsm
from xbsm.simulate import reflectance_to_photoelectrons

BAND = dict(wavelength_min=0.55e-6, wavelength_max=0.85e-6)
SENSOR = dict(aperture_diameter=0.275, focal_length=4.0, pixel_pitch_x=8e-6, **BAND,
              integration_time=0.03, max_well=96000.0, max_well_fill=0.6)
SCENARIO = dict(altitude=9000.0, ground_range=20e3, visibility=5.0)
S = xbsm.sensor(**SENSOR)
SC = xbsm.scenario(**SCENARIO)
PYBSM_SENSOR = dict(D=0.275, f=4.0, p_x=8e-6, opt_trans_wavelengths=np.array([0.55e-6, 0.85e-6]))


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

# frequencies and wavelengths for the OTF mechanisms' rows [cycles/rad], [m]
FX = xr.DataArray([0.0, 1e5], dims="fx")
FY = xr.DataArray([0.0, 1e5], dims="fy")
WAVELENGTHS = xr.DataArray([0.6e-6, 0.7e-6], dims="wavelength")


ERROR_ROWS = [
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
    ("visibility_not_in_database", lambda: xbsm.scenario(**{**SCENARIO, "visibility": 2.0}),
     ValueError, "visibility must be within [5, 23] km"),
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
     "targets must be one of 'giqe', 'scenario'"),
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
    # the OTF mechanisms' declared contracts (xbsm/otf/_contracts.py): the same message as
    # every other public function, the argument's name, interval and units
    ("otf_aperture_wavelength_zero", lambda: xbsm.otf.aperture.circular_aperture(
        FX, FY, 0.0, 0.275), ValueError, "wavelength must lie in (0, inf) m; got 0.0"),
    ("otf_aperture_obscuration_one", lambda: xbsm.otf.aperture.circular_aperture(
        FX, FY, 0.6e-6, 0.275, obscuration_ratio=1.0), ValueError,
     "obscuration_ratio must lie in [0, 1) 1; got 1.0"),
    ("otf_defocused_aperture_waves_inf", lambda: xbsm.otf.aperture.defocused_aperture(
        FX, FY, 0.6e-6, 0.275, defocus_waves=np.inf), ValueError,
     "defocus_waves must lie in (-inf, inf) 1; got inf"),
    ("otf_defocus_coefficient_focal_length_nan",
     lambda: xbsm.otf.aperture.defocus_wavefront_coefficient(1e-5, 0.275, np.nan), ValueError,
     "focal_length must lie in (0, inf) m; got nan"),
    ("otf_gaussian_defocus_size_negative", lambda: xbsm.otf.defocus.gaussian_defocus(
        FX, FY, -1e-6, 0.0), ValueError,
     "blur_radius_x must lie in [0, inf) rad; got -1e-06"),
    ("otf_object_defocus_focus_range_zero",
     lambda: xbsm.otf.defocus.object_domain_defocus_radius(0.275, 1000.0, 0.0), ValueError,
     "focus_range must lie in (0, inf] m; got 0.0"),
    ("otf_object_defocus_object_range_nan",
     lambda: xbsm.otf.defocus.object_domain_defocus_radius(0.275, np.nan, np.inf), ValueError,
     "object_range must lie in (0, inf] m; got nan"),
    ("otf_image_defocus_focal_length_negative",
     lambda: xbsm.otf.defocus.image_domain_defocus_radius(0.275, 1e-5, -4.0), ValueError,
     "focal_length must lie in (0, inf) m; got -4.0"),
    ("otf_detector_width_negative", lambda: xbsm.otf.detector.detector(FX, FY, -8e-6, 8e-6, 4.0),
     ValueError, "detector_width_x must lie in (0, inf) m; got -8e-06"),
    ("otf_aggregation_fractional", lambda: xbsm.otf.detector.aggregated_detector(
        FX, FY, 8e-6, 8e-6, 8e-6, 8e-6, 4.0, aggregation=1.5), ValueError,
     "aggregation must be a whole number in [1, inf); got 1.5"),
    ("otf_transfer_efficiency_above_one", lambda: xbsm.otf.detector.charge_transfer(
        FX, FY, 8e-6, 8e-6, 4.0, 100, 100, 1.5), ValueError,
     "transfer_efficiency must lie in [0, 1] 1; got 1.5"),
    ("otf_diffusion_depletion_negative", lambda: xbsm.otf.detector.diffusion(
        FX, FY, 1e5, -1e-6, 1e-5, 4.0), ValueError,
     "depletion_width must lie in [0, inf) m; got -1e-06"),
    ("otf_gaussian_blur_negative", lambda: xbsm.otf.filters.gaussian(FX, FY, -1e-6, 0.0),
     ValueError,
     "blur_size_x must lie in [0, inf) rad; got -1e-06"),
    ("otf_sharpening_ifov_zero", lambda: xbsm.otf.filters.sharpening_filter(
        FX, FY, np.ones((1, 1)), 0.0), ValueError, "ifov_x must lie in (0, inf) rad; got 0.0"),
    ("otf_jitter_negative", lambda: xbsm.otf.motion.jitter(FX, FY, -1e-6, 0.0), ValueError,
     "jitter_rms_x must lie in [0, inf) rad; got -1e-06"),
    ("otf_drift_inf", lambda: xbsm.otf.motion.drift(FX, FY, np.inf, 0.0), ValueError,
     "drift_x must lie in (-inf, inf) rad s-1; got inf"),
    ("otf_tdi_half_stage", lambda: xbsm.otf.motion.tdi(FX, 8e-6, 4.0, 2.5, 1.0), ValueError,
     "stages must make stages * phases a whole number >= 1"),
    ("otf_random_phase_variance_negative", lambda: xbsm.otf.wavefront.random_phase_wavefront(
        FX, FY, 0.6e-6, -0.1, 0.1, 0.1), ValueError,
     "phase_variance must lie in [0, inf) rad2; got -0.1"),
    ("otf_shannon_error_too_large", lambda: xbsm.otf.wavefront.shannon_wavefront(
        FX, FY, 0.6e-6, 0.275, 0.2), ValueError,
     "rms_wavefront_error must lie in [0, 0.18] 1; got 0.2"),
    ("otf_hufnagel_valley_cn2_negative", lambda: xbsm.otf.turbulence.hufnagel_valley(
        1000.0, cn2_at_1m=-1e-14), ValueError,
     "cn2_at_1m must lie in [0, inf) m-2/3; got -1e-14"),
    ("otf_slant_path_samples_one", lambda: xbsm.otf.turbulence.slant_path_coherence_diameter(
        2e4, 9000.0, path_samples=1), ValueError,
     "path_samples must be a whole number in [2, inf); got 1"),
    ("otf_turbulence_r0_zero", lambda: xbsm.otf.turbulence.turbulence(FX, FY, 0.6e-6, 0.275, 0.0),
     ValueError, "coherence_diameter must lie in (0, inf) m; got 0.0"),
    ("otf_wind_blended_speed_negative", lambda: xbsm.otf.turbulence.wind_blended_turbulence(
        FX, FY, 0.6e-6, 0.275, 0.05, 0.01, -1.0), ValueError,
     "wind_speed must lie in [0, inf) m s-1; got -1.0"),
    ("otf_band_r0_weights_all_zero", lambda: xbsm.otf.turbulence.band_coherence_diameter(
        0.05, WAVELENGTHS, xr.zeros_like(WAVELENGTHS)), ValueError,
     "weights must not be all zero along 'wavelength'"),
    ("otf_spectral_average_weights_negative", lambda: xbsm.otf.spectral.spectral_average(
        xr.ones_like(WAVELENGTHS), -xr.ones_like(WAVELENGTHS)), ValueError,
     "weights must lie in [0, inf) 1; got -1.0"),
]


# Fragments of library internals an error message must never show the user (issue 8):
# raw xarray / numpy reprs and errors, dask's byte-unit parser, netCDF error codes.
INTERNALS = ("<xarray.", "array([", "AlignmentError", "reindex", "unhashable",
             "byte unit", "Errno", "NetCDF:")


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
