"""Filter OTFs: generic Gaussian and the discrete sharpening kernel (paper Sec. 2.4)."""

from __future__ import annotations

import numpy as np
import xarray as xr
from scipy import fft as sp_fft
from scipy.interpolate import RegularGridInterpolator

from .._kernels import apply_kernel
from .._metadata import described
from ..params import Values, contract
from ._contracts import ANGLE, BLUR

__all__ = ["gaussian", "sharpening_filter", "FILTER_METHODS"]

FILTER_METHODS = ("dtft", "pybsm")

PYBSM_FFT_SIZE = 100
"""Zero-padded FFT size of pyBSM 0.16.1's ``filter_OTF``."""


@contract(blur_size_x=BLUR, blur_size_y=BLUR)
def gaussian(fx, fy, blur_size_x, blur_size_y):
    r"""Real Gaussian OTF parameterised by the blur-spot size.

    Parameters
    ----------
    fx, fy : xr.DataArray
        Angular spatial frequencies, broadcast against each other. [cycles/rad]
    blur_size_x, blur_size_y : float or xr.DataArray
        Angular blur-spot size along x and y, >= 0: the PSF falls to
        :math:`e^{-\pi} \approx 0.043` of its peak at half this size, and the
        OTF to 0.043 at the frequency :math:`1/b`. [rad]

    Returns
    -------
    xr.DataArray
        Real OTF, broadcast over every input dimension. [1]

    Notes
    -----
    The generic Gaussian of the paper's Table 1; its PSF is
    :math:`b_x^{-1} b_y^{-1} \exp[-\pi(x^2/b_x^2 + y^2/b_y^2)]`:

    .. math:: H = \exp\left[-\pi\left(b_x^2 f_x^2 + b_y^2 f_y^2\right)\right]
    """
    out = apply_kernel(_gaussian_kernel, fx, blur_size_x, fy, blur_size_y)
    return described(out, gaussian)


def _gaussian_kernel(fx, blur_size_x, fy, blur_size_y):
    """Gaussian OTF on plain arrays (arguments in the order of the result's dims)."""
    return np.exp(-np.pi * ((fx * blur_size_x) ** 2 + (fy * blur_size_y) ** 2))


def _as_kernel(kernel) -> np.ndarray:
    arr = np.asarray(getattr(kernel, "values", kernel), dtype=float)
    if arr.ndim != 2 or arr.size == 0:
        raise ValueError(
            f"kernel must be a non-empty 2-D array (rows along y, columns along x; "
            f"use shape (1, N) or (N, 1) for a 1-D filter); got shape {arr.shape}"
        )
    if not np.all(np.isfinite(arr)):
        raise ValueError("kernel must be finite")
    return arr


def pybsm_filter_kernel(u, v, kernel, ifov):
    """Look up pyBSM 0.16.1's table of ``|FFT2(kernel)|``, quirks included."""
    n = PYBSM_FFT_SIZE
    table = np.abs(sp_fft.fftshift(sp_fft.fft2(kernel, [n, n])))
    nyquist = 0.5 / ifov
    # The table's first axis (kernel rows, i.e. y) is indexed by u (x), the
    # second runs from +Nyquist down, and both span [-Nyquist, Nyquist] with
    # n points where the FFT has spacing 2 Nyquist / n.
    first = np.linspace(-nyquist, nyquist, n)
    second = np.linspace(nyquist, -nyquist, n)
    lookup = RegularGridInterpolator((first, second), table, method="linear", fill_value=0)

    def wrap(value):
        return (value + nyquist) % (2 * nyquist) - nyquist

    u, v = np.broadcast_arrays(u, v)
    return lookup((wrap(u), wrap(v)))


@contract(ifov_x=ANGLE, ifov_y=Values(ANGLE.spec, optional=True))
def sharpening_filter(fx, fy, kernel, ifov_x, ifov_y=None, method="dtft"):
    r"""OTF of a discrete filter kernel applied to the sampled image.

    Parameters
    ----------
    fx, fy : xr.DataArray
        Angular spatial frequencies, broadcast against each other. [cycles/rad]
    kernel : array_like, 2-D
        Filter kernel; rows run along y and columns along x. Shapes (1, N) and
        (N, 1) are 1-D filters along x and y. Element ``[i, j]`` is the weight
        at offset ``(i - rows // 2, j - columns // 2)`` pixels, the centring of
        :func:`scipy.ndimage.convolve`. [1]
    ifov_x : float or xr.DataArray
        Angular sample spacing along x, > 0. [rad]
    ifov_y : float or xr.DataArray, optional
        Angular sample spacing along y, > 0; default ``ifov_x``. [rad]
    method : {"dtft", "pybsm"}
        ``"dtft"`` (default): the exact discrete-space Fourier transform,
        complex and periodic above Nyquist. ``"pybsm"``: pyBSM 0.16.1's
        ``filter_OTF`` (real |FFT| on a 100 x 100 table, axes swapped,
        frequency stretched by 100/99, linear interpolation; ``ifov_y`` is
        ignored as in pyBSM).

    Returns
    -------
    xr.DataArray
        Complex OTF for ``"dtft"``, real for ``"pybsm"``, broadcast over every
        input dimension. [1]

    Notes
    -----
    Paper Sec. 2.4: the transfer function of the kernel :math:`k_{ij}` is its
    discrete-space Fourier transform, periodic beyond Nyquist, with
    :math:`\Delta_x, \Delta_y` the sample spacings:

    .. math:: H(f_x, f_y) = \sum_{i,j} k_{ij}\,
              e^{-2\pi i\,[f_x \Delta_x (j - j_0) + f_y \Delta_y (i - i_0)]}

    Kernels with an even size have a half-pixel linear phase. The kernel is
    not required to sum to one (then :math:`H(0) \ne 1`).
    """
    if method not in FILTER_METHODS:
        raise ValueError(f"method must be one of {FILTER_METHODS}; got {method!r}")
    k = _as_kernel(kernel)
    if method == "pybsm":
        if isinstance(ifov_x, xr.DataArray):
            raise ValueError("ifov_x must be a float for method='pybsm'")
        out = apply_kernel(pybsm_filter_kernel, fx, fy, kernel=k, ifov=float(ifov_x))
        return described(out, sharpening_filter)
    if ifov_y is None:
        ifov_y = ifov_x
    out = apply_kernel(dtft_filter_kernel, fy, ifov_y, fx, ifov_x, kernel=k, dtype=complex)
    return described(out, sharpening_filter)


def dtft_filter_kernel(fy, ifov_y, fx, ifov_x, kernel):
    """Discrete-space Fourier transform of ``kernel`` on plain arrays (paper Sec. 2.4).

    Arguments in the order of the result's dims; ``kernel`` rows run along y.
    """
    rows, cols = kernel.shape
    offset_y = np.arange(rows) - rows // 2
    offset_x = np.arange(cols) - cols // 2
    phase_x = np.exp(-2j * np.pi * (fx * ifov_x)[..., None] * offset_x)
    phase_y = np.exp(-2j * np.pi * (fy * ifov_y)[..., None] * offset_y)
    return np.einsum("...i,ij,...j->...", phase_y, kernel, phase_x)
