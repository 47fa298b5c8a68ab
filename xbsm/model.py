"""The model chain: parameters -> atmosphere -> radiometry -> noise -> (OTF -> GIQE).

``snr(sensor, scenario)`` and ``niirs(sensor, scenario)`` return datasets of
named intermediate results; every sweep dimension of the inputs is kept.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from . import _one_scenario, geometry, metrics, noise, params, radiometry
from . import flags as fl
from ._metadata import result
from .atmosphere import band_atmosphere
from .methods import Method
from .methods import method as resolve_method
from .otf.system import otf_weights, system_components
from .params import check_inputs
from .quadrature import UNRESOLVED_RER, edge_nodes, optics_cutoff, undersampled


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
    m = resolve_method(method)
    return _one_scenario.snr(sensor, scenario, m, targets,
                             lambda: _snr(sensor, scenario, m, targets)[0])


def _snr(sensor: xr.Dataset, scenario: xr.Dataset, m: Method, targets: str):
    """The SNR chain on validated inputs, and the optics cutoff over the same band curves."""
    atm = band_atmosphere(scenario["altitude"], scenario["ground_range"], scenario["visibility"],
                          sensor["wavelength_min"], sensor["wavelength_max"],
                          interpolation=m.atmosphere_interpolation, band_edges=m.band_edges)
    target, background = radiometry.aperture_radiances(
        atm, scenario, targets, sensor["wavelength_min"], m.constants)
    band = radiometry.sensor_band_terms(sensor, atm["wavelength"], m.constants)
    signal = radiometry.signal_terms(sensor, atm, target, background, m.constants, band=band)
    cutoff = optics_cutoff(sensor["aperture_diameter"], atm["wavelength"],
                           band["quantum_efficiency"], band["optics_transmission"])
    # no wavelength with signal (cold_filter_transmission = 0): the band's own D / lambda_min,
    # so that the call completes; the SNR there is 0, flagged snr_nonpositive
    cutoff = cutoff.fillna(sensor["aperture_diameter"] / sensor["wavelength_min"])
    noise_ = noise.noise_terms(signal, sensor)
    brighter = np.maximum(signal["target_photoelectrons"], signal["background_photoelectrons"])
    flags = fl.set_flag(atm["flags"], "well_fill_limited", signal["well_fill_scale"] < 1.0)
    if params._partial_spectral_coverage(sensor):  # one bit for the whole sensor
        flags = fl.set_flag(flags, "partial_spectral_coverage", xr.DataArray(True))
    return result({
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
    }, m, targets=targets), cutoff


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
    return _one_scenario.niirs(sensor, scenario, m, calibration,
                               lambda: _niirs(sensor, scenario, m, calibration))


def _niirs(sensor: xr.Dataset, scenario: xr.Dataset, m: Method, calibration) -> xr.Dataset:
    """The NIIRS chain on validated inputs, labelled stage by stage."""
    r, cutoff = _snr(sensor, scenario, m, "giqe")
    view = geometry.viewing_geometry(
        scenario["ground_range"], scenario["altitude"], sensor["pixel_pitch_x"],
        sensor["pixel_pitch_y"], sensor["focal_length"], elevation=m.elevation, form=m.geometry)
    ifov = xr.concat([view["ifov_x"], view["ifov_y"]], dim="orientation").assign_coords(
        orientation=["x", "y"])
    edges = _edge_terms(sensor, scenario, r, cutoff, view, ifov, m)
    giqe = metrics.giqe_by_version(
        rer=edges["rer"], eho=edges["eho"], rer_x=edges["rer_unfiltered_x"],
        rer_y=edges["rer_unfiltered_y"], gsd_x=view["gsd_x"], gsd_y=view["gsd_y"],
        snr=r["snr"], elevation=view["elevation_angle"],
        noise_gain=noise.noise_gain(sensor["filter_kernel"]),
        # GIQE 5's Q = lambda N / p at the band centre, per orientation (flags only)
        q=metrics.sampling_q(0.5 * (sensor["wavelength_min"] + sensor["wavelength_max"]),
                             sensor["aperture_diameter"], ifov),
        noise_coefficient=m.giqe4_noise_coefficient, calibration=calibration)
    flags = giqe["flags"] | r["flags"] | edges["undersampled"]
    return result({
        "niirs": giqe["niirs"],
        **{name: r[name] for name in r.data_vars if name not in ("spectral_weights", "flags")},
        **{name: value for name, value in edges.items()
           if name not in ("undersampled", "rer_unfiltered_x", "rer_unfiltered_y")},
        **{name: giqe[name] for name in giqe.data_vars if name not in ("niirs", "flags")},
        **{name: view[name] for name in ("slant_range", "elevation_angle")},
        "flags": flags.astype(np.int32).assign_attrs(fl.flag_attrs("NIIRS validity flags")),
    }, m)


def _edge_terms(s: xr.Dataset, sc: xr.Dataset, r: xr.Dataset, cutoff: xr.DataArray,
                view: xr.Dataset, ifov: xr.DataArray, m: Method) -> dict:
    """RER and EHO of the system OTF on the x and y slices, at the method's quadrature nodes."""
    weights = r["spectral_weights"]
    ifov_x, ifov_y = view["ifov_x"], view["ifov_y"]
    nodes, quad_weights = edge_nodes(cutoff, ifov_x, ifov_y, **m.edge_quadrature_knobs())
    otf = system_components(s, sc, nodes, spectral_weights=otf_weights(weights),
                            integration_time=r["effective_integration_time"],
                            slant_range=view["slant_range"], method=m)

    def edge(system):
        return metrics.edge_terms(abs(system) if m.edge_otf == "abs" else system, ifov,
                                  quad_weights)

    filtered = edge(otf["system"])
    unfiltered = filtered if s["filter_kernel"].shape == (1, 1) else edge(
        otf["system_unfiltered"])
    by_orientation = {o: filtered.sel(orientation=o, drop=True) for o in ("x", "y")}
    terms = {f"{name}_{o}": by_orientation[o][name].assign_attrs(
                 units="1", long_name=f"{long} along {o}")
             for name, long in (("rer", "relative edge response"),
                                ("eho", "edge height overshoot")) for o in ("x", "y")}
    coarse = False
    if m.edge_rule == "uniform_trapezoid":
        coarse = undersampled(nodes, cutoff, ifov_x, ifov_y, m.undersampling_threshold)
    rer = np.sqrt(terms["rer_x"] * terms["rer_y"])
    flags = fl.set_flag(xr.DataArray(np.int32(0)), "undersampled_grid", coarse)
    unfiltered_rer = unfiltered["rer"]
    return {
        **terms,
        "rer": rer.assign_attrs(units="1", long_name="relative edge response (geometric mean)"),
        "eho": np.sqrt(terms["eho_x"] * terms["eho_y"]).assign_attrs(
            units="1", long_name="edge height overshoot (geometric mean)"),
        "rer_unfiltered_x": unfiltered_rer.sel(orientation="x", drop=True),
        "rer_unfiltered_y": unfiltered_rer.sel(orientation="y", drop=True),
        "coherence_diameter": otf["coherence_diameter"],
        "cutoff_frequency": cutoff,
        "undersampled": fl.set_flag(flags, "blur_unresolved", rer < UNRESOLVED_RER),
    }


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
    r, cutoff = _snr(sensor, scenario, m, "giqe")
    weights = r["spectral_weights"]
    if frequency is None:
        frequency = np.linspace(0.0, float(cutoff.max()), 201)
    frequency = params.frequencies("frequency", params.labelled("frequency", frequency,
                                                                "frequency"))
    if "frequency" in frequency.coords:
        frequency["frequency"].attrs.update(units="cycles/rad", long_name="spatial frequency")
    if fy is not None:
        fy = params.frequencies("fy", fy)
    slant = geometry.slant_range(scenario["ground_range"], scenario["altitude"], form=m.geometry)
    out = system_components(sensor, scenario, frequency, spectral_weights=otf_weights(weights),
                            integration_time=r["effective_integration_time"], slant_range=slant,
                            method=m, fy=fy)
    return result({**out.data_vars, "flags": r["flags"]}, m)
