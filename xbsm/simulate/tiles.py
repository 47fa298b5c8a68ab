"""Large reference images in tiles: working memory set by the tile, not the image.

:func:`xbsm.simulate_image` takes this path when a reference image is larger than
``tile_size`` (:data:`TILE_SIZE` reference pixels by default) along ``y`` or ``x``
and the method's knobs are the accurate path's (``psf="exact"``,
``convolution="fft"``, ``resampling`` ``"cubic"``, ``"area"`` or ``"none"``):

1. **Global statistics in a streaming pass.** The 0.2 and 99.8 percentiles (or the
   minimum and maximum) of each image over all its colour channels are found in
   strips of about ``tile_size ** 2`` pixels: exact order statistics by histogram
   narrowing (each pass bins the values inside the interval that holds the wanted
   rank; an interval of at most 65536 values is sorted), then numpy's own linear
   interpolation between the two neighbouring order statistics, so the percentiles
   equal ``numpy.nanpercentile``'s to the bit. A second pass gives the mean
   reflectance that fills non-finite pixels.
2. **Overlap-save convolution.** The blur kernel is the middle
   ``(2 halo + 1) ** 2`` samples of the system OTF's kernel on a grid of its own
   (:func:`xbsm.simulate.psf.kernel_from_otf`); the halo is chosen from the
   kernel's energy (:func:`tile_halo`: doubled from ``TILE_HALO_FACTOR`` cores
   until the wings beyond it hold at most :data:`TILE_WING_TOLERANCE` of its sum),
   and the wings' share of each pixel is given the image's mean reflectance (over
   all its colour channels, from the statistics pass) rather than spread over the
   kernel. Each block of the reference (read with reflected
   borders, mapped to reflectance) is convolved with it by FFT and only its middle,
   where the linear convolution is exact, is kept. The tiles join without seams: a
   tiled image does not depend on the tile size beyond floating-point rounding.
3. **Tile-wise resampling.** Output pixels are taken in blocks whose taps fall in
   one tile; each block is the same tap arithmetic as the untiled path.

The untiled path multiplies the whole image's spectrum by the OTF (an exact
periodic convolution, no truncation); the tiled path truncates the kernel at the
halo. The difference is the wings' energy beyond the halo (at most
:data:`TILE_WING_TOLERANCE`) times the image's departure from its mean, and near
the borders the untiled path's own boundary (measured in
``tests/simulate/test_tiles_wings.py`` and ``docs/simulate.md``).

Memory is checked before anything image-sized is allocated
(:func:`check_memory`): a request that cannot fit in the memory available
(``MemAvailable`` of ``/proc/meminfo``) is refused with a one-line
``MemoryError`` naming the image and both sizes.
"""

from __future__ import annotations

import math
import os

import numpy as np
import xarray as xr
from scipy import fft

from .. import flags as fl
from ._arrays import align_leading
from .psf import kernel_from_otf, otf_rfft_grid
from .reflectance import PERCENTILES
from .resample import apply_taps, reflect_index

__all__ = ["TILE_HALO_FACTOR", "TILE_HALO_MAX", "TILE_SIZE", "TILE_WING_TOLERANCE",
           "available_memory", "check_memory", "tile_core", "tile_halo", "tile_reflectance",
           "tile_statistics", "tiled_blur_and_resample", "tiled_psf"]

TILE_SIZE = 2048
"""Default ``simulate_image(tile_size=)``: reference pixels per side of a tile's core."""
TILE_HALO_FACTOR = 4
"""The tiled kernel's smallest half-width in multiples of the blur's core half-width."""
TILE_WING_TOLERANCE = 2e-3
"""The largest energy (sum) of the kernel's wings beyond the halo: the halo doubles from
``TILE_HALO_FACTOR`` cores until the wings hold no more (or it reaches
:data:`TILE_HALO_MAX`)."""
TILE_HALO_MAX = 512
"""The largest halo the wing tolerance may ask for (unless ``TILE_HALO_FACTOR`` cores are
more). [reference pixels]"""
_BINS = 4096
_GATHER = 1 << 16


# --- streaming statistics -------------------------------------------------------------

def _strips(one, pixels: int):
    """Row strips of one image (..., rows, columns) as float64, about ``pixels`` each."""
    per_row = max(1, math.prod(one.shape) // max(1, one.shape[-2]))
    rows = max(1, pixels // per_row)
    for start in range(0, one.shape[-2], rows):
        yield np.asarray(one[..., start: start + rows, :], dtype=np.float64)


def _members(v, interval):
    low, high, closed = interval[:3]
    inside = (v >= low) & (v < high)
    if closed:
        inside |= v == high
    return v[inside]


def _order_statistics(values, ranks, low, high, count):
    """The 0-based ``ranks`` of the finite values, exactly, by histogram narrowing.

    ``values()`` yields the finite values in pieces; ``low``, ``high``: their extremes;
    ``count``: how many there are.
    """
    found = {}
    todo = {r: (low, high, True, 0, count) for r in ranks}
    while todo:
        intervals = sorted(set(todo.values()))
        edges = [np.linspace(iv[0], iv[1], _BINS + 1) for iv in intervals]
        counts = [np.zeros(_BINS, np.int64) for _ in intervals]
        kept = [[] for _ in intervals]
        lows = [np.inf] * len(intervals)
        highs = [-np.inf] * len(intervals)
        for piece in values():
            for i, iv in enumerate(intervals):
                m = _members(piece, iv)
                if m.size == 0:
                    continue
                if iv[4] <= _GATHER:
                    kept[i].append(m)
                    continue
                lows[i], highs[i] = min(lows[i], m.min()), max(highs[i], m.max())
                bins = np.searchsorted(edges[i], m, side="right") - 1
                counts[i] += np.bincount(np.minimum(bins, _BINS - 1), minlength=_BINS)
        for rank, iv in list(todo.items()):
            i = intervals.index(iv)
            below = iv[3]
            if iv[4] <= _GATHER:
                found[rank] = np.sort(np.concatenate(kept[i]))[rank - below]
            elif lows[i] == highs[i]:
                found[rank] = lows[i]
            else:
                cum = np.cumsum(counts[i])
                j = int(np.searchsorted(cum, rank - below, side="right"))
                todo[rank] = (float(edges[i][j]), float(edges[i][j + 1]),
                              iv[2] and j == _BINS - 1,
                              below + (int(cum[j - 1]) if j else 0), int(counts[i][j]))
                continue
            del todo[rank]
    return found


def _integer_order_statistics(one, ranks, low, high, strip):
    """The 0-based ``ranks`` of an integer image's values, by one counting pass."""
    counts = np.zeros(int(high - low) + 1, np.int64)
    rows = max(1, strip // max(1, math.prod(one.shape) // max(1, one.shape[-2])))
    for start in range(0, one.shape[-2], rows):
        part = np.asarray(one[..., start: start + rows, :]).ravel().astype(np.int64)
        counts += np.bincount(part - int(low), minlength=counts.size)
    cum = np.cumsum(counts)
    return {r: float(int(low) + int(np.searchsorted(cum, r, side="right"))) for r in ranks}


def _percentiles(values, count, low, high):
    """numpy.nanpercentile's linear interpolation at :data:`PERCENTILES`, from order statistics.

    ``values``: a callable yielding the finite values in pieces, or a callable of the
    ranks that returns the order statistics (an integer image's counting pass).
    """
    quantiles = np.true_divide(np.asarray(PERCENTILES), 100)
    virtual = (count - 1) * quantiles
    previous = np.floor(virtual)
    gamma = virtual - previous
    prev_i = np.where(virtual >= count - 1, count - 1, np.maximum(previous, 0)).astype(int)
    next_i = np.where(virtual >= count - 1, count - 1, np.maximum(previous + 1, 0)).astype(int)
    ranks = {*prev_i.tolist(), *next_i.tolist()}
    stats = (values(ranks) if getattr(values, "ranks", False)
             else _order_statistics(values, ranks, low, high, count))
    out = []
    for p, n, t in zip(prev_i, next_i, gamma, strict=True):
        a, b = np.float64(stats[int(p)]), np.float64(stats[int(n)])
        diff = b - a
        out.append(b - diff * (1 - t) if t >= 0.5 else a + diff * t)
    return out


def _image_statistics(one, *, kind, low, high, pixel_low, pixel_high, pixels, reflectances,
                      strip):
    """[p1 used, scale, flat, fill] and the flag bits of one image (all its channels)."""
    count, lowest, highest = 0, np.inf, -np.inf
    for s in _strips(one, strip):
        finite = s[np.isfinite(s)]
        count += finite.size
        if finite.size:
            lowest, highest = min(lowest, finite.min()), max(highest, finite.max())
    total = math.prod(one.shape)
    if kind == "identity" and count and (lowest < 0.0 or highest > 1.0):
        raise ValueError(
            "image must hold reflectances in [0, 1] with reflectance='identity'; got values "
            f"from {lowest!r} to {highest!r} (use reflectance='percentile', 'minmax' or a "
            "(pixel_values, reflectance_values) table)")
    p1 = p2 = 0.0
    if kind == "percentile" and count:
        def values(ranks=None):
            if ranks is not None:
                return _integer_order_statistics(one, ranks, lowest, highest, strip)
            return (s[np.isfinite(s)] for s in _strips(one, strip))
        # an integer image (up to 2^24 levels): its values counted once, exactly
        values.ranks = one.dtype.kind in "biu" and highest - lowest < 2**24
        p1, p2 = _percentiles(values, count, float(lowest), float(highest))
    elif kind == "minmax" and count:
        p1, p2 = lowest, highest
    elif kind == "table":
        p1, p2 = pixel_low, pixel_high
    flat = not p2 > p1
    scale = (high - low) / (1.0 if flat else p2 - p1)
    stat = np.array([0.0 if flat else p1, scale, float(flat), np.nan])
    middle = 0.5 * (low + high) if kind in ("percentile", "minmax", "table") else 0.5
    mapping = dict(kind=kind, low=low, high=high, pixels=pixels, reflectances=reflectances)
    fill = middle
    if count:
        total_refl = 0.0
        for s in _strips(one, strip):
            finite = np.isfinite(s)
            total_refl += np.where(finite, _pointwise(s, finite, stat, **mapping), 0.0).sum()
        fill = total_refl / count
    stat[3] = fill
    bits = (fl.flag("image_nonfinite") if count < total else 0) | (
        fl.flag("image_flat") if flat and kind in ("percentile", "minmax") else 0)
    return stat, bits


def _pointwise(x, finite, stat, *, kind, low, high, pixels, reflectances):
    """Reflectance of finite pixel values, the arithmetic of xbsm.simulate.reflectance."""
    if kind == "identity":
        return np.where(finite, x, 0.0)
    if kind == "multitable":
        x = np.where(finite, x, pixels[0])
        refl = np.interp(x, pixels, reflectances)
        below = (reflectances[1] - reflectances[0]) / (pixels[1] - pixels[0])
        above = (reflectances[-1] - reflectances[-2]) / (pixels[-1] - pixels[-2])
        refl = np.where(x < pixels[0], reflectances[0] + below * (x - pixels[0]), refl)
        refl = np.where(x > pixels[-1], reflectances[-1] + above * (x - pixels[-1]), refl)
        return np.clip(refl, 0.0, 1.0)
    p1, scale, flat = stat[0], stat[1], bool(stat[2])
    with np.errstate(invalid="ignore"):
        refl = scale * (np.where(finite, x, np.nan) - p1) + low
    return np.clip(np.where(flat, 0.5 * (low + high), refl), 0.0, 1.0)


def _reflectance(x, stat, mapping):
    finite = np.isfinite(x)
    return np.where(finite, _pointwise(x, finite, stat, **mapping), stat[3])


def _mapping_of(mapping, reflectance_range):
    """Keyword arguments of the pointwise mapping for a reflectance choice."""
    low, high = reflectance_range
    out = dict(kind=mapping, low=low, high=high, pixels=None, reflectances=None,
               pixel_low=None, pixel_high=None)
    if not isinstance(mapping, str):
        pixels, reflectances = (np.asarray(a, dtype=float) for a in mapping)
        if pixels.size == 2:
            out.update(kind="table", low=reflectances[0], high=reflectances[1],
                       pixel_low=pixels[0], pixel_high=pixels[1])
        else:
            out.update(kind="multitable", pixels=pixels, reflectances=reflectances)
    return out


def _statistics_kernel(img, *, ncore, strip, **mapping):
    lead = img.shape[: img.ndim - ncore]
    stats, bits = np.empty(lead + (4,)), np.zeros(lead, np.int32)
    for index in np.ndindex(lead):
        stats[index], bits[index] = _image_statistics(img[index], strip=strip, **mapping)
    return stats, bits


def tile_statistics(image: xr.DataArray, mapping, reflectance_range, dims, tile_size):
    """Per image, what the reflectance mapping needs, in a streaming pass over strips.

    Parameters
    ----------
    image : xr.DataArray
        Pixel values over ``dims`` (the colour dim first if any, then rows, columns). [any]
    mapping : str or (array_like, array_like)
        As ``reflectance`` of :func:`xbsm.simulate.image_to_reflectance`.
    reflectance_range : (float, float)
        Reflectances of the two pixel values of "percentile" and "minmax". [1]
    dims : sequence of str
        The per-image dims.
    tile_size : int
        Strips hold about ``tile_size ** 2`` pixels. [pixels]

    Returns
    -------
    xr.Dataset
        ``statistics`` over (image dims, ``statistic``): the first pixel value, the
        scale, whether the image is flat and the fill reflectance of non-finite pixels;
        ``flags`` per image (``image_nonfinite``, ``image_flat``). [1]
    """
    kwargs = _mapping_of(mapping, reflectance_range)
    dims = list(dims)
    if image.chunks is not None:
        image = image.chunk({d: -1 for d in dims})
    stats, bits = xr.apply_ufunc(
        _statistics_kernel, image,
        kwargs={"ncore": len(dims), "strip": tile_size**2, **kwargs},
        input_core_dims=[dims], output_core_dims=[["statistic"], []], dask="parallelized",
        output_dtypes=[float, np.int32], dask_gufunc_kwargs={"output_sizes": {"statistic": 4}})
    return xr.Dataset({"statistics": stats, "flags": bits.assign_attrs(
        fl.flag_attrs("image validity flags"))})


def _mapping_kwargs(kwargs):
    return {k: kwargs[k] for k in ("kind", "low", "high", "pixels", "reflectances")}


def _map_kernel(img, stats, *, strip, **mapping):
    img, stats = align_leading(img, 2, stats, 1)
    lead = np.broadcast_shapes(img.shape[:-2], stats.shape[:-1])
    out = np.empty(lead + img.shape[-2:])
    rows = max(1, strip // img.shape[-1])
    for index in np.ndindex(lead):
        one = img[_pick(index, img.shape[:-2])]
        stat = stats[_pick(index, stats.shape[:-1])]
        for start in range(0, one.shape[-2], rows):
            part = np.asarray(one[start: start + rows], dtype=np.float64)
            out[index][start: start + rows] = _reflectance(part, stat, mapping)
    return out


def tile_reflectance(image: xr.DataArray, statistics: xr.DataArray, mapping, reflectance_range,
                     tile_size, dims=("y_input", "x_input")) -> xr.DataArray:
    """The reflectance image, mapped strip by strip from :func:`tile_statistics`.

    Parameters
    ----------
    image : xr.DataArray
        Pixel values over ``dims``. [any]
    statistics : xr.DataArray
        From :func:`tile_statistics`.
    mapping, reflectance_range
        As for :func:`tile_statistics`.
    tile_size : int
        Strips hold about ``tile_size ** 2`` pixels. [pixels]
    dims : (str, str)
        The image's row and column dims.

    Returns
    -------
    xr.DataArray
        Reflectance, like ``image``. [1]
    """
    kwargs = _mapping_kwargs(_mapping_of(mapping, reflectance_range))
    if image.chunks is not None:
        image = image.chunk({d: -1 for d in dims})
    return xr.apply_ufunc(
        _map_kernel, image, statistics, kwargs={"strip": tile_size**2, **kwargs},
        input_core_dims=[list(dims), ["statistic"]], output_core_dims=[list(dims)],
        dask="parallelized", output_dtypes=[float])


# --- overlap-save blur and tile-wise resampling --------------------------------------

def _pick(index, shape):
    """Index of a broadcast position into an array of ``shape`` (size-1 axes broadcast)."""
    return tuple(i if n > 1 else 0 for i, n in zip(index, shape, strict=True))


def _blocks(index, tile: int):
    """Output blocks (start, stop) and their reference spans (first, stop) within a tile."""
    first, last = index.min(axis=1), index.max(axis=1)
    out, start = [], 0
    while start < index.shape[0]:
        lo, hi = np.minimum.accumulate(first[start:]), np.maximum.accumulate(last[start:])
        fits = hi - lo + 1 <= tile
        stop = start + (fits.size if fits.all() else max(1, int(np.argmin(fits))))
        out.append((start, stop, int(lo[stop - start - 1]), int(hi[stop - start - 1]) + 1))
        start = stop
    return out


def tile_core(taps, axis, size, tile):
    """A tile's core along one axis: ``tile``, at least the widest tap span, at most ``size``.

    Parameters
    ----------
    taps : xr.Dataset
        From :func:`xbsm.simulate.resample.resampling_taps`.
    axis : {"y", "x"}
    size : int
        The reference image's rows or columns. [pixels]
    tile : int
        The requested tile size. [pixels]

    Returns
    -------
    int
        Reference pixels per tile along the axis, without the overlap: the image split
        into ``ceil(size / tile)`` equal tiles, each widened by two tap spans (at most
        ``tile``). [pixels]
    """
    index, weight = taps[f"index_{axis}"].values, taps[f"weight_{axis}"].values
    valid = np.isfinite(weight[..., 0])
    span = int(np.where(valid, index.max(-1) - index.min(-1) + 1, 1).max())
    # as many tiles as ``tile`` needs, of equal size (plus a tap span for the greedy
    # blocking), not full tiles and a thin last one: smaller FFTs
    count = -(-size // tile)
    return int(min(max(-(-size // count) + 2 * span, span), size, max(tile, span)))


def _kernel(optics, angle, halo: int):
    """The middle (2 halo + 1)^2 samples of the kernel on a grid of its own, and its sum.

    The grid does not depend on the tile, so tiles of any size join the same way (its
    wrapped-around wings start 3 halo from the centre). The sum of the whole kernel is
    the OTF at zero frequency.
    """
    own = fft.next_fast_len(4 * halo + 2, real=True)
    otf = otf_rfft_grid(optics, angle, own, own)
    return kernel_from_otf(otf, own, halo), otf.isel(fy=0, fx=0).real


def tile_halo(optics, angle, half: int, shape):
    """The tiles' halo chosen from the kernel's energy, and the energy of its wings.

    Parameters
    ----------
    optics : xbsm.simulate.psf.Optics
    angle : xr.DataArray
        Reference image sample angle, per scenario. [rad]
    half : int
        The blur's core half-width (:func:`xbsm.simulate.psf.kernel_half_width`).
        [reference pixels]
    shape : (int, int)
        The image's rows and columns. [reference pixels]

    Returns
    -------
    int, float
        The halo: ``TILE_HALO_FACTOR`` cores, doubled while the kernel's wings beyond
        it hold more than :data:`TILE_WING_TOLERANCE` of its sum, up to
        :data:`TILE_HALO_MAX` (whatever the image's size, so images of one sampling
        share one kernel; the first halo is at most the image's larger side); the
        wings' largest energy over the scenarios at that halo (on the kernel's own
        grid, whose sum is the OTF at zero frequency). [reference pixels], [1]
    """
    halo = min(TILE_HALO_FACTOR * half, max(shape))
    top = max(TILE_HALO_MAX, halo)
    while True:
        psf, total = _kernel(optics, angle, halo)
        wing = float((total - psf.sum(("psf_y", "psf_x"))).max())
        if wing <= TILE_WING_TOLERANCE or halo >= top:
            return halo, wing
        halo = min(2 * halo, top)


def tiled_psf(optics, angle, halo: int, core_y: int, core_x: int):
    """The truncated blur kernel of the tiles and its spectrum on one tile's FFT grid.

    Parameters
    ----------
    optics : xbsm.simulate.psf.Optics
    angle : xr.DataArray
        Reference image sample angle, per scenario. [rad]
    halo : int
        Half-width of the kernel and of each tile's overlap. [reference pixels]
    core_y, core_x : int
        A tile's rows and columns without the overlap. [reference pixels]

    Returns
    -------
    xr.DataArray, xr.DataArray
        The kernel over (scenario dims, ``psf_y``, ``psf_x``), summing to one less its
        wings beyond the halo (the tiles give the wings the image's mean reflectance),
        and its ``rfft2`` over (scenario dims, ``ky``, ``kx``) on the grid of
        ``next_fast_len(core + 2 halo)`` samples per axis. [1]
    """
    grid = tuple(fft.next_fast_len(c + 2 * halo, real=True) for c in (core_y, core_x))
    psf, _ = _kernel(optics, angle, halo)

    def spectrum(k):
        placed = np.zeros(k.shape[:-2] + grid)
        offsets = np.arange(-halo, halo + 1)
        placed[..., (offsets % grid[0])[:, None], (offsets % grid[1])[None, :]] = k
        return fft.rfft2(placed, axes=(-2, -1))

    spec = xr.apply_ufunc(spectrum, psf, input_core_dims=[["psf_y", "psf_x"]],
                          output_core_dims=[["ky", "kx"]])
    return psf.assign_attrs(units="1", long_name="blur kernel at the reference image's "
                            "sampling"), spec.assign_attrs(grid_y=grid[0], grid_x=grid[1])


def _tiled_kernel(img, stats, spectrum, index_y, weight_y, index_x, weight_x, *, halo, grid,
                  core_y, core_x, mapping):
    """Overlap-save blur and resampling of (..., rows, columns) images, block by block."""
    img, stats, spectrum, index_y, weight_y, index_x, weight_x = align_leading(
        img, 2, stats, 1, spectrum, 2, index_y, 2, weight_y, 2, index_x, 2, weight_x, 2)
    tables = (index_y, weight_y, index_x, weight_x)
    lead = np.broadcast_shapes(img.shape[:-2], stats.shape[:-1], spectrum.shape[:-2],
                               *(t.shape[:-2] for t in tables))
    out = np.full(lead + (index_y.shape[-2], index_x.shape[-2]), np.nan)
    n_y, n_x = img.shape[-2:]
    for index in np.ndindex(lead):
        one = img[_pick(index, img.shape[:-2])]
        stat = stats[_pick(index, stats.shape[:-1])]
        spec = spectrum[_pick(index, spectrum.shape[:-2])]
        iy, wy, ix, wx = (t[_pick(index, t.shape[:-2])] for t in tables)
        rows_out, cols_out = int(np.isfinite(wy[:, 0]).sum()), int(np.isfinite(wx[:, 0]).sum())
        for oy0, oy1, r0, r1 in _blocks(iy[:rows_out], core_y):
            rows = reflect_index(np.arange(r0 - halo, r1 + halo), n_y)
            for ox0, ox1, c0, c1 in _blocks(ix[:cols_out], core_x):
                cols = reflect_index(np.arange(c0 - halo, c1 + halo), n_x)
                region = np.asarray(one[np.ix_(rows, cols)], dtype=np.float64)
                refl = _reflectance(region, stat, mapping)
                blurred = fft.irfft2(fft.rfft2(refl, s=grid) * spec, s=grid)
                # the kernel's wings beyond the halo (its missing sum) see the image's mean
                blurred += (1.0 - spec[0, 0].real) * stat[3]
                blurred = blurred[halo: halo + r1 - r0, halo: halo + c1 - c0]
                out[index][oy0:oy1, ox0:ox1] = apply_taps(
                    blurred, iy[oy0:oy1] - r0, wy[oy0:oy1], ix[ox0:ox1] - c0, wx[ox0:ox1])
    return out


def tiled_blur_and_resample(image: xr.DataArray, statistics: xr.DataArray, spectrum,
                            taps: xr.Dataset, halo: int, core, mapping, reflectance_range,
                            dims=("y_input", "x_input")) -> xr.DataArray:
    """Reflectance blurred by the tiled kernel and resampled, tile by tile.

    Parameters
    ----------
    image : xr.DataArray
        Pixel values over ``dims``. [any]
    statistics : xr.DataArray
        From :func:`tile_statistics`.
    spectrum : xr.DataArray
        From :func:`tiled_psf`.
    taps : xr.Dataset
        From :func:`xbsm.simulate.resample.resampling_taps`.
    halo : int
        The kernel's half-width. [reference pixels]
    core : (int, int)
        A tile's rows and columns without the overlap. [reference pixels]
    mapping, reflectance_range
        As for :func:`tile_statistics`.
    dims : (str, str)
        The image's row and column dims.

    Returns
    -------
    xr.DataArray
        Reflectance over (broadcast dims, ``y``, ``x``), NaN past each scenario's size. [1]
    """
    kwargs = {"halo": halo, "grid": (spectrum.attrs["grid_y"], spectrum.attrs["grid_x"]),
              "core_y": core[0], "core_x": core[1],
              "mapping": _mapping_kwargs(_mapping_of(mapping, reflectance_range))}
    if image.chunks is not None:
        image = image.chunk({d: -1 for d in dims})
    sizes = {"y": taps.sizes["y"], "x": taps.sizes["x"]}
    return xr.apply_ufunc(
        _tiled_kernel, image, statistics, spectrum, taps["index_y"], taps["weight_y"],
        taps["index_x"], taps["weight_x"], kwargs=kwargs,
        input_core_dims=[list(dims), ["statistic"], ["ky", "kx"], ["y", "tap_y"],
                         ["y", "tap_y"], ["x", "tap_x"], ["x", "tap_x"]],
        output_core_dims=[["y", "x"]], dask="parallelized", output_dtypes=[float],
        dask_gufunc_kwargs={"output_sizes": sizes})


# --- the memory guard ------------------------------------------------------------------

def available_memory() -> int:
    """Bytes of memory available to a new allocation (``MemAvailable``, else free pages)."""
    try:
        with open("/proc/meminfo") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    try:
        return os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (ValueError, OSError, AttributeError):
        return 1 << 62


def _gib(n):
    return f"{n / 2**30:.1f} GiB"


def check_memory(needed: int, name: str, shape, *, available=None) -> None:
    """Refuse a simulation that would need more than the memory available.

    Parameters
    ----------
    needed : int
        Estimated peak bytes of the request. [bytes]
    name : str
        The image's name or index, for the message.
    shape : (int, int)
        Its rows and columns.
    available : int, optional
        Bytes available; default :func:`available_memory`. [bytes]

    Raises
    ------
    MemoryError
        One line naming the image, the size needed and the size available.
    """
    available = available_memory() if available is None else available
    if needed > available:
        raise MemoryError(
            f"simulate_image: image {name} ({shape[0]} x {shape[1]} reference pixels) needs "
            f"about {_gib(needed)}, {_gib(available)} available: lower tile_size, keep "
            "fewer outputs (outputs=('counts',), counts_dtype='uint16') or simulate fewer "
            "scenarios per call")
