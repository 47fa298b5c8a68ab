"""pyBSM 0.16.1 keyword names in, xbsm parameter datasets out.

``sensor(**kw)`` accepts every keyword of ``pybsm.simulation.Sensor`` plus the
attributes pyBSM users set after construction (``optics_transmission``,
``filter_kernel``, ``other_noise``, ``L_x``, ``L_y``); ``scenario(**kw)``
accepts every keyword of ``pybsm.simulation.Scenario``. The name mapping is
the table :data:`SENSOR_NAMES` / :data:`SCENARIO_NAMES` (also in
``docs/migration.md``). Where pyBSM derives a default differently from xbsm,
this module follows pyBSM, so that ``xbsm.niirs(..., method="pybsm")`` on
these datasets reproduces pyBSM's numbers.
"""

from __future__ import annotations

from types import MappingProxyType

import numpy as np
import xarray as xr

from . import params
from .atmosphere.database import IHAZE, VISIBILITIES

SENSOR_NAMES: dict[str, str] = {
    "D": "aperture_diameter",
    "f": "focal_length",
    "p_x": "pixel_pitch_x",
    "p_y": "pixel_pitch_y",
    "w_x": "detector_width_x",
    "w_y": "detector_width_y",
    "eta": "obscuration_ratio",
    "int_time": "integration_time",
    "dark_current": "dark_current",
    "other_irradiance": "stray_irradiance",
    "read_noise": "read_noise",
    "max_n": "max_well",
    "max_well_fill": "max_well_fill",
    "bit_depth": "bit_depth",
    "n_tdi": "tdi_stages",
    "cold_shield_temperature": "cold_shield_temperature",
    "optics_temperature": "optics_temperature",
    "optics_emissivity": "optics_emissivity",
    "cold_filter_transmission": "cold_filter_transmission",
    "cold_filter_temperature": "cold_filter_temperature",
    "cold_filter_emissivity": "cold_filter_emissivity",
    "s_x": "jitter_x",
    "s_y": "jitter_y",
    "da_x": "drift_rate_x",
    "da_y": "drift_rate_y",
    "pv": "wavefront_variance",
    "pv_wavelength": "wavefront_wavelength",
    "L_x": "wavefront_correlation_length_x",
    "L_y": "wavefront_correlation_length_y",
    "filter_kernel": "filter_kernel",
    "frame_stacks": "frame_stacks",
    "other_noise": "other_noise",
    # Spectral: opt_trans_wavelengths gives the band edges and, with
    # optics_transmission, the transmission curve; qe with qe_wavelengths.
    "opt_trans_wavelengths": "wavelength_min, wavelength_max (first and last)",
    "optics_transmission": "optics_transmission (over opt_trans_wavelengths)",
    "qe": "quantum_efficiency (over qe_wavelengths)",
    "qe_wavelengths": "quantum_efficiency wavelength coordinate",
    "name": "(dataset attribute 'name')",
}
"""pyBSM Sensor keyword -> xbsm.sensor parameter."""

SCENARIO_NAMES: dict[str, str] = {
    "ihaze": "visibility (1 -> 23 km, 2 -> 5 km)",
    "altitude": "altitude",
    "ground_range": "ground_range",
    "aircraft_speed": "platform_speed",
    "target_reflectance": "target_reflectance",
    "target_temperature": "target_temperature",
    "background_reflectance": "background_reflectance",
    "background_temperature": "background_temperature",
    "ha_wind_speed": "high_altitude_wind_speed",
    "cn2_at_1m": "cn2_at_1m",
    "interp": "(ignored: xbsm interpolates between database nodes and is exact on them)",
    "name": "(dataset attribute 'name')",
}
"""pyBSM Scenario keyword -> xbsm.scenario parameter."""

IHAZE_VISIBILITY = dict(zip(IHAZE, VISIBILITIES, strict=True))
"""MODTRAN IHAZE code -> visibility. [km]"""


def _curve(values, wavelengths, value_name, wavelength_name):
    values = np.atleast_1d(np.asarray(values, dtype=float))
    wavelengths = np.atleast_1d(np.asarray(wavelengths, dtype=float))
    if values.shape != wavelengths.shape:
        raise ValueError(
            f"{value_name} must have one value per entry of {wavelength_name}: "
            f"got {values.shape[0]} values for {wavelengths.shape[0]} wavelengths"
        )
    return xr.DataArray(values, dims="wavelength", coords={"wavelength": wavelengths})


def sensor(**kw) -> xr.Dataset:
    """An xbsm sensor dataset from pyBSM 0.16.1 ``Sensor`` keywords.

    Parameters
    ----------
    **kw
        Any keyword of ``pybsm.simulation.Sensor`` and the post-construction
        attributes ``optics_transmission``, ``filter_kernel``, ``other_noise``,
        ``L_x`` and ``L_y``. Required: ``D``, ``f``, ``p_x``, ``opt_trans_wavelengths``.

    Returns
    -------
    xr.Dataset
        As :func:`xbsm.sensor`.

    Notes
    -----
    pyBSM conventions kept here: the band is ``opt_trans_wavelengths[0]`` to
    ``[-1]``; ``w_y`` defaults to ``p_x / w_x * p_y``; ``other_noise`` (an
    array) enters as its root-sum-square; ``L_x``, ``L_y`` default to ``D``.
    ``other_irradiance`` becomes xbsm's stray irradiance (pyBSM 0.16.1 stores
    it but never uses it).
    """
    for key in kw:
        if key not in SENSOR_NAMES:
            raise params.unknown_keyword("pyBSM Sensor keyword", key, SENSOR_NAMES)
    for required in ("D", "f", "p_x", "opt_trans_wavelengths"):
        if required not in kw:
            raise ValueError(f"pyBSM Sensor keyword {required!r} is required")
    kw = dict(kw)
    name = kw.pop("name", None)
    band = np.atleast_1d(np.asarray(kw.pop("opt_trans_wavelengths"), dtype=float))
    if band.size < 2 or np.any(np.diff(band) <= 0):
        raise ValueError(
            "opt_trans_wavelengths must hold at least two strictly increasing wavelengths [m]"
        )
    out = {"wavelength_min": band[0], "wavelength_max": band[-1]}
    transmission = kw.pop("optics_transmission", None)
    if transmission is not None:
        out["optics_transmission"] = _curve(
            transmission, band, "optics_transmission", "opt_trans_wavelengths"
        )
    qe = kw.pop("qe", None)
    qe_wavelengths = kw.pop("qe_wavelengths", None)
    if qe is None and qe_wavelengths is not None:
        qe = np.ones(np.shape(qe_wavelengths))  # pyBSM: QE 1 over qe_wavelengths, 0 elsewhere
    if qe is not None:
        out["quantum_efficiency"] = _curve(
            qe, band if qe_wavelengths is None else qe_wavelengths, "qe", "qe_wavelengths"
        )
    other_noise = kw.pop("other_noise", None)
    if other_noise is not None:
        out["other_noise"] = _other_noise(other_noise)
    other_irradiance = kw.pop("other_irradiance", None)
    if other_irradiance is not None:
        out["stray_irradiance"] = other_irradiance
    if kw.get("w_x") is not None and not np.all(np.asarray(kw["w_x"], dtype=float) > 0):
        raise ValueError(f"w_x (detector_width_x) must lie in (0, inf) m; got {kw['w_x']!r}")
    if kw.get("w_y") is None and kw.get("w_x") is not None:
        p_y = kw.get("p_y") if kw.get("p_y") is not None else kw["p_x"]
        kw["w_y"] = kw["p_x"] / kw["w_x"] * p_y  # pyBSM 0.16.1's default
    for key, value in kw.items():
        if value is not None:
            out[SENSOR_NAMES[key]] = value
    try:
        ds = params.sensor(**out)
    except ValueError as err:
        raise _in_pybsm_terms(err) from err
    if name is not None:
        ds.attrs["name"] = str(name)
    return ds


#: xbsm parameter -> the pyBSM keyword(s) it comes from, where the names differ.
_PYBSM_KEYWORDS = MappingProxyType({
    **{ours: theirs for names, specs in ((SENSOR_NAMES, params.SENSOR_SPECS),
                                         (SCENARIO_NAMES, params.SCENARIO_SPECS))
       for theirs, ours in names.items() if ours in specs and ours != theirs},
    "wavelength_min": "opt_trans_wavelengths[0]",
    "wavelength_max": "opt_trans_wavelengths[-1]",
    "optics_transmission": "optics_transmission over opt_trans_wavelengths",
    "quantum_efficiency": "qe over qe_wavelengths",
    "visibility": "ihaze",
})


def _in_pybsm_terms(err: ValueError) -> ValueError:
    """``err`` of :func:`xbsm.sensor` / :func:`xbsm.scenario`, naming the pyBSM keyword too."""
    text = str(err)
    first = text.split(" ", 1)[0].rstrip(":,;.")
    if first not in _PYBSM_KEYWORDS:
        return err
    return ValueError(f"{text} (pyBSM keyword: {_PYBSM_KEYWORDS[first]})")


def _other_noise(values) -> float:
    """Root-sum-square of pyBSM's ``other_noise`` array, refusing negative entries."""
    try:
        array = np.atleast_1d(np.asarray(values, dtype=float))
    except (TypeError, ValueError):
        raise ValueError("other_noise must be an array of rms noise values in [0, inf) "
                         f"electrons; got {values!r:.60}") from None
    valid = (array >= 0) & np.isfinite(array)
    if not np.all(valid):
        bad = float(array[~valid][0])
        note = " (pyBSM squares each entry: it counted this one as positive)" if bad < 0 else ""
        raise ValueError(
            f"other_noise must hold rms noise values in [0, inf) electrons; got {bad!r}{note}")
    return float(np.sqrt(np.sum(array**2)))


def scenario(**kw) -> xr.Dataset:
    """An xbsm scenario dataset from pyBSM 0.16.1 ``Scenario`` keywords.

    Parameters
    ----------
    **kw
        Any keyword of ``pybsm.simulation.Scenario``. Required: ``ihaze``,
        ``altitude``, ``ground_range``.

    Returns
    -------
    xr.Dataset
        As :func:`xbsm.scenario`.
    """
    for key in kw:
        if key not in SCENARIO_NAMES:
            raise params.unknown_keyword("pyBSM Scenario keyword", key, SCENARIO_NAMES)
    for required in ("ihaze", "altitude", "ground_range"):
        if required not in kw:
            raise ValueError(f"pyBSM Scenario keyword {required!r} is required")
    kw = dict(kw)
    name = kw.pop("name", None)
    kw.pop("interp", None)
    ihaze = kw.pop("ihaze")
    if isinstance(ihaze, xr.DataArray):
        visibility = ihaze.copy(data=np.vectorize(IHAZE_VISIBILITY.get, otypes=[float])(ihaze))
        if np.any(np.isnan(visibility)):
            raise ValueError("ihaze must be 1 (23 km visibility) or 2 (5 km visibility)")
    elif ihaze in IHAZE_VISIBILITY:
        visibility = IHAZE_VISIBILITY[ihaze]
    else:
        raise ValueError(
            f"ihaze must be 1 (23 km visibility) or 2 (5 km visibility); got {ihaze!r}"
        )
    out = {"visibility": visibility}
    for key, value in kw.items():
        out[SCENARIO_NAMES[key]] = value
    try:
        ds = params.scenario(**out)
    except ValueError as err:
        raise _in_pybsm_terms(err) from err
    if name is not None:
        ds.attrs["name"] = str(name)
    return ds
