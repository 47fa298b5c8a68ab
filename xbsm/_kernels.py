"""The xarray boundary of a numpy kernel (private): one ``apply_ufunc`` per stage result.

A stage's arithmetic runs once in numpy over already-broadcast arrays; xarray
aligns, labels and carries dask only here (STYLE.md, "A kernel under a thin
xarray layer"). One xarray binary operation costs an alignment and index copies;
hundreds of them made one scenario slower than pyBSM.

:func:`apply_kernel` is what every stage of the model chain calls (image
simulation, measurement and studies, whose kernels run once per whole image or
chunk, call ``xr.apply_ufunc`` directly). It keeps what the xarray
arithmetic it replaces did: the arguments join as arithmetic joins them (inner,
without copies when their indexes already agree), the result's dims are the
union of the arguments' dims in order of first appearance, coordinates keep
their attributes, floating-point exceptions give IEEE results without warnings,
and dask arguments give lazy results with the chunks they came with (a
contraction inside a kernel keeps them; ``xr.dot`` hands dask's ``einsum``,
which rechunks its inputs whenever the output chunk would outgrow the largest
input chunk).
"""

from __future__ import annotations

import numpy as np
import xarray as xr


def join_for(objects, otherwise: str = "inner") -> str:
    """How to align ``objects``: as arithmetic would (``otherwise``), without its copies.

    When the objects' indexes already agree, an inner or outer join changes nothing
    but copies every object; "exact" then gives the same result without the copies.
    """
    seen = {}
    for a in objects:
        for dim, index in getattr(a, "xindexes", {}).items():
            first = seen.setdefault(dim, index)
            if first is not index and not first.equals(index):
                return otherwise
    return "exact"


def dataset(variables: dict) -> xr.Dataset:
    """``xr.Dataset(variables)``, without aligning DataArrays that already share coordinates.

    The variables of one stage come from the same inputs, so their coordinates agree;
    the Dataset is then built from their Variables and the coordinates (with their
    indexes and attributes) they carry. Any disagreement, which xarray would align or
    merge, takes xarray's own path.
    """
    arrays = [v for v in variables.values() if isinstance(v, xr.DataArray)]
    # equal coordinate variables (index coordinates included) mean agreeing indexes
    coords = _merged_coords(arrays, set()) if len(arrays) == len(variables) else None
    if coords is None or not coords[0].keys().isdisjoint(variables):
        return xr.Dataset(variables)
    return xr.Dataset({name: v.variable for name, v in variables.items()},
                      coords=xr.Coordinates(*coords))


def apply_kernel(kernel, /, *args, core=None, outputs=((),), sizes=None, dtype=float, **knobs):
    """``kernel(*arrays, **knobs)`` once over the aligned, broadcast data of ``args``.

    Parameters
    ----------
    kernel : callable
        Plain numpy function; no checks, no xarray.
    *args : float or xr.DataArray or xr.Variable
        Its arguments, in the order their operands appear in its equation (that
        order gives the result's dimension order, as in arithmetic).
    core : sequence of sequence of str, optional
        Core dimensions of each argument, moved to its last axes (default none).
    outputs : sequence of sequence of str
        Core dimensions of each output; one entry per output.
    sizes : mapping of str to int, optional
        Lengths of output core dimensions that no argument has.
    dtype : dtype or sequence of dtype
        Of each output (one for all).
    **knobs
        Plain keyword arguments of ``kernel``.

    Returns
    -------
    xr.DataArray or tuple of xr.DataArray
        (Plain arrays if every argument is plain.) Attributes are those of the first
        argument: callers name their results.
    """
    n = len(outputs)
    dtypes = list(dtype) if isinstance(dtype, (list, tuple)) else [dtype] * n

    def quiet(*arrays):
        with np.errstate(all="ignore"):  # IEEE results, as xarray arithmetic gives them
            return kernel(*arrays, **knobs)

    labelled = [a for a in args if isinstance(a, (xr.DataArray, xr.Variable))]
    if not any(_is_lazy(a) for a in labelled):
        out = _apply_eager(quiet, args, labelled, core or [[]] * len(args), outputs)
        if out is not None:
            return out
    return xr.apply_ufunc(
        quiet, *args, input_core_dims=core, output_core_dims=[list(o) for o in outputs],
        join=join_for(args), dask="parallelized", output_dtypes=dtypes,
        keep_attrs="override",
        dask_gufunc_kwargs={"allow_rechunk": True, "output_sizes": dict(sizes or {})})


def _is_lazy(a) -> bool:
    return getattr(a.data, "chunks", None) is not None


def _apply_eager(func, args, labelled, core, outputs):
    """:func:`xr.apply_ufunc`'s result for eager arguments whose indexes agree, built directly.

    The same dims (the arguments' non-core dims in order of first appearance, then each
    output's core dims), data layout, coordinates (those without a dropped core dim, with
    their attributes and indexes) and attributes (the first labelled argument's), without
    apply_ufunc's per-call machinery. None where xarray's own path is needed: a
    coordinate that differs between arguments, a dimension of two lengths, indexes that
    differ (an alignment).
    """
    if not labelled:
        return func(*args)
    if join_for(args) != "exact":
        return None
    core_dims = {d for c in core for d in c} | {d for o in outputs for d in o}
    sizes = {}
    for a in labelled:
        for dim, size in zip(a.dims, a.shape, strict=True):
            if sizes.setdefault(dim, size) != size:
                return None
    arrays = [a for a in labelled if isinstance(a, xr.DataArray)]
    coords = _merged_coords(arrays, {d for c in core for d in c} - {d for o in outputs for d in o})
    if coords is None:  # decided before the kernel runs, so that it never runs twice
        return None
    broadcast = tuple(d for d in sizes if d not in core_dims)
    data = [_layout(a, broadcast, tuple(c)) if isinstance(a, (xr.DataArray, xr.Variable))
            else a for a, c in zip(args, core, strict=True)]
    result = func(*data)
    attrs = dict((arrays or labelled)[0].attrs)
    results = result if len(outputs) > 1 else (result,)
    made = []
    for values, out_core in zip(results, outputs, strict=True):
        variable = xr.Variable(broadcast + tuple(out_core), values, attrs)
        if arrays:
            kept = {name: coords[0][name] for name in coords[0]
                    if set(coords[0][name].dims) <= set(variable.dims)}
            variable = xr.DataArray(variable, coords=xr.Coordinates(
                kept, {n: i for n, i in coords[1].items() if n in kept}))
        made.append(variable)
    return tuple(made) if len(outputs) > 1 else made[0]


def _layout(a, broadcast, core):
    """``a``'s data with its broadcast dims in ``broadcast`` order and its core dims last.

    Missing broadcast dims become length-1 axes, except leading ones (numpy broadcasts).
    """
    dims, data = a.dims, a.data
    present = tuple(d for d in broadcast if d in dims)
    order = present + core
    if order != dims:
        data = np.transpose(data, [dims.index(d) for d in order])
    key, started = [], False
    for d in broadcast:
        if d in dims:
            key.append(slice(None))
            started = True
        elif started:
            key.append(np.newaxis)
    if len(key) != len(present):
        data = data[(*key, *(slice(None) for _ in core))]
    return data


def _merged_coords(arrays, dropped):
    """Coordinate variables and indexes of ``arrays`` without those on ``dropped`` dims.

    None when a name holds different coordinates in two arrays (xarray's merge decides).
    """
    variables, indexes = {}, {}
    for a in arrays:
        own = a.xindexes
        for name, coord in a.coords.variables.items():
            if dropped.intersection(coord.dims):
                continue
            known = variables.setdefault(name, coord)
            if known is not coord:
                if not known.equals(coord):
                    return None
                if not known.attrs:  # the coordinate as described where it is
                    variables[name] = coord
            if name in own:
                indexes.setdefault(name, own[name])
    return variables, indexes
