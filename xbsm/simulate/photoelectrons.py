"""Reflectance to photoelectrons: the radiometry an image simulation applies.

The radiometric mapping an image simulation applies to a reflectance map is the
same chain as :func:`xbsm.snr`'s (paper Eq. 1 and 2), for Lambertian targets of
any reflectance.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from .. import _chain, params
from ..methods import method as resolve_method
from ..params import Resolved, check_inputs, contract

__all__ = ["reflectance_to_photoelectrons"]


@contract(method=Resolved(resolve_method))
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
    s = sensor
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
    return _chain.reflectance_to_photoelectrons(sensor, scenario, method, reflectance, temperature,
                                                integration_time)
