"""The system blur at the reference image's own sampling (paper Eq. 6, h = R[F[g]]).

``method="accurate"`` does not truncate the blur to a kernel: the system OTF is
sampled on the discrete-Fourier grid of the reference image (reflect-padded by
the blur's core, :func:`kernel_half_width`) and multiplies the image's
transform, an exact convolution with the band-limited system response. The
kernel reported with a simulation is the middle of that grid's inverse
transform (:func:`kernel_from_otf`), centred on its middle sample.

Any grid costs little: the polychromatic, radially symmetric parts (aperture,
turbulence) are evaluated once per scenario on a 1-D radial table
(``RADIAL_SAMPLES`` points, linear interpolation)
or, for pyBSM's grid, once per distinct radius (:func:`otf_on_grid`); the
separable parts (detector, jitter, drift) are outer products of their exact x
and y slices; only the wavefront, defocus and filter OTFs, when present, are
evaluated on the full grid.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import xarray as xr
from scipy import fft as sp_fft

from .._metadata import Output
from ..methods import Method
from ..otf import defocus, detector, filters, motion, wavefront
from ..otf.system import spectral_bins, system_components
from ..params import contract

__all__ = ["Optics", "kernel_from_otf", "kernel_half_width", "nyquist_otf", "otf_on_grid",
           "otf_rfft_grid"]

RADIAL_SAMPLES = 4097
"""Points of the radial table of the aperture and turbulence OTFs, from 0 to the grid's
corner or the largest optics cutoff; linear interpolation (within 1e-6 of the exactly
evaluated OTF: ``tests/simulate/test_simulate.py``)."""
_RADIAL = ("aperture", "turbulence")
_BLOCK = 4_000_000


@dataclass(frozen=True)
class Optics:
    """What the blur of one simulation depends on (every field may carry sweep dims)."""

    sensor: xr.Dataset
    scenario: xr.Dataset
    weights: xr.DataArray
    """Spectral weights of the polychromatic OTFs (:func:`xbsm.otf.system.otf_weights`)."""
    integration_time: xr.DataArray
    slant_range: xr.DataArray
    method: Method
    components: tuple
    """OTF components in the blur (``xbsm.simulate.options.COMPONENTS``)."""
    defocus_radius: tuple | None = None
    """Blur sizes w (x, y) of the Gaussian defocus OTF (its PSF's 1/e radius is w / 2). [rad]"""
    pixel_angle: tuple | None = None
    """The camera's pixel angles (x, y), for a filter kernel in the blur. [rad]"""


def _slices(optics: Optics, frequency: xr.DataArray) -> xr.Dataset:
    """System components along x and y at ``frequency``, in blocks that bound memory."""
    n_wl = optics.weights.sizes.get("wavelength", 1)
    cells = max(1, math.prod(s for d, s in frequency.sizes.items() if d != "frequency"))
    block = max(16, _BLOCK // (n_wl * cells))
    parts = []
    for start in range(0, frequency.sizes["frequency"], block):
        f = frequency.isel(frequency=slice(start, start + block))
        out = system_components(
            optics.sensor, optics.scenario, f, spectral_weights=optics.weights,
            integration_time=optics.integration_time, slant_range=optics.slant_range,
            method=optics.method)
        parts.append(out[list(_RADIAL)])
    return xr.concat(parts, dim="frequency"), out["coherence_diameter"]


def kernel_half_width(optics: Optics, angle, shape):
    """Half-width of the blur's core in reference pixels, and where it exceeds the image.

    Parameters
    ----------
    optics : Optics
    angle : xr.DataArray
        Reference image sample angle. [rad]
    shape : (int, int)
        Reference image rows and columns.

    Returns
    -------
    int, xr.DataArray
        The largest half-width over the scenarios (at most the image size), which pads
        the FFT grid: the sum of 4 lambda_max / D plus the defocus blur circle, the
        detector width, 4 rms jitter,
        the drift, 4 lambda_max / r0, 3 defocus radii and the filter kernel; and per
        scenario whether twice the same sum over the chosen components only exceeds
        the image (flag ``image_small``).
    """
    s = optics.sensor
    _, r0 = _slices(optics, xr.DataArray([0.0], dims="frequency"))
    exposure = optics.integration_time * s["tdi_stages"]
    widths = {  # the core of each component's blur
        # plus the defocus blur circle d = 8 W020 / D (0 in focus: the same to the bit)
        "aperture": lambda: (4 * s["wavelength_max"] / s["aperture_diameter"]
                             + 8.0 * s["defocus_opd"] / s["aperture_diameter"]),
        "detector": lambda: (np.maximum(s["detector_width_x"], s["detector_width_y"])
                             / s["focal_length"]),
        "jitter": lambda: 4 * np.maximum(s["jitter_x"], s["jitter_y"]),
        "drift": lambda: np.maximum(abs(s["drift_rate_x"]), abs(s["drift_rate_y"])) * exposure,
        "turbulence": lambda: 4 * s["wavelength_max"] / r0,
    }
    extra = xr.DataArray(0.0)
    if optics.defocus_radius is not None:
        extra = extra + 3 * max(float(np.max(r)) for r in optics.defocus_radius)
    if "filter" in optics.components:
        extra = extra + max(s["filter_kernel"].shape) * np.maximum(*optics.pixel_angle)
    # the padding keeps every component's width (a wide margin costs only FFT size); the
    # image_small test counts only the chosen components' blur
    padding_px = np.ceil((sum(width() for width in widths.values()) + extra) / angle)
    chosen_px = np.ceil((sum((width() for name, width in widths.items()
                              if name in optics.components), xr.DataArray(0.0)) + extra) / angle)
    half = int(min(max(1.0, float(np.max(padding_px))), max(shape)))
    return half, (2 * chosen_px + 1 > min(shape))


def _along(values: xr.DataArray, orientation: str) -> xr.DataArray:
    """The slice along x or y (radially symmetric components have no orientation dim)."""
    if "orientation" in values.dims:
        return values.sel(orientation=orientation, drop=True)
    return values


def _separable(optics: Optics, fx, fy):
    """The chosen detector, jitter and drift OTFs: products of their x and y factors."""
    s = optics.sensor
    exposure = optics.integration_time * s["tdi_stages"]
    factors = {
        "detector": lambda u, v: detector.detector(u, v, s["detector_width_x"],
                                                   s["detector_width_y"], s["focal_length"]),
        "jitter": lambda u, v: motion.jitter(u, v, s["jitter_x"], s["jitter_y"]),
        "drift": lambda u, v: motion.drift(u, v, s["drift_rate_x"] * exposure,
                                           s["drift_rate_y"] * exposure),
    }
    along_x, along_y = xr.DataArray(1.0), xr.DataArray(1.0)
    for name in optics.components:
        if name in factors:
            along_x = along_x * factors[name](fx, 0.0 * fx)
            along_y = along_y * factors[name](0.0 * fy, fy)
    return along_y * along_x


def _radial_product(table: xr.Dataset, components) -> xr.DataArray | None:
    """The product of the chosen radially symmetric components on a radial table."""
    chosen = [_along(table[name], "x") for name in components if name in _RADIAL]
    return math.prod(chosen) if chosen else None


def _wavefront(optics: Optics, fx, fy):
    """Polychromatic random-phase wavefront OTF on the 2-D grid (as system_components)."""
    s = optics.sensor
    wl, w = spectral_bins(optics.weights["wavelength"], optics.weights,
                          optics.method.otf_wavelengths)
    wl = xr.DataArray(np.asarray(wl), dims="wavelength", coords={"wavelength": np.asarray(wl)})
    mono = wavefront.random_phase_wavefront(
        fx, fy, wl, s["wavefront_variance"], s["wavefront_correlation_length_x"],
        s["wavefront_correlation_length_y"], s["wavefront_wavelength"])
    return (mono * (w / w.sum("wavelength"))).sum("wavelength")


def _grid_only_parts(optics: Optics, fx, fy) -> list:
    """Wavefront, defocus and filter OTFs on the full grid, where chosen and not 1."""
    s, parts = optics.sensor, []
    if "wavefront" in optics.components and bool((s["wavefront_variance"] > 0).any()):
        parts.append(_wavefront(optics, fx, fy))
    if "defocus" in optics.components:
        parts.append(defocus.gaussian_defocus(fx, fy, *optics.defocus_radius))
    kernel = s["filter_kernel"]
    if "filter" in optics.components and kernel.size > 1:
        method = optics.method.filter_otf
        if method == "pybsm":
            parts.append(filters.sharpening_filter(fx, fy, kernel.values,
                                                   float(optics.pixel_angle[0]), method=method))
        else:
            parts.append(filters.sharpening_filter(fx, fy, kernel.values, *optics.pixel_angle))
    return parts


def otf_on_grid(optics: Optics, step, size: int, *, rows_descending=False) -> xr.DataArray:
    """The chosen OTF components on a square grid of ``size`` (odd) frequencies per axis.

    Parameters
    ----------
    optics : Optics
    step : xr.DataArray
        Frequency step of the grid, per scenario. [cycles/rad]
    size : int
        Odd number of frequencies per axis, ``(k - size // 2) * step``.
    rows_descending : bool
        Rows run from +fy down (pyBSM's grid), which matters for the pyBSM filter only.

    Returns
    -------
    xr.DataArray
        Over (scenario dims, ``fy``, ``fx``), coordinates in cycles per reference pixel
        ``k / size`` (for :func:`xbsm.otf.psf.otf_to_psf`). [1]
    """
    half = size // 2
    k = np.arange(size) - half
    squares, where = np.unique(k[:, None] ** 2 + k[None, :] ** 2, return_inverse=True)
    fx = xr.DataArray(k, dims="fx") * step
    fy = xr.DataArray(-k if rows_descending else k, dims="fy") * step
    otf = _separable(optics, fx, fy)
    if any(name in _RADIAL for name in optics.components):
        radial, _ = _slices(optics, xr.DataArray(np.sqrt(squares), dims="frequency") * step)
        index = xr.DataArray(where.reshape(size, size), dims=("fy", "fx"))
        otf = otf * _radial_product(radial, optics.components).isel(frequency=index)
    for part in _grid_only_parts(optics, fx, fy):
        otf = otf * part
    cycles = xr.DataArray(k / size, dims="fx")
    otf = otf.drop_vars([c for c in otf.coords if c not in otf.dims])
    return otf.broadcast_like(cycles * cycles.rename(fx="fy")).assign_coords(
        fx=k / size, fy=k / size)


def otf_rfft_grid(optics: Optics, angle, size_y: int, size_x: int) -> xr.DataArray:
    """The chosen OTF components at the frequencies of ``rfft2`` on a size_y x size_x grid.

    Parameters
    ----------
    optics : Optics
    angle : xr.DataArray
        Reference image sample angle, per scenario. [rad]
    size_y, size_x : int
        The (padded) image's rows and columns.

    Returns
    -------
    xr.DataArray
        Over (scenario dims, ``fy``, ``fx``): ``fy`` in ``numpy.fft.fftfreq`` order,
        ``fx`` from 0 to Nyquist (``rfftfreq``), both in cycles per reference pixel. [1]
    """
    fy, fx = np.fft.fftfreq(size_y), np.fft.rfftfreq(size_x)
    otf = _separable(optics, xr.DataArray(fx, dims="fx") / angle,
                     xr.DataArray(fy, dims="fy") / angle)
    if any(name in _RADIAL for name in optics.components):
        # to the grid's corner or the largest optics cutoff, whichever is lower
        extent = min(np.sqrt(0.5), 1.0001 * float((_cutoff(optics) * angle).max()))
        table_px = np.linspace(0.0, extent, RADIAL_SAMPLES)
        table, _ = _slices(optics, np.minimum(xr.DataArray(table_px, dims="frequency") / angle,
                                              _cutoff(optics)))
        rho = np.hypot(fy[:, None], fx[None, :]) / table_px[1]
        first = np.minimum(rho.astype(np.int64), RADIAL_SAMPLES - 2)
        frac = xr.DataArray(np.minimum(rho - first, 1.0), dims=("fy", "fx"))
        index = xr.DataArray(first, dims=("fy", "fx"))
        radial = _radial_product(table, optics.components)
        low = radial.isel(frequency=index)
        otf = otf * (low + (radial.isel(frequency=index + 1) - low) * frac)
    for part in _grid_only_parts(optics, xr.DataArray(fx, dims="fx") / angle,
                                 xr.DataArray(fy, dims="fy") / angle):
        otf = otf * part
    otf = otf.drop_vars([c for c in otf.coords if c not in otf.dims])
    grid = xr.DataArray(np.zeros((size_y, fx.size)), dims=("fy", "fx"))
    return otf.broadcast_like(grid).assign_coords(fy=fy, fx=fx)


@contract(Output("psf", "1", "blur kernel at the reference image's sampling"))
def kernel_from_otf(otf: xr.DataArray, size_x: int, half_width: int) -> xr.DataArray:
    """The middle (2 half_width + 1)^2 samples of the blur kernel of an ``otf_rfft_grid``.

    Parameters
    ----------
    otf : xr.DataArray
        From :func:`otf_rfft_grid` (``size_x`` columns before the real FFT halving).
    size_x : int
        Columns of the grid.
    half_width : int
        Half-width of the window. [reference pixels]

    Returns
    -------
    xr.DataArray
        Over (scenario dims, ``psf_y``, ``psf_x``), coordinates in reference pixels from
        the kernel's centre; it sums to one less the energy of the wings beyond the
        window. [1]
    """
    offsets = np.arange(-half_width, half_width + 1)

    def middle(spectrum):  # the inverse transform along y, the window's rows, then along x
        rows = np.take(sp_fft.ifft(spectrum, axis=-2), offsets % spectrum.shape[-2], axis=-2)
        return np.take(sp_fft.irfft(rows, n=size_x, axis=-1), offsets % size_x, axis=-1)

    out = xr.apply_ufunc(middle, otf, input_core_dims=[["fy", "fx"]],
                         output_core_dims=[["psf_y", "psf_x"]])
    out = out.assign_coords(psf_y=("psf_y", offsets.astype(float), {"units": "1"}),
                            psf_x=("psf_x", offsets.astype(float), {"units": "1"}))
    return out


def _cutoff(optics: Optics):
    """The optics cutoff D / lambda_min, in cycles/rad.

    Beyond it the aperture OTF is zero and the radial components are held at their
    cutoff values (the short-exposure turbulence OTF is not defined there and overflows
    beyond 8 D / lambda).
    """
    return optics.sensor["aperture_diameter"] / optics.sensor["wavelength_min"]


@contract(Output("nyquist_otf", "1", "largest |OTF| at the reference image's Nyquist frequency"))
def nyquist_otf(optics: Optics, angle: xr.DataArray) -> xr.DataArray:
    """The chosen components' |OTF| at the reference image's Nyquist frequency.

    Aperture, turbulence, detector, jitter and drift; the larger of the x and y slices. [1]
    """
    nyquist = 0.5 / angle
    zero = 0.0 * nyquist
    otf = np.maximum(np.abs(_separable(optics, nyquist, zero)),
                     np.abs(_separable(optics, zero, nyquist)))
    radial, _ = _slices(optics, np.minimum(nyquist, _cutoff(optics)).expand_dims("frequency"))
    for name in optics.components:
        if name in _RADIAL:
            otf = otf * np.abs(_along(radial[name], "x").isel(frequency=0, drop=True))
    return otf
