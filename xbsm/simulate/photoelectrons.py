"""Reflectance to photoelectrons: the radiometry an image simulation applies.

The radiometric mapping an image simulation applies to a reflectance map is the
same chain as :func:`xbsm.snr`'s (paper Eq. 1 and 2), for Lambertian targets of
any reflectance.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from .. import flags as fl
from .. import params, radiometry
from .._metadata import result
from ..atmosphere import band_atmosphere
from ..methods import method as resolve_method
from ..params import check_inputs

__all__ = ["reflectance_to_photoelectrons"]


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
    reflectance = params.labelled("reflectance", reflectance, "reflectance")
    if "reflectance" not in reflectance.dims:
        raise ValueError("reflectance must have a 'reflectance' dimension (the brightest value "
                         f"sets the well-fill scaling); got dims {reflectance.dims}")
    reflectance = params.argument("reflectance", reflectance, allowed_dims=("reflectance",))
    temperature = params.argument("temperature", temperature)
    integration_time = (s["integration_time"] if integration_time is None
                        else params.argument("integration_time", integration_time))
    atm = band_atmosphere(scenario["altitude"], scenario["ground_range"], scenario["visibility"],
                          s["wavelength_min"], s["wavelength_max"],
                          interpolation=m.atmosphere_interpolation, band_edges=m.band_edges)
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
    return result({
        "photoelectrons": counts.assign_attrs(units="count", long_name="photoelectrons per pixel"),
        "effective_integration_time": (integration_time * scale).assign_attrs(
            units="s", long_name="integration time after the well limit"),
        "spectral_weights": (brightest / brightest.max("wavelength")).assign_attrs(
            units="1", long_name="normalised spectral photoelectron rate"),
        "flags": flags,
    }, m)
