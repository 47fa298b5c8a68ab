"""Noise in flat regions of an image: standard deviation and mean, optionally detrended."""

from __future__ import annotations

import numpy as np
import xarray as xr

from .._metadata import named
from ._image import as_image, finite_values, lead_coords, select, units_of

__all__ = ["flat_noise"]


def _plane_residual(values):
    """``values`` (..., y, x) minus each image's least-squares plane, flattened."""
    y, x = np.indices(values.shape[-2:])
    design = np.column_stack([np.ones(y.size), y.ravel(), x.ravel()])
    flat = values.reshape(-1, y.size).T
    coef, *_ = np.linalg.lstsq(design, flat, rcond=None)
    return (flat - design @ coef).T.reshape(values.shape[:-2] + (y.size,))


def flat_noise(image, region=None, *, detrend=False) -> xr.Dataset:
    r"""Noise standard deviation and mean of a flat region of an image.

    Parameters
    ----------
    image : xr.DataArray or array_like
        Over (``y``, ``x``), with any leading dimensions (kept). [any]
    region : tuple of two slices or dict, optional
        The flat region by position: ``(rows, columns)`` or
        ``{"y": slice, "x": slice}``; default the whole image.
    detrend : bool
        Remove each image's least-squares plane first (a gradient of
        illumination or shading is not noise).

    Returns
    -------
    xr.Dataset
        ``noise``, the sample standard deviation, and ``mean`` of the region,
        in the image's units.

    Notes
    -----
    .. math:: s = \sqrt{\textstyle\sum_i (v_i - \hat v_i)^2 / (N - p)}

    with :math:`\hat v` the mean (:math:`p = 1`) or the fitted plane
    (:math:`p = 3`). For :math:`N` independent Gaussian samples its relative
    standard error is about :math:`1/\sqrt{2(N - p)}`; blurred noise is
    correlated and has fewer independent samples.
    """
    img = select(as_image(image, "image"), region, "region")
    if img.sizes["y"] < 2 or img.sizes["x"] < 2:
        raise ValueError(f"region is {img.sizes['y']} x {img.sizes['x']} pixels (y x x); "
                         "flat_noise needs at least 2 x 2")
    values = finite_values(img, "image")
    flat = values.reshape(values.shape[:-2] + (-1,))
    mean = flat.mean(axis=-1)
    residual, fitted = ((_plane_residual(values), 3) if detrend
                        else (flat - mean[..., None], 1))
    noise = np.sqrt(np.square(residual).sum(axis=-1) / (flat.shape[-1] - fitted))
    lead = img.dims[:-2]
    coords = lead_coords(img)
    units = units_of(img)
    return xr.Dataset({
        "noise": named(xr.DataArray(noise, dims=lead, coords=coords), units,
                       "noise standard deviation in a flat region"),
        "mean": named(xr.DataArray(mean, dims=lead, coords=coords), units,
                      "mean in a flat region"),
    }, attrs={"detrend": "plane" if detrend else "none"})

