"""Back from photoelectrons: reflectance, display pixels, Wiener restoration, 8-bit stretch.

pyBSM 0.16.1's reverse pass (``ImageSimulator.photoelectrons_to_reflectance`` and
``photoelectrons_to_pixels``) and its ``wiener_filter`` and
``stretch_contrast_convert_8bit``. The photoelectron count is affine in
reflectance (paper Eq. 1), so its inverse is exact: the offset and gain of each
scenario are in the :func:`xbsm.simulate_image` result.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from .._metadata import Output
from ..params import Choice, Pair, Spec, Values, contract

__all__ = ["photoelectrons_to_reflectance", "photoelectrons_to_pixels", "wiener_filter",
           "stretch_contrast_8bit"]


@contract(Output("reflectance", "1", "scene reflectance"))
def photoelectrons_to_reflectance(photoelectrons: xr.DataArray, simulation: xr.Dataset, *,
                                  clip=True) -> xr.DataArray:
    """Scene reflectance that gives these photoelectrons in the simulation's radiometry.

    Parameters
    ----------
    photoelectrons : xr.DataArray
        Photoelectrons per pixel (``blurred`` or ``noisy``). [count]
    simulation : xr.Dataset
        From :func:`xbsm.simulate_image` (``photoelectron_offset``, ``photoelectron_gain``).
    clip : bool
        Clip to [0, 1] (noise and blur overshoot leave it).

    Returns
    -------
    xr.DataArray
        (N - offset) / gain. [1]
    """
    for name in ("photoelectron_offset", "photoelectron_gain"):
        if name not in simulation:
            raise ValueError(f"simulation must be the Dataset of xbsm.simulate_image (no {name})")
    gain = simulation["photoelectron_gain"]
    with np.errstate(divide="ignore", invalid="ignore"):
        out = (photoelectrons - simulation["photoelectron_offset"]) / gain.where(gain > 0)
    if clip:
        out = out.clip(0.0, 1.0)
    return out


def _minmax_kernel(img, low, high):
    """Each image's finite min and max to [low, high]; a flat image to the middle."""
    flat = img.reshape(*img.shape[:-2], -1)
    finite = np.isfinite(flat)
    some = finite.any(axis=-1)
    lo = np.where(some, np.min(np.where(finite, flat, np.inf), axis=-1), 0.0)[..., None, None]
    hi = np.where(some, np.max(np.where(finite, flat, -np.inf), axis=-1), 0.0)[..., None, None]
    span = hi - lo
    with np.errstate(invalid="ignore"):
        out = (img - lo) / np.where(span > 0, span, 1.0) * (high - low) + low
    out = np.where(span > 0, np.clip(out, low, high), 0.5 * (low + high))
    return np.where(np.isfinite(img), out, np.nan)


@contract(Output("pixels", "1", "display pixel value"),
          mode=Choice(("radiometric", "minmax")), pixel_range=Pair(Spec("1", "pixel value")),
          reflectance_range=Pair(Spec("1", "reflectance")))
def photoelectrons_to_pixels(photoelectrons: xr.DataArray, simulation: xr.Dataset | None = None,
                             *, mode="radiometric", pixel_range=(0.0, 255.0),
                             reflectance_range=(0.05, 0.95), dims=("y", "x")) -> xr.DataArray:
    """Display pixel values of photoelectron images.

    Parameters
    ----------
    photoelectrons : xr.DataArray
        Images over ``dims``. [count]
    simulation : xr.Dataset, optional
        From :func:`xbsm.simulate_image`; needed by "radiometric".
    mode : {"radiometric", "minmax"}
        "radiometric": through reflectance (:func:`photoelectrons_to_reflectance`), with
        ``reflectance_range`` mapped to ``pixel_range``: comparable across sensors (pyBSM's
        default); "minmax": each image's own min and max to ``pixel_range`` (a flat image to
        its middle).
    pixel_range : (float, float)
        Output pixel values of the two ends. [1]
    reflectance_range : (float, float)
        Reflectances mapped to the ends of ``pixel_range`` ("radiometric"). [1]
    dims : (str, str)
        Row and column dims.

    Returns
    -------
    xr.DataArray
        Pixel values clipped to ``pixel_range``; NaN stays NaN. [1]
    """
    low, high = pixel_range
    if mode == "minmax":
        out = xr.apply_ufunc(_minmax_kernel, photoelectrons, kwargs={"low": low, "high": high},
                             input_core_dims=[list(dims)], output_core_dims=[list(dims)],
                             dask="parallelized", output_dtypes=[float])
    elif mode == "radiometric":
        if simulation is None:
            raise ValueError("mode='radiometric' needs the simulation (its radiometry)")
        r1, r2 = reflectance_range
        refl = photoelectrons_to_reflectance(photoelectrons, simulation)
        out = ((refl - r1) / (r2 - r1) * (high - low) + low).clip(low, high)
    return out


@contract(Output("wiener_filter", "1", "Wiener restoration filter"),
          noise_to_signal=Values(Spec("1", "noise-to-signal power ratio", low=0.0)))
def wiener_filter(otf, noise_to_signal, *, normalize=True):
    r"""Wiener restoration filter of an OTF (Gonzalez and Woods, Digital Image Processing).

    Parameters
    ----------
    otf : xr.DataArray
        System OTF. [1]
    noise_to_signal : float or xr.DataArray
        Noise-to-signal power spectrum ratio, >= 0 (a scalar or per frequency). [1]
    normalize : bool
        Multiply by (1 + noise_to_signal), so that the filter is 1 at zero frequency where
        the OTF is 1; pyBSM's ``wiener_filter`` is not normalised (``normalize=False``).

    Returns
    -------
    xr.DataArray
        The filter's transfer function, complex. [1]

    Notes
    -----
    .. math:: W = \frac{H^*}{|H|^2 + S_n / S_f}
    """
    out = np.conj(otf) / (np.abs(otf) ** 2 + noise_to_signal)
    if normalize:
        out = out * (1.0 + noise_to_signal)
    return out


def _stretch_kernel(img, low, high):
    flat = img.reshape(*img.shape[:-2], -1)
    finite = np.isfinite(flat)
    safe = np.where(finite.any(axis=-1, keepdims=True), np.where(finite, flat, np.nan), 0.0)
    p1 = np.nanpercentile(safe, low, axis=-1)[..., None, None]
    shifted = img - p1
    p2 = np.nanpercentile(safe - p1[..., 0], high, axis=-1)[..., None, None]
    with np.errstate(invalid="ignore", divide="ignore"):
        scaled = shifted / np.where(p2 > 0, p2 / 255.0, np.inf)
    return np.round(np.clip(np.nan_to_num(scaled, nan=0.0), 0, 255)).astype(np.uint8)


@contract(Output("pixels", "1", "contrast-stretched 8-bit image"))
def stretch_contrast_8bit(image: xr.DataArray, percentiles=(0.1, 99.9), dims=("y", "x")):
    """Images contrast-stretched between two percentiles to 8-bit (pyBSM's stretch).

    Parameters
    ----------
    image : xr.DataArray
        Images over ``dims``. [any]
    percentiles : (float, float)
        Lower and upper percentiles, mapped to 0 and 255. [%]
    dims : (str, str)
        Row and column dims.

    Returns
    -------
    xr.DataArray
        uint8 values, rounded; NaN pixels and flat images give 0. [1]
    """
    low, high = (float(p) for p in percentiles)
    if not 0 <= low < high <= 100:
        raise ValueError(f"percentiles must satisfy 0 <= low < high <= 100; got {percentiles!r}")
    if image.chunks is not None:
        image = image.chunk({d: -1 for d in dims})
    out = xr.apply_ufunc(_stretch_kernel, image, kwargs={"low": low, "high": high},
                         input_core_dims=[list(dims)], output_core_dims=[list(dims)],
                         dask="parallelized", output_dtypes=[np.uint8])
    return out
