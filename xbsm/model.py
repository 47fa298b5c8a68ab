"""The model chain: parameters -> atmosphere -> radiometry -> noise -> (OTF -> GIQE).

``snr(sensor, scenario)`` and ``niirs(sensor, scenario)`` return datasets of
named intermediate results; every sweep dimension of the inputs is kept.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from . import flags as fl
from . import geometry, metrics, noise, params, radiometry
from .atmosphere import band_atmosphere
from .methods import Method
from .methods import method as resolve_method
from .otf.system import system_components
from .params import check_inputs
from .quadrature import edge_nodes, optics_cutoff, undersampled


def _result(variables: dict, m: Method, **attrs) -> xr.Dataset:
    """A result Dataset without scalar coordinates, saying which method made it.

    The ``method`` attribute names the preset and every knob that differs from it.

    An output that repeats an input swept on a dimension of its own name (``read_noise``
    swept on ``read_noise``) is left to that coordinate, which holds the same values.
    """
    dims = {d for v in variables.values() for d in v.dims}
    attrs = {"method": m.describe(), **attrs}
    ds = xr.Dataset({k: v for k, v in variables.items() if k not in dims}, attrs=attrs)
    return ds.drop_vars([c for c in ds.coords if ds[c].ndim == 0 and c not in ds.dims])


def snr(sensor: xr.Dataset, scenario: xr.Dataset, method="accurate", *, targets="giqe"):
    """Contrast signal-to-noise ratio and its breakdown (paper Sec. 2.2-2.3, Figure 4).

    Parameters
    ----------
    sensor : xr.Dataset
        From :func:`xbsm.sensor`.
    scenario : xr.Dataset
        From :func:`xbsm.scenario`.
    method : str or Method
        "accurate" (default), "fast" or "pybsm", or a :class:`xbsm.methods.Method`.
    targets : {"giqe", "scenario"}
        "giqe": the GIQE standard target and background (15% / 7% at 282 K /
        280 K; reflectance 0 in bands starting at or beyond 2.9 um), as the
        NIIRS chain uses; "scenario": the scenario's own reflectances and
        temperatures.

    Returns
    -------
    xr.Dataset
        ``snr`` (after frame stacking), ``snr_frame``, ``effective_integration_time``,
        ``target_photoelectrons``, ``background_photoelectrons``,
        ``contrast_photoelectrons``, ``well_fill``, every noise term
        (``shot_noise``, ``scene_noise``, ``path_noise``, ``self_emission_noise``,
        ``dark_current_noise``, ``quantization_noise``, ``read_noise``,
        ``other_noise``, ``total_noise``), ``spectral_weights`` (the target's
        spectral photoelectron rate, which weights the OTFs, paper Eq. 3) and
        ``flags``.
    """
    check_inputs(sensor, scenario)
    if targets not in ("giqe", "scenario"):
        raise ValueError(f"targets must be 'giqe' or 'scenario'; got {targets!r}")
    return _snr(sensor, scenario, resolve_method(method), targets)


def _snr(sensor: xr.Dataset, scenario: xr.Dataset, m: Method, targets: str) -> xr.Dataset:
    """The SNR chain on validated inputs: atmosphere, radiometry, noise."""
    atm = _band_atmosphere(sensor, scenario, m)
    target, background = radiometry.aperture_radiances(
        atm, scenario, targets, sensor["wavelength_min"], m.constants)
    signal = radiometry.signal_terms(sensor, atm, target, background, m.constants)
    noise_ = noise.noise_terms(signal, sensor)
    brighter = np.maximum(signal["target_photoelectrons"], signal["background_photoelectrons"])
    flags = fl.set_flag(atm["flags"], "well_fill_limited", signal["well_fill_scale"] < 1.0)
    return _result({
        "snr": noise_["snr"],
        "snr_frame": noise_["snr_frame"],
        **{name: signal[name] for name in (
            "effective_integration_time", "target_photoelectrons", "background_photoelectrons",
            "contrast_photoelectrons")},
        "well_fill": (brighter / sensor["max_well"]).assign_attrs(
            units="1", long_name="well fill fraction"),
        **{name: noise_[name] for name in noise_.data_vars if name not in ("snr", "snr_frame")},
        "spectral_weights": signal["spectral_weights"],
        "flags": flags,
    }, m, targets=targets)


def _band_atmosphere(sensor: xr.Dataset, scenario: xr.Dataset, m: Method) -> xr.Dataset:
    """The atmosphere over the sensor's band for every scenario, by the method's knobs."""
    return band_atmosphere(
        scenario["altitude"], scenario["ground_range"], scenario["visibility"],
        sensor["wavelength_min"], sensor["wavelength_max"],
        interpolation=m.atmosphere_interpolation, band_edges=m.band_edges)


def reflectance_to_photoelectrons(sensor: xr.Dataset, scenario: xr.Dataset, reflectance=None,
                                  method="accurate", *, temperature=300.0,
                                  integration_time=None) -> xr.Dataset:
    """Photoelectrons per pixel from Lambertian targets of given reflectance.

    The radiometric mapping an image simulation applies to a reflectance map
    (pyBSM's ``reflectance_to_photoelectrons``).

    Parameters
    ----------
    sensor, scenario : xr.Dataset
        From :func:`xbsm.sensor` and :func:`xbsm.scenario`.
    reflectance : xr.DataArray or array_like, optional
        Target reflectances; default 100 values from 0 to 1 (dim ``reflectance``). [1]
    method : str or Method
        Knobs ``constants``, ``atmosphere_interpolation``, ``band_edges``.
    temperature : float or xr.DataArray
        Target temperature (pyBSM fixes 300 K). [K]
    integration_time : float or xr.DataArray, optional
        Default the sensor's maximum integration time. [s]

    Returns
    -------
    xr.Dataset
        ``photoelectrons`` over ``reflectance`` (and the sweep dims), scaled so
        that the brightest reflectance fills the well at most (pyBSM's rule);
        ``effective_integration_time`` after that scaling; ``spectral_weights``, the
        spectral photoelectron rate of the brightest target normalised to a
        peak of 1; ``flags`` (``well_fill_limited`` where scaled).

    Notes
    -----
    Paper Eq. 1 and 2 with the dark current; the count is linear in
    reflectance (Eq. 1 is).
    """
    check_inputs(sensor, scenario)
    m = resolve_method(method)
    s, k = sensor, m.constants
    if reflectance is None:
        reflectance = np.linspace(0.0, 1.0, 100)
    if not isinstance(reflectance, xr.DataArray):
        values = np.atleast_1d(np.asarray(reflectance))
        reflectance = xr.DataArray(values, dims="reflectance", coords={"reflectance": values})
    reflectance = params.argument("reflectance", reflectance, allowed_dims=("reflectance",))
    temperature = params.argument("temperature", temperature)
    integration_time = (s["integration_time"] if integration_time is None
                        else params.argument("integration_time", integration_time))
    atm = _band_atmosphere(s, scenario, m)
    band = radiometry.sensor_band_terms(s, atm["wavelength"], k)
    radiance = radiometry.total_radiance(atm, reflectance, temperature, k)
    spectral = radiometry.photon_detection_rate(
        radiometry.detector_irradiance(radiance, band, s), band["quantum_efficiency"],
        s["detector_width_x"], s["detector_width_y"], k)
    rate = radiometry.band_integral(spectral) + s["dark_current"]
    counts = rate * integration_time * s["tdi_stages"]
    saturation = counts.max("reflectance") / s["max_well"]
    scale = xr.where(saturation > 1.0, 1.0 / saturation, 1.0)
    counts = np.minimum(counts * scale, s["max_well"])
    brightest = spectral.isel(reflectance=-1, drop=True)
    flags = fl.set_flag(atm["flags"], "well_fill_limited", scale < 1.0)
    return _result({
        "photoelectrons": counts.assign_attrs(units="count", long_name="photoelectrons per pixel"),
        "effective_integration_time": (integration_time * scale).assign_attrs(
            units="s", long_name="integration time after the well limit"),
        "spectral_weights": (brightest / brightest.max("wavelength")).assign_attrs(
            units="1", long_name="normalised spectral photoelectron rate"),
        "flags": flags,
    }, m)


GIQE_VERSIONS = (3, 4, 5)


def _optics_cutoff(sensor: xr.Dataset, wavelength: xr.DataArray) -> xr.DataArray:
    """The optics cutoff over the band, from the sensor's QE and transmission curves."""
    curves = [radiometry.resample_spectral(sensor[name], wavelength, name)
              for name in ("quantum_efficiency", "optics_transmission")]
    return optics_cutoff(sensor["aperture_diameter"], wavelength, *curves)


def _otf_weights(spectral_weights: xr.DataArray) -> xr.DataArray:
    """Spectral weights for the polychromatic OTFs (paper Eq. 3).

    Non-positive weights count as zero. Cells with no usable weight at all are
    beyond the database (their SNR is NaN and flagged ``beyond_database``);
    they get uniform weights so the OTF stays finite while the NIIRS is NaN.
    """
    weights = spectral_weights.where(spectral_weights > 0, 0.0)
    usable = weights.sum("wavelength") > 0
    return xr.where(usable, weights, 1.0)


def niirs(sensor: xr.Dataset, scenario: xr.Dataset, method="accurate", *, calibration=None):
    """Predicted NIIRS by GIQE 3, 4 and 5 with every intermediate (paper Sec. 3).

    Parameters
    ----------
    sensor : xr.Dataset
        From :func:`xbsm.sensor`.
    scenario : xr.Dataset
        From :func:`xbsm.scenario`.
    method : str or Method
        "accurate" (default), "fast" or "pybsm", or a :class:`xbsm.methods.Method`.
    calibration : mapping of int to GiqeCalibration, optional
        GIQE calibration ranges for the flags, by version, e.g.
        ``{5: xbsm.metrics.GIQE5_CALIBRATION.replace(snr=(2, 130))}``; versions
        left out keep :data:`xbsm.metrics.GIQE_CALIBRATIONS`. Changes flags only.

    Returns
    -------
    xr.Dataset
        ``niirs`` over ``giqe`` = 3, 4, 5; ``snr`` (after frame stacking);
        ``rer`` and ``eho`` (geometric means of the x and y slices, as GIQE 3
        and 4 use), ``rer_x``, ``rer_y``, ``eho_x``, ``eho_y``, ``rer_giqe5``
        (GIQE 5's (max min^2)^(1/3) of the unfiltered system); ``gsd``
        (geometric mean, image plane), ``gsd_gp`` (GIQE 4 ground plane),
        ``gsd_w`` (GIQE 5); ``noise_gain``; ``effective_integration_time``;
        ``slant_range``; ``elevation_angle``; ``coherence_diameter``;
        ``cutoff_frequency``; the SNR breakdown of :func:`snr` (photoelectrons,
        noise terms, ``snr_frame``, ``well_fill``); ``flags`` over ``giqe``.

    Notes
    -----
    The chain: :func:`snr` gives the SNR, the integration time and the
    spectral weights; :func:`xbsm.otf.system.system_components` the system OTF on the
    x and y slices at the nodes of the method's edge-response quadrature;
    :mod:`xbsm.metrics` the edge terms and the GIQE. GIQE 5 uses the system
    without the post-processing filter (as pyBSM's ``niirs5``), GIQE 3 and 4
    with it, with its noise gain.
    """
    check_inputs(sensor, scenario)
    m = resolve_method(method)
    calibration = metrics.giqe_calibrations(calibration)
    r = _snr(sensor, scenario, m, "giqe")
    view = _viewing_geometry(sensor, scenario, m)
    edges = _edge_terms(sensor, scenario, r, view, m)
    giqe = _giqe_terms(sensor, r, view, edges, m, calibration)
    flags = giqe["flags"] | r["flags"] | edges["undersampled"]
    return _result({
        "niirs": giqe["niirs"],
        **{name: r[name] for name in r.data_vars if name not in ("spectral_weights", "flags")},
        **{name: edges[name] for name in edges.data_vars
           if name not in ("undersampled", "rer_unfiltered_x", "rer_unfiltered_y")},
        **{name: giqe[name] for name in giqe.data_vars if name not in ("niirs", "flags")},
        **{name: view[name] for name in ("slant_range", "elevation_angle")},
        "flags": flags.astype(np.int32).assign_attrs(fl.flag_attrs("NIIRS validity flags")),
    }, m)


def _viewing_geometry(s: xr.Dataset, sc: xr.Dataset, m: Method) -> xr.Dataset:
    """Slant range, GIQE elevation angle, IFOVs and GSDs of every scenario."""
    slant = geometry.slant_range(sc["ground_range"], sc["altitude"], form=m.geometry)
    if m.elevation == "look-down":
        elevation = geometry.elevation_angle(slant, sc["altitude"], form=m.geometry)
    else:
        elevation = geometry.target_elevation_angle(slant, sc["altitude"], form=m.geometry)
    ifov_x = geometry.ifov(s["pixel_pitch_x"], s["focal_length"])
    ifov_y = geometry.ifov(s["pixel_pitch_y"], s["focal_length"])
    return xr.Dataset({
        "slant_range": slant.assign_attrs(units="m", long_name="slant range"),
        "elevation_angle": elevation.assign_attrs(units="rad", long_name="GIQE elevation angle"),
        "ifov_x": ifov_x, "ifov_y": ifov_y,
        "gsd_x": geometry.ground_sample_distance(ifov_x, slant),
        "gsd_y": geometry.ground_sample_distance(ifov_y, slant),
    })


def _edge_terms(s: xr.Dataset, sc: xr.Dataset, r: xr.Dataset, view: xr.Dataset,
                m: Method) -> xr.Dataset:
    """RER and EHO of the system OTF on the x and y slices, at the method's quadrature nodes."""
    weights = r["spectral_weights"]
    cutoff = _optics_cutoff(s, weights["wavelength"])
    ifov_x, ifov_y = view["ifov_x"], view["ifov_y"]
    nodes, quad_weights = edge_nodes(cutoff, ifov_x, ifov_y, **m.edge_quadrature_knobs())
    otf = system_components(s, sc, nodes, spectral_weights=_otf_weights(weights),
                            integration_time=r["effective_integration_time"],
                            slant_range=view["slant_range"], method=m)
    ifov = xr.concat([ifov_x, ifov_y], dim="orientation").assign_coords(orientation=["x", "y"])

    def edge(system):
        return metrics.edge_terms(abs(system) if m.edge_otf == "abs" else system, ifov,
                                  quad_weights)

    filtered = edge(otf["system"])
    unfiltered = filtered if s["filter_kernel"].shape == (1, 1) else edge(
        otf["system_unfiltered"])
    terms = {f"{name}_{o}": filtered[name].sel(orientation=o, drop=True).assign_attrs(
                 units="1", long_name=f"{long} along {o}")
             for name, long in (("rer", "relative edge response"),
                                ("eho", "edge height overshoot")) for o in ("x", "y")}
    coarse = False
    if m.edge_rule == "uniform_trapezoid":
        coarse = undersampled(nodes, cutoff, ifov_x, ifov_y, m.undersampling_threshold)
    return xr.Dataset({
        **terms,
        "rer": np.sqrt(terms["rer_x"] * terms["rer_y"]).assign_attrs(
            units="1", long_name="relative edge response (geometric mean)"),
        "eho": np.sqrt(terms["eho_x"] * terms["eho_y"]).assign_attrs(
            units="1", long_name="edge height overshoot (geometric mean)"),
        "rer_unfiltered_x": unfiltered["rer"].sel(orientation="x", drop=True),
        "rer_unfiltered_y": unfiltered["rer"].sel(orientation="y", drop=True),
        "coherence_diameter": otf["coherence_diameter"],
        "cutoff_frequency": cutoff,
        "undersampled": fl.set_flag(xr.DataArray(np.int32(0)), "undersampled_grid", coarse),
    })


def _giqe_terms(s: xr.Dataset, r: xr.Dataset, view: xr.Dataset, edges: xr.Dataset, m: Method,
                calibration) -> xr.Dataset:
    """NIIRS by GIQE 3, 4 and 5 (dim ``giqe``), their flags and their GSD terms."""
    gsd = np.sqrt(view["gsd_x"] * view["gsd_y"]).assign_attrs(
        units="m", long_name="ground sample distance (geometric mean)")
    gain = noise.noise_gain(s["filter_kernel"])
    elevation = view["elevation_angle"]
    ifov = xr.concat([view["ifov_x"], view["ifov_y"]], dim="orientation").assign_coords(
        orientation=["x", "y"])
    # GIQE 5's Q = lambda N / p at the band centre, per orientation (flags only)
    q = metrics.sampling_q(0.5 * (s["wavelength_min"] + s["wavelength_max"]),
                           s["aperture_diameter"], ifov)
    common = dict(rer=edges["rer"], gsd=gsd, eho=edges["eho"], snr=r["snr"], noise_gain=gain,
                  elevation=elevation)
    g3 = metrics.giqe3(**common, calibration=calibration[3])
    g4 = metrics.giqe4(**common, noise_coefficient=m.giqe4_noise_coefficient,
                       calibration=calibration[4])
    g5 = metrics.giqe5(rer_x=edges["rer_unfiltered_x"], rer_y=edges["rer_unfiltered_y"],
                       gsd=view["gsd_x"], snr=r["snr"], elevation=elevation,
                       calibration=calibration[5], q=q)
    versions = xr.DataArray(list(GIQE_VERSIONS), dims="giqe", name="giqe",
                            attrs={"long_name": "GIQE version"})

    def by_version(name):
        return xr.concat([g[name] for g in (g3, g4, g5)], dim=versions, coords="minimal",
                         compat="override")

    return xr.Dataset({
        "niirs": by_version("niirs").assign_attrs(
            units="1", long_name="National Imagery Interpretability Rating Scale",
            references="; ".join(f"GIQE {v}: {metrics.GIQE_REFERENCES[v]}"
                                 for v in GIQE_VERSIONS)),
        "flags": by_version("flags"),
        "rer_giqe5": g5["rer"].assign_attrs(units="1", long_name="GIQE 5 relative edge response"),
        "gsd": gsd,
        "gsd_gp": g4["gsd_gp"],
        "gsd_w": g5["gsd_w"].assign_attrs(units="m", long_name="GIQE 5 elevation-weighted GSD"),
        "noise_gain": gain,
    })


def system_otf(sensor: xr.Dataset, scenario: xr.Dataset, frequency=None, method="accurate",
               *, fy=None):
    """System OTF and every component for a sensor in a scenario (paper Figure 5).

    Parameters
    ----------
    sensor, scenario : xr.Dataset
        From :func:`xbsm.sensor` and :func:`xbsm.scenario`.
    frequency : xr.DataArray or array_like, optional
        Slice frequencies along x and y (dim ``frequency``), or with ``fy`` the
        x frequencies of a 2-D grid. Default: 201 points from 0 to the optics
        cutoff D / lambda_min. [cycles/rad]
    method : str or Method
        As for :func:`niirs`.
    fy : xr.DataArray, optional
        y frequencies of a 2-D grid (dims of your choice, e.g. ``fy``, ``fx``). [cycles/rad]

    Returns
    -------
    xr.Dataset
        ``aperture``, ``turbulence``, ``detector``, ``jitter``, ``drift``,
        ``wavefront``, ``filter``, ``system``, ``system_unfiltered``,
        ``coherence_diameter``; slices carry an ``orientation`` dim (x, y);
        ``flags`` (those of the radiometry: ``beyond_database`` where the spectral
        weights, and so the polychromatic OTFs, are undefined).
    """
    check_inputs(sensor, scenario)
    m = resolve_method(method)
    r = _snr(sensor, scenario, m, "giqe")
    weights = r["spectral_weights"]
    if frequency is None:
        cutoff = float(_optics_cutoff(sensor, weights["wavelength"]).max())
        frequency = np.linspace(0.0, cutoff, 201)
    if not isinstance(frequency, xr.DataArray):
        frequency = np.atleast_1d(np.asarray(frequency))
        frequency = xr.DataArray(frequency, dims="frequency", coords={"frequency": frequency})
    frequency = _frequency_argument("frequency", frequency)
    if "frequency" in frequency.coords:
        frequency["frequency"].attrs.update(units="cycles/rad", long_name="spatial frequency")
    if fy is not None:
        fy = _frequency_argument("fy", fy)
    slant = geometry.slant_range(scenario["ground_range"], scenario["altitude"], form=m.geometry)
    out = system_components(sensor, scenario, frequency, spectral_weights=_otf_weights(weights),
                            integration_time=r["effective_integration_time"], slant_range=slant,
                            method=m, fy=fy)
    return _result({**out.data_vars, "flags": r["flags"]}, m)


MAX_FREQUENCIES = 1_000_000
"""Most frequencies :func:`system_otf` evaluates per call (each costs a wavelength axis)."""


def _frequency_argument(name, values: xr.DataArray) -> xr.DataArray:
    """Finite frequencies on any dims but xbsm's own 2-D ones, and not absurdly many."""
    if values.size > MAX_FREQUENCIES:
        raise ValueError(f"{name} has {values.size} values; at most {MAX_FREQUENCIES} per call "
                         "(xbsm.model.MAX_FREQUENCIES): evaluate the grid in pieces")
    out = params.argument("frequency", values, allowed_dims=tuple(values.dims))
    return out.rename(name) if name != "frequency" else out
