"""Gaussian defocus OTF and blur radii (IBSM 3-25 to 3-27)."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr
from otf_helpers import check_lazy, polar
from scipy.integrate import trapezoid

from xbsm.otf.defocus import (
    gaussian_defocus,
    image_domain_defocus_radius,
    object_domain_defocus_radius,
)


def test_reference_value_case_20():
    # pybsm_test_cases.md C-20 [T]: defocus_OTF(u=[1], v=[1], w_x=1, w_y=1) = 0.007191883355826368
    out = gaussian_defocus(xr.DataArray([1.0]), xr.DataArray([1.0]), 1.0, 1.0)
    np.testing.assert_allclose(out, [0.007191883355826368], rtol=1e-13)


def test_is_the_transform_of_a_gaussian_psf():
    # H = exp(-pi^2 w^2 f^2 / 4) is the Fourier transform of exp(-4 x^2 / w^2) / (w sqrt(pi) / 2).
    w = 2e-6
    x = np.linspace(-20 * w, 20 * w, 40001)
    psf = np.exp(-4 * x**2 / w**2)
    psf /= trapezoid(psf, x)
    f = np.array([0.0, 5e4, 1e5, 3e5, 6e5])
    numeric = [trapezoid(psf * np.cos(2 * np.pi * fi * x), x) for fi in f]
    out = gaussian_defocus(xr.DataArray(f, dims="frequency"), 0.0, w, 0.0)
    np.testing.assert_allclose(out, numeric, atol=1e-12)


def test_zero_frequency_is_one_and_otf_is_bounded():
    fx, fy = polar(np.linspace(0, 1e6, 21))
    out = gaussian_defocus(fx, fy, xr.DataArray([0.0, 1e-6, 5e-6], dims="blur"), 2e-6)
    assert float(out.isel(frequency=0).min()) == 1.0
    assert float(out.max()) <= 1.0
    assert set(out.dims) == {"frequency", "orientation", "blur"}


def test_object_and_image_radii_formulas():
    # IBSM 3-26: 0.62 D |1/R - 1/R0|; 3-27: 0.62 D dz / f^2
    assert object_domain_defocus_radius(0.2, 1000.0, 2000.0) == pytest.approx(0.62 * 0.2 * 0.5e-3)
    assert object_domain_defocus_radius(0.2, 2000.0, np.inf) == pytest.approx(0.62 * 0.2 / 2000)
    assert image_domain_defocus_radius(0.2, -1e-4, 2.0) == pytest.approx(0.62 * 0.2 * 1e-4 / 4)
    r = object_domain_defocus_radius(0.2, xr.DataArray([1e3, 2e3], dims="range"), 2e3)
    assert r.dims == ("range",) and r.attrs["units"] == "rad"


def test_dask_stays_lazy():
    fx, fy = polar(np.linspace(0, 1e6, 20))
    check_lazy(gaussian_defocus, (fx.chunk(5), fy.chunk(5), 1e-6, 2e-6), (fx, fy, 1e-6, 2e-6))


@pytest.mark.parametrize(
    ("call", "name"),
    [
        (lambda: gaussian_defocus(xr.DataArray([0.0]), 0.0, -1e-6, 0.0), "blur_radius_x"),
        (lambda: object_domain_defocus_radius(0.1, 0.0, 10.0), "object_range"),
        (lambda: image_domain_defocus_radius(0.1, 1e-4, 0.0), "focal_length"),
    ],
)
def test_impossible_input_raises(call, name):
    with pytest.raises(ValueError, match=name):
        call()
