"""The model chain: parameters -> atmosphere -> radiometry -> noise -> (OTF -> GIQE).

``snr(sensor, scenario)`` and ``niirs(sensor, scenario)`` return datasets of
named intermediate results; every sweep dimension of the inputs is kept.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from . import flags as fl
from . import noise, radiometry
from .atmosphere import band_atmosphere
from .methods import Method
from .methods import method as resolve_method
from .params import check_kind


def _drop_scalar_coords(ds: xr.Dataset) -> xr.Dataset:
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
        ``snr`` (after frame stacking), ``snr_frame``, ``integration_time``,
        ``target_photoelectrons``, ``background_photoelectrons``,
        ``contrast_photoelectrons``, ``well_fill``, every noise term
        (``shot_noise``, ``scene_noise``, ``path_noise``, ``self_emission_noise``,
        ``dark_current_noise``, ``quantization_noise``, ``read_noise``,
        ``other_noise``, ``total_noise``), ``spectral_weights`` (the target's
        spectral photoelectron rate, which weights the OTFs, paper Eq. 3) and
        ``flags``.
    """
    check_kind(sensor, "sensor", "sensor")
    check_kind(scenario, "scenario", "scenario")
    if targets not in ("giqe", "scenario"):
        raise ValueError(f"targets must be 'giqe' or 'scenario'; got {targets!r}")
    m = resolve_method(method)
    atm = _band_atmosphere(sensor, scenario, m)
    target, background = radiometry.aperture_radiances(
        atm, scenario, targets, sensor["wavelength_min"], m.constants)
    signal = radiometry.signal_terms(sensor, atm, target, background, m.constants)
    noise_ = noise.noise_terms(signal, sensor)
    brighter = np.maximum(signal["target_photoelectrons"], signal["background_photoelectrons"])
    flags = fl.set_flag(atm["flags"], "well_fill_limited", signal["well_fill_scale"] < 1.0)
    out = xr.Dataset({
        "snr": noise_["snr"],
        "snr_frame": noise_["snr_frame"],
        **{name: signal[name] for name in (
            "integration_time", "target_photoelectrons", "background_photoelectrons",
            "contrast_photoelectrons")},
        "well_fill": (brighter / sensor["max_well"]).assign_attrs(
            units="1", long_name="well fill fraction"),
        **{name: noise_[name] for name in noise_.data_vars if name not in ("snr", "snr_frame")},
        "spectral_weights": signal["spectral_weights"],
        "flags": flags,
    })
    out.attrs.update(method=m.name, targets=targets)
    return _drop_scalar_coords(out)


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
        ``integration_time`` after that scaling; ``spectral_weights``, the
        spectral photoelectron rate of the brightest target normalised to a
        peak of 1; ``flags`` (``well_fill_limited`` where scaled).

    Notes
    -----
    Paper Eq. 1 and 2 with the dark current; the count is linear in
    reflectance (Eq. 1 is).
    """
    check_kind(sensor, "sensor", "sensor")
    check_kind(scenario, "scenario", "scenario")
    m = resolve_method(method)
    s, k = sensor, m.constants
    if reflectance is None:
        reflectance = np.linspace(0.0, 1.0, 100)
    if not isinstance(reflectance, xr.DataArray):
        values = np.asarray(reflectance, dtype=float)
        reflectance = xr.DataArray(values, dims="reflectance", coords={"reflectance": values})
    if integration_time is None:
        integration_time = s["integration_time"]
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
    out = xr.Dataset({
        "photoelectrons": counts.assign_attrs(units="count", long_name="photoelectrons per pixel"),
        "integration_time": (integration_time * scale).assign_attrs(
            units="s", long_name="integration time after the well limit"),
        "spectral_weights": (brightest / brightest.max("wavelength")).assign_attrs(
            units="1", long_name="normalised spectral photoelectron rate"),
        "flags": flags,
    })
    out.attrs["method"] = m.name
    return _drop_scalar_coords(out)


GIQE_VERSIONS = (3, 4, 5)


def _band_curves(sensor: xr.Dataset, wavelength: xr.DataArray):
    qe = radiometry.resample_spectral(sensor["quantum_efficiency"], wavelength,
                                      "quantum_efficiency")
    transmission = radiometry.resample_spectral(sensor["optics_transmission"], wavelength,
                                                "optics_transmission")
    return qe, transmission


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
        ``gsd_w`` (GIQE 5); ``noise_gain``; ``integration_time``;
        ``slant_range``; ``elevation_angle``; ``coherence_diameter``;
        ``cutoff_frequency``; ``flags`` over ``giqe``.

    Notes
    -----
    The chain: :func:`snr` gives the SNR, the integration time and the
    spectral weights; :func:`xbsm.otf.system.system_otf` the system OTF on the
    x and y slices at the nodes of the method's edge-response quadrature;
    :mod:`xbsm.metrics` the edge terms and the GIQE. GIQE 5 uses the system
    without the post-processing filter (as pyBSM's ``niirs5``), GIQE 3 and 4
    with it, with its noise gain.
    """
    check_kind(sensor, "sensor", "sensor")
    check_kind(scenario, "scenario", "scenario")
    m = resolve_method(method)
    from .metrics import giqe_calibrations

    cal = giqe_calibrations(calibration)
    return _niirs_from_snr(sensor, scenario, m, snr(sensor, scenario, m), calibration=cal)


def _niirs_from_snr(s: xr.Dataset, sc: xr.Dataset, m: Method, r: xr.Dataset,
                    calibration=None) -> xr.Dataset:
    """The NIIRS chain after the radiometry, for a :func:`snr` result ``r`` of (s, sc, m)."""
    from . import geometry, metrics
    from .otf.system import cutoff_wavelength, system_otf
    from .quadrature import edge_nodes, samples_per_oscillation

    slant = geometry.slant_range(sc["ground_range"], sc["altitude"])
    if m.elevation == "look-down":
        elevation = geometry.elevation_angle(slant, sc["altitude"])
    elif m.elevation == "target":
        elevation = geometry.target_elevation_angle(slant, sc["altitude"])
    else:
        raise ValueError(f"elevation must be 'look-down' or 'target'; got {m.elevation!r}")

    ifov_x = geometry.ifov(s["pixel_pitch_x"], s["focal_length"])
    ifov_y = geometry.ifov(s["pixel_pitch_y"], s["focal_length"])
    weights = r["spectral_weights"]
    qe, transmission = _band_curves(s, weights["wavelength"])
    cutoff = s["aperture_diameter"] / cutoff_wavelength(weights["wavelength"], qe, transmission)
    nodes, quad_weights = edge_nodes(cutoff, ifov_x, ifov_y, **m.edge_quadrature_knobs())
    otf = system_otf(s, sc, nodes, spectral_weights=_otf_weights(weights),
                     integration_time=r["integration_time"], slant_range=slant, method=m)

    ifov = xr.concat([ifov_x, ifov_y], dim="orientation").assign_coords(
        orientation=["x", "y"])

    def edges(system):
        h = abs(system) if m.edge_otf == "abs" else system
        return metrics.edge_terms(h, ifov, quad_weights)

    filtered = edges(otf["system"])
    unfiltered = filtered if s["filter_kernel"].shape == (1, 1) else edges(
        otf["system_unfiltered"])
    rer_x, rer_y = (filtered["rer"].sel(orientation=o, drop=True) for o in ("x", "y"))
    eho_x, eho_y = (filtered["eho"].sel(orientation=o, drop=True) for o in ("x", "y"))
    rer = np.sqrt(rer_x * rer_y)
    eho = np.sqrt(eho_x * eho_y)
    gsd_x = geometry.ground_sample_distance(ifov_x, slant)
    gsd_y = geometry.ground_sample_distance(ifov_y, slant)
    gsd = np.sqrt(gsd_x * gsd_y)
    gain = noise.noise_gain(s["filter_kernel"])
    stacked = r["snr"]

    cal = metrics.giqe_calibrations(calibration)
    # GIQE 5's Q = lambda N / p at the band centre, per orientation (flags only)
    q = metrics.sampling_q(0.5 * (s["wavelength_min"] + s["wavelength_max"]),
                           s["aperture_diameter"], ifov)
    g3 = metrics.giqe3(rer=rer, gsd=gsd, eho=eho, snr=stacked, noise_gain=gain,
                       elevation=elevation, calibration=cal[3])
    g4 = metrics.giqe4(rer=rer, gsd=gsd, eho=eho, snr=stacked, elevation=elevation,
                       noise_gain=gain, noise_coefficient=m.giqe4_noise_coefficient,
                       calibration=cal[4])
    g5 = metrics.giqe5(rer_x=unfiltered["rer"].sel(orientation="x", drop=True),
                       rer_y=unfiltered["rer"].sel(orientation="y", drop=True),
                       gsd=gsd_x, snr=stacked, elevation=elevation, calibration=cal[5], q=q)
    giqe = xr.DataArray(list(GIQE_VERSIONS), dims="giqe", name="giqe",
                        attrs={"long_name": "GIQE version"})
    niirs_ = xr.concat([g3["niirs"], g4["niirs"], g5["niirs"]], dim=giqe, coords="minimal",
                       compat="override")
    giqe_flags = xr.concat([g3["flags"], g4["flags"], g5["flags"]], dim=giqe,
                           coords="minimal", compat="override")

    flags = giqe_flags | r["flags"]
    if m.edge_rule == "uniform_trapezoid":
        coarse = samples_per_oscillation(nodes, cutoff, ifov_x, ifov_y) < (
            m.undersampling_threshold)
        flags = fl.set_flag(flags, "undersampled_grid", coarse)
    flags = flags.astype(np.int32).assign_attrs(fl.flag_attrs("NIIRS validity flags"))

    def named(da, units, long_name):
        return da.assign_attrs(units=units, long_name=long_name)

    out = xr.Dataset({
        "niirs": named(niirs_, "1", "National Imagery Interpretability Rating Scale"),
        "snr": r["snr"],
        "rer": named(rer, "1", "relative edge response (geometric mean)"),
        "rer_x": named(rer_x, "1", "relative edge response along x"),
        "rer_y": named(rer_y, "1", "relative edge response along y"),
        "rer_giqe5": named(g5["rer"], "1", "GIQE 5 relative edge response"),
        "eho": named(eho, "1", "edge height overshoot (geometric mean)"),
        "eho_x": named(eho_x, "1", "edge height overshoot along x"),
        "eho_y": named(eho_y, "1", "edge height overshoot along y"),
        "gsd": named(gsd, "m", "ground sample distance (geometric mean)"),
        "gsd_gp": g4["gsd_gp"],
        "gsd_w": named(g5["gsd_w"], "m", "GIQE 5 elevation-weighted GSD"),
        "noise_gain": gain,
        "integration_time": r["integration_time"],
        "slant_range": named(slant, "m", "slant range"),
        "elevation_angle": named(elevation, "rad", "GIQE elevation angle"),
        "coherence_diameter": otf["coherence_diameter"],
        "cutoff_frequency": named(cutoff, "cycles/rad", "optics cutoff frequency D/lambda_min"),
        "flags": flags,
    })
    out.attrs["method"] = m.name
    return _drop_scalar_coords(out)


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
        ``coherence_diameter``; slices carry an ``orientation`` dim (x, y).
    """
    from . import geometry
    from .otf.system import cutoff_wavelength
    from .otf.system import system_otf as _system_otf

    check_kind(sensor, "sensor", "sensor")
    check_kind(scenario, "scenario", "scenario")
    m = resolve_method(method)
    r = snr(sensor, scenario, m)
    weights = r["spectral_weights"]
    if frequency is None:
        qe, transmission = _band_curves(sensor, weights["wavelength"])
        cutoff = float((sensor["aperture_diameter"] / cutoff_wavelength(
            weights["wavelength"], qe, transmission)).max())
        frequency = np.linspace(0.0, cutoff, 201)
    if not isinstance(frequency, xr.DataArray):
        frequency = np.asarray(frequency, dtype=float)
        frequency = xr.DataArray(frequency, dims="frequency", coords={"frequency": frequency},
                                 attrs={"units": "cycles/rad", "long_name": "spatial frequency"})
    slant = geometry.slant_range(scenario["ground_range"], scenario["altitude"])
    out = _system_otf(sensor, scenario, frequency, spectral_weights=_otf_weights(weights),
                      integration_time=r["integration_time"], slant_range=slant, method=m, fy=fy)
    out.attrs["method"] = m.name
    return _drop_scalar_coords(out)
