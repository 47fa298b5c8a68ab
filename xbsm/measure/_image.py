"""Images in, for the measurements: DataArrays over (..., y, x), regions, values, flags."""

from __future__ import annotations

from types import MappingProxyType

import numpy as np
import xarray as xr

IMAGE_DIMS = frozenset({"y", "x"})

PIXEL_UNITS = ("1", "pixel", "pixels")
"""Units of a ``y`` / ``x`` coordinate that counts pixels (its step must be 1)."""

# bit -> (meaning, description); bits above xbsm.flags.FLAGS', so the two never collide
FLAGS = MappingProxyType({
    "edge_clipped": (
        1 << 28,
        "slanted edge clipped: in at least half of the rows a pixel within the edge's "
        "10-90 % rise of the fitted edge sits at the region's minimum or maximum, or at the "
        "limits of an integer dtype; the measured MTF is too high (a sharpened edge)",
    ),
    "region_not_flat": (
        1 << 29,
        "flat_noise region not flat: a plane (without detrend) or a step along a row or a "
        "column holds more than 10 % of the residual variance (and more than 40 / N), so the "
        "noise is overestimated",
    ),
})


def flag(name):
    """The bit of the measurement flag called ``name`` (:data:`FLAGS`)."""
    return FLAGS[name][0]


def flags_variable(bits, dims, coords, long_name):
    """An int32 flag variable with CF ``flag_masks`` / ``flag_meanings``."""
    return xr.DataArray(np.asarray(bits, dtype=np.int32), dims=dims, coords=coords, attrs={
        "long_name": long_name, "units": "1",
        "flag_masks": np.array([bit for bit, _ in FLAGS.values()], dtype=np.int32),
        "flag_meanings": " ".join(FLAGS)})


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


def _check_pixel_steps(image):
    """Refuse an image whose pixel-index coordinates show that it was strided (decimated)."""
    for dim in ("y", "x"):
        coord = image.coords.get(dim)
        if coord is None or coord.size < 2 or coord.dtype.kind not in "iuf":
            continue
        if coord.dtype.kind == "f" and str(coord.attrs.get("units")) not in PIXEL_UNITS:
            continue
        steps = np.unique(np.abs(np.diff(np.asarray(coord.values, dtype=float))))
        if steps.size == 1 and steps[0] > 1:
            raise ValueError(
                f"image's {dim!r} coordinate steps by {steps[0]:g} pixels: a strided view "
                "of an image is a decimated image; use the full-resolution pixels "
                "(select a region with unit steps)")


def select(image, region, name):
    """The part of ``image`` inside ``region`` (positional slices over y and x)."""
    _check_pixel_steps(image)
    if region is None:
        return image
    if isinstance(region, dict) and set(region) <= IMAGE_DIMS:
        slices = dict(region)
    elif isinstance(region, tuple) and len(region) == 2:
        slices = {"y": region[0], "x": region[1]}
    else:
        raise ValueError(f"{name} must be None, a (rows, columns) pair of slices or a dict "
                         f"with keys 'y' and 'x'; got {region!r}")
    for dim, part in slices.items():
        if isinstance(part, slice):
            step = part.step
        else:  # positions: contiguous, in either direction
            steps = np.unique(np.abs(np.diff(np.ravel(part)))) if np.size(part) > 1 else [1]
            step = None if list(steps) == [1] else ", ".join(map(str, steps[:3]))
        if step not in (None, 1, -1):
            raise ValueError(f"{name} must select contiguous pixels: slices with step 1; got "
                             f"step {step} along {dim!r} (a strided region decimates the "
                             "image)")
    return image.isel(slices)


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
