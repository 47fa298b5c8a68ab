"""``simulate_image``: a reference image seen by a camera in a scenario (paper Eq. 5-6).

``i = R[h (x) o]``: the reference image ``o`` (pixel values) becomes scene
reflectance, then photoelectrons through the same radiometry as :func:`xbsm.snr`;
``h`` is the system blur at the reference image's sampling; ``R`` resamples to the
camera's pixels at the scenario's slant range; then shot, dark, read and
quantization noise and the ADC. One call broadcasts over a stack of images and
every sweep dimension of the sensor and scenario; the blur is computed once per
scenario cell, and dask-backed images stay lazy.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import xarray as xr
from scipy import fft

from .. import flags as fl
from .._metadata import named
from ..otf.system import COMPONENTS as SYSTEM_COMPONENTS
from ..otf.system import otf_weights
from ..params import Selection, check_inputs, contract
from . import camera
from .convolve import blur, blur_by_otf
from .options import COMPONENTS, ImageMethod, image_method
from .photoelectrons import reflectance_to_photoelectrons
from .psf import Optics, kernel_from_otf, kernel_half_width, nyquist_otf, otf_rfft_grid
from .pybsm_psf import pybsm_psf
from .reflectance import image_to_reflectance
from .resample import blur_and_resample, resample, resampling_taps
from .sampling import sampling
from .tiles import (
    TILE_HALO_MAX,
    TILE_SIZE,
    check_memory,
    tile_core,
    tile_halo,
    tile_reflectance,
    tile_statistics,
    tiled_blur_and_resample,
    tiled_psf,
)

__all__ = ["simulate_image", "simulate_images"]

CHANNEL_DIMS = ("band", "channel", "colour", "color")
"""Dimension names taken as an image's colour channel (percentiles span every channel)."""
INPUT_DIMS = ("y_input", "x_input")
RESULT_VARIABLES = ("reflectance", "ideal", "blurred", "noisy", "counts", "psf", "gsd",
                    "gsd_x", "gsd_y", "slant_range", "scale_y", "scale_x", "offset_y",
                    "offset_x", "size_y", "size_x", "photoelectron_offset",
                    "photoelectron_gain", "effective_integration_time", "flags")
"""The variables of a :func:`simulate_image` result."""
RESERVED_IMAGE_DIMS = (*INPUT_DIMS, "psf_y", "psf_x", *RESULT_VARIABLES)
"""Names an image's other dims may not take: the result's own dims and variables."""
IMAGE_OUTPUTS = ("reflectance", "ideal", "blurred", "noisy", "counts", "psf")
"""The image-sized variables ``outputs=`` chooses from (the rest are always kept)."""


def _counts_fill(counts_dtype, sensor):
    """The integer dtype of the counts and its fill value (its maximum), or (None, None)."""
    if counts_dtype is None:
        return None, None
    try:
        dtype = np.dtype(counts_dtype)
    except TypeError:
        dtype = None
    if dtype is None or dtype.kind != "u":
        raise ValueError("counts_dtype must be an unsigned integer dtype ('uint8', 'uint16', "
                         f"'uint32', 'uint64') or None (float64); got {counts_dtype!r}")
    fill = np.iinfo(dtype).max
    top = float(np.max(2.0 ** sensor["bit_depth"].values - 1.0))
    if not top < fill:
        raise ValueError(f"counts_dtype {dtype.name} holds 0 to {fill - 1} ({fill} marks "
                         f"cells without a count); the sensor's bit_depth gives counts up to "
                         f"{top:.0f}: choose a wider dtype")
    return dtype, fill


def _integer_counts_kernel(counts, *, dtype, fill):
    return np.where(np.isfinite(counts), counts, fill).astype(dtype)


def _integer_counts(counts, dtype, fill):
    """The counts in an unsigned integer dtype, ``fill`` (the ``_FillValue``) where NaN."""
    out = xr.apply_ufunc(_integer_counts_kernel, counts, kwargs={"dtype": dtype, "fill": fill},
                         dask="parallelized", output_dtypes=[dtype]).assign_attrs(counts.attrs)
    out.encoding["_FillValue"] = dtype.type(fill)
    return out


ALPHA_LABELS = ("a", "alpha")
"""Labels (any case) of a colour channel that is opacity, dropped from the simulation."""


def _drop_alpha(image, channel_dim):
    """The image without its alpha channel (labelled "A" or "alpha"), and whether it had one."""
    if channel_dim is None or channel_dim not in image.coords:
        return image, False
    keep = [str(label).lower() not in ALPHA_LABELS for label in image[channel_dim].values]
    if all(keep):
        return image, False
    if not any(keep):
        raise ValueError(f"image has only an alpha channel along {channel_dim!r}; give its "
                         "colour channels")
    return image.isel({channel_dim: np.flatnonzero(keep)}), True


def _as_image(image, channel_dim):
    """The reference image as a float DataArray over (..., y_input, x_input).

    Also the colour channel's dim (or None) and whether an alpha channel was dropped: the
    fourth channel of a (rows, columns, 4) array, a channel labelled "A" or "alpha".
    """
    alpha = False
    if isinstance(image, np.ndarray):
        if image.ndim == 2:
            image = xr.DataArray(image, dims=("y", "x"))
        elif image.ndim == 3 and image.shape[-1] in (3, 4):
            alpha = image.shape[-1] == 4  # RGBA: opacity is not a colour band
            image = xr.DataArray(image[..., :3], dims=("y", "x", "band"))
        else:
            raise ValueError("image must be 2-D (rows, columns), 3-D (rows, columns, 3 or 4 "
                             f"channels) or a DataArray with dims 'y' and 'x'; got shape "
                             f"{image.shape}")
    if not isinstance(image, xr.DataArray):
        raise ValueError("image must be an xr.DataArray with dims 'y' and 'x' or a numpy "
                         f"array; got {type(image).__name__}")
    if "y" not in image.dims or "x" not in image.dims:
        raise ValueError(f"image must have dims 'y' (rows) and 'x' (columns); got {image.dims}")
    if image.sizes["y"] == 0 or image.sizes["x"] == 0:
        raise ValueError("image must have at least one pixel along 'y' and 'x'; got "
                         f"{image.sizes['y']} x {image.sizes['x']}")
    reserved = [d for d in image.dims if d in RESERVED_IMAGE_DIMS]
    if reserved:
        raise ValueError(f"image has a dimension {reserved[0]!r}, a name simulate_image uses "
                         f"itself; rename it (reserved: {', '.join(RESERVED_IMAGE_DIMS)})")
    if image.dtype.kind not in "biuf":
        raise ValueError(f"image must hold real numbers; got dtype {image.dtype}")
    if channel_dim is None:
        channel_dim = next((d for d in CHANNEL_DIMS if d in image.dims), None)
    elif channel_dim not in image.dims:
        raise ValueError(f"channel_dim {channel_dim!r} is not a dim of the image {image.dims}")
    image, labelled_alpha = _drop_alpha(image, channel_dim)
    image = image.rename(y="y_input", x="x_input")  # cast to float tile by tile, or once
    return (image.drop_vars([c for c in image.coords if c in INPUT_DIMS]), channel_dim,
            alpha or labelled_alpha)


def _reference_gsd(image, gsd):
    gsd = image.attrs.get("gsd") if gsd is None else gsd
    if gsd is None:
        raise ValueError("gsd: give the reference image's ground sample distance as gsd= or "
                         "image.attrs['gsd'], in (0, inf) m")
    if isinstance(gsd, xr.DataArray):
        if set(gsd.dims) & {"y", "x"}:
            raise ValueError(f"gsd must not vary over 'y' or 'x'; got dims {gsd.dims}")
        values = gsd.values
    else:
        values = np.asarray(gsd, dtype=float)
        gsd = float(values) if values.ndim == 0 else None
        if gsd is None:
            raise ValueError("gsd must be a float or an xr.DataArray with named dims [m]")
    if not np.all(np.isfinite(values) & (values > 0)):
        raise ValueError(f"gsd must be in (0, inf) m; got {values!r}")
    return gsd


def _components(components, defocus_radius, sensor, im: ImageMethod):
    """The OTF components of the blur, and the defocus radii they need."""
    if components is None:
        components = (*SYSTEM_COMPONENTS, *(("defocus",) if defocus_radius is not None else ()))
    components = (components,) if isinstance(components, str) else tuple(components)
    unknown = [c for c in components if c not in COMPONENTS]
    if unknown or not components:
        raise ValueError(f"components must be a non-empty selection of {COMPONENTS}; "
                         f"got {components!r}")
    if "defocus" in components and defocus_radius is None:
        if im.model.name != "pybsm":
            raise ValueError("defocus_radius (x, y) [rad] must be given with the 'defocus' "
                             "component (xbsm.otf.defocus gives it from a focus error)")
        # pyBSM's DefocusSimulator takes the detector widths as blur radii
        defocus_radius = (sensor["detector_width_x"], sensor["detector_width_y"])
    if defocus_radius is not None:
        pair = isinstance(defocus_radius, tuple | list)
        defocus_radius = tuple(defocus_radius) if pair else (defocus_radius, defocus_radius)
        values = [np.asarray(getattr(r, "values", r), dtype=float) for r in defocus_radius]
        if len(values) != 2 or not all(np.all(np.isfinite(v) & (v >= 0)) for v in values):
            raise ValueError("defocus_radius must be one radius or a pair (x, y) in [0, inf) "
                             f"rad; got {defocus_radius!r}")
    return components, defocus_radius


def _optics(sensor, scenario, radiometry, samp, im: ImageMethod, components, radius, digital):
    """The inputs of the blur kernel."""
    time = (radiometry["effective_integration_time"] if im.integration_time == "effective"
            else sensor["integration_time"])
    # a filter kernel in the blur acts on the camera's pixels, pitch / focal length (pyBSM)
    pixel_angle = (sensor["pixel_pitch_x"] / sensor["focal_length"],
                   sensor["pixel_pitch_y"] / sensor["focal_length"])
    kept = tuple(c for c in components if not (digital and c == "filter"))
    return Optics(sensor, scenario, otf_weights(radiometry["spectral_weights"]), time,
                  samp["slant_range"], im.model, kept, radius, pixel_angle)


def _camera_image(images: dict, optics: Optics, samp, gsd, shape, im: ImageMethod):
    """The blurred image on the camera's pixels, the kernel, and the flags the blur sets.

    The accurate path blurs and resamples the reflectance (both are affine-preserving:
    weights and kernel sum to one) and scales to photoelectrons last; pyBSM's path
    blurs the photoelectrons, as its zero-padded zoom is not affine-preserving.
    """
    angle = samp["reference_angle"]
    taps = resampling_taps(samp, shape, im.resampling)
    if im.psf == "pybsm":
        psf = pybsm_psf(optics, 2 * np.arctan(gsd / 2 / samp["slant_range"]))
        small = (np.abs(psf) > 0).any("psf_x").sum("psf_y") > min(shape)
        out = resample(blur(images["ideal"], psf, im.convolution), taps,
                       single=im.resampling == "pil")
    else:
        half, small = kernel_half_width(optics, angle, shape)
        size_y, size_x = (fft.next_fast_len(n + 2 * half, real=True) for n in shape)
        otf = otf_rfft_grid(optics, angle, size_y, size_x)
        psf = kernel_from_otf(otf, size_x, half)
        if im.convolution == "fft" and im.resampling in ("cubic", "area", "none"):
            out = blur_and_resample(images["reflectance"], otf, half, size_x, taps)
            out = images["offset"] + images["gain"] * out
        elif im.convolution == "fft":
            out = resample(blur_by_otf(images["ideal"], otf, half, size_x), taps,
                           single=im.resampling == "pil")
        else:  # a kernel convolution: the window of the kernel, normalised
            out = resample(blur(images["ideal"], psf / psf.sum(("psf_y", "psf_x")),
                                im.convolution), taps, single=im.resampling == "pil")
    flags = fl.set_flag(fl.empty_flags(), "image_small", small)
    flags = fl.set_flag(flags, "reference_unresolved", nyquist_otf(optics, angle) > 0.05)
    return out, psf, flags


def _tiled(shape, tile_size, im: ImageMethod) -> bool:
    """Whether the image goes through the tiled path (larger than a tile, accurate knobs)."""
    return (max(shape) > tile_size and im.psf == "exact" and im.convolution == "fft"
            and im.resampling in ("cubic", "area", "none"))


def _tiled_camera_image(img, stats, optics: Optics, samp, shape, im: ImageMethod, tile_size,
                        mapping, reflectance_range):
    """The blurred reflectance on the camera's pixels by tiles, the kernel and the flags."""
    angle = samp["reference_angle"]
    taps = resampling_taps(samp, shape, im.resampling)
    half, small = kernel_half_width(optics, angle, shape)
    halo, _ = tile_halo(optics, angle, half, shape)
    core = (tile_core(taps, "y", shape[0], tile_size), tile_core(taps, "x", shape[1], tile_size))
    psf, spectrum = tiled_psf(optics, angle, halo, *core)
    out = tiled_blur_and_resample(img, stats, spectrum, taps, halo, core, mapping,
                                  reflectance_range)
    flags = fl.set_flag(fl.empty_flags(), "image_small", small)
    flags = fl.set_flag(flags, "reference_unresolved", nyquist_otf(optics, angle) > 0.05)
    return out, psf, flags


def _image_name(image) -> str:
    """How the memory guard names an image: its name, and how many a stack holds."""
    name = repr(image.name) if isinstance(image, xr.DataArray) and image.name is not None \
        else "(unnamed)"
    return name


def _memory_needed(img, samp, outputs, counts_dtype, tiled, tile_size) -> int:
    """Estimated peak bytes of a simulation, before anything image-sized is allocated.

    Held: the requested outputs (and, for a dask-backed image, one chunk of the input,
    loaded); working: the untiled path's whole-image arrays (a float copy, the
    percentile mapping's copies, the padded spectrum, the OTF grid) or the tiled path's
    few tile-sized arrays. Output-sized intermediates: about four per output image.
    """
    ny, nx = img.sizes["y_input"], img.sizes["x_input"]
    pixels = ny * nx
    others = [d for d in img.dims if d not in INPUT_DIMS]
    if img.chunks is not None:
        n_img = math.prod(max(img.chunksizes[d]) for d in others)
        held = pixels * n_img * img.dtype.itemsize
    else:
        n_img, held = math.prod(img.sizes[d] for d in others), 0
    cells = samp["size_y"].size
    out_px = int(samp["size_y"].max()) * int(samp["size_x"].max()) * n_img * cells
    chosen = IMAGE_OUTPUTS if outputs is None else outputs
    held += 8 * pixels * n_img * (("reflectance" in chosen) + cells * ("ideal" in chosen))
    held += 8 * out_px * (("blurred" in chosen) + ("noisy" in chosen) + 4)
    held += out_px * (8 if counts_dtype is None else np.dtype(counts_dtype).itemsize)
    if tiled:
        # a tile with the largest halo the wing tolerance may ask for
        grid = (min(tile_size, ny) + 2 * TILE_HALO_MAX) * (min(tile_size, nx)
                                                           + 2 * TILE_HALO_MAX)
        working = 8 * grid * (6 + 4 * cells) + 32 * tile_size**2
    else:
        padded = (ny + 64) * (nx + 64)
        working = 8 * pixels * n_img * 6 + 8 * padded * (n_img + 2 * cells + 2)
    return int(held + working)


def _digital(sensor, components, im: ImageMethod) -> bool:
    kernel = sensor["filter_kernel"]
    identity = kernel.shape == (1, 1) and float(kernel[0, 0]) == 1.0
    return ("filter" in components and not identity and im.filter_stage == "digital"
            and im.resampling != "none")


def _warn_upsampled(samp) -> None:
    upsampled = fl.has_flag(samp["flags"], "upsampled")
    if bool(upsampled.any()):
        warnings.warn(
            f"{int(upsampled.sum())} of {upsampled.size} simulated images are more finely "
            "sampled than the reference image (flag 'upsampled'): the camera is better than "
            "the reference, so they lack detail it would record", UserWarning, stacklevel=3)


def _pixel_coords(ds: xr.Dataset) -> xr.Dataset:
    coords = {}
    for dim, what in (("y", "row of the simulated image"), ("x", "column of the simulated image"),
                      ("y_input", "row of the reference image"),
                      ("x_input", "column of the reference image")):
        if dim in ds.dims:
            coords[dim] = (dim, np.arange(ds.sizes[dim]), {"units": "1", "long_name": what})
    return ds.assign_coords(coords)


def _assemble(images: dict, samp, radiometry, psf, flags, im: ImageMethod, attrs: dict,
              outputs=IMAGE_OUTPUTS):
    """The result Dataset: images (those of ``outputs``), kernel, pixel map and flags."""
    count = "count"
    images = {k: (xr.DataArray(np.nan) if v is None else v) for k, v in images.items()}
    out = xr.Dataset({
        "reflectance": images["reflectance"],
        "ideal": named(images["ideal"], count, "ideal image in photoelectrons (reference "
                       "sampling)"),
        "blurred": named(images["blurred"], count, "blurred image in photoelectrons"),
        "noisy": named(images["noisy"], count, "noisy image in photoelectrons"),
        "counts": images["counts"],
        "psf": psf,
        **{name: samp[name] for name in ("gsd", "gsd_x", "gsd_y", "slant_range", "scale_y",
                                          "scale_x", "offset_y", "offset_x", "size_y",
                                          "size_x")},
        "photoelectron_offset": named(images["offset"], count, "photoelectrons at reflectance 0"),
        "photoelectron_gain": named(images["gain"], count, "photoelectrons per unit "
                                    "reflectance"),
        "effective_integration_time": radiometry["effective_integration_time"],
        "flags": flags.astype(np.int32).assign_attrs(fl.flag_attrs(
            "image simulation validity flags")),
    }, attrs={"method": im.describe(), **attrs})
    return _pixel_coords(out.drop_vars([v for v in IMAGE_OUTPUTS if v not in outputs]))


@contract(outputs=Selection(IMAGE_OUTPUTS))
def simulate_image(image, sensor: xr.Dataset, scenario: xr.Dataset, *, gsd=None, seed=None,
                   noise=True, method="accurate", components=None, reflectance=None,
                   reflectance_range=(0.05, 0.95), convolution=None, resampling=None,
                   basis=None, defocus_radius=None, channel_dim=None, outputs=None,
                   counts_dtype=None, tile_size=None, warn_upsampled=True) -> xr.Dataset:
    """A reference image as the camera would record it in the scenario (paper Eq. 5-6).

    Parameters
    ----------
    image : xr.DataArray or np.ndarray
        Reference image(s): dims ``y`` (rows) and ``x`` (columns), optionally a colour
        channel (``band``, ``channel``, ``colour`` or ``color``, or ``channel_dim``) and any
        leading dims (a stack; not named as a dim or variable of the result,
        :data:`RESERVED_IMAGE_DIMS`). A numpy array is (rows, columns) or
        (rows, columns, 3|4). At least one pixel each way. An alpha channel (the
        fourth of a (rows, columns, 4) array, or a channel labelled "A" or "alpha")
        is dropped: it is not simulated and does not enter the reflectance mapping
        (the result's ``alpha`` attribute says "dropped").
        Dask-backed images stay lazy. [any: pixel values, see ``reflectance``]
    sensor, scenario : xr.Dataset
        From :func:`xbsm.sensor` and :func:`xbsm.scenario`; sweep dims broadcast (the
        parameters are evaluated when called: they set the output sizes).
    gsd : float or xr.DataArray, optional
        Ground sample distance of the reference image; default ``image.attrs["gsd"]``. [m]
    seed : int, optional
        Noise seed (one independent stream per image); ``None``: fresh entropy, recorded
        in the result's ``seed`` attribute.
    noise : bool
        Add shot, dark-current, read and other noise (``noisy`` equals ``blurred`` if not).
    method : str, Method or ImageMethod
        "accurate" (default), "fast", "pybsm" (pyBSM 0.16.1's noiseless outputs, quirks
        included) or :func:`xbsm.simulate.image_method` with knobs.
    components : sequence of str, optional
        OTF components of the blur (``xbsm.simulate.options.COMPONENTS``); default the
        system OTF (plus "defocus" when ``defocus_radius`` is given). One component alone
        is pyBSM's ``JitterSimulator``, ``DetectorSimulator``, ... (``PYBSM_SIMULATORS``).
    reflectance : {"percentile", "minmax", "identity"} or (pixel_values, reflectances)
        Pixel values to reflectance (:func:`xbsm.simulate.image_to_reflectance`); default
        the method's ("percentile").
    reflectance_range : (float, float)
        Reflectances of the two pixel values of "percentile" and "minmax", a pair
        ``0 <= low < high <= 1``. [1]
    convolution, resampling, basis : str, optional
        Override the method's knobs (:class:`xbsm.simulate.ImageMethod`).
    defocus_radius : float or (float, float), optional
        Blur sizes w of IBSM's Gaussian defocus OTF along x and y, as
        :func:`xbsm.otf.defocus.gaussian_defocus` takes them (IBSM's "1/e radius" is
        the PSF's 1/e diameter: it falls to 1/e at w / 2). The exact defocus is the
        sensor's ``defocus_opd``, which enters the "aperture" component as in the
        NIIRS chain. [rad]
    channel_dim : str, optional
        The colour dim, if not one of the usual names.
    outputs : str or sequence of str, optional
        The image-sized variables to return, of :data:`IMAGE_OUTPUTS`; default all.
        ``("counts",)`` for datasets; the pixel map, sizes, GSDs, radiometry and
        ``flags`` are always kept.
    counts_dtype : str or np.dtype, optional
        An unsigned integer dtype for ``counts`` (``"uint16"`` for up to 16-bit
        cameras); cells without a count (past each scenario's size, NaN photoelectrons)
        hold the dtype's maximum, the variable's ``_FillValue`` (its ``encoding``: a
        NetCDF file reads them back as NaN). Default float64 with NaN.
    tile_size : int, optional
        Reference pixels per side of a tile (:data:`xbsm.simulate.tiles.TILE_SIZE`,
        2048, by default; at least 64). A reference image larger than this along ``y``
        or ``x`` is simulated in tiles (with the accurate path's knobs:
        :mod:`xbsm.simulate.tiles`), so the working memory depends on the tile, not the
        image. Any request is refused before allocation (a one-line ``MemoryError``
        naming the image and the sizes) if it cannot fit in the memory available.
    warn_upsampled : bool, optional
        Warn when the camera samples finer than the reference (the ``upsampled`` flag is
        set either way). False for a caller that warns once for many images
        (:func:`simulate_images`, image-dataset studies).

    Returns
    -------
    xr.Dataset
        ``reflectance`` [1] and ``ideal`` [count] on (``y_input``, ``x_input``), the
        reference grid; ``blurred``, ``noisy`` [count] and ``counts`` [1] on (``y``,
        ``x``), the camera's pixels, NaN past each scenario's ``size_y`` x ``size_x``;
        ``psf`` (the blur kernel at the reference sampling) [1]; the pixel map
        ``scale_*``, ``offset_*`` (:func:`xbsm.simulate.transform_points`); ``gsd``,
        ``gsd_x``, ``gsd_y``, ``slant_range`` [m]; ``photoelectron_offset``,
        ``photoelectron_gain`` [count]; ``effective_integration_time`` [s]; ``flags``
        (radiometry, ``upsampled`` with one warning per call, ``image_small``,
        ``image_nonfinite``, ``image_flat``, ``reference_unresolved``).
    """
    return _simulate(image, sensor, scenario, gsd=gsd, seed=seed, noise=noise, method=method,
                     components=components, reflectance=reflectance,
                     reflectance_range=reflectance_range, convolution=convolution,
                     resampling=resampling, basis=basis, defocus_radius=defocus_radius,
                     channel_dim=channel_dim, outputs=outputs, counts_dtype=counts_dtype,
                     tile_size=tile_size, warn=warn_upsampled)


def _simulate(image, sensor, scenario, *, gsd, seed, noise, method, components, reflectance,
              reflectance_range, convolution, resampling, basis, defocus_radius, channel_dim,
              outputs, counts_dtype, tile_size, warn):
    """:func:`simulate_image`; ``warn``: the ``upsampled`` warning (off: the caller's)."""
    check_inputs(sensor, scenario)
    tile_size = TILE_SIZE if tile_size is None else tile_size
    if isinstance(tile_size, bool) or not isinstance(tile_size, int | np.integer) \
            or tile_size < 64:
        raise ValueError(f"tile_size must be a whole number of pixels in [64, inf); got "
                         f"{tile_size!r}")
    counts_dtype, fill = _counts_fill(counts_dtype, sensor)
    im = image_method(method, convolution=convolution, resampling=resampling, basis=basis,
                      reflectance=reflectance if isinstance(reflectance, str) else None)
    img, channel, alpha = _as_image(image, channel_dim)
    gsd = _reference_gsd(img, gsd)
    shape = (img.sizes["y_input"], img.sizes["x_input"])
    mapping = im.reflectance if reflectance is None or isinstance(reflectance, str) else reflectance
    radiometry = reflectance_to_photoelectrons(sensor, scenario, reflectance=[0.0, 1.0],
                                               method=im.model)
    samp = sampling(sensor, scenario, gsd, shape, im)
    tiled = _tiled(shape, tile_size, im)
    check_memory(_memory_needed(img, samp, outputs, counts_dtype, tiled, tile_size),
                 _image_name(image), shape)
    per_image = [*([channel] if channel else []), *INPUT_DIMS]
    comps, radius = _components(components, defocus_radius, sensor, im)
    digital = _digital(sensor, comps, im)
    optics = _optics(sensor, scenario, radiometry, samp, im, comps, radius, digital)
    pe = radiometry["photoelectrons"]
    offset, gain = pe.isel(reflectance=0, drop=True), (pe.isel(reflectance=-1, drop=True)
                                                       - pe.isel(reflectance=0, drop=True))
    chosen = IMAGE_OUTPUTS if outputs is None else outputs
    if tiled:
        mapped = tile_statistics(img, mapping, reflectance_range, per_image, tile_size)
        out, psf, psf_flags = _tiled_camera_image(img, mapped["statistics"], optics, samp,
                                                  shape, im, tile_size, mapping,
                                                  reflectance_range)
        refl = None
        if "reflectance" in chosen or "ideal" in chosen:
            refl = named(tile_reflectance(img, mapped["statistics"], mapping, reflectance_range,
                                          tile_size), "1", "scene reflectance")
        images = dict(reflectance=refl, offset=offset, gain=gain, blurred=offset + gain * out,
                      ideal=None if refl is None or "ideal" not in chosen
                      else offset + gain * refl)
        blurred = images["blurred"]
    else:
        mapped = image_to_reflectance(img, mapping, reflectance_range, dims=per_image)
        # the ideal image (reference-sized, per scenario) only where it is kept or blurred
        fused = (im.psf == "exact" and im.convolution == "fft"
                 and im.resampling in ("cubic", "area", "none"))
        images = dict(reflectance=mapped["reflectance"], offset=offset, gain=gain,
                      ideal=offset + gain * mapped["reflectance"]
                      if "ideal" in chosen or not fused else None)
        blurred, psf, psf_flags = _camera_image(images, optics, samp, gsd, shape, im)
    # a DataArray of seeds: one per image of a stack (simulate_images' batches)
    entropy = seed if isinstance(seed, xr.DataArray) else camera.seed_entropy(seed)
    noisy = (camera.add_noise(blurred, sensor, seed=entropy, quantization=im.quantization)
             if noise else blurred)
    if digital:
        blurred, noisy = (camera.digital_filter(a, sensor["filter_kernel"], samp["size_y"],
                                                samp["size_x"]) for a in (blurred, noisy))
    flags = radiometry["flags"] | samp["flags"] | psf_flags | mapped["flags"]
    if warn:
        _warn_upsampled(samp)
    counts = camera.digitize(noisy, sensor, im.quantization)
    if counts_dtype is not None:
        counts = _integer_counts(counts, counts_dtype, fill)
    images.update(blurred=blurred, noisy=noisy, counts=counts)
    return _assemble(images, samp, radiometry, psf, flags, im, outputs=outputs, attrs={
        "seed": "per image" if isinstance(entropy, xr.DataArray) else str(entropy),
        "noise": "on" if noise else "off",
        "components": " ".join(comps), "reference_gsd": str(gsd),
        **({"alpha": "dropped"} if alpha else {})})


def _image_seed(entropy: int, index: int) -> int:
    """The seed of image ``index`` of a list: spawned from the run's seed and its position."""
    words = np.random.SeedSequence(entropy, spawn_key=(index,)).generate_state(2, np.uint32)
    return int(words[0]) << 32 | int(words[1])


def _as_list_item(item, index: int):
    """One image of a list as a DataArray named by its name or its index (for messages)."""
    if isinstance(item, xr.DataArray):
        return item if item.name is not None else item.rename(f"#{index}")
    array = np.asarray(item)
    dims = ("y", "x") if array.ndim == 2 else ("y", "x", "band")
    if array.ndim == 3 and array.shape[-1] == 4:  # RGBA: the alpha channel labelled, dropped
        return xr.DataArray(array, dims=dims, name=f"#{index}",
                            coords={"band": ["R", "G", "B", "A"]})
    if array.ndim not in (2, 3):
        raise ValueError(f"images[{index}] must be 2-D (rows, columns) or 3-D (rows, columns, "
                         f"3 or 4 channels); got shape {array.shape}")
    return xr.DataArray(array, dims=dims, name=f"#{index}")


BATCH_PIXELS = 1 << 22
"""Reference pixel values (rows x columns x channels) of one batch of
:func:`simulate_images`: images of one shape, dtype and GSD are simulated together
in batches up to this size (about 4 million values, 32 MB per float64 copy)."""


def _batches(images, gsds, tile_size):
    """Lists of image indices simulated together.

    Numpy images of one shape, dtype and GSD go together (untiled, up to
    :data:`BATCH_PIXELS` values per batch); every other image goes alone.
    """
    groups, order = {}, []
    for i, (item, g) in enumerate(zip(images, gsds, strict=True)):
        key = None
        if isinstance(item, np.ndarray) and item.ndim in (2, 3) and np.ndim(g) == 0 \
                and max(item.shape[:2]) <= tile_size and item.size > 0:
            key = (item.shape, item.dtype.str, float(g))
        if key is None or key not in groups or \
                (len(groups[key]) + 1) * item.size > max(BATCH_PIXELS, item.size):
            groups[key if key is not None else ("alone", i)] = group = []
            order.append(group)
        groups[key if key is not None else ("alone", i)].append(i)
    return order


def _stacked(images, indices):
    """Images of one shape as one DataArray over ("stack", y, x[, band])."""
    array = np.stack([images[i] for i in indices])
    dims = ("stack", "y", "x") if array.ndim == 3 else ("stack", "y", "x", "band")
    coords = {"band": ["R", "G", "B", "A"]} if array.ndim == 4 and array.shape[-1] == 4 else {}
    return xr.DataArray(array, dims=dims, coords=coords, name=f"#{indices[0]}")


def _seeds(seed, seeds, n: int) -> list:
    """One seed per image: spawned from ``seed`` and the position, or ``seeds`` as given."""
    if seeds is None:
        entropy = camera.seed_entropy(seed)
        return [_image_seed(entropy, i) for i in range(n)]
    if seed is not None:
        raise ValueError("give seed (the run's) or seeds (one per image), not both")
    seeds = list(seeds)
    if len(seeds) != n:
        raise ValueError(f"seeds must give one seed per image ({n}); got {len(seeds)}")
    for i, value in enumerate(seeds):
        if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < 0:
            raise ValueError(f"seeds[{i}] must be a non-negative whole number; got {value!r}")
    return [int(value) for value in seeds]


def simulate_images(images, sensor: xr.Dataset, scenario: xr.Dataset, *, gsd, seed=None,
                    seeds=None, warn_upsampled=True, **kwargs) -> list:
    """A list of reference images of any sizes and channel counts, one run of the camera.

    Each image is simulated on its own sampling, as :func:`simulate_image` does (its own
    blur: one kernel per distinct optical state and reference sampling, never one image's
    kernel reused for another's sampling); a camera that samples finer than a reference
    is flagged ``upsampled`` on each such image and warned about once for the whole list.

    Images of one shape, dtype and GSD (numpy arrays no larger than a tile) are
    simulated together, as one stack (up to :data:`BATCH_PIXELS` values at a time):
    the radiometry, sampling and blur are computed once per batch, the reflectance
    mapping and the noise stream stay each image's own, so every result equals the
    :func:`simulate_image` call of that image alone with its seed.

    Parameters
    ----------
    images : sequence of np.ndarray or xr.DataArray
        Reference images, each as :func:`simulate_image` takes one; a DataArray's name
        (else ``#index``) names it in messages.
    sensor, scenario : xr.Dataset
        As for :func:`simulate_image`.
    gsd : float or sequence of float
        Reference GSD, one for all or one per image. [m]
    seed : int, optional
        The run's seed; image ``i`` gets a seed spawned from it and ``i`` (recorded in its
        result's ``seed`` attribute, so any image can be regenerated alone). ``None``:
        fresh entropy.
    seeds : sequence of int, optional
        Instead of ``seed``: the seed of each image, used as given (image-dataset
        studies give each output its own).
    warn_upsampled : bool
        The one ``upsampled`` warning for the list (False: the caller warns, from the
        flags, e.g. once for a whole dataset).
    **kwargs
        Any other keyword of :func:`simulate_image`.

    Returns
    -------
    list of xr.Dataset
        One :func:`simulate_image` result per image, in order.
    """
    images = list(images)
    gsds = [gsd] * len(images) if np.ndim(gsd) == 0 else list(gsd)
    if len(gsds) != len(images):
        raise ValueError(f"gsd must be one value or one per image ({len(images)}); got "
                         f"{len(gsds)}")
    per_image = _seeds(seed, seeds, len(images))
    options = dict(noise=True, method="accurate", components=None, reflectance=None,
                   reflectance_range=(0.05, 0.95), convolution=None, resampling=None,
                   basis=None, defocus_radius=None, channel_dim=None, outputs=None,
                   counts_dtype=None, tile_size=None)
    unknown = sorted(set(kwargs) - set(options))
    if unknown:
        raise ValueError(f"simulate_images got unknown keywords {unknown}; it takes those of "
                         "simulate_image")
    options.update(kwargs)
    options["outputs"] = Selection(IMAGE_OUTPUTS).check("outputs", options["outputs"])
    tile_size = TILE_SIZE if options["tile_size"] is None else options["tile_size"]
    tile_size = tile_size if isinstance(tile_size, int | np.integer) else TILE_SIZE
    results = [None] * len(images)
    for batch in _batches(images, gsds, tile_size):
        if len(batch) == 1:
            i = batch[0]
            results[i] = _simulate(_as_list_item(images[i], i), sensor, scenario, gsd=gsds[i],
                                   seed=per_image[i], warn=False, **options)
            continue
        stack = _stacked(images, batch)
        out = _simulate(stack, sensor, scenario, gsd=gsds[batch[0]], warn=False,
                        seed=xr.DataArray(np.array([per_image[i] for i in batch], dtype=object),
                                          dims="stack"), **options)
        for k, i in enumerate(batch):
            results[i] = out.isel(stack=k, drop=True).assign_attrs(seed=str(per_image[i]))
    upsampled = [i for i, r in enumerate(results)
                 if bool(fl.has_flag(r["flags"], "upsampled").any())]
    if upsampled and warn_upsampled:
        shown = ", ".join(str(i) for i in upsampled[:10]) + (", ..." if len(upsampled) > 10
                                                              else "")
        warnings.warn(
            f"{len(upsampled)} of {len(results)} images (indices {shown}) are more finely "
            "sampled by the camera than by their reference (flag 'upsampled'): the camera "
            "is better than the reference, so they lack detail it would record",
            UserWarning, stacklevel=2)
    return results
