"""A study's fixed parameters as global attributes of its result (what the figures read).

A study result carries its study file as text (``xbsm_study``), but a reader of the
result should not have to parse a study file to learn at which sensor and scenario it
was computed: :func:`parameter_attributes` writes every fixed parameter as a plain
NetCDF attribute and :func:`parameters_of` reads them back. The names:

- ``xbsm_scenario_<name>``: a fixed scenario parameter [SI];
- ``xbsm_sensor_<name>``: a sensor parameter shared by every band [SI]; a spectral
  curve as its values with its wavelengths in ``xbsm_sensor_<name>_wavelength`` [m];
  the filter kernel flattened, its shape in ``xbsm_sensor_filter_kernel_shape``;
- ``xbsm_band<i>_<name>``: the same for the band at position ``i`` along ``band``.

Swept parameters are the result's coordinates, not attributes.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from ..params import SPECTRAL
from .spec import SCENARIO_PARAMETERS, SENSOR_PARAMETERS, Study

SCENARIO_PREFIX = "xbsm_scenario_"
SENSOR_PREFIX = "xbsm_sensor_"


def band_prefix(index: int) -> str:
    """Prefix of the attributes of the band at position ``index`` along ``band``."""
    return f"xbsm_band{index}_"


def _as_attributes(prefix: str, values) -> dict:
    out = {}
    for name, value in values.items():
        if isinstance(value, xr.DataArray):  # a spectral curve
            out[f"{prefix}{name}"] = np.asarray(value.values, dtype=float)
            out[f"{prefix}{name}_wavelength"] = np.asarray(value["wavelength"].values, float)
        elif np.ndim(value) > 1:  # the filter kernel
            out[f"{prefix}{name}"] = np.asarray(value, dtype=float).ravel()
            out[f"{prefix}{name}_shape"] = np.asarray(np.shape(value), dtype=np.int32)
        else:
            out[f"{prefix}{name}"] = value
    return out


def parameter_attributes(study: Study) -> dict:
    """The global attributes that record ``study``'s fixed parameters (module docstring)."""
    out = _as_attributes(SCENARIO_PREFIX, study.scenario)
    out.update(_as_attributes(SENSOR_PREFIX, study.sensor))
    for index, band in enumerate(study.bands.values()):
        out.update(_as_attributes(band_prefix(index), band))
    return out


def _read(attrs: dict, prefix: str, names) -> dict:
    """The parameters among ``names`` recorded under ``prefix``, in the attributes' order."""
    out = {}
    for key, value in attrs.items():
        name = key.removeprefix(prefix)
        if name == key or name not in names:
            continue
        if name in SPECTRAL and f"{key}_wavelength" in attrs:
            value = xr.DataArray(np.atleast_1d(value), dims="wavelength",
                                 coords={"wavelength": np.atleast_1d(attrs[f"{key}_wavelength"])})
        elif f"{key}_shape" in attrs:
            value = np.reshape(value, tuple(np.atleast_1d(attrs[f"{key}_shape"])))
        else:
            value = float(np.asarray(value).ravel()[0])
        out[name] = value
    return out


def parameters_of(ds: xr.Dataset, band: int | None = None) -> tuple[dict, dict]:
    """The fixed sensor and scenario parameters a study result records in its attributes.

    Parameters
    ----------
    ds : xr.Dataset
        A result of :func:`xbsm.study.run` (or the file :func:`xbsm.study.write` wrote).
    band : int, optional
        Position along ``band``: its own parameters join (and override) the shared ones.

    Returns
    -------
    sensor, scenario : dict
        Parameter name -> value [SI] (a spectral curve as a DataArray over ``wavelength``);
        empty for a result written before the attributes existed.
    """
    sensor = _read(ds.attrs, SENSOR_PREFIX, SENSOR_PARAMETERS)
    if band is not None:
        sensor.update(_read(ds.attrs, band_prefix(band), SENSOR_PARAMETERS))
    return sensor, _read(ds.attrs, SCENARIO_PREFIX, SCENARIO_PARAMETERS)
