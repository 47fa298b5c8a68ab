"""pyBSM 0.16.1 numerics reproduced bit for bit, for ``method="pybsm"`` only.

pyBSM 0.16.1 finds the frequency at which the MTF falls to 3/SNR (ground
resolved distance, IBSM Eq. 3-54) with
``numpy.interp(3.0 / snr, mtf_slice[::-1], w[::-1])``
(``pybsm/metrics/functional.py``, ``ground_resolved_distance``). ``numpy.interp``
assumes increasing abscissae and does not check them; a reversed MTF that is
not monotonic (a contrast-reversed lobe) gives whatever bracket NumPy's search
happens to land on. That answer is physically wrong but it is pyBSM's, so
:func:`xbsm.metrics.ground_resolved_distance` with ``method="pybsm"`` needs the
same search to agree with pyBSM number for number on every MTF.

This module is a vectorised copy of that search, NumPy's
``binary_search_with_guess`` as called by ``arr_interp``
(``numpy/_core/src/multiarray/compiled_base.c``) for the first query point,
and of the interpolation around it. It runs row-wise over a whole sweep inside
``xr.apply_ufunc`` (dask-parallelised) instead of one ``numpy.interp`` call
per scenario. The physical rule, the first crossing of the threshold, is in
:mod:`xbsm.metrics.grd`; nothing outside the ``"pybsm"`` method uses this
module.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

__all__: list[str] = []


def np_interp_reversed(mtf, freq, threshold, n):
    """``numpy.interp(threshold, mtf[::-1], freq[::-1])``, vectorised.

    Reproduces NumPy's search (a guess-then-bisect lookup that assumes
    increasing abscissae) so that non-monotonic MTFs give pyBSM's answer.
    """
    xp = mtf.isel(frequency=slice(None, None, -1))
    fp = freq.isel(frequency=slice(None, None, -1))
    key = threshold

    def kernel(xp_, fp_, key_):
        shape = np.broadcast_shapes(xp_.shape[:-1], fp_.shape[:-1], np.shape(key_))
        xp_ = np.broadcast_to(xp_, shape + (n,))
        fp_ = np.broadcast_to(fp_, shape + (n,))
        key_ = np.broadcast_to(key_, shape)
        xp2 = xp_.reshape(-1, n)
        fp2 = fp_.reshape(-1, n)
        k = key_.reshape(-1)
        rows = np.arange(k.size)
        j = _numpy_binary_search(k, xp2)
        jc = np.clip(j, 0, n - 2)
        x0, x1 = xp2[rows, jc], xp2[rows, jc + 1]
        y0, y1 = fp2[rows, jc], fp2[rows, jc + 1]
        with np.errstate(divide="ignore", invalid="ignore"):
            slope = (y1 - y0) / (x1 - x0)
            res = slope * (k - x0) + y0
            alt = slope * (k - x1) + y1
        res = np.where(np.isnan(res), alt, res)
        res = np.where(np.isnan(res) & (y0 == y1), y0, res)
        res = np.where(x0 == k, y0, res)
        res = np.where(j == n - 1, fp2[:, n - 1], res)
        res = np.where(j == -1, fp2[:, 0], res)
        res = np.where(j == n, fp2[:, n - 1], res)
        res = np.where(np.isnan(k), np.nan, res)
        return res.reshape(shape)

    return xr.apply_ufunc(
        kernel,
        xp,
        fp,
        key,
        input_core_dims=[["frequency"], ["frequency"], []],
        dask="parallelized",
        output_dtypes=[float],
    )


_LIKELY_IN_CACHE = 8  # NumPy's LIKELY_IN_CACHE_SIZE: the cells probed before bisecting


def _numpy_binary_search(key, arr):
    """Row-wise index j with arr[j] <= key < arr[j+1], as NumPy's interp finds it.

    Mirrors the search NumPy's ``interp`` performs for its first query point
    (initial guess 0): a check of the first few cells, then bisection. For
    increasing rows it is the ordinary bracket; for other rows it returns the
    same (arbitrary) bracket NumPy does.
    """
    m, n = arr.shape
    rows = np.arange(m)
    out = np.full(m, -2, dtype=np.int64)
    out[key > arr[:, -1]] = n
    out[(out == -2) & (key < arr[:, 0])] = -1
    todo = out == -2
    if n <= 4:
        # linear search: first i with key < arr[i], minus one
        less = key[:, None] < arr
        first = np.where(less.any(axis=1), less.argmax(axis=1), n)
        out[todo] = first[todo] - 1
        return out
    guess = 1
    imin = np.zeros(m, dtype=np.int64)
    imax = np.full(m, n, dtype=np.int64)
    a_g = arr[:, guess]
    lt_g = key < a_g
    # key < arr[guess] and key >= arr[guess-1] (= arr[0], checked above)
    done = todo & lt_g
    out[done] = guess - 1
    todo &= ~done
    a_g1, a_g2 = arr[:, guess + 1], arr[:, guess + 2]
    done = todo & (key < a_g1)
    out[done] = guess
    todo &= ~done
    done = todo & (key < a_g2)
    out[done] = guess + 1
    todo &= ~done
    imin[todo] = guess + 2
    if guess < n - _LIKELY_IN_CACHE - 1:
        narrow = todo & (key < arr[:, guess + _LIKELY_IN_CACHE])
        imax[narrow] = guess + _LIKELY_IN_CACHE
    lo, hi = imin.copy(), imax.copy()
    for _ in range(int(np.ceil(np.log2(n))) + 2):
        active = todo & (lo < hi)
        if not active.any():
            break
        mid = lo + ((hi - lo) >> 1)
        ge = key >= arr[rows, np.clip(mid, 0, n - 1)]
        lo = np.where(active & ge, mid + 1, lo)
        hi = np.where(active & ~ge, mid, hi)
    out[todo] = lo[todo] - 1
    return out
