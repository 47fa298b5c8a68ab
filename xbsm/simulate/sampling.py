"""Where the camera's pixels fall on the reference image: sample angles, sizes, the pixel map.

Coordinates are continuous pixel coordinates with pixel ``i`` covering ``[i, i + 1)``
(its centre at ``i + 0.5``: the convention of OpenCV, Pillow and most box formats).
A reference pixel coordinate ``u`` maps to the output coordinate
``scale * u + offset`` along each axis; the resampling kernels use exactly this map,
so points and boxes moved by :mod:`xbsm.simulate.labels` stay on their features.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from .. import flags as fl
from .. import geometry
from .._metadata import named
from .options import ImageMethod

__all__ = ["sampling"]

MAX_OUTPUT_PIXELS = 1 << 26
"""Most pixels one simulated image may have (a guard against a mistyped GSD)."""


def _slant_range(scenario, im: ImageMethod):
    if im.viewing == "pybsm":  # pyBSM's image simulation: flat earth
        out = np.sqrt(scenario["altitude"] ** 2 + scenario["ground_range"] ** 2)
        return named(out, "m", "slant range (flat earth, pyBSM image simulation)")
    return geometry.slant_range(scenario["ground_range"], scenario["altitude"],
                                form=im.model.geometry)


def _output_angles(sensor, scenario, gsd, im: ImageMethod):
    """Angular output sample spacing along y and x, in rad."""
    if im.basis == "ground-angle":
        angle = gsd / scenario["altitude"]
        return angle, angle
    if im.viewing == "pybsm":  # pyBSM: the mean pitch for both axes
        mean = (sensor["pixel_pitch_x"] + sensor["pixel_pitch_y"]) / 2 / sensor["focal_length"]
        return mean, mean
    return (sensor["pixel_pitch_y"] / sensor["focal_length"],
            sensor["pixel_pitch_x"] / sensor["focal_length"])


def _round_half_even(x):
    return np.round(x).astype(np.int64)


def _axis_map(n_y: int, n_x: int, ratio_y, ratio_x, resampling: str):
    """Output sizes and the map's scales and offsets, per axis, for one resampling rule.

    ``ratio`` is reference sample angle over output sample angle (output pixels per
    reference pixel).
    """
    if resampling == "none":
        one = np.ones_like(ratio_x)
        return (np.full_like(ratio_y, n_y, dtype=np.int64),
                np.full_like(ratio_x, n_x, dtype=np.int64), one, one, 0 * one, 0 * one)
    if resampling in ("cubic", "area"):  # the camera's own pitch, centred on the image
        size_y = np.maximum(1, np.floor(n_y * ratio_y + 1e-9)).astype(np.int64)
        size_x = np.maximum(1, np.floor(n_x * ratio_x + 1e-9)).astype(np.int64)
        return (size_y, size_x, ratio_y, ratio_x,
                (size_y - ratio_y * n_y) / 2, (size_x - ratio_x * n_x) / 2)
    new_y = np.maximum(1, _round_half_even(n_y * ratio_y))
    new_x = np.maximum(1, _round_half_even(n_x * ratio_x))
    if resampling == "zoom":  # pyBSM resample_2D: zoom factors of the two axes swapped
        new_y, new_x = (np.maximum(1, _round_half_even(n_y * (new_x / n_x))),
                        np.maximum(1, _round_half_even(n_x * (new_y / n_y))))
    zero = np.zeros(np.shape(new_y))
    return new_y, new_x, new_y / n_y, new_x / n_x, zero, zero


def sampling(sensor: xr.Dataset, scenario: xr.Dataset, gsd, shape, im: ImageMethod):
    """Sample angles, output sizes and the reference-to-output pixel map of each scenario.

    Parameters
    ----------
    sensor, scenario : xr.Dataset
        From :func:`xbsm.sensor` and :func:`xbsm.scenario`.
    gsd : float or xr.DataArray
        Ground sample distance of the reference image. [m]
    shape : (int, int)
        Rows and columns of the reference image.
    im : ImageMethod
        Knobs ``basis``, ``viewing``, ``resampling``.

    Returns
    -------
    xr.Dataset
        ``slant_range`` [m]; ``reference_angle`` (gsd / slant range) [rad];
        ``size_y``, ``size_x`` (output rows and columns); ``scale_y``, ``scale_x``
        [output pixels per reference pixel] and ``offset_y``, ``offset_x`` [output
        pixels] of the map ``scale * u + offset``; ``gsd_y``, ``gsd_x``, ``gsd``
        (geometric mean) of the output [m]; ``flags`` (``upsampled``; ``image_small``
        where the image covers less than one output pixel).
    """
    n_y, n_x = shape
    slant = _slant_range(scenario, im)
    angle = gsd / slant
    out_y, out_x = _output_angles(sensor, scenario, gsd, im)
    ratio_y, ratio_x = xr.broadcast(angle / out_y, angle / out_x)
    parts = _axis_map(n_y, n_x, ratio_y.values, ratio_x.values, im.resampling)
    like = ratio_y.copy(data=np.zeros(ratio_y.shape))
    size_y, size_x, scale_y, scale_x, offset_y, offset_x = (like.copy(data=p) for p in parts)
    if int((size_y * size_x).max()) > MAX_OUTPUT_PIXELS:
        raise ValueError(f"gsd {gsd!r} m asks for a simulated image of {int(size_y.max())} x "
                         f"{int(size_x.max())} pixels; at most {MAX_OUTPUT_PIXELS} pixels "
                         "(check the units of gsd, which are metres)")
    gsd_y, gsd_x = gsd / scale_y, gsd / scale_x
    flags = fl.set_flag(fl.empty_flags(like), "upsampled", (scale_y > 1 + 1e-9)
                        | (scale_x > 1 + 1e-9))
    flags = fl.set_flag(flags, "image_small", (n_y * ratio_y < 1) | (n_x * ratio_x < 1))
    pixels = "output pixels per reference pixel"
    return xr.Dataset({
        "slant_range": named(slant, "m", "slant range"),
        "reference_angle": named(angle, "rad", "reference image sample angle"),
        "size_y": named(size_y, "1", "rows of the simulated image"),
        "size_x": named(size_x, "1", "columns of the simulated image"),
        "scale_y": named(scale_y, "1", f"row scale ({pixels})"),
        "scale_x": named(scale_x, "1", f"column scale ({pixels})"),
        "offset_y": named(offset_y, "1", "row offset of the pixel map (output pixels)"),
        "offset_x": named(offset_x, "1", "column offset of the pixel map (output pixels)"),
        "gsd_y": named(gsd_y, "m", "ground sample distance of the simulated image along y"),
        "gsd_x": named(gsd_x, "m", "ground sample distance of the simulated image along x"),
        "gsd": named(np.sqrt(gsd_x * gsd_y), "m", "ground sample distance of the simulated "
                     "image (geometric mean)"),
        "flags": flags,
    })
