"""Spectral weighting of wavelength-dependent OTFs (paper Eq. 3).

The OTF mechanisms declare their checked arguments with :func:`xbsm.params.contract`
(the shared rules are in ``xbsm/otf/_contracts.py``). The CF attributes of a
result come from :func:`xbsm._metadata.described` (the first docstring line is the
``long_name``).
"""

from __future__ import annotations

import math

import numpy as np
import xarray as xr

from .._kernels import apply_kernel
from .._metadata import described
from ._contracts import Weights

__all__ = ["spectral_average"]


def is_lazy(value) -> bool:
    """Tell whether ``value`` is dask-backed (checking it would compute it)."""
    data = getattr(value, "data", value)
    return type(data).__module__.startswith("dask")


def _spectral(func, *args, spectral: int = 2, dtype=float, blocked: bool = False, mono=None,
              **knobs):
    """``apply_kernel`` for a kernel ``func`` whose last ``spectral`` arguments are spectral.

    Those arguments reach the kernel with ``wavelength`` as their last axis, which
    the kernel reduces; ``wavelength`` is one dask chunk inside the kernel. With
    ``blocked``, the kernel runs in cache-sized slices (:func:`_in_blocks`), for
    kernels that do not block their own work; ``mono`` (with ``blocked``) is the
    kernel's monochromatic part, for sweeps that repeat its inputs (:func:`_in_blocks`).
    """
    core = [[]] * (len(args) - spectral) + [["wavelength"]] * spectral
    if not blocked:
        return apply_kernel(func, *args, core=core, dtype=dtype, **knobs)
    return apply_kernel(_in_blocks, *args, core=core, dtype=dtype, kernel=func,
                        spectral=spectral, mono=mono, **knobs)


_BLOCK_VALUES = 2**15
"""Monochromatic values a polychromatic kernel holds at once in :func:`_in_blocks` (256 KiB
of float64 per temporary: a sweep of 10^4 optical states x 80 nodes x 31 wavelengths is
25 million values, and a kernel's dozen temporaries of that size run at the speed of
memory, not of the arithmetic)."""


def _in_blocks(*args, kernel, spectral: int, mono=None, **knobs):
    """``kernel(*args, **knobs)`` over slices of the broadcast shape, in cache-sized blocks.

    The last ``spectral`` arguments carry ``wavelength`` on their last axis, which the
    kernel reduces; the very last is the weights, which enter only the sum. The others
    broadcast (numpy's rules: missing leading axes). The monochromatic OTFs have the
    broadcast shape of every argument but the weights: when that is small (a sensor
    quantity summed with per-scenario weights), the kernel runs once, as it is; else
    in slices along its longest axis, each holding about :data:`_BLOCK_VALUES` values.
    Every output value is the kernel's value on its own inputs (the kernels are
    elementwise outside the spectral sum).

    ``mono``, if given, is the kernel's monochromatic part: ``mono(*args[:-1], **knobs)``
    has the wavelength last and ``kernel`` is ``np.einsum("...k,...k->...", mono(...),
    weights)`` to the bit. Where the arguments but the weights repeat along the axes
    after the first (a focal-length or pixel-pitch sweep: each optical state has its own
    frequency nodes, but a few columns of them serve thousands of states), ``mono`` is
    evaluated once per distinct column (:func:`_distinct_columns`) and the blocks take
    the weighted sums of its values gathered, the same contraction on the same numbers.
    """
    arrays = [np.asarray(a) for a in args]
    plain, spec = arrays[:len(arrays) - spectral], arrays[len(arrays) - spectral:]
    shape = np.broadcast_shapes(*(a.shape for a in plain), *(a.shape[:-1] for a in spec))
    work = np.broadcast_shapes(*(a.shape for a in plain), *(a.shape[:-1] for a in spec[:-1]))
    work = (1,) * (len(shape) - len(work)) + work
    per_value = max(a.shape[-1] for a in spec)
    if not shape or math.prod(work) * per_value <= 2 * _BLOCK_VALUES:
        return kernel(*args, **knobs)
    # the wavelength axis alone on the spectral arguments but the weights
    if mono is not None and all(math.prod(a.shape[:-1]) == 1 for a in spec[:-1]):
        distinct = _distinct_columns(plain)
        if distinct is not None:
            columns, rows, index = distinct
            values = mono(*columns, *(a.reshape(-1) for a in spec[:-1]), **knobs)
            return _in_blocks(rows, index, spec[-1], kernel=_gathered_sum, spectral=1,
                              values=values)
    axis = int(np.argmax(work))
    rest = math.prod(work) // work[axis]
    step = max(1, _BLOCK_VALUES // (rest * per_value))
    out = None
    for lo in range(0, shape[axis], step):
        hi = min(lo + step, shape[axis])
        part = kernel(*(_slab(a, len(shape), axis, lo, hi, 0) for a in plain),
                      *(_slab(a, len(shape), axis, lo, hi, 1) for a in spec), **knobs)
        if out is None:
            out = np.empty(shape, dtype=np.result_type(part))
        out[(slice(None),) * axis + (slice(lo, hi),)] = part
    return out


def _distinct_columns(arrays):
    """The distinct columns of ``arrays`` broadcast together, if they repeat; else None.

    A column is one position along the axes after the first, taken through every array
    (the first axis is the kernel's frequency nodes). Where at most half of the columns
    are distinct, returns ``(columns, rows, index)``: each array that varies along those
    axes at the distinct columns (node, column), each other one with its node axis alone
    (or none); and two index arrays broadcasting to the full shape that pick each
    position's (node, distinct column).
    """
    shape = np.broadcast_shapes(*(a.shape for a in arrays))
    n, m = (shape[0], math.prod(shape[1:])) if len(shape) > 1 else (0, 0)
    if n == 0 or m < 2:
        return None

    def varies(a):  # an extent along the axes after the first
        return math.prod(a.shape[1:] if a.ndim == len(shape) else a.shape) > 1

    full = {i: np.broadcast_to(a, shape).reshape(n, m) for i, a in enumerate(arrays)
            if varies(a)}
    if not full:
        return None
    key = np.concatenate(list(full.values())) if len(full) > 1 else next(iter(full.values()))
    # each column's bits; first where it differs from the one before (a sweep in order
    # repeats a column in runs; np.unique of every column cost 10 us a state), then
    # np.unique of those
    if key.dtype.itemsize == 8:
        key = key.view(np.int64)
    changed = np.empty(m, dtype=bool)
    changed[0] = True
    changed[1:] = (key[:, 1:] != key[:, :-1]).any(axis=0)
    starts = np.flatnonzero(changed)
    # a bound first: no fewer distinct columns than distinct values in one row (an
    # aperture-diameter sweep moves every column: np.unique of them all cost 20 us a state)
    if 2 * starts.size > m and any(2 * np.unique(last[starts]).size > m
                                   for last in key[n - 1::n]):
        return None
    _, first, inverse = np.unique(np.ascontiguousarray(key[:, starts].T), axis=0,
                                  return_index=True, return_inverse=True)
    if 2 * first.size > m:
        return None
    first, inverse = starts[first], inverse.reshape(-1)[np.cumsum(changed) - 1]
    columns = [full[i][:, first] if i in full
               else a.reshape(a.shape[0], 1) if a.ndim == len(shape) else a.reshape(())
               for i, a in enumerate(arrays)]
    rows = np.arange(n).reshape((n,) + (1,) * (len(shape) - 1))
    return columns, rows, inverse.reshape((1,) + shape[1:])


def _gathered_sum(rows, index, weights, *, values):
    """The weighted sum over the last axis of ``values`` at (``rows``, ``index``)."""
    return np.einsum("...k,...k->...", values[rows, index], weights)


def _slab(a, ndim, axis, lo, hi, core):
    """Entries ``lo:hi`` of broadcast axis ``axis`` of ``a`` (``core`` trailing axes)."""
    own = axis - (ndim - (a.ndim - core))  # numpy broadcasting aligns the axes on the right
    if own < 0 or a.shape[own] == 1:
        return a
    index = [slice(None)] * a.ndim
    index[own] = slice(lo, hi)
    return a[tuple(index)]


def normalised_weights(weights):
    """``weights`` over their sum along the last axis, a NaN counting as zero (numpy).

    ``np.nansum``'s own steps (a copy with every NaN set to 0, then its sum), without its
    wrappers, which cost a single scenario 7 us a call.
    """
    present = np.array(weights)
    np.copyto(present, 0, where=np.isnan(present))
    return weights / present.sum(axis=-1, keepdims=True)


def weighted_sum_kernel(otf, weights):
    """Sum over the last (wavelength) axis of ``otf`` times the normalised ``weights``."""
    return np.einsum("...k,...k->...", otf, normalised_weights(weights))


def spectral_average(otf, weights, dim: str = "wavelength"):
    r"""Spectrally weighted OTF, the weights normalised to sum to one.

    Parameters
    ----------
    otf : xr.DataArray
        Wavelength-dependent OTF (real or complex), with dimension ``dim``. [1]
    weights : xr.DataArray
        Non-negative spectral weights over ``dim`` (e.g. the spectral
        photoelectron rate); they may carry further (sweep) dimensions and are
        normalised to sum to one along ``dim``. [any]
    dim : str
        The spectral dimension to reduce. Default ``"wavelength"``.

    Returns
    -------
    xr.DataArray
        OTF with ``dim`` reduced, broadcast over every other input dimension. [1]

    Notes
    -----
    Paper Eq. 3 (also used for the band coherence diameter):

    .. math:: g(u, v) = \sum_\lambda w(\lambda)\, g_\lambda(u, v),
              \qquad \sum_\lambda w(\lambda) = 1

    pyBSM's ``weighted_by_wavelength`` accumulates the sum in wavelength order;
    this uses one tensor contraction, so the two agree to floating-point rounding
    (about 1e-16 relative).
    """
    if not isinstance(weights, xr.DataArray) or dim not in weights.dims:
        raise ValueError(f"weights must be a DataArray with dimension {dim!r}")
    if dim not in otf.dims:
        raise ValueError(f"otf must have dimension {dim!r}; it has {otf.dims}")
    Weights(dim).check("weights", weights)
    out = apply_kernel(weighted_sum_kernel, otf, weights, core=[[dim], [dim]],
                       dtype=np.result_type(otf.dtype, weights.dtype))
    return described(out, spectral_average)
