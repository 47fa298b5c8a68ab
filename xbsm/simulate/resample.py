"""Resampling the blurred reference image onto the camera's pixels (paper Eq. 5, R).

Every rule is separable and written as a small table of taps per output pixel
(input index and weight, along y and along x), built from the pixel map of
:func:`xbsm.simulate.sampling.sampling`; one numpy kernel applies the tables to a
stack of images. Output pixels past a scenario's own size are NaN (a sweep's
images share one array, sized for the largest).

- "cubic" (default): Keys cubic convolution (a = -1/2) at each output pixel
  centre, reflect at the borders. The detector footprint is already in the blur
  (the detector OTF), so the camera's sampling is a point sampling of the blurred
  image; an antialiasing filter here would blur twice.
- "area": the mean of the reference over each output pixel's footprint (a box
  detector, for blurs without the detector OTF).
- "pil": Pillow's ``Image.resize(..., BILINEAR)`` in float32 (pyBSM's
  ``ImageSimulator``): a triangle filter stretched by the reduction factor.
- "zoom": ``scipy.ndimage.zoom(order=1, grid_mode=True, mode="grid-constant")``
  (pyBSM's ``resample_2D``): zero outside the image, so borders darken when
  upsampling.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from ._arrays import align_leading
from .convolve import cropped_inverse, padded_spectrum

__all__ = ["apply_taps", "blur_and_resample", "cell_key", "reflect_index", "resample",
           "resampling_taps"]


def reflect_index(index, n: int):
    """Whole-sample reflection of integer indices into [0, n - 1]."""
    if n == 1:
        return np.zeros_like(index)
    period = 2 * (n - 1)
    index = np.abs(index) % period
    return np.where(index >= n, period - index, index)


def _keys(t):
    """Keys cubic-convolution weights (a = -1/2) of the taps at -1, 0, 1, 2 for fraction t."""
    return np.stack([((-0.5 * t + 1.0) * t - 0.5) * t,
                     (1.5 * t - 2.5) * t * t + 1.0,
                     ((-1.5 * t + 2.0) * t + 0.5) * t,
                     (0.5 * t - 0.5) * t * t], axis=-1)


def _cubic(n_in, centre):
    u = centre - 0.5
    first = np.floor(u)
    index = first[:, None].astype(np.int64) + np.arange(-1, 3)
    return reflect_index(index, n_in), _keys(u - first)


def _area(n_in, lower, upper):
    width = int(np.ceil(np.max(upper - lower))) + 2
    index = np.floor(lower)[:, None].astype(np.int64) + np.arange(width)
    overlap = np.clip(np.minimum(index + 1, upper[:, None]) - np.maximum(index, lower[:, None]),
                      0.0, None)
    return reflect_index(index, n_in), overlap / (upper - lower)[:, None]


def _pil(n_in, n_out):
    """Pillow's bilinear resize coefficients (its precompute_coeffs, support 1)."""
    scale = n_in / n_out
    stretch = max(scale, 1.0)
    support = stretch
    centre = (np.arange(n_out) + 0.5) * scale
    low = np.maximum(np.trunc(centre - support + 0.5), 0).astype(np.int64)
    high = np.minimum(np.trunc(centre + support + 0.5), n_in).astype(np.int64)
    width = int(np.ceil(support)) * 2 + 1
    index = low[:, None] + np.arange(width)
    weight = np.clip(1.0 - np.abs((index - centre[:, None] + 0.5) * (1.0 / stretch)), 0.0, None)
    weight = np.where(index < high[:, None], weight, 0.0)
    total = weight.sum(axis=1, keepdims=True)
    weight = np.where(total != 0, weight / np.where(total != 0, total, 1.0), 0.0)
    return np.minimum(index, n_in - 1), weight


def _zoom(n_in, n_out):
    """Taps of scipy's order-1 zoom with grid_mode=True: zero beyond the edge samples."""
    u = (np.arange(n_out) + 0.5) * (n_in / n_out) - 0.5
    first = np.floor(u)
    index = first[:, None].astype(np.int64) + np.arange(2)
    frac = u - first
    weight = np.stack([1.0 - frac, frac], axis=-1)
    inside = (index >= 0) & (index < n_in)
    return np.clip(index, 0, n_in - 1), np.where(inside, weight, 0.0)


def _axis_taps(kind, n_in, n_out, scale, offset):
    """Taps (index, weight) of one axis of one scenario; rows are output pixels."""
    if kind == "cubic":
        return _cubic(n_in, (np.arange(n_out) + 0.5 - offset) / scale)
    if kind == "area":
        edges = (np.arange(n_out + 1) - offset) / scale
        return _area(n_in, edges[:-1], edges[1:])
    if kind == "pil":
        return _pil(n_in, n_out)
    if kind == "zoom":
        return _zoom(n_in, n_out)
    index = np.arange(n_out)[:, None]  # "none": the identity
    return index, np.ones(index.shape)


def _stack_taps(tables, rows):
    """One array of taps for every scenario: padded rows get a NaN weight (NaN pixels)."""
    width = max(index.shape[1] for index, _ in tables)
    index = np.zeros((len(tables), rows, width), dtype=np.int64)
    weight = np.zeros((len(tables), rows, width))
    weight[:, :, 0] = np.nan
    for i, (idx, w) in enumerate(tables):
        index[i, : idx.shape[0], : idx.shape[1]] = idx
        weight[i, : w.shape[0], :] = 0.0
        weight[i, : w.shape[0], : w.shape[1]] = w
    return index, weight


def resampling_taps(sampling: xr.Dataset, shape, kind: str) -> xr.Dataset:
    """Tap tables of a resampling rule for every scenario of a :func:`sampling` result.

    Parameters
    ----------
    sampling : xr.Dataset
        From :func:`xbsm.simulate.sampling.sampling` (``size_*``, ``scale_*``, ``offset_*``).
    shape : (int, int)
        Rows and columns of the reference image.
    kind : {"cubic", "area", "pil", "zoom", "none"}
        The resampling rule.

    Returns
    -------
    xr.Dataset
        ``index_y``, ``weight_y`` over (scenario dims, ``y``, ``tap_y``) and ``index_x``,
        ``weight_x`` over (scenario dims, ``x``, ``tap_x``): output pixel = sum over taps
        of weight times reference pixel at index (y first, then x). [1]
    """
    dims = sampling["size_y"].dims
    cells = list(np.ndindex(sampling["size_y"].shape))
    out = {}
    for axis, n_in in (("y", shape[0]), ("x", shape[1])):
        size, scale, offset = (sampling[f"{name}_{axis}"].values for name in
                               ("size", "scale", "offset"))
        rows = int(size.max())
        tables = [_axis_taps(kind, n_in, int(size[c]), float(scale[c]), float(offset[c]))
                  for c in cells]
        index, weight = _stack_taps(tables, rows)
        tail = (axis, f"tap_{axis}")
        shape_out = (*sampling["size_y"].shape, *index.shape[1:])
        coords = {d: sampling[d] for d in dims if d in sampling.coords}
        out[f"index_{axis}"] = xr.DataArray(index.reshape(shape_out), dims=(*dims, *tail),
                                            coords=coords)
        out[f"weight_{axis}"] = xr.DataArray(weight.reshape(shape_out), dims=(*dims, *tail),
                                             coords=coords, attrs={"units": "1",
                                                                   "long_name": "tap weight"})
        out[f"index_{axis}"].attrs.update(units="1", long_name="reference pixel index of a tap")
    return xr.Dataset(out)


def apply_taps(img, index_y, weight_y, index_x, weight_x, single=False):
    """Resample (..., rows, columns) by tap tables; ``single``: float32 passes (Pillow)."""
    img, index_y, weight_y, index_x, weight_x = align_leading(
        img, 2, index_y, 2, weight_y, 2, index_x, 2, weight_x, 2)
    dtype = np.float32 if single else np.float64
    img = img.astype(dtype)
    rows = 0.0
    for t in range(index_x.shape[-1]):
        taps = np.take_along_axis(img, index_x[..., None, :, t], axis=-1)
        rows = rows + weight_x[..., None, :, t] * taps
    rows = np.asarray(rows, dtype=dtype)
    out = 0.0
    for t in range(index_y.shape[-1]):
        taps = np.take_along_axis(rows, index_y[..., :, t, None], axis=-2)
        out = out + weight_y[..., :, t, None] * taps
    return np.asarray(out, dtype=dtype).astype(np.float64)


def resample(image: xr.DataArray, taps: xr.Dataset, dims=("y_input", "x_input"),
             single=False) -> xr.DataArray:
    """Resample images onto the camera's pixels with :func:`resampling_taps` tables.

    Parameters
    ----------
    image : xr.DataArray
        Images over ``dims`` (rows, columns); other dims broadcast against the taps'. [any]
    taps : xr.Dataset
        From :func:`resampling_taps`.
    dims : (str, str)
        The image's row and column dims.
    single : bool
        Round to float32 after each pass (Pillow's "F" images, pyBSM's ``ImageSimulator``).

    Returns
    -------
    xr.DataArray
        Over (broadcast dims, ``y``, ``x``), NaN past each scenario's own size; the
        input's units. [any]
    """
    if image.chunks is not None:
        image = image.chunk({d: -1 for d in dims})
    sizes = {"y": taps.sizes["y"], "x": taps.sizes["x"]}
    out = xr.apply_ufunc(
        apply_taps, image, taps["index_y"], taps["weight_y"], taps["index_x"],
        taps["weight_x"], kwargs={"single": single},
        input_core_dims=[list(dims), ["y", "tap_y"], ["y", "tap_y"], ["x", "tap_x"],
                         ["x", "tap_x"]],
        output_core_dims=[["y", "x"]], dask="parallelized", output_dtypes=[float],
        dask_gufunc_kwargs={"output_sizes": sizes})
    return out.assign_attrs(image.attrs)


def cell_key(cell, cells, shape):
    """Index of one scenario cell into an array of ``shape`` (size-1 dims broadcast)."""
    return tuple((i if n > 1 else 0) if m > 1 else slice(None)
                 for i, m, n in zip(cell, cells, shape, strict=True))


def _blur_resample_kernel(img, otf, index_y, weight_y, index_x, weight_x, pad, size_x):
    """Blur by the OTF and resample, one scenario cell at a time (the image FFT once)."""
    img, otf, index_y, weight_y, index_x, weight_x = align_leading(
        img, 2, otf, 2, index_y, 2, weight_y, 2, index_x, 2, weight_x, 2)
    spectrum = padded_spectrum(img, pad, otf.shape[-2], size_x)
    tables = (index_y, weight_y, index_x, weight_x)
    cells = np.broadcast_shapes(otf.shape[:-2], *(t.shape[:-2] for t in tables))
    lead = np.broadcast_shapes(img.shape[:-2], cells)
    out = np.empty(lead + (index_y.shape[-2], index_x.shape[-2]))
    for cell in np.ndindex(cells):
        part = spectrum[cell_key(cell, cells, spectrum.shape[:-2])]
        part = part * otf[cell_key(cell, cells, otf.shape[:-2])]
        blurred = cropped_inverse(part, pad, img.shape[-2:], size_x)
        taps = [t[cell_key(cell, cells, t.shape[:-2])] for t in tables]
        out[cell_key(cell, cells, lead)] = apply_taps(blurred, *taps)
    return out


def blur_and_resample(image: xr.DataArray, otf: xr.DataArray, pad: int, size_x: int,
                      taps: xr.Dataset, dims=("y_input", "x_input")) -> xr.DataArray:
    """:func:`xbsm.simulate.convolve.blur_by_otf` then :func:`resample`, fused.

    The image's transform is computed once and each scenario's blurred image exists
    only while it is resampled, so a sweep never holds every blurred reference at once.

    Parameters
    ----------
    image : xr.DataArray
        Images over ``dims``. [any]
    otf : xr.DataArray
        From :func:`xbsm.simulate.psf.otf_rfft_grid`. [1]
    pad, size_x : int
        As for :func:`xbsm.simulate.convolve.blur_by_otf`.
    taps : xr.Dataset
        From :func:`resampling_taps`.
    dims : (str, str)
        The image's row and column dims.

    Returns
    -------
    xr.DataArray
        Over (broadcast dims, ``y``, ``x``), NaN past each scenario's size. [any]
    """
    if image.chunks is not None:
        image = image.chunk({d: -1 for d in dims})
    sizes = {"y": taps.sizes["y"], "x": taps.sizes["x"]}
    out = xr.apply_ufunc(
        _blur_resample_kernel, image, otf, taps["index_y"], taps["weight_y"],
        taps["index_x"], taps["weight_x"], kwargs={"pad": pad, "size_x": size_x},
        input_core_dims=[list(dims), ["fy", "fx"], ["y", "tap_y"], ["y", "tap_y"],
                         ["x", "tap_x"], ["x", "tap_x"]],
        output_core_dims=[["y", "x"]], dask="parallelized", output_dtypes=[float],
        dask_gufunc_kwargs={"output_sizes": sizes})
    return out.assign_attrs(image.attrs)
