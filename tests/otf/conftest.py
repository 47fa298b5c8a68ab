"""Shared helpers for the OTF tests."""

from __future__ import annotations

from pathlib import Path

import dask
import numpy as np
import pytest
import xarray as xr

FIXTURE = Path(__file__).resolve().parents[1] / "fixtures" / "pybsm_otf.npz"


@pytest.fixture(scope="session")
def pybsm_otf():
    """pyBSM 0.16.1 reference values written by recipes/pybsm_reference_otf.py."""
    with np.load(FIXTURE) as data:
        return {key: data[key] for key in data.files}


def grid_da(u, v):
    """Wrap pyBSM-style 2-D (v, u) arrays as fx, fy DataArrays on dims (fy, fx)."""
    dims = ("fy", "fx")
    return xr.DataArray(np.asarray(u), dims=dims), xr.DataArray(np.asarray(v), dims=dims)


def polar(frequency, orientation=(0.0, np.pi / 4, np.pi / 2)):
    """fx, fy of 1-D slices: dims (frequency, orientation)."""
    f = xr.DataArray(np.asarray(frequency, float), dims="frequency")
    o = xr.DataArray(np.asarray(orientation, float), dims="orientation")
    f = f.assign_coords(frequency=f.values)
    o = o.assign_coords(orientation=o.values)
    return f * np.cos(o), f * np.sin(o)


class RaiseOnCompute:
    """A dask scheduler that fails the test if anything is computed."""

    def __call__(self, dsk, keys, **kwargs):
        raise AssertionError("a dask computation was triggered")


@pytest.fixture
def no_compute():
    """Context in which any dask computation raises."""
    return dask.config.set(scheduler=RaiseOnCompute())


def assert_lazy_equals_eager(func, lazy_args, eager_args, no_compute_ctx, **kwargs):
    """Call func lazily (under a raising scheduler) and eagerly and compare."""
    with no_compute_ctx:
        lazy = func(*lazy_args, **kwargs)
    assert lazy.chunks is not None, "result is not dask-backed"
    eager = func(*eager_args, **kwargs)
    xr.testing.assert_allclose(lazy.compute(), eager, rtol=1e-14, atol=0)
    return lazy, eager
