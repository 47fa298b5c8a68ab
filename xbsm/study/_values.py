"""The values a study file gives a parameter, checked one by one.

A fixed parameter is a number, a spectral curve ``{wavelength, values}`` or a
filter kernel; a swept one is a list of numbers, a range ``{start, stop, num,
spacing}`` or, for ``ground_range``, the word ``"database"``.
"""

from __future__ import annotations

import inspect
import math

import numpy as np
import xarray as xr

from .. import examples, params
from ._source import Source, shown, suggestion

__all__ = ["BAND_PARAMETERS", "MAX_SWEEP_VALUES", "PARAMETERS", "RANGE_KEYS",
           "SCENARIO_PARAMETERS", "SENSOR_PARAMETERS", "fixed_parameters", "is_number",
           "sweep_values"]

SENSOR_PARAMETERS = tuple(inspect.signature(params.sensor).parameters)
SCENARIO_PARAMETERS = tuple(inspect.signature(params.scenario).parameters)
#: Every parameter a study may set or sweep.
PARAMETERS = frozenset(SENSOR_PARAMETERS) | frozenset(SCENARIO_PARAMETERS)
#: Parameters that set the spectral grid: a band is a dimension of its own ([bands]).
BAND_PARAMETERS = ("wavelength_min", "wavelength_max")
RANGE_KEYS = ("start", "stop", "num", "spacing")
#: The most values one range may produce (its coordinate is held in memory).
MAX_SWEEP_VALUES = 10**7


def is_number(value) -> bool:
    """A TOML integer or float (never a boolean) that a float can hold."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return False
    try:
        float(value)
    except OverflowError:
        return False
    return True


def _number_list(src: Source, table: str, key: str, value) -> np.ndarray:
    """A non-empty list of finite numbers as a float array."""
    if not isinstance(value, list) or not value or not all(is_number(v) for v in value):
        word = ' or "database"' if key == "ground_range" else ""
        raise src.error(table, key, "must be a non-empty list of numbers, a range "
                        f"{{start, stop, num[, spacing]}}{word}; got {shown(value)}")
    array = np.asarray(value, dtype=float)
    if not np.all(np.isfinite(array)):
        raise src.error(table, key, f"values must be finite numbers; got {shown(value)}")
    return array


def _check_range_keys(src: Source, table: str, key: str, spec: dict) -> None:
    """Only the keys of a range, and start, stop and num all given."""
    for name in spec:
        if name not in RANGE_KEYS:
            hint = (" (a table under a parameter's name is a range; a paired sweep needs a "
                    "dimension name that is not a parameter, e.g. [sweep.case])"
                    if name in PARAMETERS else "")
            raise src.error(f"{table}.{key}", name, f"unknown key of a range; "
                            f"{suggestion(name, RANGE_KEYS)}{hint}")
    for name in ("start", "stop", "num"):
        if name not in spec:
            raise src.error(table, key, f"a range needs start, stop and num; {name} is missing")


def _range(src: Source, table: str, key: str, spec: dict) -> np.ndarray:
    """``{start, stop, num, spacing}`` as linearly or logarithmically spaced values."""
    _check_range_keys(src, table, key, spec)
    where = f"{table}.{key}"
    start, stop, num = spec["start"], spec["stop"], spec["num"]
    for name, value in (("start", start), ("stop", stop)):
        if not is_number(value) or not math.isfinite(value):
            raise src.error(where, name, f"must be a finite number; got {shown(value)}")
    if isinstance(num, bool) or not isinstance(num, int) or not 1 <= num <= MAX_SWEEP_VALUES:
        raise src.error(where, "num", f"must be a whole number from 1 to {MAX_SWEEP_VALUES:.0e};"
                        f" got {shown(num)}")
    spacing = spec.get("spacing", "linear")
    if spacing not in ("linear", "log"):
        raise src.error(where, "spacing", f'must be "linear" or "log"; got {shown(spacing)}')
    if spacing == "log" and (start <= 0 or stop <= 0):
        raise src.error(where, "start" if start <= 0 else "stop", "a log range needs start > 0 "
                        f"and stop > 0; got start = {start!r}, stop = {stop!r}")
    return np.geomspace(start, stop, num) if spacing == "log" else np.linspace(start, stop, num)


def sweep_values(src: Source, table: str, key: str, value) -> np.ndarray:
    """The values of one swept parameter (or the MTF frequencies), written any of three ways."""
    if key in BAND_PARAMETERS:
        raise src.error(table, key, "a band edge cannot be swept (it sets the spectral grid); "
                        "give each band as a [bands.NAME] table instead")
    if key in params.SPECTRAL or key == "filter_kernel":
        raise src.error(table, key, f"{key} cannot be swept in a study; set it in [sensor] or "
                        "per band in [bands.NAME]")
    if isinstance(value, str):
        if key == "ground_range" and value == "database":
            return np.array(examples.DATABASE_GROUND_RANGES)
        allowed = ('the only word allowed is "database" (the 97 ground ranges of the '
                   'atmosphere database)' if key == "ground_range" else
                   "must be a list of numbers or a range {start, stop, num[, spacing]}")
        raise src.error(table, key, f"{allowed}; got {shown(value)}")
    values = (_range(src, table, key, value) if isinstance(value, dict)
              else _number_list(src, table, key, value))
    repeated = len(values) - len(np.unique(values))
    if repeated and table in ("sweep", "outputs"):
        raise src.error(table, key, f"values must not repeat (they label the dimension); "
                        f"{repeated} value(s) repeated")
    return values


def fixed_parameters(src: Source, values: dict, table: str, known) -> dict:
    """The fixed parameters of a table ([sensor] ``preset`` and ``band`` aside)."""
    out = {}
    for key, value in values.items():
        if key in ("preset", "band") and table == "sensor":
            continue
        if key not in known:
            raise src.error(table, key, f"unknown parameter; {suggestion(key, known)}")
        out[key] = _parameter(src, table, key, value)
    return out


def _parameter(src: Source, table: str, key: str, value):
    """One fixed parameter value: a number, a spectral curve table or a filter kernel."""
    if is_number(value):
        return float(value)
    if key == "filter_kernel":
        return _kernel(src, table, key, value)
    if key in params.SPECTRAL and isinstance(value, dict):
        return _curve(src, table, key, value)
    units = params.parameter_spec(key).units
    curve = (" or a curve {wavelength = [...], values = [...]}" if key in params.SPECTRAL
             else "")
    hint = ("; to sweep it, move it to [sweep]" if isinstance(value, (list, dict))
            and key not in params.SPECTRAL else "")
    raise src.error(table, key, f"must be a number in SI units [{units}]{curve}; "
                    f"got {shown(value)}{hint}")


def _kernel(src: Source, table: str, key: str, value) -> np.ndarray:
    """A filter kernel: a list of numbers (one row) or a list of rows of one length."""
    rows = (value if isinstance(value, list) and value
            and all(isinstance(row, list) for row in value) else [value])
    if (not all(isinstance(row, list) and row and all(is_number(v) for v in row)
                for row in rows) or len({len(row) for row in rows}) != 1):
        raise src.error(table, key, "must be a list of numbers (one row) or a list of rows of "
                        f"one length, e.g. [[-0.25, 1.5, -0.25]]; got {shown(value)}")
    return np.asarray(rows, dtype=float)


def _curve(src: Source, table: str, key: str, value: dict) -> xr.DataArray:
    """A spectral curve ``{wavelength = [...], values = [...]}`` as a DataArray."""
    if set(value) != {"wavelength", "values"}:
        raise src.error(table, key, "a spectral curve is a table {wavelength = [...] (m), "
                        f"values = [...]}}; got keys {', '.join(value) or 'none'}")
    wavelength = _number_list(src, f"{table}.{key}", "wavelength", value["wavelength"])
    curve = _number_list(src, f"{table}.{key}", "values", value["values"])
    if len(wavelength) != len(curve):
        raise src.error(table, key, f"wavelength and values differ in length "
                        f"({len(wavelength)} and {len(curve)})")
    return xr.DataArray(curve, dims="wavelength", coords={"wavelength": wavelength})
