"""The camera's steps after sampling: noise, the digital filter, the ADC.

Noise is drawn from numpy's ``Generator`` with one stream per image: the seed
and the image's position in the broadcast result (scenario cell and stack
index) make a ``np.random.SeedSequence`` spawn key, so a seed gives the same
images eagerly and with any dask chunking, and every image of a sweep gets
independent noise.
"""

from __future__ import annotations

import math
import numbers

import numpy as np
import xarray as xr
from scipy.ndimage import convolve

from .. import noise as noise_terms
from .._metadata import Output
from ..params import contract
from ._arrays import align_leading

__all__ = ["add_noise", "digital_filter", "digitize", "seed_entropy"]

_STRIP = 1 << 20
"""Pixels per strip of the noise draws (their temporaries are strip-sized)."""


def seed_entropy(seed) -> int:
    """The entropy of a seed: a non-negative whole number, or fresh entropy for ``None``."""
    if seed is None:
        return int(np.random.SeedSequence().entropy)
    if isinstance(seed, bool) or not isinstance(seed, numbers.Integral) or seed < 0:
        raise ValueError(f"seed must be None or a non-negative whole number; got {seed!r}")
    return int(seed)


def _noise_kernel(mean, sigma, ids, entropy):
    """Poisson shot noise plus Gaussian noise, one seeded stream per image (last 2 axes).

    ``entropy``: one seed's entropy for all, or an array of them (one per image,
    broadcast like ``ids``).
    """
    mean, sigma, ids, entropy = align_leading(mean, 2, sigma, 0, ids, 0, entropy, 0)
    lead = np.broadcast_shapes(mean.shape[:-2], np.shape(sigma), np.shape(ids),
                               np.shape(entropy))
    mean = np.broadcast_to(mean, lead + mean.shape[-2:])
    sigma, ids = np.broadcast_to(sigma, lead), np.broadcast_to(ids, lead)
    entropy = np.broadcast_to(entropy, lead)
    out = np.empty(mean.shape)
    for index in np.ndindex(lead):
        rng = np.random.default_rng(np.random.SeedSequence(int(entropy[index]),
                                                           spawn_key=(int(ids[index]),)))
        lam, draw = mean[index], out[index]
        # in strips of rows: the generator's stream is sequential, so the draws are those
        # of one call over the whole image (all Poisson, then all normal), to the bit
        rows = max(1, _STRIP // max(1, lam.shape[-1]))
        strips = [slice(start, start + rows) for start in range(0, lam.shape[-2], rows)]
        for part in strips:
            valid = np.isfinite(lam[part])
            rate = np.where(valid, np.maximum(lam[part], 0.0), 0.0)
            draw[part] = rng.poisson(rate) + np.minimum(np.where(valid, lam[part], 0.0), 0.0)
        for part in strips:
            noisy = draw[part] + rng.normal(0.0, float(sigma[index]), lam[part].shape)
            draw[part] = np.where(np.isfinite(lam[part]), noisy, np.nan)
    return out


def _gaussian_sigma(sensor, quantization):
    s = sensor
    if quantization == "pybsm":  # pyBSM: sqrt(quantization^2 + read^2), no other noise
        q = noise_terms.quantization_noise(s["max_well"], s["bit_depth"])
        return np.sqrt(q**2 + s["read_noise"] ** 2)
    return np.sqrt(s["read_noise"] ** 2 + s["other_noise"] ** 2)


@contract(Output("noisy", "count", "photoelectrons with noise"))
def add_noise(photoelectrons: xr.DataArray, sensor: xr.Dataset, *, seed=None,
              quantization="round", dims=("y", "x")) -> xr.DataArray:
    """Photoelectron images with shot, dark-current, read and other noise.

    Parameters
    ----------
    photoelectrons : xr.DataArray
        Mean photoelectrons per pixel (dark current included), over ``dims``; NaN
        pixels stay NaN. [count]
    sensor : xr.Dataset
        ``read_noise``, ``other_noise`` (and ``max_well``, ``bit_depth``). [count]
    seed : int or xr.DataArray, optional
        Seed; ``None`` draws fresh entropy. A DataArray of seeds (non-negative whole
        numbers) gives every image along its dims its own seed, as if each
        were drawn alone: the stream of an image is then numbered by its position
        along the other dims only.
    quantization : {"round", "pybsm"}
        "pybsm" adds the quantization noise max_well / (sqrt(12) (2^b - 1)) as Gaussian
        noise too (with the read noise, without other noise), as pyBSM.
    dims : (str, str)
        Row and column dims.

    Returns
    -------
    xr.DataArray
        Poisson(mean) plus Normal(0, sigma) per pixel, sigma the root-sum-square of
        the Gaussian terms; one independent stream per image. [count]
    """
    sigma = _gaussian_sigma(sensor, quantization)
    lead = xr.broadcast(photoelectrons.isel({d: 0 for d in dims}, drop=True), sigma)[0]
    if isinstance(seed, xr.DataArray):  # a seed per image: streams numbered without its dims
        entropy = xr.DataArray(np.vectorize(seed_entropy, otypes=[object])(seed.values),
                               dims=seed.dims)
        lead = lead.isel({d: 0 for d in seed.dims if d in lead.dims}, drop=True)
    else:
        entropy = xr.DataArray(np.array(seed_entropy(seed), dtype=object))
    ids = xr.DataArray(np.arange(math.prod(lead.shape)).reshape(lead.shape), dims=lead.dims)
    if photoelectrons.chunks is not None:
        photoelectrons = photoelectrons.chunk({d: -1 for d in dims})
    out = xr.apply_ufunc(
        _noise_kernel, photoelectrons, sigma, ids, entropy,
        input_core_dims=[list(dims), [], [], []], output_core_dims=[list(dims)],
        dask="parallelized", output_dtypes=[float])
    return out


def _filter_kernel(img, size_y, size_x, kernel):
    """The kernel convolved over each image's valid (size_y x size_x) part, mirror borders."""
    img, size_y, size_x = align_leading(img, 2, size_y, 0, size_x, 0)
    lead = np.broadcast_shapes(img.shape[:-2], np.shape(size_y), np.shape(size_x))
    img = np.broadcast_to(img, lead + img.shape[-2:])
    size_y, size_x = np.broadcast_to(size_y, lead), np.broadcast_to(size_x, lead)
    out = np.full(img.shape, np.nan)
    for index in np.ndindex(lead):
        rows, cols = int(size_y[index]), int(size_x[index])
        out[index][:rows, :cols] = convolve(img[index][:rows, :cols], kernel, mode="mirror")
    return out


def digital_filter(image: xr.DataArray, kernel, size_y, size_x, dims=("y", "x")):
    """Images filtered by a post-processing kernel on the camera's own pixels.

    Parameters
    ----------
    image : xr.DataArray
        Images over ``dims``, NaN past each one's ``size_y`` x ``size_x``. [any]
    kernel : array_like or xr.DataArray
        2-D kernel, rows along y (``scipy.ndimage.convolve``'s centring: the OTF is
        :func:`xbsm.otf.filters.sharpening_filter`). [1]
    size_y, size_x : int or xr.DataArray
        Valid rows and columns per image. [1]
    dims : (str, str)
        Row and column dims.

    Returns
    -------
    xr.DataArray
        The filtered images, mirror borders at each image's own edge, NaN padding kept.
        [any]
    """
    kernel = np.asarray(getattr(kernel, "values", kernel), dtype=float)
    if image.chunks is not None:
        image = image.chunk({d: -1 for d in dims})
    out = xr.apply_ufunc(
        _filter_kernel, image, size_y, size_x, kwargs={"kernel": kernel},
        input_core_dims=[list(dims), [], []], output_core_dims=[list(dims)],
        dask="parallelized", output_dtypes=[float])
    return out.assign_attrs(image.attrs)


def _adc_kernel(pe, well, levels, mode):
    with np.errstate(invalid="ignore"):
        if mode == "pybsm":  # pyBSM's ADC: the fraction of the well, floored
            return np.floor(np.clip(pe, 0.0, well) / well * levels)
        return np.clip(np.round(pe / well * levels), 0.0, np.floor(levels))


@contract(Output("counts", "1", "digital counts"))
def digitize(photoelectrons: xr.DataArray, sensor: xr.Dataset, quantization="round"):
    """Digital counts of the analog-to-digital converter.

    Parameters
    ----------
    photoelectrons : xr.DataArray
        Photoelectrons per pixel. [count]
    sensor : xr.Dataset
        ``max_well`` (full scale) and ``bit_depth``.
    quantization : {"round", "pybsm"}
        "round": round(N / max_well (2^b - 1)), clipped to [0, 2^b - 1]; "pybsm":
        floor of the fraction of the well clipped to [0, 1] (pyBSM's ADC).

    Returns
    -------
    xr.DataArray
        Digital numbers (floats, NaN where the input is). [1]
    """
    levels = 2.0 ** sensor["bit_depth"] - 1.0
    out = xr.apply_ufunc(_adc_kernel, photoelectrons, sensor["max_well"], levels,
                         kwargs={"mode": quantization}, dask="parallelized",
                         output_dtypes=[float])
    return out
