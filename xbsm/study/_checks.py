"""Checks of a study as a whole, once its tables are read one by one.

A parameter is fixed or swept, never both; the study holds at most
:data:`MAX_SCENARIOS` scenarios; and xbsm's own checks accept the sensor and the
scenario of every band with the full sweeps.
"""

from __future__ import annotations

import inspect
import math
import re
from typing import TYPE_CHECKING

import xarray as xr

from .. import params
from ._source import Source
from ._values import SCENARIO_PARAMETERS, SENSOR_PARAMETERS

if TYPE_CHECKING:
    from .spec import Study

__all__ = ["MAX_SCENARIOS", "check_model_inputs", "check_not_both", "check_size",
           "dimension_sizes"]

#: The most scenarios one study may hold (a guard against a typo of 10 zeros).
MAX_SCENARIOS = 10**10


def dimension_sizes(bands, sweeps) -> dict:
    """Length of every study dimension (``band`` first when there are bands)."""
    sizes = {"band": len(bands)} if bands else {}
    sizes.update({sweep.dim: sweep.size for sweep in sweeps})
    return sizes


def check_not_both(src: Source, sweeps, tables: dict) -> None:
    """A parameter is fixed ([sensor], [scenario], a band) or swept, never both."""
    for sweep in sweeps:
        for name in sweep.values:
            for table, given in tables.items():
                if name in given:
                    raise src.error(table, name, "is set here and swept in [sweep]; keep one")


def check_size(src: Source, bands: dict, sweeps) -> None:
    """At most :data:`MAX_SCENARIOS` scenarios."""
    sizes = dimension_sizes(bands, sweeps)
    total = math.prod(sizes.values())
    if total > MAX_SCENARIOS:
        shown = " x ".join(f"{dim} {size}" for dim, size in sizes.items())
        raise src.error("sweep", None, f"{total:.3g} scenarios ({shown}); at most "
                        f"{MAX_SCENARIOS:.0e} per study: sweep fewer values")


def check_model_inputs(src: Source, study: Study) -> None:
    """Build the sensor and scenario of every band with the full sweeps: xbsm's own checks."""
    swept = {name: (sweep.dim, values) for sweep in study.sweeps
             for name, values in sweep.values.items()}
    origin = {name: f"sweep.{dim}" if dim != name else "sweep" for name, (dim, _) in
              swept.items()}
    for band, band_params in (study.bands or {None: {}}).items():
        for name in band_params:
            origin.setdefault(name, f"bands.{band}")
        kwargs = {**study.sensor, **band_params, **study.scenario}
        kwargs.update({name: xr.DataArray(values, dims=dim)
                       for name, (dim, values) in swept.items()})
        sensor = {k: v for k, v in kwargs.items() if k in SENSOR_PARAMETERS}
        scenario = {k: v for k, v in kwargs.items() if k in SCENARIO_PARAMETERS}
        for kind, call, given in (("sensor", params.sensor, sensor),
                                  ("scenario", params.scenario, scenario)):
            missing = [p for p, v in inspect.signature(call).parameters.items()
                       if v.default is inspect.Parameter.empty and p not in given]
            if missing:
                raise src.error(kind, None, f"missing {kind} parameter {missing[0]!r} "
                                f"(set it in [{kind}] or sweep it in [sweep])")
            try:
                call(**given)
            except ValueError as err:
                name = _first_named(str(err), given)
                raise src.error(origin.get(name, kind), name, str(err)) from None


def _first_named(message: str, names) -> str | None:
    """The parameter a model error message names first."""
    found = [(message.find(name), name) for name in names if re.search(
        rf"\b{re.escape(name)}\b", message)]
    return min(found)[1] if found else None
