"""Detector OTFs: pixel (IBSM 3-36), aggregation, charge transfer (3-39), diffusion (3-40)."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr
from otf_helpers import check_lazy, polar

from xbsm.otf.detector import aggregated_detector, charge_transfer, detector, diffusion

F, W, P = 4.0, 8e-6, 10e-6


def test_detector_is_one_at_zero_and_vanishes_at_focal_length_over_width():
    f = xr.DataArray([0.0, F / W, 2 * F / W], dims="frequency")
    out = detector(f, 0.0 * f, W, W, F)
    np.testing.assert_allclose(out, [1.0, 0.0, 0.0], atol=1e-16)
    out = detector(0.0 * f, f, W, 2 * W, F)
    np.testing.assert_allclose(out, [1.0, 0.0, 0.0], atol=1e-16)


def test_aggregation_of_one_equals_detector_and_n_is_a_dirichlet_kernel():
    fx, fy = polar(np.linspace(0, 3 * F / P, 37))
    xr.testing.assert_allclose(
        aggregated_detector(fx, fy, W, W, P, P, F, 1), detector(fx, fy, W, W, F), atol=1e-16
    )
    for n in (2, 3, 4):
        out = aggregated_detector(fx, fy, W, W, P, P, F, n)
        x = P * fx / F
        y = P * fy / F
        with np.errstate(divide="ignore", invalid="ignore"):
            dx = np.where(
                np.abs(np.sin(np.pi * x)) < 1e-12,
                np.cos(n * np.pi * x) / np.cos(np.pi * x),
                np.sin(n * np.pi * x) / (n * np.sin(np.pi * x)),
            )
            dy = np.where(
                np.abs(np.sin(np.pi * y)) < 1e-12,
                np.cos(n * np.pi * y) / np.cos(np.pi * y),
                np.sin(n * np.pi * y) / (n * np.sin(np.pi * y)),
            )
        np.testing.assert_allclose(out, dx * dy * detector(fx, fy, W, W, F), atol=1e-14)


def test_charge_transfer_is_one_for_perfect_transfer_and_at_zero():
    fx, fy = polar(np.linspace(0, F / P, 11))
    cte = xr.DataArray([1.0, 0.999], dims="cte").assign_coords(cte=[1.0, 0.999])
    out = charge_transfer(fx, fy, P, P, F, 100, 50, cte, 3)
    np.testing.assert_allclose(out.sel(cte=1.0), 1.0)
    np.testing.assert_allclose(out.isel(frequency=0), 1.0)
    assert float(out.max()) <= 1.0


def test_diffusion_is_one_at_zero_and_decreases():
    f = xr.DataArray(np.linspace(0, 2 * F / P, 50), dims="frequency")
    alpha = xr.DataArray([1e4, 1e5, 1e6], dims="wavelength")
    out = diffusion(f, 0 * f, alpha, 5e-6, 1e-5, F)
    np.testing.assert_allclose(out.isel(frequency=0), 1.0, rtol=1e-14)
    assert bool((out.diff("frequency") <= 1e-14).all())  # decreasing, to within rounding
    assert set(out.dims) == {"frequency", "wavelength"}


def test_sweeps_and_dask():
    fx, fy = polar(np.linspace(0, F / W, 16))
    widths = xr.DataArray([6e-6, 8e-6], dims="width")
    out = detector(fx, fy, widths, W, F)
    assert set(out.dims) == {"frequency", "orientation", "width"}
    check_lazy(detector, (fx.chunk(4), fy.chunk(4), widths, W, F), (fx, fy, widths, W, F))
    check_lazy(
        aggregated_detector,
        (fx.chunk(4), fy.chunk(4), W, W, P, P, F, 3),
        (fx, fy, W, W, P, P, F, 3),
    )


@pytest.mark.parametrize(
    ("call", "name"),
    [
        (lambda f: detector(f, f, 0.0, W, F), "detector_width_x"),
        (lambda f: detector(f, f, W, W, -1.0), "focal_length"),
        (lambda f: aggregated_detector(f, f, W, W, P, P, F, 0), "aggregation"),
        (lambda f: aggregated_detector(f, f, W, W, P, P, F, 1.5), "aggregation"),
        (lambda f: charge_transfer(f, f, P, P, F, 10, 10, 1.2), "transfer_efficiency"),
        (lambda f: diffusion(f, f, 1e5, 5e-6, 0.0, F), "diffusion_length"),
    ],
)
def test_impossible_input_raises(call, name):
    with pytest.raises(ValueError, match=name):
        call(xr.DataArray([0.0]))
