"""The paper's worked examples as ready-made parameter datasets.

:func:`olson_sensor` is the full-motion-video camera of the paper's Sec. 3
(Olson; Table 2), :func:`olson_scenario` its 9 km flight over every database
ground range and both visibilities; :func:`infrared_sensor` the cooled MWIR and LWIR
cameras of the infrared guide (docs/infrared.md).
"""

from __future__ import annotations

from types import MappingProxyType

import numpy as np
import xarray as xr

from .atmosphere.database import GROUND_RANGES, VISIBILITIES
from .params import scenario, sensor
from .radiometry import dark_current_from_density

OLSON_BANDS = MappingProxyType({
    "red": (0.50e-6, 0.66e-6, 0.80),
    "nir": (0.55e-6, 0.85e-6, 0.71),
})
"""Band edges [m] and band-average quantum efficiency [1] of paper Table 2."""

DATABASE_GROUND_RANGES = np.array(GROUND_RANGES)
"""The 97 ground ranges of the atmosphere database (paper Appendix A). [m]"""
DATABASE_GROUND_RANGES.flags.writeable = False  # a read-only table


def olson_sensor_parameters(band: str = "nir") -> dict:
    """The keyword arguments of :func:`xbsm.sensor` that make the Olson camera.

    The plain parameters behind :func:`olson_sensor` (SI units), for callers
    that combine them with their own, such as study files.

    Parameters
    ----------
    band : {"red", "nir"}
        500-660 nm (QE 0.80) or 550-850 nm (QE 0.71).

    Returns
    -------
    dict
    """
    if band not in OLSON_BANDS:
        raise ValueError(f"band must be one of {sorted(OLSON_BANDS)}; got {band!r}")
    lo, hi, qe = OLSON_BANDS[band]
    pitch, focal = 8.0e-6, 4.0
    return dict(
        aperture_diameter=0.275, focal_length=focal, pixel_pitch_x=pitch,
        wavelength_min=lo, wavelength_max=hi, obscuration_ratio=0.4,
        optics_transmission=0.5, quantum_efficiency=qe, integration_time=0.03,
        read_noise=25.0, max_well=96000.0, bit_depth=11.9, max_well_fill=0.6,
        jitter_x=0.25 * pitch / focal, jitter_y=0.25 * pitch / focal,
        drift_rate_x=100e-6, drift_rate_y=100e-6,
        dark_current=float(dark_current_from_density(1e-5, pitch, pitch)),
    )


def olson_sensor(band: str = "nir", **overrides) -> xr.Dataset:
    """The paper's Olson camera (Table 2) in the red or near-infrared band.

    Parameters
    ----------
    band : {"red", "nir"}
        500-660 nm (QE 0.80) or 550-850 nm (QE 0.71).
    **overrides
        Any :func:`xbsm.sensor` parameter, e.g. a ``focal_length`` sweep.

    Returns
    -------
    xr.Dataset

    Notes
    -----
    Table 2 plus the paper's stated assumptions: relative obscuration 0.4,
    dark current density 1 nA/cm^2, 1/4-pixel rms jitter (0.5 urad), 100
    urad/s drift, 60% well-fill limit, 30 ms maximum integration time. The
    paper's silicon-CCD QE curve is not tabulated; the band averages are used.
    """
    params = olson_sensor_parameters(band)
    params.update(overrides)
    out = sensor(**params)
    out.attrs["name"] = f"Olson camera, {band} band (LeMaster & Eismann 2017, Table 2)"
    return out


def olson_scenario(ground_range=None, visibility=None, **overrides) -> xr.Dataset:
    """The paper's Sec. 3 flight: 9 km altitude, 100 m/s, HV 5/7 turbulence.

    Parameters
    ----------
    ground_range : xr.DataArray, optional
        Default: every database ground range (dim ``ground_range``). [m]
    visibility : xr.DataArray, optional
        Default: both database visibilities (dim ``visibility``). [km]
    **overrides
        Any other :func:`xbsm.scenario` parameter.

    Returns
    -------
    xr.Dataset
    """
    if ground_range is None:
        ground_range = xr.DataArray(DATABASE_GROUND_RANGES, dims="ground_range")
    if visibility is None:
        visibility = xr.DataArray(list(VISIBILITIES), dims="visibility")
    params = dict(altitude=9000.0, ground_range=ground_range, visibility=visibility,
                  platform_speed=100.0)
    params.update(overrides)
    return scenario(**params)


INFRARED_CAMERAS = MappingProxyType({
    # issue 25's first trial: 3-5 um, f/4, 15 um pitch; the other values are typical of a
    # cooled InSb staring array (the guide's choice, stated in docs/infrared.md)
    "mwir": MappingProxyType(dict(
        aperture_diameter=0.05, focal_length=0.2, pixel_pitch_x=15e-6,
        wavelength_min=3e-6, wavelength_max=5e-6, quantum_efficiency=0.8,
        optics_transmission=0.8, integration_time=2e-3, read_noise=100.0, max_well=1.1e7,
        bit_depth=14.0, dark_current=1e4, cold_shield_temperature=77.0,
        cold_filter_temperature=77.0)),
    # 8-12 um, f/2, 17 um pitch: a cooled HgCdTe array, short exposure for the large flux
    "lwir": MappingProxyType(dict(
        aperture_diameter=0.1, focal_length=0.2, pixel_pitch_x=17e-6,
        wavelength_min=8e-6, wavelength_max=12e-6, quantum_efficiency=0.6,
        optics_transmission=0.8, integration_time=1e-4, read_noise=500.0, max_well=2e7,
        bit_depth=14.0, dark_current=1e6, cold_shield_temperature=77.0,
        cold_filter_temperature=77.0)),
})
"""The :func:`xbsm.sensor` keywords of the infrared guide's two cameras, by band (SI)."""


def infrared_sensor(band: str = "mwir", **overrides) -> xr.Dataset:
    """The infrared guide's cooled MWIR (3-5 um, f/4) or LWIR (8-12 um, f/2) camera.

    Parameters
    ----------
    band : {"mwir", "lwir"}
        Which of :data:`INFRARED_CAMERAS`.
    **overrides
        Any :func:`xbsm.sensor` parameter.

    Returns
    -------
    xr.Dataset
    """
    if band not in INFRARED_CAMERAS:
        raise ValueError(f"band must be one of {sorted(INFRARED_CAMERAS)}; got {band!r}")
    out = sensor(**{**INFRARED_CAMERAS[band], **overrides})
    out.attrs["name"] = f"infrared guide's {band.upper()} camera (docs/infrared.md)"
    return out
