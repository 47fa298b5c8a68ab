"""Noise in flat regions of an image: standard deviation and mean, optionally detrended."""

from __future__ import annotations

import numpy as np
import xarray as xr

from .._metadata import named
from ._image import as_image, finite_values, flag, flags_variable, lead_coords, select, units_of

__all__ = ["flat_noise"]

STRUCTURE_SHARE = 0.1
"""Largest share of the noise variance that scene structure may hold in a flat region."""

STRUCTURE_SAMPLES = 40.0
"""The share must also exceed this over the pixel count N (the best step of white noise
alone explains a few / N of its variance)."""


def _plane_residual(values):
    """``values`` (..., y, x) minus each image's least-squares plane, flattened."""
    y, x = np.indices(values.shape[-2:])
    design = np.column_stack([np.ones(y.size), y.ravel(), x.ravel()])
    flat = values.reshape(-1, y.size).T
    coef, *_ = np.linalg.lstsq(design, flat, rcond=None)
    return (flat - design @ coef).T.reshape(values.shape[:-2] + (y.size,))


def _step_variance(means):
    """Variance per pixel that the best step along the last axis explains beyond a plane.

    ``means`` are the plane residual's means across the other axis: they sum to zero and
    are orthogonal to the ramp, so a step's projection is its tail sum, over the norm of
    the step minus its plane part.
    """
    n = means.shape[-1]
    k = np.arange(1, n)  # the step starts at index k
    ramp = np.arange(n) - (n - 1) / 2.0
    tail = np.cumsum(means[..., ::-1], axis=-1)[..., -2::-1]  # sum over j >= k
    ones = n - k
    along = np.cumsum(ramp[::-1])[-2::-1]  # the ramp summed over j >= k
    norm = ones - ones**2 / n - along**2 / np.sum(ramp**2)
    safe = np.where(norm > 1e-12 * n, norm, np.inf)
    return np.max(tail**2 / safe, axis=-1) / n


def _not_flat(values, plane_residual, detrend):
    """Whether scene structure holds too much of a region's variance.

    Structure: the fitted plane (without ``detrend``) and the best step along x or y
    beyond it (an edge). Too much: more than :data:`STRUCTURE_SHARE` of the remaining
    (noise) variance and more than :data:`STRUCTURE_SAMPLES` / N of it.
    """
    n = values.shape[-2] * values.shape[-1]
    flat = values.reshape(values.shape[:-2] + (n,))
    plane = 0.0 if detrend else np.mean(np.square(
        flat - flat.mean(axis=-1, keepdims=True) - plane_residual), axis=-1)
    residual = plane_residual.reshape(values.shape)
    step = np.maximum(_step_variance(residual.mean(axis=-2)),
                      _step_variance(residual.mean(axis=-1)))
    noise = np.square(plane_residual).sum(axis=-1) / (n - 3) - step
    rounding = 16 * np.finfo(float).eps * flat.var(axis=-1)  # a noiseless plane, detrended
    return plane + step > np.maximum(max(STRUCTURE_SHARE, STRUCTURE_SAMPLES / n) * noise,
                                     rounding)


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
        in the image's units; ``flags`` (:data:`xbsm.measure.FLAGS`:
        ``region_not_flat``, a plane (without ``detrend``) or a step along a
        row or column holds more than 10 % of the residual variance and more
        than 40 / N, so part of ``noise`` is scene structure).

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
    plane_residual = _plane_residual(values)
    residual, fitted = (plane_residual, 3) if detrend else (flat - mean[..., None], 1)
    noise = np.sqrt(np.square(residual).sum(axis=-1) / (flat.shape[-1] - fitted))
    bits = np.where(_not_flat(values, plane_residual, detrend), flag("region_not_flat"), 0)
    lead = img.dims[:-2]
    coords = lead_coords(img)
    units = units_of(img)
    return xr.Dataset({
        "noise": named(xr.DataArray(noise, dims=lead, coords=coords), units,
                       "noise standard deviation in a flat region"),
        "mean": named(xr.DataArray(mean, dims=lead, coords=coords), units,
                      "mean in a flat region"),
        "flags": flags_variable(bits, lead, coords, "flat-region validity flags"),
    }, attrs={"detrend": "plane" if detrend else "none"})

