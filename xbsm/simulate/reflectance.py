"""Pixel values to scene reflectance: the first step of an image simulation.

Three mappings, each per image (over its rows, columns and colour channel):
pyBSM's ``RefImage`` percentile mapping (the 0.2 and 99.8 percentiles go to
reflectance 0.05 and 0.95), pyBSM's ``ImageSimulator`` min-max stretch, and an
image that already is reflectance; or an explicit table of pixel values and
their reflectances (pyBSM's ``img_to_reflectance``). Mapped values are clipped
to [0, 1] as in pyBSM. Flat images and non-finite pixels give a finite, flagged
result instead of NaN.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from .. import flags as fl
from .._metadata import named
from ..params import FRACTION, Either, Pair, Spec, Table, contract
from .options import IMAGE_RULES

__all__ = ["image_to_reflectance"]

PERCENTILES = (0.2, 99.8)
"""Percentiles of pyBSM's ``RefImage`` mapping. [%]"""


def _fill_nonfinite(refl, finite, middle):
    """Non-finite pixels take the mean finite reflectance of their image (or ``middle``)."""
    with np.errstate(invalid="ignore"):
        count = finite.sum(axis=-1, keepdims=True)
        mean = np.where(finite, refl, 0.0).sum(axis=-1, keepdims=True) / np.maximum(count, 1)
    fill = np.where(count > 0, mean, middle)
    return np.where(finite, refl, fill)


def _stretch_kernel(img, mode, low, high, pixel_low=None, pixel_high=None):
    """Linear map of each image (last axis: its pixels) onto [low, high], clipped to [0, 1].

    ``mode`` "percentile" or "minmax" picks the two pixel values per image; "table" uses
    ``pixel_low`` / ``pixel_high``. Returns the reflectances and the image flags.
    """
    finite = np.isfinite(img)
    masked = np.where(finite, img, np.nan)
    # an image without a finite pixel is all zeros here (and flagged), not an all-NaN warning
    masked = np.where(finite.any(axis=-1, keepdims=True), masked, 0.0)
    with np.errstate(invalid="ignore"):
        if mode == "percentile":
            p1, p2 = np.nanpercentile(masked, PERCENTILES, axis=-1, keepdims=True)
        elif mode == "minmax":
            p1, p2 = (np.nanmin(masked, axis=-1, keepdims=True),
                      np.nanmax(masked, axis=-1, keepdims=True))
        else:
            p1, p2 = np.full_like(img[..., :1], pixel_low), np.full_like(img[..., :1], pixel_high)
    flat = ~(p2 > p1)
    safe = np.where(flat, 1.0, p2 - p1)
    with np.errstate(invalid="ignore"):
        refl = (high - low) / safe * (masked - np.where(flat, 0.0, p1)) + low
    middle = 0.5 * (low + high)
    refl = np.clip(np.where(flat, middle, refl), 0.0, 1.0)
    refl = _fill_nonfinite(refl, finite, middle)
    bits = (np.where(~finite.all(axis=-1), fl.flag("image_nonfinite"), 0)
            | np.where(flat[..., 0] & (mode != "table"), fl.flag("image_flat"), 0))
    return refl, bits.astype(np.int32)


def _table_kernel(img, pixels, reflectances):
    """Reflectance by a table (pyBSM ``img_to_reflectance``): piecewise linear, clipped."""
    finite = np.isfinite(img)
    x = np.where(finite, img, pixels[0])
    refl = np.interp(x, pixels, reflectances)
    below = (reflectances[1] - reflectances[0]) / (pixels[1] - pixels[0])
    above = (reflectances[-1] - reflectances[-2]) / (pixels[-1] - pixels[-2])
    refl = np.where(x < pixels[0], reflectances[0] + below * (x - pixels[0]), refl)
    refl = np.where(x > pixels[-1], reflectances[-1] + above * (x - pixels[-1]), refl)
    refl = _fill_nonfinite(np.clip(refl, 0.0, 1.0), finite, 0.5)
    bits = np.where(~finite.all(axis=-1), fl.flag("image_nonfinite"), 0)
    return refl, bits.astype(np.int32)


def _identity_kernel(img):
    """The image is reflectance already: check [0, 1], flag and fill non-finite pixels."""
    finite = np.isfinite(img)
    with np.errstate(invalid="ignore"):
        bad = finite & ((img < 0.0) | (img > 1.0))
    if bad.any():
        raise ValueError(
            "image must hold reflectances in [0, 1] with reflectance='identity'; got values "
            f"from {np.nanmin(img[finite])!r} to {np.nanmax(img[finite])!r} (use "
            "reflectance='percentile', 'minmax' or a (pixel_values, reflectance_values) table)")
    refl = _fill_nonfinite(np.where(finite, img, 0.0), finite, 0.5)
    bits = np.where(~finite.all(axis=-1), fl.flag("image_nonfinite"), 0)
    return refl, bits.astype(np.int32)


def _flat_kernel(img, *, func, ncore, **kwargs):
    """Run a per-image kernel on (..., pixels...) by flattening the core axes."""
    shape = img.shape
    lead = shape[: img.ndim - ncore]
    refl, bits = func(img.reshape(*lead, -1), **kwargs)
    return refl.reshape(shape), bits


def _kernel_for(mapping, reflectance_range):
    """The per-image numpy kernel and its keyword arguments for a mapping choice."""
    if isinstance(mapping, str):
        if mapping == "identity":
            return _identity_kernel, {}
        low, high = reflectance_range
        return _stretch_kernel, dict(mode=mapping, low=low, high=high)
    pixels, reflectances = mapping
    if pixels.size == 2:  # pyBSM's two-point form, same arithmetic as the stretches
        return _stretch_kernel, dict(mode="table", low=reflectances[0], high=reflectances[1],
                                     pixel_low=pixels[0], pixel_high=pixels[1])
    return _table_kernel, dict(pixels=pixels, reflectances=reflectances)


@contract(reflectance=Either(IMAGE_RULES["reflectance"], Table(
    "pixel_values", "reflectance_values", Spec("1", "reflectance", **FRACTION))),
          reflectance_range=Pair(Spec("1", "reflectance", **FRACTION)))
def image_to_reflectance(image: xr.DataArray, reflectance="percentile",
                         reflectance_range=(0.05, 0.95), *, dims=("y", "x")) -> xr.Dataset:
    """Scene reflectance of each image of a stack, clipped to [0, 1].

    Parameters
    ----------
    image : xr.DataArray
        Pixel values over ``dims`` (rows, columns) and optionally a colour channel
        (any further dims are a stack of images). [any]
    reflectance : {"percentile", "minmax", "identity"} or (pixel_values, reflectance_values)
        "percentile": each image's 0.2 and 99.8 percentiles map to ``reflectance_range``
        (pyBSM ``RefImage``); "minmax": its min and max (pyBSM ``ImageSimulator`` with
        ``use_reflectance=True``); "identity": the image is reflectance, in [0, 1];
        a table: piecewise linear through the points, extrapolated (pyBSM
        ``img_to_reflectance``).
    reflectance_range : (float, float)
        Reflectances of the two pixel values of "percentile" and "minmax". [1]
    dims : sequence of str
        The per-image dims over which percentiles and extremes are taken (add the colour
        dim: pyBSM takes them over every channel together).

    Returns
    -------
    xr.Dataset
        ``reflectance`` [1] like ``image``; ``flags`` per image (``image_nonfinite``:
        NaN or infinite pixels, set to the image's mean reflectance; ``image_flat``: a
        flat image, mapped to the middle of ``reflectance_range``).
    """
    func, kwargs = _kernel_for(reflectance, reflectance_range)
    dims = list(dims)
    image = image.astype(float)
    if image.chunks is not None:
        image = image.chunk({d: -1 for d in dims})
    refl, bits = xr.apply_ufunc(
        _flat_kernel, image, kwargs={"func": func, "ncore": len(dims), **kwargs},
        input_core_dims=[dims], output_core_dims=[dims, []], dask="parallelized",
        output_dtypes=[float, np.int32])
    return xr.Dataset({
        "reflectance": named(refl, "1", "scene reflectance"),
        "flags": bits.assign_attrs(fl.flag_attrs("image validity flags")),
    })
