"""OTF to PSF on odd and even grids."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr
from otf_helpers import raise_on_compute

from xbsm.otf.filters import gaussian
from xbsm.otf.psf import otf_to_psf


def freq_grid(n, df):
    f = (np.arange(n) - n // 2) * df
    fx = xr.DataArray(f, dims="fx", coords={"fx": f})
    fy = xr.DataArray(f, dims="fy", coords={"fy": f})
    return fx, fy


@pytest.mark.parametrize("n", [65, 64, 101, 100])
def test_gaussian_psf_sums_to_one_is_centred_and_matches_the_analytic_psf(n):
    # PSF sampled at 1 urad; b = 8 urad puts the OTF at 1e-22 at Nyquist, so the unpaired
    # Nyquist row and column of an even grid cannot move the centroid.
    b, df = 8e-6, 1.0 / (n * 1e-6)
    fx, fy = freq_grid(n, df)
    psf = otf_to_psf(gaussian(fx, fy, b, b))
    assert psf.dims == ("y", "x")
    assert float(psf.sum()) == pytest.approx(1.0, abs=1e-14)
    # centroid at the centre to within 1e-12 pixel (rounding of sum(psf * x) is ~1e-15 px;
    # a bound of 1e-20 m = 1e-14 px was only 10x that and fragile)
    pixel = 1e-6
    assert abs(float((psf * psf.x).sum())) <= 1e-12 * pixel
    assert abs(float((psf * psf.y).sum())) <= 1e-12 * pixel
    assert np.argmax(psf.values) == (n // 2) * n + n // 2
    analytic = np.exp(-np.pi * (psf.x**2 + psf.y**2) / b**2)
    analytic = analytic / analytic.sum()
    np.testing.assert_allclose(psf, analytic.transpose("y", "x"), atol=1e-12)


def test_odd_grid_has_no_fftshift_modulation():
    # pyBSM's fftshift-before-ifft2 multiplies the PSF by cos-type sign alternation on odd
    # grids; the correct transform of a real, even OTF is non-negative here.
    n = 101
    fx, fy = freq_grid(n, 1.0 / (n * 1e-6))
    psf = otf_to_psf(gaussian(fx, fy, 20e-6, 20e-6))
    # non-negative to within rounding relative to the peak: the tails are ~1e-21, so their
    # sign is rounding (numpy 2.4 without AVX-512 gives -3e-21)
    peak = float(psf.max())
    assert float(psf.min()) >= -1e-12 * peak
    wrong = np.real(
        np.fft.fftshift(np.fft.ifft2(np.fft.fftshift(gaussian(fx, fy, 20e-6, 20e-6).values)))
    )
    assert float(wrong.min()) < -1e-3 * peak  # pyBSM's modulation is -0.8 % of the peak


def test_other_dims_broadcast_and_dask_stays_lazy():
    n = 33
    fx, fy = freq_grid(n, 1.0 / (n * 1e-6))
    b = xr.DataArray([2e-6, 4e-6, 6e-6], dims="blur")
    otf = gaussian(fx, fy, b, b)
    eager = otf_to_psf(otf)
    assert set(eager.dims) == {"blur", "y", "x"}
    with raise_on_compute():
        lazy = otf_to_psf(otf.chunk({"blur": 1, "fx": 11}))
    assert lazy.chunks is not None
    xr.testing.assert_allclose(lazy.compute(), eager, rtol=1e-13)
    np.testing.assert_allclose(eager.sum(("x", "y")), 1.0, rtol=1e-14)


def test_bad_grid_raises():
    fx, fy = freq_grid(16, 1e4)
    otf = gaussian(fx, fy, 1e-6, 1e-6)
    with pytest.raises(ValueError, match="fx"):
        otf_to_psf(otf.assign_coords(fx=fx.values + 5e3))
    with pytest.raises(ValueError, match="fy"):
        otf_to_psf(otf.rename(fy="v"))
