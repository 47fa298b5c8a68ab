"""Conventions every public output follows (architectural tests, in the spirit of prysm's).

Every public function of the stage modules is run on a standard case: the paper's
Olson camera (:func:`xbsm.examples.olson_sensor`) at 20 km ground range in 5 km
visibility for the model chain, and small literal inputs (a 3 x 5 frequency grid, a
few wavelengths) for the stage functions. On every result:

- every data variable and every non-index coordinate carries a non-empty ``units``
  and ``long_name``;
- ``units`` equals :data:`EXPECTED_UNITS`, a table of what each variable *is*
  (keyed by variable name, or by the function name for a DataArray result;
  :data:`CASE_UNITS` for the one name that means two things), and a variable the
  table does not know fails, so the table grows with the code;
- a CF ``standard_name`` (on any variable, index coordinates included) is in
  :data:`CF_STANDARD_NAMES` with its canonical units and sits on a variable
  :data:`STANDARD_NAMES` says is that quantity (xarray arithmetic copies the
  attributes of its operands: a rate computed from ``wavelength`` inherited
  ``standard_name: radiation_wavelength``);
- flag variables (those with ``flag_masks``) carry ``flag_masks`` and
  ``flag_meanings`` of equal length and a ``long_name``; they are exempt from the
  units table (CF flags are dimensionless codes; ``units`` is absent or "1");
- a GIQE result cites that version's own source (:data:`xbsm.metrics.GIQE_REFERENCES`):
  only GIQE 3 is IBSM Eq. 3-56.

Every public function of those modules must have a case here or be listed in
:data:`NOT_LABELLED` with the reason. Method knobs rejecting bad values are tested
in ``test_methods.py`` (``test_every_knob_rejects_a_bad_value_when_the_method_is_made``);
the other enumerated choices of the public functions are tested at the end.
"""

from __future__ import annotations

import functools
import importlib
import inspect
from types import MappingProxyType

import numpy as np
import pytest
import xarray as xr

import xbsm
from xbsm import atmosphere, geometry, metrics, noise, quadrature, radiometry
from xbsm.examples import olson_scenario, olson_sensor
from xbsm.otf import (
    aperture,
    defocus,
    detector,
    filters,
    motion,
    psf,
    spectral,
    system,
    turbulence,
    user,
    wavefront,
)
from xbsm.simulate import reflectance_to_photoelectrons

RADIANCE = "W m-2 sr-1 m-1"
IRRADIANCE = "W m-2 m-1"

EXPECTED_UNITS = MappingProxyType({
    # model chain and noise terms [count = electrons, rms for the noise terms]
    "snr": "1", "snr_frame": "1", "niirs": "1", "well_fill": "1", "well_fill_scale": "1",
    "effective_integration_time": "s",
    "photoelectrons": "count", "target_photoelectrons": "count",
    "background_photoelectrons": "count", "contrast_photoelectrons": "count",
    "shot_noise": "count", "scene_noise": "count", "path_noise": "count",
    "self_emission_noise": "count", "dark_current_noise": "count",
    "quantization_noise": "count", "read_noise": "count", "other_noise": "count",
    "total_noise": "count", "cold_shield_noise": "count", "optics_emission_noise": "count",
    "cold_filter_emission_noise": "count", "stray_light_noise": "count",
    "spectral_weights": "s-1 m-1",
    "path_rate": "s-1", "target_scene_rate": "s-1", "background_scene_rate": "s-1",
    "sensor_rate": "s-1", "target_rate": "s-1",
    # noise-equivalent quantities
    "signal_derivative": "count K-1", "netd": "K", "netd_frame": "K", "ner": "W m-2 sr-1",
    "ner_target": "W m-2 sr-1", "nei": "W m-2", "mrtd": "K", "mtf": "1",
    "minimum_resolvable": "K", "mrc": "1", "noise_equivalent_contrast": "1",
    "reflectance_signal": "count",
    # target acquisition
    "probability": "1", "cycles_on_target": "1", "ttp": "cycles/rad",
    "limiting_frequency": "cycles/rad", "ctf_system": "1", "displayed_target_size": "deg",
    # edge terms and GIQE
    "rer": "1", "rer_x": "1", "rer_y": "1", "eho": "1", "eho_x": "1", "eho_y": "1",
    "rer_giqe5": "1", "noise_gain": "1", "edge_response": "1",
    "relative_edge_response": "1", "edge_height_overshoot": "1", "giqe5_rer": "1",
    "sampling_q": "1", "gsd": "m", "gsd_gp": "m", "gsd_w": "m",
    "ground_resolved_distance": "m",
    "coherence_diameter": "m", "cutoff_frequency": "cycles/rad",
    # geometry
    "slant_range": "m", "elevation_angle": "rad", "target_elevation_angle": "rad",
    "nadir_angle": "rad", "altitude_along_path": "m", "ifov": "rad",
    "ground_range_at_elevation": "m",
    "ground_sample_distance": "m", "ifov_x": "rad", "ifov_y": "rad", "gsd_x": "m", "gsd_y": "m",
    "otf_weights": "s-1 m-1",
    # atmosphere
    "transmission": "1", "path_thermal": RADIANCE, "surface_emission": RADIANCE,
    "solar_scatter": RADIANCE, "ground_reflected": RADIANCE,
    "wavelength": "m",
    # radiometry
    "blackbody_radiance": RADIANCE, "total_radiance": RADIANCE, "path_radiance": RADIANCE,
    "giqe_radiance": RADIANCE, "target_radiance": RADIANCE, "background_radiance": RADIANCE,
    "throughput_factor": "sr", "focal_plane_irradiance": IRRADIANCE,
    "detector_irradiance": IRRADIANCE, "sensor_irradiance": IRRADIANCE,
    "cold_shield_self_emission": IRRADIANCE, "cold_stop_self_emission": IRRADIANCE,
    "optics_self_emission": IRRADIANCE, "photon_detection_rate": "s-1 m-1",
    "band_integral": "s-1", "dark_current_from_density": "s-1",
    "optics_transmission": "1", "quantum_efficiency": "1",
    # noise functions
    "stacked_snr": "1",
    # quadrature
    "nodes": "cycles/rad", "weights": "cycles/rad", "sine_frequency": "cycles/rad",
    "error_weights": "cycles/rad", "edge_error": "1",
    "cutoff_wavelength": "m", "optics_cutoff": "cycles/rad", "band_cutoff": "cycles/rad",
    "rer_unfiltered_x": "1", "rer_unfiltered_y": "1",
    "samples_per_oscillation": "1",
    # OTFs [1] and their helpers
    "aperture": "1", "turbulence": "1", "detector": "1", "jitter": "1", "drift": "1",
    "wavefront": "1", "filter": "1", "system": "1", "system_unfiltered": "1",
    "circular_aperture": "1", "defocused_aperture": "1", "gaussian_defocus": "1",
    "defocused_aperture_otf": "1", "geometric_defocus": "1", "blur_circle_diameter": "rad",
    "aggregated_detector": "1", "charge_transfer": "1", "diffusion": "1", "gaussian": "1",
    "sharpening_filter": "1", "tdi": "1", "otf_to_psf": "1", "spectral_average": "1",
    "wind_blended_turbulence": "1", "polychromatic_turbulence": "1", "user_defined": "1",
    "random_phase_wavefront": "1", "shannon_wavefront": "1",
    "defocus_wavefront_coefficient": "m", "object_domain_defocus_radius": "rad",
    "image_domain_defocus_radius": "rad", "hufnagel_valley": "m-2/3",
    "path_coherence_diameter": "m", "slant_path_coherence_diameter": "m",
    "scale_coherence_diameter": "m", "band_coherence_diameter": "m",
})
"""What each variable is, by name: its CF ``units`` (UDUNITS; ``count`` for electrons)."""

CASE_UNITS = MappingProxyType({
    # reflectance_to_photoelectrons normalises the weights to a peak of one
    ("reflectance_to_photoelectrons", "spectral_weights"): "1",
})
"""Units of a variable whose name means something else in one case."""

CF_STANDARD_NAMES = MappingProxyType({"radiation_wavelength": "m"})
"""CF standard names xbsm uses, with their canonical units (CF standard name table)."""

STANDARD_NAMES = MappingProxyType({
    "wavelength": "radiation_wavelength",
    "cutoff_wavelength": "radiation_wavelength",
})
"""The variables that are a CF standard-name quantity (any other must not claim one)."""

GIQE_CASES = MappingProxyType({"giqe3": 3, "giqe4": 4, "giqe5": 5})
"""Cases that compute one GIQE version."""

NOT_LABELLED = MappingProxyType({
    "xbsm.atmosphere.database.open_atmosphere": "the raw database cube; units differ by "
    "component and are in its component_units coordinate (docs/atmosphere.md)",
    "xbsm.atmosphere.lookup.band_wavelengths": "returns a numpy array",
    "xbsm.atmosphere.database.database_path": "returns a path",
    "xbsm.atmosphere.database.use_database": "a context manager; yields a path",
    "xbsm.atmosphere.database.check_supported": "a validator: returns None or raises",
    "xbsm.atmosphere.database.database_visibilities": "returns a tuple of floats",
    "xbsm.atmosphere.database.database_conditions": "returns a dict of tuples of floats",
    **{f"xbsm.atmosphere.database.{name}": "returns the text of an error message"
       for name in ("describe_conditions", "listed", "visibility_range")},
    "xbsm.atmosphere.lookup.across_visibility": "a kernel: plain numpy arrays in and out "
    "(atmosphere_at labels the result)",
    "xbsm.atmosphere.lookup.condition_inputs": "returns the inputs, in the database's order",
    "xbsm.atmosphere.tables.from_tables": "the raw database cube in the file's schema; units "
    "differ by component and are in its component_units coordinate (docs/atmosphere.md)",
    "xbsm.atmosphere.tables.validate_database": "a validator: returns None or raises",
    "xbsm.atmosphere.tables.write_database": "writes a file; returns its path",
    "xbsm.atmosphere.tables.horizon": "returns a numpy array (the geometry of the checks)",
    "xbsm.atmosphere.database.database_wavelengths": "returns a numpy array",
    "xbsm.atmosphere.database.load_database": "returns the database's numpy arrays",
    "xbsm.atmosphere.lookup.interpolate_database": "a kernel: plain numpy arrays in and out "
    "(atmosphere_at labels the same interpolation)",
    **{f"xbsm.atmosphere.rules.{name}": "a kernel of the fixed-range rules: plain numpy "
       "arrays in and out (atmosphere_at labels the result)"
       for name in ("bracket", "fixed_range", "gather", "interpolate", "ln_interpolate")},
    **{f"xbsm.geometry.{name}": "a kernel: plain numpy arrays in and out, composed by "
       "xbsm.atmosphere (labelled by viewing_geometry and ground_range_at_elevation)"
       for name in ("slant_and_elevation_kernel", "ground_range_at_elevation_kernel")},
    "xbsm.geometry.altitude_along_path_kernel": "a kernel: plain numpy arrays in and out, "
    "composed by xbsm.otf.turbulence's slant-path r0 (labelled by altitude_along_path)",
    "xbsm.radiometry.is_emissive_band": "returns a bool",
    "xbsm.noise.noise_inputs": "returns the arguments of noise_arrays, as given",
    **{f"xbsm.radiometry.{name}_inputs": f"returns the arguments of {name}_arrays, as given"
       for name in ("radiance", "sensor_band", "signal", "sensitivity")},
    "xbsm.radiometry.surfaces": "returns the (reflectance, temperature) pairs, as given",
    "xbsm.radiometry.target_set": "returns a target set: parameters (with units), not a result",
    "xbsm.radiometry.standard_targets": "returns a target set: parameters, not a result",
    "xbsm.radiometry.check_target_set": "a validator: returns its argument or raises",
    "xbsm.radiometry.targets_on_scenario": "returns a scenario dataset (parameters)",
    "xbsm.radiometry.standard_target": "returns a bool that feeds a flag",
    "xbsm.radiometry.planck_knobs": "returns the kernels' constants as plain floats",
    "xbsm.radiometry.curve_on_band": "resample_spectral on plain arrays (the direct applier)",
    "xbsm.radiometry.resample_spectral": "keeps the attributes of the sensor curve it resamples",
    "xbsm.quadrature.aperture_breakpoints": "returns a numpy array",
    "xbsm.quadrature.detector_breakpoints": "returns a numpy array",
    "xbsm.quadrature.aperture_kink_fractions": "returns a numpy array",
    "xbsm.quadrature.band_optics_limits": "returns a dict of the stage's DataArrays, labelled "
    "from quadrature.CUTOFF_OUTPUTS (band_cutoff's case checks the cutoff's units)",
    "xbsm.quadrature.pybsm_slice_count": "returns an int",
    "xbsm.quadrature.undersampled": "returns a boolean mask that feeds a flag",
    "xbsm.metrics.giqe.giqe_calibrations": "returns a table of calibrations",
    "xbsm.metrics.acquisition.bar_constant": "returns the MRTD formula's constant, a float",
    "xbsm.metrics.acquisition.minimum_resolvable_kernel": "a kernel: plain numpy arrays in "
    "and out (labelled by minimum_resolvable)",
    "xbsm.otf.system.spectral_bins": "internal binning of the polychromatic OTF",
    "xbsm.otf.system.binning_error_kernel": "a kernel: plain numpy arrays in and out (the "
    "chain's flag criterion; tests/metrics/test_edge_reference.py checks it)",
    "xbsm.metrics.edge.binning_niirs_error": "plain arithmetic on the chain's RERs (a flag "
    "criterion, not a result variable)",
    "xbsm.metrics.edge.check_slice": "a validator: raises or returns None",
    "xbsm.otf.spectral.is_lazy": "returns a bool",
    **{f"xbsm.otf.{name}": "a kernel: plain numpy arrays in and out, composed by "
       "xbsm.otf.system (labelled by the mechanism's public function)"
       for name in ("aperture.circular_aperture_kernel",
                    "aperture.circular_aperture_band_kernel", "detector.detector_kernel",
                    "aperture.hopkins_kernel", "defocus.annular_defocus_kernel",
                    "defocus.defocused_aperture_kernel",
                    "filters.dtft_filter_kernel", "filters.pybsm_filter_kernel",
                    "motion.drift_kernel", "motion.drift_slices_kernel",
                    "motion.jitter_kernel",
                    "spectral.normalised_weights", "spectral.weighted_sum_kernel",
                    "turbulence.band_kernel",
                    "turbulence.polychromatic_kernel", "turbulence.slant_path_kernel",
                    "turbulence.table_kernel",
                    "wavefront.random_phase_kernel")},
    **{f"xbsm.{name}": "a stage's array orchestrator: plain arrays in and out, labelled by "
       "xbsm._chain from the stage's declared outputs (tests/test_chain.py)"
       for name in ("atmosphere.lookup.band_atmosphere_arrays", "geometry.viewing_arrays",
                    "noise.noise_arrays", "noise.noise_gain_arrays",
                    "quadrature.band_cutoff_arrays", "quadrature.edge_rule_arrays",
                    "quadrature.undersampled_arrays", "radiometry.radiance_arrays",
                    "radiometry.sensor_band_arrays", "radiometry.signal_arrays",
                    "radiometry.reflectance_counts_arrays", "radiometry.sensitivity_arrays",
                    "metrics.edge.slice_terms_arrays", "metrics.giqe.giqe_arrays",
                    "metrics.giqe.sampling_q_arrays", "otf.system.system_slice_arrays")},
})
"""Public functions whose result is not a labelled quantity, with the reason."""

MODULES = (atmosphere.database, atmosphere.rules, atmosphere.lookup, atmosphere.tables,
           geometry, noise, quadrature, radiometry, xbsm.model,
           metrics.edge, metrics.grd, metrics.giqe, metrics.acquisition,
           aperture, defocus, detector, filters, motion, psf, spectral, system, turbulence,
           user, wavefront)


# ---- the standard cases -------------------------------------------------------------

@functools.cache
def _olson():
    return olson_sensor(), olson_scenario(ground_range=20e3, visibility=5.0)


@functools.cache
def _band():
    s, sc = _olson()
    return atmosphere.atmosphere_at(
        sc["altitude"], sc["ground_range"], sc["visibility"],
        wavelength_bounds=(float(s["wavelength_min"]), float(s["wavelength_max"])))


@functools.cache
def _signal():
    s, sc = _olson()
    atm = _band()
    target, background = radiometry.aperture_radiances(atm, sc, "giqe", s["wavelength_min"])
    return radiometry.signal_terms(s, atm, target, background)


def _fx():
    return xr.DataArray(np.linspace(0.0, 2.0e5, 5), dims="fx")


def _fy():
    return xr.DataArray(np.linspace(-1.0e5, 1.0e5, 3), dims="fy")


def _wavelength():
    return xr.DataArray([0.6e-6, 0.7e-6, 0.8e-6], dims="wavelength")


def _weights():
    return xr.DataArray([1.0, 2.0, 1.0], dims="wavelength")


def _quadrature():
    return quadrature.edge_quadrature(cutoff=0.275 / 0.55e-6, ifov=2e-6,
                                      **xbsm.method("accurate").edge_quadrature_knobs())


def _edge_slice():
    nodes, weights = _quadrature()
    otf = aperture.circular_aperture(nodes, 0.0 * nodes, 0.55e-6, 0.275)
    return otf, weights


def _system_slices():
    """The x and y slices of an aperture OTF at the quadrature nodes, unfiltered and ifov."""
    otf, weights = _edge_slice()
    orientation = xr.DataArray(["x", "y"], dims="orientation")
    slices = xr.concat([otf, otf], dim=orientation)
    ifov = xr.DataArray([2e-6, 3e-6], dims="orientation", coords={"orientation": orientation})
    return slices, None, ifov, weights


def _psf_input():
    f = np.linspace(-2e5, 2e5, 8, endpoint=False)
    fx = xr.DataArray(f, dims="fx", coords={"fx": f})
    fy = xr.DataArray(f, dims="fy", coords={"fy": f})
    return motion.jitter(fx, fy, 1e-6, 1e-6)


def _geometry(func):
    return func(xr.DataArray([1.0e3, 20.0e3], dims="ground_range"), 9000.0)


def _model_cases():
    s, sc = _olson()
    cases = {
        "snr": lambda: xbsm.snr(s, sc),
        "netd": lambda: xbsm.netd(s, sc),
        "mrtd": lambda: xbsm.mrtd(s, sc, frequency=[1e4, 1e5]),
        "mrc": lambda: xbsm.mrc(s, sc, frequency=[1e4, 1e5]),
        "system_otf": lambda: xbsm.system_otf(s, sc),
        "target_acquisition": lambda: xbsm.target_acquisition(
            s, sc, xbsm.radiometry.target_set(2.5, reflectance_contrast=0.5)),
        "reflectance_to_photoelectrons": lambda: reflectance_to_photoelectrons(s, sc),
    }
    for m in ("accurate", "fast", "pybsm"):
        cases[f"niirs[{m}]"] = functools.partial(xbsm.niirs, s, sc, method=m)
    return cases


def _cases():
    fx, fy, wl, w = _fx(), _fy(), _wavelength(), _weights()
    rng = xr.DataArray([1.0e3, 20.0e3], dims="ground_range")
    s, sc = _olson()
    r0 = xr.DataArray([0.05, 0.1], dims="r0")
    cases = {
        # model chain (Olson camera)
        **_model_cases(),
        "atmosphere_at": _band,
        "band_atmosphere": lambda: atmosphere.band_atmosphere(
            9000.0, 20e3, 5.0, 0.55e-6, 0.85e-6, interpolation="log-linear",
            band_edges="exact"),
        "signal_terms": _signal,
        "noise_terms": lambda: noise.noise_terms(_signal(), s),
        "self_emission_noise_terms": lambda: noise.self_emission_noise_terms(
            noise.noise_terms(_signal(), s).self_emission_noise, s, _signal().wavelength),
        # geometry
        "slant_range": lambda: geometry.slant_range(rng, 9000.0),
        "ground_range_at_elevation": lambda: geometry.ground_range_at_elevation(
            xr.DataArray([0.1, 0.5, 1.2], dims="elevation"), 9000.0),
        "viewing_geometry": lambda: geometry.viewing_geometry(rng, 9000.0, 8e-6, 8e-6, 4.0),
        "nadir_angle": lambda: _geometry(lambda g, h: geometry.nadir_angle(
            geometry.slant_range(g, h), h)),
        "elevation_angle": lambda: _geometry(lambda g, h: geometry.elevation_angle(
            geometry.slant_range(g, h), h)),
        "target_elevation_angle": lambda: _geometry(lambda g, h: geometry.target_elevation_angle(
            geometry.slant_range(g, h), h)),
        "altitude_along_path": lambda: geometry.altitude_along_path(
            xr.DataArray([0.0, 5e3], dims="path"), geometry.slant_range(rng, 9000.0), 9000.0),
        "ifov": lambda: geometry.ifov(xr.DataArray([8e-6, 16e-6], dims="pitch"), 4.0),
        "ground_sample_distance": lambda: geometry.ground_sample_distance(
            2e-6, geometry.slant_range(rng, 9000.0)),
        # radiometry
        "blackbody_radiance": lambda: radiometry.blackbody_radiance(wl, 300.0),
        "total_radiance": lambda: radiometry.total_radiance(_band(), 0.15, 282.0),
        "path_radiance": lambda: radiometry.path_radiance(_band()),
        "giqe_radiance": lambda: radiometry.giqe_radiance(
            _band(), radiometry.GIQE_TARGET, False),
        "aperture_radiances": lambda: xr.Dataset(dict(zip(
            ("target_radiance", "background_radiance"),
            radiometry.aperture_radiances(_band(), sc, "scenario", s["wavelength_min"]),
            strict=True))),
        "throughput_factor": lambda: radiometry.throughput_factor(
            xr.DataArray([0.1, 0.275], dims="d"), 4.0),
        "focal_plane_irradiance": lambda: radiometry.focal_plane_irradiance(
            radiometry.blackbody_radiance(wl, 300.0), 0.275, 4.0),
        "cold_shield_self_emission": lambda: radiometry.cold_shield_self_emission(
            wl, 70.0, 0.275, 4.0),
        "cold_stop_self_emission": lambda: radiometry.cold_stop_self_emission(
            wl, 70.0, 0.5, 0.275, 4.0),
        "optics_self_emission": lambda: radiometry.optics_self_emission(
            wl, 270.0, 0.1, 0.9, 0.275, 4.0),
        "photon_detection_rate": lambda: radiometry.photon_detection_rate(
            radiometry.focal_plane_irradiance(radiometry.total_radiance(_band(), 0.15, 282.0),
                                              0.275, 4.0), 0.7, 8e-6, 8e-6),
        "band_integral": lambda: radiometry.band_integral(_signal()["spectral_weights"]),
        "dark_current_from_density": lambda: radiometry.dark_current_from_density(
            xr.DataArray([1e-5, 2e-5], dims="density"), 8e-6, 8e-6),
        "well_fill_scale": lambda: radiometry.well_fill_scale(
            xr.DataArray([1e4, 1e5], dims="n"), 96000.0, 0.6),
        "sensor_band_terms": lambda: radiometry.sensor_band_terms(s, _band()["wavelength"]),
        "noise_equivalent_terms": lambda: radiometry.noise_equivalent_terms(
            s, sc, _band(), radiometry.sensor_band_terms(s, _band()["wavelength"]), _signal(),
            noise.noise_terms(_signal(), s)["total_noise"]),
        "detector_irradiance": lambda: radiometry.detector_irradiance(
            radiometry.total_radiance(_band(), 0.15, 282.0),
            radiometry.sensor_band_terms(s, _band()["wavelength"]), s),
        # noise functions
        "shot_noise": lambda: noise.shot_noise(xr.DataArray([1e3, 1e4], dims="n")),
        "dark_current_noise": lambda: noise.dark_current_noise(
            xr.DataArray([1e3, 1e4], dims="n"), 0.01),
        "quantization_noise": lambda: noise.quantization_noise(
            xr.DataArray([1e4, 1e5], dims="n"), 12.0),
        "noise_gain": lambda: noise.noise_gain(xr.DataArray(
            [[0.0, -0.25, 0.0], [-0.25, 2.0, -0.25], [0.0, -0.25, 0.0]],
            dims=("kernel_y", "kernel_x"))),
        "total_noise": lambda: noise.total_noise(
            xr.DataArray([1e3, 1e4], dims="n"), 10.0, 25.0, 0.0),
        "stacked_snr": lambda: noise.stacked_snr(xr.DataArray([5.0, 50.0], dims="n"), 4.0),
        # quadrature
        "edge_quadrature": lambda: xr.Dataset(dict(zip(("nodes", "weights"), _quadrature(),
                                                       strict=True))),
        "edge_nodes": lambda: xr.Dataset(dict(zip(("nodes", "weights"), quadrature.edge_nodes(
            xr.DataArray([5e5, 6e5], dims="cutoff"), 2e-6, 2e-6,
            **xbsm.method("accurate").edge_quadrature_knobs()), strict=True))),
        "gauss_legendre_rule": lambda: xr.Dataset(dict(zip(
            ("nodes", "weights"), quadrature.gauss_legendre_rule(np.array([0.0, 1e5, 2e5]), 4),
            strict=True))),
        "uniform_trapezoid_rule": lambda: xr.Dataset(dict(zip(
            ("nodes", "weights"), quadrature.uniform_trapezoid_rule(11, 1e4), strict=True))),
        "samples_per_oscillation": lambda: quadrature.samples_per_oscillation(
            _quadrature()[0], xr.DataArray([5e5], dims="c"), 2e-6, 2e-6),
        "cutoff_wavelength": lambda: quadrature.cutoff_wavelength(
            _band()["wavelength"], 0.7, 0.5),
        "optics_cutoff": lambda: quadrature.optics_cutoff(0.275, _band()["wavelength"], 0.7, 0.5),
        "band_cutoff": lambda: quadrature.band_cutoff(0.275, _band()["wavelength"], 0.7, 0.5,
                                                      0.5e-6),
        # metrics
        "edge_response": lambda: metrics.edge_response(
            _edge_slice()[0], 2e-6, xr.DataArray([0.0, 1.0], dims="position"), _edge_slice()[1]),
        "relative_edge_response": lambda: metrics.relative_edge_response(
            _edge_slice()[0], 2e-6, _edge_slice()[1]),
        "edge_height_overshoot": lambda: metrics.edge_height_overshoot(
            _edge_slice()[0], 2e-6, _edge_slice()[1]),
        "edge_terms": lambda: metrics.edge_terms(_edge_slice()[0], 2e-6, _edge_slice()[1]),
        "slice_terms": lambda: metrics.edge.slice_terms(*_system_slices(), "real"),
        "ground_resolved_distance": lambda: metrics.ground_resolved_distance(
            _edge_slice()[0], xr.DataArray([10.0, 50.0], dims="snr"), 2e-6, 20e3),
        "minimum_resolvable": lambda: metrics.minimum_resolvable(
            0.05, xr.DataArray([[1.0, 0.5]], dims=("orientation", "frequency"),
                               coords={"orientation": ["x"], "frequency": [1e4, 2e4]}),
            2e-6, 3e-6),
        "giqe3": lambda: metrics.giqe3(rer=0.35, gsd=0.5, eho=1.0, snr=50.0),
        "giqe4": lambda: metrics.giqe4(rer=0.35, gsd=0.5, eho=1.0, snr=50.0, elevation=1.0),
        "giqe5": lambda: metrics.giqe5(rer_x=0.35, rer_y=0.4, gsd=0.5, snr=20.0, elevation=1.0),
        "giqe5_rer": lambda: metrics.giqe5_rer(xr.DataArray([0.3, 0.5], dims="r"), 0.4),
        "giqe_flags": lambda: metrics.giqe_flags(snr=xr.DataArray([1.0, 50.0], dims="n"),
                                                 rer=0.35, gsd=0.5),
        "sampling_q": lambda: metrics.sampling_q(0.7e-6, 0.275, xr.DataArray([2e-6], dims="p")),
        "giqe_by_version": lambda: metrics.giqe_by_version(
            rer=xr.DataArray([0.3, 0.5], dims="r"), eho=1.0, rer_x=0.35, rer_y=0.4, gsd_x=0.5,
            gsd_y=0.5, snr=20.0, elevation=1.0, noise_gain=1.0, q=1.5,
            noise_coefficient=0.344, calibration=metrics.giqe_calibrations()),
        # OTFs on a 3 x 5 frequency grid
        "circular_aperture": lambda: aperture.circular_aperture(fx, fy, wl, 0.275, 0.4),
        "defocus_wavefront_coefficient": lambda: aperture.defocus_wavefront_coefficient(
            xr.DataArray([1e-5, 2e-5], dims="shift"), 0.275, 4.0),
        "defocused_aperture": lambda: aperture.defocused_aperture(
            fx, fy, wl, 0.275, defocus_waves=0.5),
        "gaussian_defocus": lambda: defocus.gaussian_defocus(fx, fy, 1e-6, 2e-6),
        "defocused_aperture_otf": lambda: defocus.defocused_aperture_otf(
            fx, fy, wl, 0.275, xr.DataArray([0.0, 0.5e-6], dims="opd"), 0.4),
        "geometric_defocus": lambda: defocus.geometric_defocus(fx, fy, 2e-6),
        "blur_circle_diameter": lambda: defocus.blur_circle_diameter(
            xr.DataArray([0.0, 0.5e-6], dims="opd"), 0.275),
        "object_domain_defocus_radius": lambda: defocus.object_domain_defocus_radius(
            0.275, xr.DataArray([1e3, 2e3], dims="range"), 1.5e3),
        "image_domain_defocus_radius": lambda: defocus.image_domain_defocus_radius(
            0.275, xr.DataArray([1e-5, 2e-5], dims="shift"), 4.0),
        "detector": lambda: detector.detector(fx, fy, 8e-6, 8e-6, 4.0),
        "aggregated_detector": lambda: detector.aggregated_detector(
            fx, fy, 8e-6, 8e-6, 8e-6, 8e-6, 4.0, aggregation=2),
        "charge_transfer": lambda: detector.charge_transfer(
            fx, fy, 8e-6, 8e-6, 4.0, 100, 100, 0.9999),
        "diffusion": lambda: detector.diffusion(fx, fy, 1e4, 5e-6, 2e-5, 4.0),
        "gaussian": lambda: filters.gaussian(fx, fy, 1e-6, 2e-6),
        "sharpening_filter": lambda: filters.sharpening_filter(
            fx, fy, np.array([[0.0, -0.25, 0.0], [-0.25, 2.0, -0.25], [0.0, -0.25, 0.0]]),
            2e-6, 2e-6),
        "jitter": lambda: motion.jitter(fx, fy, 1e-6, 2e-6),
        "drift": lambda: motion.drift(fx, fy, 1e-6, 2e-6),
        "tdi": lambda: motion.tdi(fx, 8e-6, 4.0, 16, 1.01),
        "otf_to_psf": lambda: psf.otf_to_psf(_psf_input()),
        "spectral_average": lambda: spectral.spectral_average(
            aperture.circular_aperture(fx, fy, wl, 0.275), w),
        "otf_weights": lambda: system.otf_weights(_signal()["spectral_weights"]),
        "system_components": lambda: system.system_components(
            s, sc, xr.DataArray(np.linspace(0.0, 4e5, 5), dims="frequency"),
            spectral_weights=_signal()["spectral_weights"],
            integration_time=_signal()["effective_integration_time"],
            slant_range=geometry.slant_range(sc["ground_range"], sc["altitude"]),
            method=xbsm.method("accurate")),
        "hufnagel_valley": lambda: turbulence.hufnagel_valley(
            xr.DataArray([0.0, 1e3, 1e4], dims="altitude")),
        "path_coherence_diameter": lambda: turbulence.path_coherence_diameter(
            xr.DataArray([1e-14, 1e-15, 1e-16], dims="path",
                         coords={"path": ("path", [0.0, 5e3, 1e4], {"units": "m"})})),
        "slant_path_coherence_diameter": lambda: turbulence.slant_path_coherence_diameter(
            rng, 9000.0),
        "scale_coherence_diameter": lambda: turbulence.scale_coherence_diameter(r0, wl),
        "band_coherence_diameter": lambda: turbulence.band_coherence_diameter(r0, wl, w),
        "turbulence": lambda: turbulence.turbulence(fx, fy, wl, 0.275, r0),
        "wind_blended_turbulence": lambda: turbulence.wind_blended_turbulence(
            fx, fy, wl, 0.275, r0, 0.01, 50.0),
        "polychromatic_turbulence": lambda: turbulence.polychromatic_turbulence(
            fx, fy, wl, w, 0.275, r0, 0.01, 50.0),
        "user_defined": lambda: user.user_defined(fx, fy, xr.DataArray(
            [1.0, 0.5, 0.0], dims="frequency", coords={"frequency": [0.0, 2e5, 4e5]})),
        "random_phase_wavefront": lambda: wavefront.random_phase_wavefront(
            fx, fy, wl, 0.1, 0.05, 0.05),
        "shannon_wavefront": lambda: wavefront.shannon_wavefront(fx, fy, wl, 0.275, 0.05),
    }
    return cases


CASES = _cases()


@functools.cache
def _output(case):
    out = CASES[case]()
    if isinstance(out, xr.DataArray):
        out = out.to_dataset(name=case)
    assert isinstance(out, xr.Dataset), f"{case}: returns {type(out).__name__}, not xarray"
    return out


def _labelled(ds):
    """Data variables and non-index coordinates: each must carry units and long_name."""
    return [*ds.data_vars, *(c for c in ds.coords if c not in ds.indexes)]


def _is_flag(var):
    return "flag_masks" in var.attrs or "flag_values" in var.attrs


# ---- the checks -----------------------------------------------------------------------

def test_every_public_function_has_a_standard_case():
    names = {name.split("[")[0] for name in CASES}
    missing = []
    for module in MODULES:
        for name, func in inspect.getmembers(module, inspect.isfunction):
            qualified = f"{module.__name__}.{name}"
            if (name.startswith("_") or func.__module__ != module.__name__
                    or qualified in NOT_LABELLED):
                continue
            if name not in names:
                missing.append(qualified)
    assert not missing, f"public functions without a case in test_conventions: {missing}"


@pytest.mark.parametrize("case", sorted(CASES))
def test_every_output_carries_units_and_long_name(case):
    ds = _output(case)
    for name in _labelled(ds):
        attrs = ds[name].attrs
        assert attrs.get("long_name"), f"{case}: variable {name!r} has no long_name"
        if _is_flag(ds[name]):
            continue
        assert attrs.get("units"), f"{case}: variable {name!r} has no units"


@pytest.mark.parametrize("case", sorted(CASES))
def test_units_match_what_each_variable_is(case):
    ds = _output(case)
    base = case.split("[")[0]
    for name in _labelled(ds):
        var = ds[name]
        if _is_flag(var):
            assert var.attrs.get("units", "1") == "1", (
                f"{case}: flag variable {name!r} has units {var.attrs['units']!r}")
            continue
        expected = CASE_UNITS.get((base, name), EXPECTED_UNITS.get(name))
        assert expected is not None, (
            f"{case}: variable {name!r} is not in EXPECTED_UNITS; add what it is")
        assert var.attrs.get("units") == expected, (
            f"{case}: variable {name!r} has units {var.attrs.get('units')!r}, "
            f"expected {expected!r}")


@pytest.mark.parametrize("case", sorted(CASES))
def test_standard_names_are_cf_and_on_the_right_quantity(case):
    ds = _output(case)
    for name, var in ds.variables.items():
        standard = var.attrs.get("standard_name")
        if standard is None:
            continue
        assert standard in CF_STANDARD_NAMES, (
            f"{case}: variable {name!r} has standard_name {standard!r}, not in the CF table")
        assert STANDARD_NAMES.get(name) == standard, (
            f"{case}: variable {name!r} claims standard_name {standard!r} but is not that "
            "quantity (attributes carried over by arithmetic?)")
        assert var.attrs.get("units") == CF_STANDARD_NAMES[standard], (
            f"{case}: variable {name!r} ({standard}) has units {var.attrs.get('units')!r}, "
            f"CF canonical {CF_STANDARD_NAMES[standard]!r}")


@pytest.mark.parametrize("case", sorted(CASES))
def test_flags_carry_masks_and_meanings_of_equal_length(case):
    ds = _output(case)
    flags = [name for name in ds.variables if _is_flag(ds[name]) or name == "flags"]
    for name in flags:
        attrs = ds[name].attrs
        assert "flag_masks" in attrs and "flag_meanings" in attrs, (
            f"{case}: flag variable {name!r} lacks flag_masks or flag_meanings")
        masks = np.atleast_1d(attrs["flag_masks"])
        meanings = attrs["flag_meanings"].split()
        assert len(masks) == len(meanings), (
            f"{case}: flag variable {name!r} has {len(masks)} masks and "
            f"{len(meanings)} meanings")
        assert np.issubdtype(ds[name].dtype, np.integer), (
            f"{case}: flag variable {name!r} is {ds[name].dtype}, not an integer")


_NIIRS_CASES = [case for case in sorted(CASES)
                if case.startswith("niirs[") or case in GIQE_CASES]


@pytest.mark.parametrize("case", _NIIRS_CASES)
def test_each_giqe_version_cites_its_own_source(case):
    niirs = _output(case)["niirs"]
    references = niirs.attrs.get("references", "")
    versions = ([GIQE_CASES[case]] if case in GIQE_CASES
                else [int(v) for v in niirs["giqe"].values])
    for version in versions:
        assert metrics.GIQE_REFERENCES[version] in references, (
            f"{case}: niirs (GIQE {version}) references {references!r}, not "
            f"{metrics.GIQE_REFERENCES[version]!r}")
    if 3 not in versions:
        assert "IBSM Eq. 3-56" not in references, (
            f"{case}: niirs cites IBSM Eq. 3-56, which is GIQE 3's")


def test_giqe_references_cite_each_version_once():
    refs = metrics.GIQE_REFERENCES
    assert refs[3] == "IBSM Eq. 3-56"
    assert "Leachtenauer" in refs[4] and "36(32)" in refs[4] and "1997" in refs[4]
    assert "Harrington" in refs[5] and "Version 5.0" in refs[5] and "2015" in refs[5]


# ---- module-level tables are immutable ------------------------------------------------

_TABLE_MODULES = ("xbsm.atmosphere.database", "xbsm.atmosphere.rules",
                  "xbsm.atmosphere.lookup", "xbsm.atmosphere._sight",
                  "xbsm.atmosphere._profile", "xbsm.examples", "xbsm.geometry", "xbsm.noise",
                  "xbsm.plot", "xbsm.plot._style", "xbsm.quadrature", "xbsm.radiometry",
                  "xbsm.units", "xbsm.study.goals",
                  "xbsm.metrics.edge", "xbsm.metrics.giqe", "xbsm.metrics.grd",
                  "xbsm.metrics.acquisition", "xbsm.metrics.eye", "xbsm.metrics.ttp",
                  *(f"xbsm.otf.{m}" for m in ("aperture", "defocus", "detector", "filters",
                                              "motion", "psf", "spectral", "system",
                                              "turbulence", "user", "wavefront")))


@pytest.mark.parametrize("module_name", _TABLE_MODULES)
def test_module_level_tables_are_immutable(module_name):
    module = importlib.import_module(module_name)
    for name, value in vars(module).items():
        if not name.lstrip("_").isupper():
            continue
        assert not isinstance(value, dict | list | set), (
            f"{module_name}.{name} is a mutable {type(value).__name__}; use a "
            "MappingProxyType, tuple or frozenset")
        if isinstance(value, np.ndarray):
            assert not value.flags.writeable, f"{module_name}.{name} is a writeable array"


# ---- enumerated choices of public functions reject a bad value ------------------------

BAD_CHOICES = MappingProxyType({
    "form": lambda: geometry.slant_range(1e3, 9e3, form="flat"),
    "rule": lambda: turbulence.slant_path_coherence_diameter(1e4, 9e3, rule="simpson"),
    "outside": lambda: user.user_defined(_fx(), _fy(), xr.DataArray(
        [1.0, 0.0], dims="frequency", coords={"frequency": [0.0, 1e5]}), outside="clip"),
    "method": lambda: filters.sharpening_filter(
        _fx(), _fy(), np.ones((1, 1)), 2e-6, 2e-6, method="fft"),
    "interpolation": lambda: atmosphere.atmosphere_at(9000.0, 20e3, 5.0,
                                                      interpolation="cubic"),
})
"""A bad value of each enumerated argument; the ValueError must name the argument."""


@pytest.mark.parametrize("argument", sorted(BAD_CHOICES))
def test_every_enumerated_argument_rejects_a_bad_value(argument):
    with pytest.raises(ValueError, match=argument):
        BAD_CHOICES[argument]()


# ---- declared contracts (xbsm.params.contract) ------------------------------------------

def _declared_functions():
    """(module name, function) for every public function that carries a contract."""
    import pkgutil

    out = []
    for info in pkgutil.walk_packages(xbsm.__path__, "xbsm."):
        module = importlib.import_module(info.name)
        out += [(info.name, f) for name, f in vars(module).items()
                if not name.startswith("_") and hasattr(f, "__contract__")
                and f.__module__ == info.name]
    return out


def test_every_declared_choice_is_documented_on_its_function():
    # a Choice is the one list of a knob's values: the docstring must offer the same ones
    declared = _declared_functions()
    assert len(declared) > 40  # the scan sees the declared functions
    for module_name, func in declared:
        for argument, rule in func.__contract__.rules.items():
            if isinstance(rule, xbsm.params.Choice):
                for choice in (c for c in rule.choices if c is not None):
                    assert f'"{choice}"' in func.__doc__, (
                        f"{module_name}.{func.__name__}: {argument} {choice!r}")
