"""pyBSM 0.16.1's blur kernel, quirks included (``method="pybsm"``; docs/quirks.md).

pyBSM samples the OTF on a 1501 x 1501 grid to the optics cutoff D / lambda_min,
transforms it with ``fftshift`` where ``ifftshift`` is needed (on its odd grid
this modulates the kernel by a checkerboard-like cosine), resamples the result
to the reference image's sample angle with an unfiltered linear ``zoom``,
normalises it, and crops the middle until it holds 95 % of the energy: kernels
of even size, which shift the image by half a pixel, and kernels under 10
samples cropped off-centre. This module rebuilds that kernel from xbsm's own OTFs
(``method="pybsm"`` knobs), scenario by scenario.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import xarray as xr
from scipy import fft
from scipy.ndimage import zoom

from .._metadata import Output
from ..params import contract
from .psf import Optics, otf_on_grid

__all__ = ["pybsm_psf"]

GRID = 1501
"""pyBSM's OTF grid size (``simulate_image`` and ``ImageSimulator``)."""
ENERGY = 0.95
"""pyBSM's crop: the smallest middle square, from 10 samples in steps of 5, above this."""


def _cell(ds, index: dict):
    """The part of a dataset or array at one scenario cell (dims it lacks are ignored)."""
    if not isinstance(ds, xr.DataArray | xr.Dataset):
        return ds
    return ds.isel({d: i for d, i in index.items() if d in ds.dims})


def _grid_otf(optics: Optics, cutoff: float):
    """The chosen OTF components on pyBSM's grid (rows from +cutoff down), and its step."""
    u = np.linspace(-1.0, 1.0, GRID) * cutoff
    v = np.linspace(1.0, -1.0, GRID) * cutoff
    step = (abs(u[1] - u[0]) + abs(v[0] - v[1])) / 2
    otf = otf_on_grid(optics, xr.DataArray(2.0 * cutoff / (GRID - 1)), GRID,
                      rows_descending=True)
    return np.real(otf.transpose("fy", "fx").values), step


def _middle(array: np.ndarray, size: int) -> np.ndarray:
    """The middle crop of pyBSM: floor(d/2 - k/2) to ceil(d/2 + k/2), Python slice rules."""
    return array[tuple(slice(int(np.floor(d / 2 - size / 2)), int(np.ceil(d / 2 + size / 2)))
                       for d in array.shape)]


def _pybsm_kernel(otf: np.ndarray, df: float, angle: float) -> np.ndarray:
    """The steps of pyBSM's otf_to_psf on one OTF grid."""
    psf = np.real(fft.fftshift(fft.ifft2(fft.fftshift(otf))))
    step = 1.0 / (otf.shape[0] * df)
    new = [max(1, int(n * step / angle)) for n in (psf.shape[1], psf.shape[0])]
    psf = zoom(psf, (new[0] / psf.shape[1], new[1] / psf.shape[0]), order=1, grid_mode=True,
               mode="grid-constant").astype(np.float64)
    psf = psf / psf.sum()
    out = np.asarray([])
    for size in np.arange(10, min(otf.shape), 5):
        out = _middle(psf, size)
        if out.sum() > ENERGY:
            break
    return out / out.sum()


def _placed(kernels: list[np.ndarray]) -> np.ndarray:
    """Kernels of any sizes in one odd array, each kernel's origin (index n // 2) centred."""
    half = max(max(k.shape) for k in kernels) // 2
    size = 2 * half + 1
    out = np.zeros((len(kernels), size, size))
    for i, k in enumerate(kernels):
        top, left = half - k.shape[0] // 2, half - k.shape[1] // 2
        out[i, top:top + k.shape[0], left:left + k.shape[1]] = k
    return out


@contract(Output("psf", "1", "blur kernel at the reference image's sampling (pyBSM 0.16.1)"))
def pybsm_psf(optics: Optics, angle: xr.DataArray):
    """The blur kernel of pyBSM 0.16.1 for every scenario, placed in one odd-sized array.

    Parameters
    ----------
    optics : Optics
        Sensor, scenario, spectral weights, timing and the chosen components (a
        ``method="pybsm"`` model method reproduces pyBSM's OTFs).
    angle : xr.DataArray
        The kernel's sample angle, pyBSM's ``2 arctan(gsd / 2 / slant_range)``. [rad]

    Returns
    -------
    xr.DataArray
        Over (scenario dims, ``psf_y``, ``psf_x``), coordinates in reference pixels from
        the kernel's origin (pyBSM's index n // 2, zero padded around each kernel). [1]
    """
    weights = optics.weights
    cells = xr.broadcast(angle, optics.slant_range, optics.integration_time,
                         optics.sensor["aperture_diameter"],
                         weights.isel(wavelength=0, drop=True))[0]
    kernels = []
    for index in np.ndindex(cells.shape):
        at = dict(zip(cells.dims, index, strict=True))
        w = _cell(weights, at)
        cutoff = float(_cell(optics.sensor["aperture_diameter"], at)
                       / w["wavelength"].where(w > 0).min())
        one = dataclasses.replace(
            optics, sensor=_cell(optics.sensor, at), scenario=_cell(optics.scenario, at),
            weights=w, integration_time=_cell(optics.integration_time, at),
            slant_range=_cell(optics.slant_range, at),
            pixel_angle=tuple(_cell(a, at) for a in optics.pixel_angle),
            defocus_radius=None if optics.defocus_radius is None else tuple(
                _cell(r, at) for r in optics.defocus_radius))
        otf, df = _grid_otf(one, cutoff)
        kernels.append(_pybsm_kernel(otf, df, float(_cell(angle, at))))
    placed = _placed(kernels)
    half = placed.shape[-1] // 2
    offsets = np.arange(-half, half + 1, dtype=float)
    psf = xr.DataArray(placed.reshape(*cells.shape, *placed.shape[1:]),
                       dims=(*cells.dims, "psf_y", "psf_x"),
                       coords={"psf_y": ("psf_y", offsets, {"units": "1"}),
                               "psf_x": ("psf_x", offsets, {"units": "1"}),
                               **{d: cells[d] for d in cells.dims if d in cells.coords}})
    return psf
