"""Point spread function from a sampled OTF."""

from __future__ import annotations

import numpy as np
import xarray as xr

from .._metadata import described

__all__ = ["otf_to_psf"]


def _frequency_step(otf, dim) -> float:
    if dim not in otf.dims or dim not in otf.coords:
        raise ValueError(f"otf must have a dimension {dim!r} with a frequency coordinate")
    f = np.asarray(otf[dim].values, dtype=float)
    n = f.size
    if n < 2:
        raise ValueError(f"otf dimension {dim!r} needs at least 2 samples")
    step = (f[-1] - f[0]) / (n - 1)
    expected = (np.arange(n) - n // 2) * step
    if step <= 0 or not np.allclose(f, expected, rtol=0, atol=1e-9 * abs(step)):
        raise ValueError(
            f"otf coordinate {dim!r} must be uniformly increasing with zero frequency at "
            f"index n // 2, i.e. (arange(n) - n // 2) * df (the np.fft.fftshift layout)"
        )
    return step


def _psf_kernel(otf):
    psf = np.fft.fftshift(
        np.fft.ifft2(np.fft.ifftshift(otf, axes=(-2, -1)), axes=(-2, -1)), axes=(-2, -1)
    ).real
    return psf / psf.sum(axis=(-2, -1), keepdims=True)


def otf_to_psf(otf, fx_dim="fx", fy_dim="fy"):
    r"""Point spread function sampled on the grid conjugate to the OTF grid, summing to one.

    Parameters
    ----------
    otf : xr.DataArray
        OTF sampled on a uniform (``fy_dim``, ``fx_dim``) grid with zero
        frequency at index ``n // 2`` (odd or even sizes); any other dimension
        broadcasts. [1]
    fx_dim, fy_dim : str
        Names of the frequency dimensions. [cycles/rad]

    Returns
    -------
    xr.DataArray
        Real PSF with dimensions ``y`` and ``x`` replacing ``fy_dim`` and
        ``fx_dim``, normalised to sum to one over (``y``, ``x``), centred at
        index ``n // 2`` (coordinate 0). Coordinates are angles
        :math:`(i - n/\!/2)/(n\,\Delta f)`. [1]

    Notes
    -----
    The inverse discrete Fourier transform with the zero-frequency sample
    moved to index 0 first (``ifftshift``) and the zero-angle sample moved back
    to the centre after (``fftshift``):

    .. math:: p(x_m, y_l) \propto \operatorname{Re} \sum_{k, j} H(f_{x,k}, f_{y,j})
              \, e^{2\pi i (f_{x,k} x_m + f_{y,j} y_l)}

    pyBSM 0.16.1's ``otf_to_psf`` applies ``fftshift`` before the inverse
    transform, which on odd grids multiplies the PSF by
    :math:`\cos(2\pi(x + y)/N)`-type sign alternation (2.8 % of the peak on
    its 101 grid); it also resamples and crops, which this function does not.
    """
    dfx = _frequency_step(otf, fx_dim)
    dfy = _frequency_step(otf, fy_dim)
    ny, nx = otf.sizes[fy_dim], otf.sizes[fx_dim]
    if otf.chunks is not None:
        otf = otf.chunk({fy_dim: -1, fx_dim: -1})
    out = xr.apply_ufunc(
        _psf_kernel,
        otf,
        input_core_dims=[[fy_dim, fx_dim]],
        output_core_dims=[["y", "x"]],
        dask="parallelized",
        output_dtypes=[float],
        dask_gufunc_kwargs={"output_sizes": {"y": ny, "x": nx}},
    )
    out = out.assign_coords(
        y=("y", (np.arange(ny) - ny // 2) / (ny * dfy), {"units": "rad"}),
        x=("x", (np.arange(nx) - nx // 2) / (nx * dfx), {"units": "rad"}),
    )
    return described(out, otf_to_psf)
