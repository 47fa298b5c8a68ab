"""A study as one lazy Dataset: a dask task per chunk of the scenario grid.

The scenario grid is the product of the study's dimensions (``band``, then
every sweep in file order). :func:`run` cuts it into chunks, one eager model
call per chunk, in symbolic dask ``blockwise`` layers: building the result costs
one small model call (which fixes the output's variables and dimensions) and
the same for any number of chunks; nothing else is computed, and a chunk's
tasks exist only once it is asked for. Inside a chunk the model still
computes each quantity on the dimensions it depends on (the atmosphere on
altitude x ground range x visibility only), which is what makes product
sweeps cheap. The same Dataset computes on the local threads or on any
``dask.distributed`` cluster.
"""

from __future__ import annotations

import dataclasses
import functools
import math
import string

import dask.array as dsa
import numpy as np
import xarray as xr

from .. import model, params
from .._version import __version__
from ..atmosphere import database_path, use_database
from ..methods import method as make_method
from . import _cf
from .attributes import parameter_attributes
from .spec import SCENARIO_PARAMETERS, SENSOR_PARAMETERS, Study


def chunk_sizes(study: Study, layout: dict | None = None) -> dict[str, int]:
    """Chunk length along every study dimension.

    ``[run] chunks`` first; ``band`` one at a time (each band has its own
    spectral grid); then, until a chunk holds at most ``chunk_scenarios``
    scenarios, the other dimensions are cut one after the other, each only as
    much as needed and into blocks of (nearly) equal length: first those that
    every output varies along, longest first, and last those that fewest
    outputs vary along. A chunk computes the outputs that do not vary along a
    cut dimension again for each of its blocks: cutting ``drift_rate_x`` before
    ``ground_range`` in ``recipes/studies/million.toml`` computed SNR, the
    atmosphere and turbulence four times (11.0 instead of 8.6 CPU us per
    scenario).

    ``layout`` (each output variable's dims) comes from one model call on the
    first scenario when not given.
    """
    sizes = study.sizes
    chunks = {dim: min(size, study.chunks.get(dim, size)) for dim, size in sizes.items()}
    if "band" in chunks:
        chunks["band"] = 1
    if layout is None:
        layout = _template(study, _coords(study))[1]
    for dim in sorted((dim for dim in sizes if dim not in study.chunks and dim != "band"),
                      key=lambda dim: (_repeated_volume(layout, sizes, dim), -sizes[dim])):
        if math.prod(chunks.values()) <= study.chunk_scenarios:
            break
        others = math.prod(chunks.values()) // chunks[dim]
        length = max(1, study.chunk_scenarios // others)
        chunks[dim] = math.ceil(sizes[dim] / math.ceil(sizes[dim] / length))
    return chunks


def _repeated_volume(layout: dict, sizes: dict, dim: str) -> int:
    """How many output values do not vary along ``dim`` (computed again per block)."""
    return sum(math.prod(sizes[d] for d in dims if d in sizes)
               for dims in layout.values() if dim not in dims)


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
    spec = params.parameter_spec(name)
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


def _outputs(coords: dict, study: Study) -> xr.Dataset:
    """Every requested output over one chunk of the scenario grid (eager)."""
    bands = list(coords["band"]) if study.bands else [None]
    parts = [_one_band(study, coords, band) for band in bands]
    return xr.concat(parts, dim="band", coords="minimal") if study.bands else parts[0]


def _chunk_coords(coords: dict, positions: dict) -> dict:
    """The coordinates of one chunk: every coordinate at its dimension's positions."""
    return {name: np.asarray(values)[positions[dim]]
            for name, (dim, values, _) in coords.items()}


def _chunk(study: Study, coords: dict, layout: dict, database, *positions) -> np.ndarray:
    """One chunk's outputs, every variable on the dims ``layout`` gives it, in a 1x..x1 cell.

    ``positions`` are the chunk's index positions along each study dimension, in order.
    ``database``: the atmosphere file in use where the graph was built. A worker thread
    sees it already where the scheduler copies the context (dask 2024 on); older dask
    (the floor, 2023.6) starts its threads without it, so the chunk sets it again.
    """
    chunk_coords = _chunk_coords(coords, dict(zip(study.sizes, positions, strict=True)))
    if database_path() == database:
        out = _outputs(chunk_coords, study)
    else:
        with use_database(database):
            out = _outputs(chunk_coords, study)
    cell = np.empty((1,) * len(positions), dtype=object)
    cell[(0,) * len(positions)] = {name: out[name].transpose(*dims).values
                                   for name, dims in layout.items()}
    return cell


def _pick(cell: np.ndarray, name: str) -> np.ndarray:
    """One variable's block out of a chunk's cell."""
    return cell.reshape(-1)[0][name]


def _template(study: Study, coords: dict) -> xr.Dataset:
    """One model call on the first scenario: the output's variables, dims, dtypes and attrs."""
    sample = _outputs(_chunk_coords(coords, dict.fromkeys(study.sizes, slice(0, 1))), study)
    layout = {name: tuple(dim for dim in study.sizes if dim in var.dims)
              + tuple(dim for dim in var.dims if dim not in study.sizes)
              for name, var in sample.data_vars.items()}
    return sample, layout


def _variable(cells, name: str, dims: tuple, sample: xr.DataArray, study: Study,
              chunks: dict):
    """One output variable as a dask array picked out of the chunks' cells, lazily."""
    grid = tuple(study.sizes)
    letters = dict(zip(grid, string.ascii_lowercase, strict=False))
    own = [dim for dim in dims if dim not in letters]
    own_letters = string.ascii_uppercase[:len(own)]
    if any(dim not in dims for dim in grid):  # blocks owned by the chunks at index 0 there
        cells = cells.blocks[tuple(slice(None) if dim in dims else slice(0, 1) for dim in grid)]
    kept = "".join(letters[dim] for dim in grid if dim in dims)
    return dsa.blockwise(
        _pick, kept + own_letters, cells, "".join(letters.values()), name, None,
        new_axes={letter: sample.sizes[dim] for letter, dim in zip(own_letters, own,
                                                                   strict=True)},
        adjust_chunks={letters[dim]: _chunks_of(study.sizes[dim], chunks[dim])
                       for dim in grid if dim in dims},
        dtype=sample.dtype, meta=np.empty((0,) * len(dims), dtype=sample.dtype),
        concatenate=True, align_arrays=False)


def _chunks_of(size: int, length: int) -> tuple:
    """Block lengths of a dimension of ``size`` cut every ``length``."""
    return tuple(min(length, size - start) for start in range(0, size, length))


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

    Notes
    -----
    The graph is symbolic (dask ``blockwise`` layers): building it costs the same
    for 10 chunks or 10^6, and a chunk's tasks are made only when it is computed.
    Each chunk is one eager model call; a variable that does not depend on a
    study dimension takes its blocks from the chunks at index 0 along it.
    """
    coords = _coords(study)
    sample, layout = _template(study, coords)
    chunks = chunk_sizes(study, layout)
    if study.variables:  # [outputs] variables: only these are kept, computed chunk by chunk
        layout = {name: dims for name, dims in layout.items() if name in study.variables}
    positions = [dsa.arange(size, chunks=chunks[dim]) for dim, size in study.sizes.items()]
    letters = string.ascii_lowercase[:len(positions)]
    cells = dsa.blockwise(
        functools.partial(_chunk, study, coords, layout, database_path()), letters,
        *[arg for pos, letter in zip(positions, letters, strict=True) for arg in (pos, letter)],
        adjust_chunks={letter: 1 for letter in letters}, dtype=object,
        meta=np.empty((0,) * len(letters), dtype=object), align_arrays=False)
    variables = {name: xr.Variable(dims, _variable(cells, name, dims, sample[name], study,
                                                   chunks), sample[name].attrs)
                 for name, dims in layout.items()}
    extra = {name: sample[name].variable for name in sample.coords if name not in study.sizes
             and any(name in dims for dims in layout.values())}
    result = xr.Dataset(variables, coords={**coords, **extra})
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
        **parameter_attributes(study),  # what the figures read (xbsm.study.attributes)
    }
