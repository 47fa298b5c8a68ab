"""Images in, for the measurements: DataArrays over (..., y, x), regions, finite values."""

from __future__ import annotations

import numpy as np
import xarray as xr

IMAGE_DIMS = frozenset({"y", "x"})


def as_image(image, name):
    """``image`` as a DataArray over (..., y, x); numpy leading axes become dim_0, ..."""
    if isinstance(image, xr.DataArray):
        if not IMAGE_DIMS <= set(image.dims):
            raise ValueError(f"{name} must have dimensions 'y' and 'x'; got {image.dims}")
        image = image.transpose(..., "y", "x")
    else:
        arr = np.asarray(image)
        if arr.ndim < 2:
            raise ValueError(f"{name} must be 2-D over (y, x), with optional leading "
                             f"dimensions; got shape {arr.shape}")
        image = xr.DataArray(arr, dims=tuple(f"dim_{i}" for i in range(arr.ndim - 2))
                             + ("y", "x"))
    if image.dtype.kind not in "biuf":
        raise ValueError(f"{name} must hold real numbers; got dtype {image.dtype}")
    return image


def select(image, region, name):
    """The part of ``image`` inside ``region`` (positional slices over y and x)."""
    if region is None:
        return image
    if isinstance(region, dict) and set(region) <= IMAGE_DIMS:
        return image.isel(region)
    if isinstance(region, tuple) and len(region) == 2:
        return image.isel(y=region[0], x=region[1])
    raise ValueError(f"{name} must be None, a (rows, columns) pair of slices or a dict with "
                     f"keys 'y' and 'x'; got {region!r}")


def finite_values(image, name):
    """The pixel values as floats; a ValueError naming any NaN or infinite pixel."""
    values = np.asarray(image.values, dtype=float)
    bad = np.size(values) - np.count_nonzero(np.isfinite(values))
    if bad:
        raise ValueError(f"{name} has {bad} NaN or infinite pixels; every pixel of the "
                         "region must be finite")
    return values


def units_of(image):
    """The ``units`` attribute of an image, ``"1"`` if it has none."""
    return str(image.attrs.get("units", "1"))


def lead_coords(image):
    """The coordinates of ``image`` that do not run along y or x (kept by every result)."""
    return {k: c for k, c in image.coords.items() if not IMAGE_DIMS & set(c.dims)}
