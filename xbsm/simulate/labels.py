"""Points and boxes carried from the reference image into the simulated image.

Coordinates are continuous pixel coordinates, pixel ``i`` covering ``[i, i + 1)``
(OpenCV's and Pillow's convention; a pixel centre is at ``i + 0.5``). The map
``u_out = scale * u_in + offset`` per axis and scenario is the one the resampling
used (:mod:`xbsm.simulate.sampling`), so a transformed point lands on the same
feature of the blurred image and a transformed box bounds the same object.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from .._metadata import Output
from ..params import contract

__all__ = ["transform_points", "transform_boxes"]

_MAP = ("scale_x", "offset_x", "scale_y", "offset_y")


def _pixel_map(simulation: xr.Dataset):
    if not isinstance(simulation, xr.Dataset) or any(v not in simulation for v in _MAP):
        raise ValueError("simulation must be the Dataset returned by xbsm.simulate_image "
                         f"(with {', '.join(_MAP)})")
    return (simulation[v] for v in _MAP)


def _labelled(values, dims, labels, what):
    """Coordinates as a DataArray with the last dim labelled by ``labels``."""
    last = dims[-1]
    if isinstance(values, xr.DataArray):
        if last not in values.dims or list(values[last].values) != list(labels):
            raise ValueError(f"{what} as a DataArray need a dim {last!r} labelled {labels}")
        return values.astype(float)
    array = np.asarray(values, dtype=float)
    if array.shape[-1:] != (len(labels),):
        raise ValueError(f"{what} must be array_like (..., {len(labels)}) with columns "
                         f"{labels}; got shape {array.shape}")
    array = array.reshape(-1, len(labels)) if array.ndim != 2 else array
    return xr.DataArray(array, dims=dims, coords={last: list(labels)})


@contract(Output("points", "1", "point in simulated-image pixel coordinates"))
def transform_points(points, simulation: xr.Dataset) -> xr.DataArray:
    """Reference-image points in the simulated image's pixel coordinates.

    Parameters
    ----------
    points : array_like (n, 2) or xr.DataArray
        Columns (x, y) in reference pixel coordinates; a DataArray needs a dim
        ``coordinate`` labelled ["x", "y"] (any other dims). [pixels]
    simulation : xr.Dataset
        From :func:`xbsm.simulate_image`.

    Returns
    -------
    xr.DataArray
        Over (scenario dims, point dims, ``coordinate``), in simulated-image pixel
        coordinates. [1]
    """
    scale_x, offset_x, scale_y, offset_y = _pixel_map(simulation)
    p = _labelled(points, ("point", "coordinate"), ("x", "y"), "points")
    x = p.sel(coordinate="x", drop=True) * scale_x + offset_x
    y = p.sel(coordinate="y", drop=True) * scale_y + offset_y
    out = xr.concat([x, y], dim="coordinate").assign_coords(coordinate=["x", "y"])
    order = [d for d in (*scale_x.dims, *scale_y.dims) if d in out.dims]
    return out.transpose(*dict.fromkeys(order), ..., "coordinate")


@contract(Output("boxes", "1", "box in simulated-image pixel coordinates"))
def transform_boxes(boxes, simulation: xr.Dataset, *, clip=False) -> xr.DataArray:
    """Reference-image boxes in the simulated image's pixel coordinates.

    Parameters
    ----------
    boxes : array_like (n, 4) or xr.DataArray
        Columns (x_min, y_min, x_max, y_max), the box's edges in reference pixel
        coordinates. ``x_max`` and ``y_max`` are the far edges, one past the last
        pixel: pass ``x_max = last column + 1`` and ``y_max = last row + 1`` (a box
        over columns 10-19 and rows 5-8 is ``(10, 5, 20, 9)``; OpenCV's
        ``(x, y, w, h)`` is ``(x, y, x + w, y + h)``). Inclusive indices make every
        box one pixel short. A DataArray needs a dim ``corner`` labelled so. [pixels]
    simulation : xr.Dataset
        From :func:`xbsm.simulate_image`.
    clip : bool
        Clip each box to its scenario's image, ``[0, size_x] x [0, size_y]``.

    Returns
    -------
    xr.DataArray
        Over (scenario dims, box dims, ``corner``), in simulated-image pixel
        coordinates. [1]
    """
    labels = ("x_min", "y_min", "x_max", "y_max")
    b = _labelled(boxes, ("box", "corner"), labels, "boxes")
    corners = [b.sel(corner=c, drop=True) for c in labels]
    points = xr.concat([xr.concat([corners[i], corners[i + 1]], dim="coordinate")
                        for i in (0, 2)], dim="end").assign_coords(coordinate=["x", "y"])
    moved = transform_points(points.transpose(..., "coordinate"), simulation)
    out = [moved.sel(end=e, coordinate=c, drop=True) for e, c in
           ((0, "x"), (0, "y"), (1, "x"), (1, "y"))]
    if clip:
        sizes = (simulation["size_x"], simulation["size_y"]) * 2
        out = [o.clip(0, size) for o, size in zip(out, sizes, strict=True)]
    result = xr.concat(out, dim="corner").assign_coords(corner=list(labels))
    order = [d for d in moved.dims if d in result.dims]
    return result.transpose(*order, ..., "corner")
