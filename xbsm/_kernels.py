"""The xarray boundary of a numpy kernel (private): one ``apply_ufunc`` per stage result.

A stage's arithmetic runs once in numpy over already-broadcast arrays; xarray
aligns, labels and carries dask only here (STYLE.md, "A kernel under a thin
xarray layer"). One xarray binary operation costs an alignment and index copies;
hundreds of them made one scenario slower than pyBSM.

:func:`apply_kernel` is what every stage of the model chain calls (image
simulation, measurement and studies, whose kernels run once per whole image or
chunk, call ``xr.apply_ufunc`` directly). It is ``xr.apply_ufunc``
with what the xarray arithmetic it replaces did: the arguments join as
arithmetic joins them (inner, without copies when their indexes already agree),
the result's dims are the union of the arguments' dims in order of first
appearance, coordinates keep their attributes, floating-point exceptions give
IEEE results without warnings, and dask arguments give lazy results with the
chunks they came with (a contraction inside a kernel keeps them; ``xr.dot``
hands dask's ``einsum``, which rechunks its inputs whenever the output chunk
would outgrow the largest input chunk). Eager arguments take the same path: a
copy of ``apply_ufunc`` for them was measured at no gain (issue 22).
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
    dtypes = list(dtype) if isinstance(dtype, (list, tuple)) else [dtype] * len(outputs)

    def quiet(*arrays):
        with np.errstate(all="ignore"):  # IEEE results, as xarray arithmetic gives them
            return kernel(*arrays, **knobs)

    return xr.apply_ufunc(
        quiet, *args, input_core_dims=core, output_core_dims=[list(o) for o in outputs],
        join=join_for(args), dask="parallelized", output_dtypes=dtypes,
        keep_attrs="override",
        dask_gufunc_kwargs={"allow_rechunk": True, "output_sizes": dict(sizes or {})})


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
