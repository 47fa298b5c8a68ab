"""A study as one lazy Dataset: a dask task per chunk of the scenario grid.

The scenario grid is the product of the study's dimensions (``band``, then
every sweep in file order). :func:`run` cuts it into chunks and wraps one
eager model call per chunk in :func:`xarray.map_blocks`, so building the
result costs one small model call (which fixes the output's variables and
dimensions) and computes nothing else. Inside a chunk the model still
computes each quantity on the dimensions it depends on (the atmosphere on
altitude x ground range x visibility only), which is what makes product
sweeps cheap. The same Dataset computes on the local threads or on any
``dask.distributed`` cluster.
"""

from __future__ import annotations

import dataclasses
import math

import dask.array as dsa
import numpy as np
import xarray as xr

from .. import __version__, model, params
from ..methods import method as make_method
from . import _cf
from .spec import SCENARIO_PARAMETERS, SENSOR_PARAMETERS, Study


def chunk_sizes(study: Study) -> dict[str, int]:
    """Chunk length along every study dimension.

    ``[run] chunks`` first; ``band`` one at a time (each band has its own
    spectral grid); then the longest remaining chunk is halved until a chunk
    holds at most ``chunk_scenarios`` scenarios.
    """
    sizes = study.sizes
    chunks = {dim: min(size, study.chunks.get(dim, size)) for dim, size in sizes.items()}
    if "band" in chunks:
        chunks["band"] = 1
    free = [dim for dim in sizes if dim not in study.chunks and dim != "band"]
    while math.prod(chunks.values()) > study.chunk_scenarios:
        splittable = [dim for dim in free if chunks[dim] > 1]
        if not splittable:
            break
        dim = max(splittable, key=lambda d: chunks[d])
        chunks[dim] = math.ceil(chunks[dim] / 2)
    return chunks


def _coords(study: Study) -> dict:
    """Coordinates of the study dimensions: the swept values (paired ones as extra coords)."""
    coords = {}
    if study.bands:
        coords["band"] = ("band", list(study.bands), {"long_name": "spectral band"})
        for name in ("wavelength_min", "wavelength_max"):
            values = [band.get(name, study.sensor.get(name)) for band in study.bands.values()]
            coords[name] = ("band", np.asarray(values, dtype=float),
                            {"units": "m", "long_name": params.SENSOR_SPECS[name].long_name})
    for sweep in study.sweeps:
        if list(sweep.values) == [sweep.dim]:
            coords[sweep.dim] = (sweep.dim, sweep.values[sweep.dim], _attrs(sweep.dim))
            continue
        coords[sweep.dim] = (sweep.dim, np.arange(sweep.size), {"long_name": "case number"})
        for name, values in sweep.values.items():
            coords[name] = (sweep.dim, values, _attrs(name))
    return coords


def _attrs(name: str) -> dict:
    spec = params.SENSOR_SPECS.get(name) or params.SCENARIO_SPECS[name]
    return {"units": spec.units, "long_name": spec.long_name}


def _model_inputs(study: Study, coords: dict, band: str | None):
    """Sensor and scenario datasets for one band over the given sweep coordinates."""
    kwargs = {**study.sensor, **(study.bands[band] if band is not None else {}),
              **study.scenario}
    for sweep in study.sweeps:
        for name in sweep.values:
            values = np.asarray(coords[name] if name in coords else sweep.values[name])
            kwargs[name] = xr.DataArray(values, dims=sweep.dim)
    return (params.sensor(**{k: v for k, v in kwargs.items() if k in SENSOR_PARAMETERS}),
            params.scenario(**{k: v for k, v in kwargs.items() if k in SCENARIO_PARAMETERS}))


def _one_band(study: Study, coords: dict, band: str | None) -> xr.Dataset:
    """Every requested output for one band over the given sweep coordinates."""
    sensor, scenario = _model_inputs(study, coords, band)
    method = make_method(study.method, **study.knobs)
    out = model.niirs(sensor, scenario, method)
    out = out.drop_vars([name for name in out.coords if name not in out.dims])
    if "mtf" in study.outputs:
        frequency = xr.DataArray(study.mtf_frequency, dims="frequency", coords={
            "frequency": ("frequency", study.mtf_frequency,
                          {"units": "cycles/rad", "long_name": "angular spatial frequency"})})
        otf = model.system_otf(sensor, scenario, frequency, method)
        otf = otf.drop_vars([name for name in otf.coords if name not in otf.dims])
        out = out.merge(otf.rename({name: f"mtf_{name}" for name in otf.data_vars}))
    return out


def _outputs(block: xr.Dataset, study: Study) -> xr.Dataset:
    """Every requested output over one chunk of the scenario grid (eager)."""
    coords = {name: block[name].values for name in block.coords}
    bands = list(coords["band"]) if study.bands else [None]
    parts = [_one_band(study, coords, band) for band in bands]
    return xr.concat(parts, dim="band", coords="minimal") if study.bands else parts[0]


def _block(block: xr.Dataset, study: Study, layout: dict, extra: dict) -> xr.Dataset:
    """One chunk of the result: every variable on the dims ``layout`` gives it."""
    out = _outputs(block, study)
    variables = {name: out[name].transpose(*dims).variable for name, dims in layout.items()}
    return xr.Dataset(variables, coords={**block.coords, **extra})


def _inputs(study: Study, chunks: dict) -> xr.Dataset:
    """The chunked scenario grid that map_blocks splits (one placeholder variable)."""
    sizes = study.sizes
    grid = dsa.zeros(tuple(sizes.values()), dtype=np.int8,
                     chunks=tuple(chunks[dim] for dim in sizes))
    return xr.Dataset({"_grid": (tuple(sizes), grid)}, coords=_coords(study))


def _template(study: Study, inputs: xr.Dataset, chunks: dict) -> xr.Dataset:
    """The output's variables, dims and attrs, from one model call on the first scenario."""
    first = inputs.drop_vars("_grid").isel({dim: slice(0, 1) for dim in inputs.dims})
    sample = _outputs(first, study)
    variables = {}
    for name, var in sample.data_vars.items():
        dims = tuple(dim for dim in inputs.dims if dim in var.dims) + tuple(
            dim for dim in var.dims if dim not in inputs.dims)
        shape = tuple(inputs.sizes.get(dim, var.sizes[dim]) for dim in dims)
        blocks = tuple(chunks.get(dim, var.sizes[dim]) for dim in dims)
        variables[name] = xr.Variable(dims, dsa.empty(shape, dtype=var.dtype, chunks=blocks),
                                      var.attrs)
    extra = {name: sample[name].variable for name in sample.coords
             if name not in inputs.coords and name in sample.dims}
    return xr.Dataset(variables, coords={**inputs.coords, **extra})


def run(study: Study) -> xr.Dataset:
    """The study's result as a lazy Dataset (nothing is computed until asked).

    Parameters
    ----------
    study : Study
        From :func:`xbsm.study.load` or :func:`xbsm.study.parse`.

    Returns
    -------
    xr.Dataset
        Every requested output (only those ``[outputs] variables`` names, and
        their flag variables, if it is given) over ``band`` (if the study has
        bands) and the swept dimensions, dask-backed with the study's chunks;
        global attributes record the study text, the method and the xbsm
        version. CF details: each data variable names its flag variable in
        ``ancillary_variables``, the flag variables say in ``comment`` which
        bits apply to which variables; each variable's ``.encoding`` says how
        to write it (no ``_FillValue`` on coordinates; zlib at ``[run]
        compress`` on the data variables), which :func:`xbsm.study.write`
        honours (``xbsm.study._cf.cf_encoding`` gives the same as a
        ``to_netcdf(encoding=...)`` mapping).
    """
    chunks = chunk_sizes(study)
    inputs = _inputs(study, chunks)
    template = _template(study, inputs, chunks)
    if study.variables:  # [outputs] variables: only these are kept, computed chunk by chunk
        template = template[[name for name in study.variables if name in template.data_vars]]
        template = template.drop_vars([name for name in template.coords
                                       if name not in inputs.coords
                                       and not any(name in var.dims
                                                   for var in template.data_vars.values())])
    layout = {name: var.dims for name, var in template.data_vars.items()}
    extra = {name: (coord.dims, coord.values, coord.attrs)
             for name, coord in template.coords.items() if name not in inputs.coords}
    result = xr.map_blocks(_block, inputs, args=(study, layout, extra), template=template)
    result = _cf.cf_attributes(result.assign_attrs(_provenance(study)))
    return _cf.set_encoding(result, study.compress)


def _provenance(study: Study) -> dict:
    method = make_method(study.method, **study.knobs)
    return {
        "title": study.title or "xbsm study",
        "Conventions": "CF-1.8",
        "source": f"xbsm {__version__}",
        "history": f"xbsm {__version__}: xbsm.study.run of the study file in xbsm_study",
        "xbsm_method": method.describe(),
        **{f"xbsm_knob_{field.name}": str(getattr(getattr(method, field.name), "name",
                                                   getattr(method, field.name)))
           for field in dataclasses.fields(method) if field.name != "name"},
        "xbsm_study": study.text,
    }
