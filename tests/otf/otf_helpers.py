"""Helpers shared by the OTF tests (not a test module)."""

from __future__ import annotations

from pathlib import Path

import dask
import numpy as np
import xarray as xr

FIXTURE = Path(__file__).resolve().parents[1] / "fixtures" / "pybsm_otf.npz"


def grid_da(u, v):
    """Wrap pyBSM-style 2-D (v, u) arrays as fx, fy DataArrays on dims (fy, fx)."""
    dims = ("fy", "fx")
    return xr.DataArray(np.asarray(u), dims=dims), xr.DataArray(np.asarray(v), dims=dims)


def polar(frequency, orientation=(0.0, np.pi / 4, np.pi / 2)):
    """fx, fy of 1-D slices, dims (frequency, orientation)."""
    f = xr.DataArray(np.asarray(frequency, float), dims="frequency")
    o = xr.DataArray(np.asarray(orientation, float), dims="orientation")
    f = f.assign_coords(frequency=f.values)
    o = o.assign_coords(orientation=o.values)
    return f * np.cos(o), f * np.sin(o)


def _refuse(*args, **kwargs):
    raise AssertionError("a dask computation was triggered")


def raise_on_compute():
    """Context manager in which any dask computation raises."""
    return dask.config.set(scheduler=_refuse)


def check_lazy(func, lazy_args, eager_args, **kwargs):
    """Build func lazily (nothing may compute), then compare it with the eager result."""
    with raise_on_compute():
        lazy = func(*lazy_args, **kwargs)
    assert lazy.chunks is not None, "result is not dask-backed"
    eager = func(*eager_args, **kwargs)
    xr.testing.assert_allclose(lazy.compute(), eager, rtol=1e-14, atol=0)
    return lazy
