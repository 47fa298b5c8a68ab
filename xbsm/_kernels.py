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


def _broadcast(array, loop: tuple, dims: tuple, lengths: dict):
    """``array`` as a view of shape ``loop`` + its core ``dims``' ``lengths`` (else its own)."""
    shape = (1,) * len(dims) + np.shape(array)
    own = shape[len(shape) - len(dims):]
    return np.broadcast_to(array, loop + tuple(lengths.get(d, n) for d, n in zip(
        dims, own, strict=True)))


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


def apply_orchestrator(orchestrator, declared, /, *args, core=None, sizes=None,
                       dask="parallelized", **knobs) -> dict:
    """A stage's array orchestrator run once over ``args``, its outputs labelled as declared.

    The labelled door of a stage: ``orchestrator(*arrays, **knobs)`` (plain arrays in,
    a dict of named arrays out) through one ``xr.apply_ufunc``, which aligns, broadcasts
    and carries dask as :func:`apply_kernel` does. Inside, numpy broadcasting computes
    each output on the axes its operands have; the output is handed to xarray as a
    broadcast view and then cut back to the dims of the arguments its declaration
    (:class:`xbsm._metadata.Output`) says it keeps, so a sensor quantity keeps only
    sensor dims in a sweep and is computed once per sensor. When some arguments are dask
    arrays, the outputs that declare only eager ones are computed eagerly apart (the lazy
    arguments, on which they do not depend, replaced by NaN).

    A core dimension declared for an argument that does not have it (a sensor quantity
    that does not vary with ``wavelength``, in a stage that integrates over it) reaches
    the orchestrator as a length-1 axis in its place, so that numpy broadcasting lines it
    up with the arguments that do. An output declares its own core dims (``dims``): a
    spectral output keeps ``wavelength``, a band total does not. An output on a core dim
    of the arguments that none of its declared inputs has is constant along it and is
    labelled without it (a quantum efficiency given as one number stays one number).

    Parameters
    ----------
    orchestrator : callable
        The stage's array orchestrator; its leading positional parameters name ``args``.
    declared : mapping of str to Output
        Its outputs, in the order it declares them (``dims``: core dims; ``inputs``:
        the arguments whose dims it keeps).
    *args : float or xr.DataArray or None
        Its array arguments (None passes through: an input the stage does without).
    core : sequence of sequence of str, optional
        Core dimensions of each argument, in the order the orchestrator sees them as its
        last axes (default none); one the argument lacks is a length-1 axis.
    sizes : mapping of str to int, optional
        Lengths of output core dimensions that no argument has.
    dask : {"parallelized", "allowed"}
        "allowed" when the orchestrator runs on whole dask arrays (it reduces over or
        reshapes a core dimension that chunks would split).
    **knobs
        Plain keyword arguments of ``orchestrator``.

    Returns
    -------
    dict of str to xr.DataArray
        Each output with exactly its declared CF attributes.
    """
    names = orchestrator.__code__.co_varnames[:len(args)]
    args = [a if a is None or isinstance(a, xr.DataArray) else xr.DataArray(a) for a in args]
    core = [list(c) for c in core] if core is not None else [[] for _ in args]
    lazy = {name for name, a in zip(names, args, strict=True)
            if a is not None and a.chunks is not None}
    groups = [list(declared.values()), []]
    if lazy:  # outputs of eager arguments only stay eager, as arithmetic would leave them
        for o in list(groups[0]):
            if o.inputs is not None and lazy.isdisjoint(o.inputs):
                groups[0].remove(o)
                groups[1].append(o)
    labelled = {}
    for group, placeholders in zip(groups, (set(), lazy), strict=True):
        if group:
            # the group's outputs do not depend on the arguments it leaves out
            given = [xr.DataArray(np.nan) if name in placeholders else a
                     for name, a in zip(names, args, strict=True)]
            results = _apply_outputs(orchestrator, group, given, core, sizes, dask, knobs)
            for o, out in zip(group, results, strict=True):
                labelled[o.name] = _kept(out, o, args, names, core)
    return {name: labelled[name] for name in declared}


def _apply_outputs(orchestrator, outputs, args, core, sizes, dask, knobs):
    """The ``outputs`` of ``orchestrator`` over ``args`` (one ``xr.apply_ufunc``), on every dim."""
    given = [i for i, a in enumerate(args) if a is not None]  # None stays out of dask's way
    # the declared core dims each argument has (the others become length-1 axes)
    present = {i: [d for d in core[i] if d in args[i].dims] for i in given}
    count = len(args)

    def run(*arrays):
        every, loops, lengths = [None] * count, [], {}
        for i, array in zip(given, arrays, strict=True):
            own = present[i]
            loop = np.shape(array)[:np.ndim(array) - len(own)]
            loops.append(loop)
            lengths.update(zip(own, np.shape(array)[len(loop):], strict=True))
            if len(own) < len(core[i]):  # a declared core dim it lacks: a length-1 axis
                array = np.reshape(array, loop + tuple(
                    lengths[d] if d in own else 1 for d in core[i]))
            every[i] = array
        with np.errstate(all="ignore"):  # IEEE results, as xarray arithmetic gives them
            out = orchestrator(*every, **knobs)
        loop = np.broadcast_shapes(*loops)
        arrays = tuple(_broadcast(out[o.name], loop, o.dims, lengths) for o in outputs)
        return arrays if len(arrays) > 1 else arrays[0]

    arrays = [args[i] for i in given]
    results = xr.apply_ufunc(
        run, *arrays, input_core_dims=[present[i] for i in given],
        output_core_dims=[list(o.dims) for o in outputs], join=join_for(arrays), dask=dask,
        output_dtypes=[o.dtype for o in outputs], keep_attrs="override",
        dask_gufunc_kwargs={"allow_rechunk": True, "output_sizes": dict(sizes or {})})
    return results if len(outputs) > 1 else (results,)


def _kept(out, output, args, names, core):
    """``out`` on the dims of the arguments ``output`` declares, with its CF attributes.

    Its core dims are kept, but for an argument's core dim that none of those arguments
    has (the output is constant along it).
    """
    if output.inputs is not None:
        keep = dict.fromkeys(d for name in output.inputs
                             for d in getattr(args[names.index(name)], "dims", ()))
        cores = {d for c in core for d in c}
        keep.update(dict.fromkeys(d for d in output.dims if d in keep or d not in cores))
        dropped = [d for d in out.dims if d not in keep]
        if dropped:
            out = out.isel(dict.fromkeys(dropped, 0), drop=True)
        order = tuple(d for d in keep if d in out.dims)
        if out.dims != order:
            out = out.transpose(*order)
    out.attrs = output.attrs()
    return out
