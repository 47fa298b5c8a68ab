"""Filter OTFs: Gaussian and the sharpening kernel (paper Sec. 2.4)."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr
from otf_helpers import check_lazy, polar
from scipy import ndimage
from scipy.integrate import trapezoid

from xbsm.otf.filters import gaussian, sharpening_filter

IFOV = 2e-6
NYQ = 0.5 / IFOV
ROW = [[-0.25, 1.5, -0.25]]


def along_axes(f):
    """fx, fy at frequency f along x (first) and along y (second)."""
    return xr.DataArray([f, 0.0], dims="axis"), xr.DataArray([0.0, f], dims="axis")


def test_gaussian_reference_case_20():
    # pybsm_test_cases.md C-20 [T]: gaussian_OTF(u=[1], v=[1], blur_size_x=1, blur_size_y=2)
    out = gaussian(xr.DataArray([1.0]), xr.DataArray([1.0]), 1.0, 2.0)
    np.testing.assert_allclose(out, [1.5070172753900654e-07], rtol=1e-14)


def test_gaussian_is_the_transform_of_its_psf():
    b = 3e-6
    x = np.linspace(-10 * b, 10 * b, 20001)
    psf = np.exp(-np.pi * x**2 / b**2) / b
    f = np.array([0.0, 1e5, 2e5, 5e5])
    numeric = [trapezoid(psf * np.cos(2 * np.pi * fi * x), x) for fi in f]
    np.testing.assert_allclose(gaussian(xr.DataArray(f, dims="f"), 0.0, b, b), numeric, atol=1e-12)


def test_row_kernel_acts_along_x_only():
    # Section F: [-1/4, 3/2, -1/4] along x gives 1.5 at half Nyquist along x and 1.0 along y
    # (pyBSM 0.16.1: 1.0005 and 1.5078); 2.0 at Nyquist along x.
    fx, fy = along_axes(0.5 * NYQ)
    np.testing.assert_allclose(sharpening_filter(fx, fy, ROW, IFOV), [1.5, 1.0], atol=1e-15)
    fx, fy = along_axes(NYQ)
    np.testing.assert_allclose(sharpening_filter(fx, fy, ROW, IFOV), [2.0, 1.0], atol=1e-15)
    column = np.array(ROW).T
    np.testing.assert_allclose(sharpening_filter(fx, fy, column, IFOV), [1.0, 2.0], atol=1e-15)


def test_pybsm_method_shows_the_quirks_documented_in_section_f(pybsm_otf):
    # pyBSM 0.16.1 filter_OTF at half Nyquist along u and v (fixture and section F).
    np.testing.assert_allclose(pybsm_otf["filter_half_nyquist/otf"], [[1.0005, 1.5078]], atol=1e-4)
    fx, fy = along_axes(0.5 * NYQ)
    out = sharpening_filter(fx, fy, ROW, IFOV, method="pybsm")
    np.testing.assert_allclose(out, pybsm_otf["filter_half_nyquist/otf"].ravel(), rtol=1e-15)


def test_filter_pybsm_reference_case_22():
    # pybsm_test_cases.md C-22 [T]: filter_OTF(u=[1], v=[1], kernel=[[0.5,0.5]], ifov=10)
    one = xr.DataArray([1.0])
    out = sharpening_filter(one, one, [[0.5, 0.5]], 10.0, method="pybsm")
    np.testing.assert_allclose(out, [0.9997532801828657], rtol=1e-14)


def test_is_periodic_above_nyquist():
    fx, fy = polar(np.linspace(0, 2 * NYQ, 17), orientation=[0.0, 0.4, np.pi / 2])
    kernel = [[0.0, -0.1, -0.05], [-0.2, 1.6, -0.1], [0.0, -0.1, -0.05]]
    base = sharpening_filter(fx, fy, kernel, IFOV)
    shifted = sharpening_filter(fx + 1 / IFOV, fy - 3 / IFOV, kernel, IFOV)
    np.testing.assert_allclose(shifted, base, atol=1e-13)


@pytest.mark.parametrize(
    "kernel",
    [
        [[-0.25, 1.5, -0.25]],
        [[0.5, 0.5]],
        [[0.0, -0.1, -0.05], [-0.2, 1.6, -0.1], [0.0, -0.1, -0.05]],
        [[0.1, 0.2], [0.3, 0.1], [0.2, 0.1]],
    ],
)
def test_equals_the_response_of_scipy_convolve_to_a_complex_exponential(kernel):
    # Convolve cos and sin images (rows along y, columns along x) with the kernel and read
    # off H = (conv(cos) + i conv(sin)) / exp(i phi) at an interior pixel.
    k = np.array(kernel)
    n = 32
    m, j = np.mgrid[:n, :n]
    for cx, cy in [(0.13, 0.0), (0.0, 0.29), (0.21, -0.37), (0.45, 0.05)]:  # cycles / pixel
        phi = 2 * np.pi * (cx * j + cy * m)
        resp = ndimage.convolve(np.cos(phi), k) + 1j * ndimage.convolve(np.sin(phi), k)
        h_numeric = (resp / np.exp(1j * phi))[n // 2, n // 2]
        out = sharpening_filter(xr.DataArray(cx / IFOV), xr.DataArray(cy / IFOV), k, IFOV)
        assert complex(out) == pytest.approx(h_numeric, abs=1e-13)


def test_even_kernel_keeps_its_half_pixel_phase():
    f = xr.DataArray(np.linspace(0, NYQ, 5), dims="frequency")
    out = sharpening_filter(f, 0 * f, [[0.5, 0.5]], IFOV)
    x = f * IFOV
    np.testing.assert_allclose(out, np.exp(1j * np.pi * x) * np.cos(np.pi * x), atol=1e-15)


def test_separate_ifovs_and_sweeps():
    fx, fy = polar(np.linspace(0, NYQ, 5))
    ifov = xr.DataArray([1e-6, 2e-6], dims="ifov")
    out = sharpening_filter(fx, fy, ROW, ifov, ifov_y=3e-6)
    assert set(out.dims) == {"frequency", "orientation", "ifov"}
    assert out.attrs["units"] == "1"


def test_dask_stays_lazy():
    fx, fy = polar(np.linspace(0, 3 * NYQ, 40))
    lazy = (fx.chunk(10), fy.chunk(10), ROW, IFOV)
    check_lazy(sharpening_filter, lazy, (fx, fy, ROW, IFOV))
    check_lazy(sharpening_filter, lazy, (fx, fy, ROW, IFOV), method="pybsm")
    check_lazy(gaussian, (fx.chunk(10), fy.chunk(10), 1e-6, 2e-6), (fx, fy, 1e-6, 2e-6))


@pytest.mark.parametrize(
    ("call", "name"),
    [
        (lambda f: sharpening_filter(f, f, [0.25, 0.5, 0.25], IFOV), "kernel"),
        (lambda f: sharpening_filter(f, f, [[np.nan]], IFOV), "kernel"),
        (lambda f: sharpening_filter(f, f, ROW, 0.0), "ifov_x"),
        (lambda f: sharpening_filter(f, f, ROW, IFOV, -1.0), "ifov_y"),
        (lambda f: sharpening_filter(f, f, ROW, IFOV, method="fft"), "method"),
        (lambda f: gaussian(f, f, -1.0, 1.0), "blur_size_x"),
    ],
)
def test_impossible_input_raises(call, name):
    with pytest.raises(ValueError, match=name):
        call(xr.DataArray([0.0]))
