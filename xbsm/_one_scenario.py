"""One scenario through the model chain on plain numpy arrays (private).

A notebook user, an optimizer or a Monte Carlo loop calls :func:`xbsm.snr` and
:func:`xbsm.niirs` one scenario at a time. Through the labelled chain such a call
builds a few hundred small DataArrays and Datasets, and that, not the arithmetic,
is its cost. Here the same stage kernels run in the same order on plain arrays,
and only the result is labelled.

The result's structure (variables, dims, coordinates, attributes) is the labelled
chain's own: the first call of each structure (the method, the targets or the
calibration, the band's wavelength count, the inputs' variables) runs the labelled
chain, returns its result and keeps it as the template that later calls fill with
their numbers. Values are never reused; ``tests/test_one_scenario.py`` checks that
both paths agree on every reference case.

Only the common case comes here: sensor and scenario eager, without sweep dims,
within their ranges, with the atmosphere inputs in the database's units. Anything
else (a sweep, dask, a bad value, a band narrower than the database spacing) takes
the labelled chain, which owns every error message.
"""

from __future__ import annotations

import threading
from collections import OrderedDict

import numpy as np
import xarray as xr

from . import atmosphere as atm_
from . import flags as fl
from . import geometry, noise, params, quadrature, radiometry
from .metrics import edge as edge_
from .metrics import giqe
from .otf import filters, system, turbulence
from .otf.detector import _detector_kernel
from .otf.motion import _jitter_kernel
from .quadrature import _cutoff_kernel

_OWN_DIMS = frozenset({"kernel_y", "kernel_x"}
                      | {f"{name}_wavelength" for name in params.SPECTRAL})
"""The parameters' own dims (a sensor curve's wavelengths, the filter kernel's rows and
columns): every other dim is a sweep."""
_ATMOSPHERE_UNITS = (("altitude", "m"), ("ground_range", "m"), ("visibility", "km"))


def inputs(sensor: xr.Dataset, scenario: xr.Dataset) -> dict | None:
    """Every parameter of a single eager scenario as a numpy array; None for anything else.

    The datasets must already have passed :func:`xbsm.params.check_inputs`.
    """
    values = {}
    for ds in (sensor, scenario):
        for name, variable in ds.variables.items():
            data = variable.data
            if not isinstance(data, np.ndarray):
                return None
            if not _OWN_DIMS.issuperset(variable.dims):
                return None
            values[name] = data
    if sensor.variables["filter_kernel"].dims != ("kernel_y", "kernel_x"):
        return None  # an edited kernel in the other order: the labelled chain transposes it
    for name, units in _ATMOSPHERE_UNITS:
        if scenario.variables[name].attrs.get("units", units) != units:
            return None
    return values


# ---- the SNR chain ---------------------------------------------------------------------

def _band_atmosphere(p: dict, m) -> tuple | None:
    """Wavelengths, component spectra and flags over the band (``band_atmosphere``'s rule)."""
    samples, bounds = atm_.band_wavelengths(float(p["wavelength_min"]),
                                            float(p["wavelength_max"]), m.band_edges)
    file = str(atm_.database_path())
    db = atm_._load_database(file)
    window = atm_._wavelength_window(db.wavelength, bounds)
    wavelength = db.wavelength[window]
    if wavelength.size < 2:
        return None
    *spectra, flags = atm_._atmosphere_kernel(
        p["altitude"], p["ground_range"], p["visibility"], wavelength, path=file,
        interpolation=m.atmosphere_interpolation, window=window)
    if samples is not None and not np.array_equal(samples, wavelength):
        spectra = [np.interp(samples, wavelength, s) for s in spectra]
        wavelength = samples
    return wavelength, dict(zip(atm_.VARIABLES, spectra, strict=True)), flags


def _on_band(p: dict, name: str, wavelength):
    """A sensor curve resampled onto the band (``resample_spectral``'s rule), or its scalar."""
    dim = f"{name}_wavelength"
    if dim not in p:
        return p[name]
    return radiometry._interp_kernel(p[name], wavelength, source=p[dim])


def _radiances(p: dict, atm: dict, wavelength, targets: str, knobs: dict):
    """Aperture radiance of target and background (``aperture_radiances``)."""
    if targets == "giqe":
        emissive = radiometry.is_emissive_band(float(p["wavelength_min"]))
        surfaces = [(0.0 if emissive else standard["reflectance"], standard["temperature"])
                    for standard in (radiometry.GIQE_TARGET, radiometry.GIQE_BACKGROUND)]
    else:
        surfaces = [(p[f"{s}_reflectance"], p[f"{s}_temperature"])
                    for s in ("target", "background")]
    return [radiometry._total_radiance_kernel(
        atm["path_thermal"], reflectance, wavelength, temperature, atm["transmission"],
        atm["solar_scatter"], atm["ground_reflected"], **knobs)
        for reflectance, temperature in surfaces]


def _signal(p: dict, atm: dict, wavelength, radiances, knobs: dict) -> dict:
    """The sensor's band terms and the photoelectron terms (radiometry's two orchestrators)."""
    optics = radiometry._optics_transmission_kernel(
        p["cold_filter_transmission"], p["obscuration_ratio"],
        _on_band(p, "optics_transmission", wavelength))
    own = radiometry._sensor_irradiance_kernel(
        p["focal_length"], p["aperture_diameter"], wavelength, p["cold_shield_temperature"],
        p["cold_filter_transmission"], p["optics_emissivity"], p["optics_temperature"],
        p["cold_filter_emissivity"], p["cold_filter_temperature"],
        _on_band(p, "stray_irradiance", wavelength), **knobs)
    qe = _on_band(p, "quantum_efficiency", wavelength)
    hc = {"h": knobs["h"], "c": knobs["c"]}
    detector = (wavelength, qe, p["detector_width_x"], p["detector_width_y"], optics)
    lens = (p["focal_length"], p["aperture_diameter"])
    (weights, target_rate, target_scene), (_, background_rate, background_scene) = (
        radiometry._scene_kernel(*detector, radiance, *lens, own, **hc)
        for radiance in radiances)
    counts = radiometry._counts_kernel(
        target_rate, p["dark_current"], p["integration_time"], p["tdi_stages"],
        background_rate, p["max_well_fill"], p["max_well"])
    out = dict(zip([name for name, *_ in radiometry._COUNT_TERMS], counts, strict=True))
    return {**out, "spectral_weights": weights,
            "path_rate": radiometry._path_rate_kernel(
                *detector, atm["path_thermal"], atm["solar_scatter"], *lens, **hc),
            "target_scene_rate": target_scene, "background_scene_rate": background_scene,
            "sensor_rate": radiometry._rate_kernel(*detector[:4], own, **hc),
            "quantum_efficiency": qe, "optics_transmission": optics}


def _noise(p: dict, signal: dict) -> dict:
    """The noise terms and the SNR (``noise_terms``)."""
    time, tdi = signal["effective_integration_time"], p["tdi_stages"]
    target, background = signal["target_photoelectrons"], signal["background_photoelectrons"]
    chain = (target, background, p["max_well"], p["bit_depth"], p["read_noise"],
             p["other_noise"])
    contrast = signal["contrast_photoelectrons"]
    return {
        "snr": noise._snr_kernel(p["frame_stacks"], contrast, *chain),
        "snr_frame": noise._snr_frame_kernel(contrast, *chain),
        "shot_noise": noise._shot_noise_of_brighter_kernel(target, background),
        "scene_noise": noise._scene_noise_kernel(signal["target_scene_rate"], time, tdi,
                                                 signal["background_scene_rate"],
                                                 signal["path_rate"]),
        "path_noise": noise._rate_noise_kernel(signal["path_rate"], time, tdi),
        "self_emission_noise": noise._rate_noise_kernel(signal["sensor_rate"], time, tdi),
        "dark_current_noise": noise._dark_current_noise_kernel(tdi, p["dark_current"], time),
        "quantization_noise": noise._quantization_noise_kernel(p["max_well"], p["bit_depth"]),
        "read_noise": p["read_noise"],
        "other_noise": p["other_noise"],
        "total_noise": noise._chain_total_kernel(*chain),
    }


def _cutoff(p: dict, wavelength, signal: dict):
    """Optics cutoff over the band with signal, else the band's own D / lambda_min."""
    spectral = [np.asarray(signal[name]) for name in ("quantum_efficiency",
                                                      "optics_transmission")]
    cutoff = _cutoff_kernel(p["aperture_diameter"], wavelength,
                            *(a if a.ndim else a[..., np.newaxis] for a in spectral))
    return np.where(np.isnan(cutoff), p["aperture_diameter"] / p["wavelength_min"], cutoff)


def snr_values(p: dict, m, targets: str, sensor: xr.Dataset) -> tuple | None:
    """Every output of ``model._snr`` (and the cutoff) as plain arrays, or None."""
    band = _band_atmosphere(p, m)
    if band is None:
        return None
    wavelength, atm, atm_flags = band
    knobs = radiometry._planck_knobs(m.constants)
    with np.errstate(all="ignore"):  # IEEE results, as the labelled chain gives them
        radiances = _radiances(p, atm, wavelength, targets, knobs)
        signal = _signal(p, atm, wavelength, radiances, knobs)
        noise_ = _noise(p, signal)
        cutoff = _cutoff(p, wavelength, signal)
        brighter = np.maximum(signal["target_photoelectrons"],
                              signal["background_photoelectrons"])
    flags = atm_flags | np.where(signal["well_fill_scale"] < 1.0, fl.flag("well_fill_limited"), 0)
    if params._partial_spectral_coverage(sensor):
        flags = flags | fl.flag("partial_spectral_coverage")
    values = {**noise_, "well_fill": brighter / p["max_well"], "flags": flags,
              "wavelength": wavelength, **{name: signal[name] for name in (
                  "effective_integration_time", "target_photoelectrons",
                  "background_photoelectrons", "contrast_photoelectrons",
                  "spectral_weights")}}
    return values, signal, cutoff


# ---- the NIIRS chain -------------------------------------------------------------------

def _otf_band(weights, wavelength, count: int):
    """Normalised OTF weights over (possibly binned) wavelengths, as the OTF stage makes them."""
    weights = np.where(weights > 0, weights, 0.0)
    if not weights.sum() > 0:
        weights = np.ones_like(weights)
    n = wavelength.size
    if 0 < count < n:
        labels = np.minimum((np.arange(n) * count) // n, count - 1)
        wavelength = np.bincount(labels, wavelength) / np.bincount(labels)
        weights = np.bincount(labels, weights)
    return wavelength, weights / weights.sum()


def _filter(p: dict, fx, fy, m):
    """The post-processing filter OTF on the slices (``otf.system._filter``)."""
    kernel = p["filter_kernel"]
    rule = system._filter_rule(kernel, m.filter_otf)
    if rule is None:
        return np.ones(fx.shape)
    if rule == "pybsm":
        return filters._pybsm_filter_kernel(fx, fy, kernel=kernel,
                                            ifov=p["pixel_pitch_x"] / p["focal_length"])
    return system._sampled_filter_kernel(fy, p["pixel_pitch_y"], p["focal_length"], fx,
                                         p["pixel_pitch_x"], kernel=kernel)


def _system(p: dict, m, nodes, wavelength, weights, time, slant):
    """Unfiltered and filtered system OTF on the x and y slices, and the band r0.

    As ``system_components``, with frequency along the first axis and orientation (x, y)
    along the second.
    """
    fx, fy = nodes[:, None] * [1.0, 0.0], nodes[:, None] * [0.0, 1.0]
    wl, w = _otf_band(weights, wavelength, m.otf_wavelengths)
    cn2 = p["cn2_at_1m"]
    r0_ref = system._turbulent_path_kernel(
        p["high_altitude_wind_speed"], slant, p["altitude"], cn2,
        nodes=turbulence._path_nodes(m.turbulence_path_samples, m.turbulence_path_rule),
        form=m.geometry)
    radial = [
        system._aperture_band_kernel(nodes, p["aperture_diameter"], p["obscuration_ratio"],
                                     wl, w),
        system._turbulence_band_kernel(cn2, nodes, r0_ref, time, p["tdi_stages"],
                                       p["platform_speed"], p["aperture_diameter"], wl, w)]
    sliced = [
        _detector_kernel(p["detector_width_x"], p["focal_length"], fx, p["detector_width_y"],
                         fy),
        _jitter_kernel(p["jitter_x"], fx, p["jitter_y"], fy),
        system._exposure_drift_kernel(p["drift_rate_x"], time, p["tdi_stages"], fx,
                                      p["drift_rate_y"], fy),
        system._wavefront_band_kernel(
            p["wavefront_variance"], p["wavefront_wavelength"], fx,
            p["wavefront_correlation_length_x"], fy,
            p["wavefront_correlation_length_y"], wl, w)]
    unfiltered = system._product_kernel(*(r[:, None] for r in radial), *sliced)
    r0 = system._band_r0_kernel(cn2, r0_ref, wl, w)
    return unfiltered, unfiltered * _filter(p, fx, fy, m), r0


def _edges(p: dict, m, signal: dict, cutoff, ifov, time, slant) -> dict:
    """RER and EHO on both slices with and without the filter (``model._edge_terms``)."""
    knobs = m.edge_quadrature_knobs()
    knobs.pop("name")
    rule = knobs.pop("rule")
    nodes, weights, sine = quadrature._edge_rule(
        *quadrature._checked(rule, cutoff, max(ifov)), rule, **knobs)
    unfiltered, filtered, r0 = _system(p, m, nodes, signal["wavelength"],
                                       signal["spectral_weights"], time, slant)

    def edge(otf):
        otf = np.abs(otf) if m.edge_otf == "abs" else otf
        return edge_._edge_terms_kernel(otf.T, weights, sine, ifov)

    (rer_x, rer_y), (eho_x, eho_y) = edge(filtered)
    rer5_x, rer5_y = (rer_x, rer_y) if p["filter_kernel"].shape == (1, 1) else edge(
        unfiltered)[0]
    coarse = False
    if m.edge_rule == "uniform_trapezoid":
        samples = quadrature._samples_per_oscillation_kernel(nodes.size, cutoff, max(ifov))
        coarse = samples < m.undersampling_threshold
    rer = np.sqrt(rer_x * rer_y)
    flags = (np.where(coarse, fl.flag("undersampled_grid"), 0)
             | np.where(rer < quadrature.UNRESOLVED_RER, fl.flag("blur_unresolved"), 0))
    return {"rer_x": rer_x, "rer_y": rer_y, "eho_x": eho_x, "eho_y": eho_y, "rer": rer,
            "eho": np.sqrt(eho_x * eho_y), "rer5_x": rer5_x, "rer5_y": rer5_y,
            "coherence_diameter": r0, "cutoff_frequency": cutoff, "edge_flags": flags}


def _giqe(p: dict, m, calibration, e: dict, snr, view: dict) -> dict:
    """NIIRS by version, its flags and the GSD terms (``giqe_by_version``)."""
    elevation, gsd_x, gsd_y = view["elevation_angle"], view["gsd_x"], view["gsd_y"]
    gsd = giqe._geometric_mean_kernel(gsd_x, gsd_y)
    gsd_gp = giqe._ground_plane_kernel(gsd, elevation, power=0.5)
    gsd_w = giqe._ground_plane_kernel(gsd_x, elevation, power=0.25)
    rer5 = giqe._giqe5_rer_kernel(e["rer5_x"], e["rer5_y"])
    gain = np.sqrt(np.sum(p["filter_kernel"] ** 2))
    niirs = giqe._niirs_by_version_kernel(
        e["rer"], gsd_x, gsd_y, e["eho"], gain, snr, elevation, e["rer5_x"], e["rer5_y"],
        noise_coefficient=m.giqe4_noise_coefficient)
    centre = 0.5 * (p["wavelength_min"] + p["wavelength_max"])
    q = xr.Variable("orientation", giqe._sampling_q_kernel(centre, p["aperture_diameter"],
                                                           view["ifov"]))
    gsd5_gp = (None if calibration[5].gsd_ground_plane is None
               else giqe._ground_plane_kernel(gsd_x, elevation, power=0.5))
    tested = (
        {"snr": snr, "rer": e["rer"], "gsd": gsd, "elevation": elevation, "niirs": niirs},
        {"snr": snr, "rer": e["rer"], "gsd": gsd_gp, "elevation": elevation, "niirs": niirs},
        {"snr": snr, "rer": rer5, "gsd": gsd_w, "gsd_ground_plane": gsd5_gp,
         "elevation": elevation, "q": q, "niirs": niirs})
    arrays, tests, _ = giqe._tests_by_version(calibration, tested)
    flags = giqe._flags_kernel(*(np.asarray(getattr(a, "values", a)) for a in arrays),
                               tests=tests, versions=len(giqe.GIQE_VERSIONS))
    return {"niirs": niirs, "giqe_flags": flags, "rer_giqe5": rer5, "gsd": gsd,
            "gsd_gp": gsd_gp, "gsd_w": gsd_w, "noise_gain": gain}


def niirs_values(p: dict, m, calibration, sensor: xr.Dataset) -> dict | None:
    """Every output of :func:`xbsm.niirs` as plain arrays, or None."""
    computed = snr_values(p, m, "giqe", sensor)
    if computed is None:
        return None
    values, signal, cutoff = computed
    slant, elevation = geometry._slant_and_elevation_kernel(
        p["altitude"], p["ground_range"], form=m.geometry, elevation=m.elevation)
    ifov = np.array([p["pixel_pitch_x"], p["pixel_pitch_y"]]) / p["focal_length"]
    view = {"elevation_angle": elevation, "gsd_x": ifov[0] * slant, "gsd_y": ifov[1] * slant,
            "ifov": ifov}
    with np.errstate(all="ignore"):
        edges = _edges(p, m, {**signal, "wavelength": values["wavelength"]}, cutoff, ifov,
                       values["effective_integration_time"], slant)
        metrics = _giqe(p, m, calibration, edges, values["snr"], view)
    flags = metrics.pop("giqe_flags") | values.pop("flags") | edges.pop("edge_flags")
    del values["spectral_weights"], values["wavelength"]
    return {**values, **edges, **metrics, "flags": flags, "slant_range": slant,
            "elevation_angle": elevation}


# ---- the labelled result ---------------------------------------------------------------

_TEMPLATES: OrderedDict = OrderedDict()
"""Result structures by key, most recently used last (at most ``_MOST_TEMPLATES``)."""
_MOST_TEMPLATES = 64
_TEMPLATES_LOCK = threading.Lock()  # calls may come from several threads (dask, a GUI)


def layout(sensor: xr.Dataset, scenario: xr.Dataset) -> tuple:
    """What of the inputs decides the result's structure: each variable's name and shape."""
    return tuple((name, v.dims, v.shape) for ds in (sensor, scenario)
                 for name, v in ds.variables.items())


def labelled(key: tuple, values: dict, make) -> xr.Dataset:
    """The result for ``key`` filled with ``values``; ``make()`` runs the labelled chain.

    On the first call of a key the labelled chain's result is returned and kept as the
    template of that structure.
    """
    with _TEMPLATES_LOCK:
        template = _TEMPLATES.get(key)
        if template is not None:
            _TEMPLATES.move_to_end(key)
    if template is None:
        result = make()
        with _TEMPLATES_LOCK:  # a copy: the caller may edit the result it gets
            _TEMPLATES[key] = result.copy(deep=True)
            while len(_TEMPLATES) > _MOST_TEMPLATES:
                _TEMPLATES.popitem(last=False)
        return result
    out = template.copy(deep=False, data={  # copies the attributes too
        name: np.asarray(values[name], dtype=v.dtype).reshape(v.shape)
        for name, v in template.data_vars.variables.items()})
    changed = {name: (v.dims, values[name], v.attrs) for name, v in out.coords.variables.items()
               if name in values and not np.array_equal(values[name], v.values)}
    return out.assign_coords(changed) if changed else out

def snr(sensor: xr.Dataset, scenario: xr.Dataset, m, targets: str, make) -> xr.Dataset:
    """:func:`xbsm.snr` of one scenario; ``make()`` is the labelled chain for the rest."""
    p = inputs(sensor, scenario)
    computed = None if p is None else snr_values(p, m, targets, sensor)
    if computed is None:
        return make()
    values = computed[0]
    key = ("snr", m, targets, values["wavelength"].size, layout(sensor, scenario))
    return labelled(key, values, make)


def niirs(sensor: xr.Dataset, scenario: xr.Dataset, m, calibration, make) -> xr.Dataset:
    """:func:`xbsm.niirs` of one scenario; ``make()`` is the labelled chain for the rest."""
    p = inputs(sensor, scenario)
    values = None if p is None else niirs_values(p, m, calibration, sensor)
    if values is None:
        return make()
    key = ("niirs", m, repr(calibration), layout(sensor, scenario))
    return labelled(key, values, make)
