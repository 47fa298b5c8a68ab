"""One way to attach CF metadata to a result (private).

Every public output carries CF ``units`` and ``long_name`` (ARCHITECTURE.md,
Conventions). :func:`named` sets exactly those (plus any extras such as
``references``) and drops whatever attributes xarray carried over from the
operands: arithmetic keeps the attributes of its inputs, so without this a
photoelectron rate computed as ``wavelength / (h c) * ...`` inherits the
wavelength's ``standard_name: radiation_wavelength``. Coordinates keep their
own attributes. :func:`described` does the same with the first line of a
function's docstring as the ``long_name`` (the rule in :mod:`xbsm.otf`).
"""

from __future__ import annotations

from types import MappingProxyType
from typing import NamedTuple

import xarray as xr
from xarray.indexes import PandasIndex

from ._kernels import dataset


def named(out, units: str, long_name: str, **extra):
    """``out`` with exactly the CF ``units``, ``long_name`` and ``extra`` attributes.

    Parameters
    ----------
    out : xr.DataArray or float
        A result. Anything that is not a DataArray (a plain float from plain
        float inputs) is returned unchanged.
    units : str
        UDUNITS string, e.g. ``"m"``, ``"count"``, ``"1"``.
    long_name : str
        What the quantity is.
    **extra : str
        Further attributes (e.g. ``references``).

    Returns
    -------
    xr.DataArray or float
        A shallow copy; the input's attributes are not modified.
    """
    if not isinstance(out, xr.DataArray):
        return out
    out = out.copy(deep=False)
    out.attrs = {"units": units, "long_name": long_name, **extra}
    return out


def long_name_of(func) -> str:
    """The first line of ``func``'s docstring, without its final full stop."""
    return func.__doc__.strip().splitlines()[0].rstrip(".")


def described(out, func, units: str = "1", **extra):
    """:func:`named` with the first docstring line of ``func`` as the ``long_name``."""
    return named(out, units, long_name_of(func), **extra)


def result(variables: dict, method, **attrs) -> xr.Dataset:
    """A result Dataset without scalar coordinates, saying which method made it.

    The ``method`` attribute names the preset and every knob that differs from it.

    An output that repeats an input swept on a dimension of its own name (``read_noise``
    swept on ``read_noise``) is left to that coordinate, which holds the same values.
    """
    dims = {d for v in variables.values() for d in v.dims}
    attrs = {"method": method.describe(), **attrs}
    ds = dataset({k: v for k, v in variables.items() if k not in dims})
    ds.attrs = attrs
    return ds.drop_vars([c for c in ds.coords if ds[c].ndim == 0 and c not in ds.dims])


class Output(NamedTuple):
    """One named array a stage's array orchestrator returns, declared beside it.

    ``dims`` are the output's own dims (those of a single eager scenario, e.g.
    ``("wavelength",)``); ``carries`` names the inputs whose sweep dims the output
    keeps (``"sensor"``, ``"scenario"``): an output that carries only the sensor keeps
    only sensor dims in a sweep. ``inputs`` names the orchestrator's arguments whose
    dims the output keeps, in the order its dims come (None: all of them); the labelled
    door (:func:`xbsm._kernels.apply_orchestrator`) labels it so; ``dtype`` is its
    dtype (flags: int32).
    """

    name: str
    units: str
    long_name: str
    dims: tuple = ()
    carries: tuple = ("sensor", "scenario")
    references: str | None = None
    inputs: tuple | None = None
    dtype: type = float

    def attrs(self) -> dict:
        """The CF attributes of the output."""
        out = {"units": self.units, "long_name": self.long_name}
        if self.references is not None:
            out["references"] = self.references
        return out


def outputs(*declared: Output) -> MappingProxyType:
    """A stage's declared outputs by name, in the order it returns them."""
    return MappingProxyType({o.name: o for o in declared})


def declared(out, output: Output):
    """``out`` labelled with the CF attributes of its declaration."""
    return named(out, **output.attrs())


def dataset_of(variables: dict, coords: dict, attrs: dict) -> xr.Dataset:
    """A Dataset of consistent ``xr.Variable`` objects, each dimension coordinate indexed.

    ``variables`` (data) and ``coords`` (one 1-D coordinate per dimension, named after
    it) must already agree on their dims' lengths: nothing is aligned or merged. The
    public constructor's merge costs about 25 us per variable, most of the labelling of
    one scenario's result, so this uses xarray's own constructor for consistent
    variables when it has one (``tests/test_chain.py`` checks such results against the
    labelled chain's).
    """
    construct = getattr(xr.Dataset, "_construct_direct", None)
    if construct is None:
        return xr.Dataset(variables, coords=coords, attrs=attrs)
    every, indexes, dims = dict(variables), {}, {}
    for name, coord in coords.items():
        indexes[name] = _index_of(name, coord)
        every.update(indexes[name].create_variables({name: coord}))
    for variable in every.values():
        if variable.ndim:  # most of one scenario's outputs are scalars
            dims.update(zip(variable.dims, variable.shape, strict=True))
    return construct(every, set(coords), dims, attrs, indexes)


def _index_of(name: str, coord: xr.Variable) -> PandasIndex:
    """The index of a 1-D dimension coordinate, the same object for the same values.

    Building a pandas index costs about 65 us, 4 % of a single ``snr`` call, and one
    scenario's results repeat their coordinates (the band's wavelengths, the
    GIQE versions). An index is immutable (xarray shares it between a Dataset and its
    shallow copies), so results may share it; the coordinate variables themselves, whose
    attributes a user may edit, stay each result's own.
    """
    key = (name, coord.dims, coord.dtype.str, coord.values.tobytes())
    index = _INDEXES.get(key)
    if index is None:
        if len(_INDEXES) >= _MAX_INDEXES:
            _INDEXES.clear()
        index = _INDEXES[key] = PandasIndex.from_variables({name: coord}, options={})
    return index


_INDEXES: dict[tuple, PandasIndex] = {}
""":func:`_index_of`'s indexes by coordinate name, dims, dtype and values."""
_MAX_INDEXES = 256
"""Most indexes :data:`_INDEXES` holds (a sweep of bands makes a new one each call)."""
