"""Spectral weighting (paper Eq. 3)."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr
from otf_helpers import check_lazy, polar

from xbsm.otf.aperture import circular_aperture
from xbsm.otf.spectral import spectral_average

WL = xr.DataArray([0.5e-6, 0.6e-6, 0.7e-6], dims="wavelength")


def test_weights_are_normalised_and_extra_dims_kept():
    fx, fy = polar(np.linspace(0, 4e5, 9))
    mono = circular_aperture(fx, fy, WL, 0.275)
    w = xr.DataArray([[1.0, 2.0, 1.0], [0.0, 1.0, 0.0]], dims=("scene", "wavelength"))
    out = spectral_average(mono, w)
    assert set(out.dims) == {"frequency", "orientation", "scene"}
    xr.testing.assert_allclose(out.isel(scene=1, drop=True), mono.isel(wavelength=1, drop=True))
    np.testing.assert_allclose(out.isel(frequency=0), 1.0, rtol=1e-15)
    xr.testing.assert_allclose(spectral_average(mono, 7 * w), out)


def test_complex_otfs_are_averaged():
    otf = xr.DataArray([1j, 1.0, -1j], dims="wavelength")
    assert complex(spectral_average(otf, xr.DataArray([1.0, 2.0, 1.0], dims="wavelength"))) == 0.5


def test_dask_stays_lazy():
    fx, fy = polar(np.linspace(0, 4e5, 20))
    mono = circular_aperture(fx, fy, WL, 0.275)
    w = xr.DataArray([1.0, 2.0, 1.0], dims="wavelength")
    check_lazy(spectral_average, (mono.chunk({"frequency": 5}), w), (mono, w))


@pytest.mark.parametrize(
    ("weights", "match"),
    [
        (xr.DataArray([1.0, -1.0, 1.0], dims="wavelength"), "weights"),
        (xr.DataArray([0.0, 0.0, 0.0], dims="wavelength"), "weights"),
        (xr.DataArray([1.0, 1.0, 1.0], dims="band"), "weights"),
        (np.ones(3), "weights"),
    ],
)
def test_bad_weights_raise(weights, match):
    with pytest.raises(ValueError, match=match):
        spectral_average(xr.DataArray(np.ones(3), dims="wavelength"), weights)
