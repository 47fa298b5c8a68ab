"""Weighted sums over one dimension that keep the caller's dask chunks (private).

``xr.dot`` hands dask's ``einsum``, which rechunks its inputs whenever the output
chunk would outgrow the largest input chunk: a spectral weighting of a
(frequency x wavelength) OTF against (scenario x wavelength) weights came back in
scenario chunks half the size the user asked for. :func:`contract` runs numpy's
``einsum`` inside ``apply_ufunc`` instead: the contracted dimension is one chunk,
every other dimension keeps the chunks it came with.
"""

from __future__ import annotations

import numpy as np
import xarray as xr


def _einsum_last(a, b):
    return np.einsum("...k,...k->...", a, b)


def contract(a: xr.DataArray, b: xr.DataArray, dim: str) -> xr.DataArray:
    """Sum of ``a * b`` over ``dim``, broadcast over every other dimension of either."""
    return xr.apply_ufunc(
        _einsum_last, a, b, input_core_dims=[[dim], [dim]], dask="parallelized",
        output_dtypes=[np.result_type(a.dtype, b.dtype)],
        dask_gufunc_kwargs={"allow_rechunk": True},
    )
