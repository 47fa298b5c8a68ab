r"""ISO 12233 slanted-edge MTF and the RER measured on the same edge spread.

The slanted-edge method (ISO 12233:2017 e-SFR; P. D. Burns, "Slanted-edge MTF
for digital camera and scanner analysis", PICS 2000, and his sfrmat3/4) turns a
straight edge tilted a few degrees off a pixel axis into an oversampled edge
spread function: each pixel is placed at its distance from the fitted edge line,
and since the edge crosses the pixel grid at every sub-pixel phase, the
distances fill the line densely. Its derivative is the line spread function,
whose Fourier transform is the MTF across the edge, up to and beyond Nyquist.

What is measured is the sampled system: optics, motion and the detector's pixel
footprint together (the pixels integrate the scene), along the edge normal.
Frequencies are in cycles per pixel along that normal.
"""

from __future__ import annotations

import numpy as np
import xarray as xr
from scipy.interpolate import CubicSpline

from .._metadata import named
from ..metrics.edge import RER_POSITIONS
from ..params import Choice, Spec, contract
from ._edge_fit import (
    MAX_EDGE_ANGLE,
    MIN_EDGE_ANGLE,
    check_geometry,
    fit_edge_line,
    hamming,
    orient,
    phase_rows,
    polarity,
)
from ._image import (
    as_image,
    finite_values,
    flag,
    flags_variable,
    lead_coords,
    select,
    units_of,
)

__all__ = [
    "MAX_EDGE_ANGLE",
    "MIN_EDGE_ANGLE",
    "MIN_SIZE",
    "edge_rer",
    "slanted_edge_mtf",
]

MIN_SIZE = 16
"""Smallest region accepted by :func:`slanted_edge_mtf`, in pixels along each axis."""

MAX_EMPTY_BIN_FRACTION = 0.25
"""Most bins of the oversampled edge spread that may be empty (and interpolated)."""

DERIVATIVE_CORRECTION_LIMIT = 10.0
"""Largest factor of the derivative-filter correction (ISO 12233 / sfrmat)."""

WINDOWS = ("hamming", None)
"""Windows :func:`slanted_edge_mtf` may apply to the line spread function."""

METHODS = ("accurate", "iso")
"""Numerics of :func:`slanted_edge_mtf`: ISO 12233's, or with its binning errors removed."""

CLIPPED_ROW_FRACTION = 0.5
"""Fraction of rows with an extreme pixel inside the edge's rise that flags clipping."""

CLIP_MARGIN = 0.5
"""Distance beyond the edge's 10-90 % rise still searched for clipped pixels (half a
pixel: a pixel straddling the end of the rise). [pixel]"""


def _check_size(image):
    rows, cols = image.sizes["y"], image.sizes["x"]
    if rows < MIN_SIZE or cols < MIN_SIZE:
        raise ValueError(f"image region is {rows} x {cols} pixels (y x x); the slanted-edge "
                         f"method needs at least {MIN_SIZE} x {MIN_SIZE}")


# ---- edge spread, line spread, MTF ----------------------------------------------------

def _bin_sums(img, intercept, slope, oversampling):
    """Per bin of 1/oversampling px along the normal: pixel count, value sum, distance sum."""
    rows = phase_rows(img.shape[0], slope)
    cos = 1.0 / np.hypot(1.0, slope)
    edge_x = intercept + slope * np.arange(img.shape[0])[rows, None]
    distance = (np.arange(img.shape[1]) - edge_x) * cos
    size = oversampling * img.shape[1]
    index = (np.rint(distance * oversampling).astype(np.intp) + size // 2).ravel()
    keep = (index >= 0) & (index < size)
    sums = [np.bincount(index[keep], weights=w, minlength=size)
            for w in (None, img[rows].ravel()[keep], distance.ravel()[keep])]
    covered = (-edge_x.min() * cos, (img.shape[1] - 1 - edge_x.max()) * cos)
    return sums, covered


def _binned_esf(img, intercept, slope, oversampling, method):
    """Edge spread at bin centres [px from the edge]; count of empty and of covered bins.

    ``"iso"``: each bin's mean assigned to its centre. ``"accurate"``: to the
    mean distance of its pixels, interpolated to the centre, then sharpened by
    the 3-tap inverse of the 1/oversampling px box that binning convolves with.
    """
    (counts, values, distances), (low, high) = _bin_sums(img, intercept, slope, oversampling)
    centres = (np.arange(counts.size) - counts.size // 2) / oversampling
    filled = counts > 0
    at = distances[filled] / counts[filled] if method == "accurate" else centres[filled]
    esf = np.interp(centres, at, values[filled] / counts[filled])
    if method == "accurate":
        padded = np.pad(esf, 1, mode="edge")
        esf = esf - (padded[2:] - 2.0 * esf + padded[:-2]) / 24.0
    inside = (centres >= low) & (centres <= high)
    return centres, esf, int(np.count_nonzero(inside & ~filled)), int(inside.sum())


def _check_bins(empty, total, angle, oversampling):
    if empty > MAX_EMPTY_BIN_FRACTION * total:
        raise ValueError(
            f"{empty} of {total} bins of the {oversampling}x oversampled edge spread are "
            f"empty: an edge at {angle:.2f} degrees puts too few pixels at distinct "
            "sub-pixel distances (angles near 0 or 45 degrees or at simple slopes such as "
            "1/2 fail); use an angle of about 5 degrees, more rows or a lower oversampling")


def _mtf_from_esf(esf, sign, oversampling, window, method):
    """Frequency [cycles/px], MTF and the unit-area LSF [1/px] of an oversampled ESF.

    The MTF is divided by the response of the central difference (ISO) and, for
    ``"accurate"``, by what the box of binning leaves after the 3-tap sharpening.
    """
    lsf = sign * np.gradient(esf)  # central difference [-1/2, 0, 1/2]
    size = esf.size
    windowed = lsf * hamming(size, size // 2) if window == "hamming" else lsf
    spectrum = np.abs(np.fft.rfft(windowed))
    frequency = np.arange(spectrum.size) * oversampling / size
    phase = frequency / oversampling  # cycles per bin
    response = np.sinc(2.0 * phase)
    if method == "accurate":
        response = response * np.sinc(phase) * (1.0 + (1.0 - np.cos(2.0 * np.pi * phase)) / 12.0)
    mtf = spectrum / spectrum[0] / np.maximum(response, 1.0 / DERIVATIVE_CORRECTION_LIMIT)
    return frequency, mtf, lsf * oversampling / lsf.sum()


def _rise(esf, oversampling):
    """Width of the edge's 10-90 % rise [px], from the ESF's outer-quarter levels; >= 1."""
    quarter = max(1, esf.size // 4)
    low, high = esf[:quarter].mean(), esf[-quarter:].mean()
    level = (esf - low) / (high - low)
    return max(1.0, np.count_nonzero((level > 0.1) & (level < 0.9)) / oversampling)


def _clipped(img, intercept, slope, rise):
    """Whether clipping reaches into the edge.

    It does if in at least half of the rows a pixel within ``rise`` + :data:`CLIP_MARGIN`
    of the fitted edge sits at the region's minimum or maximum.

    An unclipped edge approaches its plateaus smoothly, so its extreme values lie far
    from the edge (or are single noise peaks); a clipped one reaches them inside the rise.
    """
    rows = phase_rows(img.shape[0], slope)
    edge_x = intercept + slope * np.arange(img.shape[0])[rows, None]
    near = np.abs(np.arange(img.shape[1]) - edge_x) / np.hypot(1.0, slope) <= rise + CLIP_MARGIN
    part = img[rows]
    extreme = (part == img.max()) | (part == img.min())
    return bool(np.mean((near & extreme).any(axis=1)) >= CLIPPED_ROW_FRACTION)


def _measure_one(img, oversampling, window, method):
    """Every slanted-edge result of one 2-D image (plain numpy)."""
    img, vertical = orient(img)
    sign = polarity(img)
    intercept, slope = fit_edge_line(img, sign)
    angle = check_geometry(img, intercept, slope)
    distance, esf, empty, total = _binned_esf(img, intercept, slope, oversampling, method)
    _check_bins(empty, total, angle, oversampling)
    frequency, mtf, lsf = _mtf_from_esf(esf, sign, oversampling, window, method)
    clipped = _clipped(img, intercept, slope, _rise(esf, oversampling))
    return {"frequency": frequency, "distance": distance, "mtf": mtf, "esf": esf,
            "lsf": lsf, "edge_angle": angle, "vertical_edge": vertical,
            "flags": flag("edge_clipped") if clipped else 0}


# ---- public functions ---------------------------------------------------------------

def _stacked(results, key, shape):
    return np.stack([r[key] for r in results]).reshape(shape + np.shape(results[0][key]))


def _edge_dataset(results, image, shape, knobs):
    """The per-image results stacked back onto the image's leading dimensions."""
    for name in ("frequency", "distance"):
        if any(r[name].shape != results[0][name].shape for r in results):
            raise ValueError("the images of a stack have edges of different orientation in a "
                             "region that is not square; measure them separately")
    lead = image.dims[:-2]
    coords = lead_coords(image)
    frequency = xr.DataArray(results[0]["frequency"], dims="frequency", attrs={
        "units": "cycles/pixel", "long_name": "spatial frequency along the edge normal"})
    distance = xr.DataArray(results[0]["distance"], dims="distance", attrs={
        "units": "pixel", "long_name": "distance from the edge along its normal"})

    def variable(key, dims, units, long_name):
        da = xr.DataArray(_stacked(results, key, shape), dims=lead + dims, coords=coords)
        return named(da, units, long_name)

    out = xr.Dataset({
        "mtf": variable("mtf", ("frequency",), "1", "modulation transfer function"),
        "esf": variable("esf", ("distance",), units_of(image), "edge spread function"),
        "lsf": variable("lsf", ("distance",), "pixel-1", "line spread function, unit area"),
        "edge_angle": variable("edge_angle", (), "degree",
                               "angle between the edge and the nearer pixel axis"),
        "vertical_edge": variable("vertical_edge", (), "1",
                                  "edge nearer the y axis (edge spread measured along x)"),
        "flags": flags_variable(_stacked(results, "flags", shape), lead, coords,
                                "slanted-edge validity flags"),
    }, coords={"frequency": frequency, "distance": distance})
    out["rer"] = edge_rer(out["esf"])
    out.attrs = {"method": "slanted edge ({}), oversampling {}, window {}".format(*knobs),
                 "references": "ISO 12233:2017; Burns, PICS 2000"}
    return out


@contract(oversampling=Spec("1", "bins per pixel of the edge spread function", low=1.0,
                            whole=True),
          window=Choice(WINDOWS), method=Choice(METHODS))
def slanted_edge_mtf(image, *, roi=None, oversampling=4, window="hamming",
                     method="accurate") -> xr.Dataset:
    r"""MTF of an imaging system measured on a slanted edge (ISO 12233 e-SFR).

    Parameters
    ----------
    image : xr.DataArray or array_like
        Over (``y``, ``x``), with any leading dimensions (a stack of images, each
        measured on its own); a numpy array's leading axes become ``dim_0``, ...
        One straight edge, of either polarity, tilted 1 to 40 degrees off the
        nearer pixel axis (about 5 is best); a near-horizontal edge is
        transposed. Values linear in exposure. [any]
    roi : tuple of two slices or dict, optional
        Region of interest by position: ``(rows, columns)`` or
        ``{"y": slice, "x": slice}``; at least :data:`MIN_SIZE` pixels each way, with
        unit steps (a strided region, or a strided view of an image whose ``y`` / ``x``
        coordinates count pixels, is refused: it is a decimated image).
    oversampling : int
        Bins per pixel of the edge spread function (ISO: 4). [1]
    window : {"hamming", None}
        Window on the line spread function, centred on the edge (ISO: Hamming).
    method : {"accurate", "iso"}
        ``"iso"``: ISO 12233:2017's numerics. ``"accurate"``: the same steps with
        the two errors of binning removed (see Notes).

    Returns
    -------
    xr.Dataset
        ``mtf`` over ``frequency`` [cycles/pixel along the edge normal], from 0 to
        ``oversampling / 2``; ``esf`` (image units) and ``lsf`` (unit area)
        [pixel-1] over ``distance`` from the edge [pixel]; ``edge_angle``
        [degree]; ``vertical_edge``; ``rer`` (:func:`edge_rer`) [1]; ``flags``
        (:data:`xbsm.measure.FLAGS`: ``edge_clipped``, the edge clipped inside its rise, which
        sharpens it and raises the MTF).

    Notes
    -----
    Per row, the centroid of the derivative times a Hamming window gives the
    edge position; a line fitted to them (twice, the second time with each
    window centred on the first fit) gives the angle :math:`\theta`. Rows are
    cut to a whole number of phase cycles, each pixel is placed at its
    distance :math:`d = (x - x_e(y))\cos\theta` from the line, and the pixels
    are averaged in bins of :math:`1/n` px. The LSF is the central difference of
    this ESF, windowed; the MTF is its normalised FFT magnitude divided by
    :math:`\operatorname{sinc}(2f/n)`, the difference's own response (capped at
    10).

    Binning as ISO does has two errors. A bin's mean belongs to the mean
    distance of its pixels, not to the bin centre (up to 0.03 at 20 degrees,
    where the phases cluster); and averaging over the bin smooths the ESF by a
    :math:`1/n` px box, lowering the MTF by :math:`\operatorname{sinc}(f/n)`
    (2.5 % at Nyquist for :math:`n = 4`). ``"accurate"`` interpolates each
    mean from its mean distance, sharpens the ESF with the 3-tap inverse of the
    box, :math:`[-1, 26, -1]/24`, and divides the MTF by what remains.
    """
    img = select(as_image(image, "image"), roi, "roi")
    _check_size(img)
    values = finite_values(img, "image")
    shape = values.shape[:-2]
    results = [_measure_one(values[index], oversampling, window, method)
               for index in np.ndindex(shape)]
    return _edge_dataset(results, img, shape, (method, oversampling, window))


def edge_rer(esf) -> xr.DataArray:
    r"""Relative edge response measured on an oversampled edge spread function.

    Parameters
    ----------
    esf : xr.DataArray
        Edge spread over ``distance`` from the edge [pixel], such as the ``esf``
        of :func:`slanted_edge_mtf`; other dimensions are kept. [any]

    Returns
    -------
    xr.DataArray
        RER. [1]

    Notes
    -----
    The GIQE definition of :func:`xbsm.metrics.relative_edge_response`
    (IBSM Eq. 3-61), on the edge response normalised by the mean levels of the
    outer quarters of the distance range (dark 0, bright 1) and interpolated by
    a cubic spline:

    .. math:: RER = ER(+\tfrac{1}{2}) - ER(-\tfrac{1}{2})

    Distance 0 is the fitted edge, the centroid of the line spread.
    """
    if not isinstance(esf, xr.DataArray) or "distance" not in esf.coords:
        raise ValueError("esf must be an xr.DataArray with a 'distance' coordinate [pixel]")
    distance = np.asarray(esf["distance"].values, dtype=float)
    esf = esf.transpose(..., "distance")
    values = np.asarray(esf.values, dtype=float)
    half = np.abs(distance).max() / 2.0
    dark = values[..., distance <= -half].mean(axis=-1)[..., None]
    bright = values[..., distance >= half].mean(axis=-1)[..., None]
    if np.any(bright == dark):
        raise ValueError("esf has no step: its two ends are at the same level")
    response = CubicSpline(distance, (values - dark) / (bright - dark), axis=-1)(RER_POSITIONS)
    rer = xr.DataArray(response[..., 1] - response[..., 0], dims=esf.dims[:-1],
                       coords={k: c for k, c in esf.coords.items() if "distance" not in c.dims})
    return named(rer, "1", "relative edge response", references="IBSM Eq. 3-61")

