"""Blurring reference images by a kernel (paper Eq. 5, h convolved with o).

- "fft" (default): the image reflect-padded by the kernel's half size, multiplied
  by the kernel's transform, the kernel placed by its coordinates (a kernel whose
  middle sample is not at offset 0, as an even-sized one, is shifted back by a
  phase ramp: no half-pixel shift); a true convolution.
- "fft_zero": zero padding (pyBSM ``DefocusSimulator``'s ``fftconvolve``: borders
  darken).
- "pad_fft": pyBSM's ``pad_fftconvolve`` (reflect padding, an even kernel padded
  to odd at its top and left).
- "correlate": ``scipy.ndimage.correlate`` in mirror mode (pyBSM's
  ``simulate_image``; its ``oaconvolve`` simulators compute the same).

The pyBSM choices centre a kernel on its index n // 2, a half-pixel shift for
even sizes, as pyBSM does.
"""

from __future__ import annotations

import numpy as np
import xarray as xr
from scipy import fft
from scipy.ndimage import correlate

from ..params import contract
from ._arrays import align_leading
from .options import IMAGE_RULES

__all__ = ["blur", "blur_by_otf", "cropped_inverse", "padded_spectrum"]


def _fft_kernel(img, psf, centre_y, centre_x):
    """Convolve (..., ny, nx) images by (..., ky, kx) kernels; reflect borders, by FFT."""
    img, psf = align_leading(img, 2, psf, 2)
    half_y, half_x = psf.shape[-2] // 2, psf.shape[-1] // 2
    lead = [(0, 0)] * (img.ndim - 2)
    padded = np.pad(img, [*lead, (half_y, half_y), (half_x, half_x)], mode="reflect")
    shape = [fft.next_fast_len(n, real=True) for n in padded.shape[-2:]]
    kernel = np.zeros(psf.shape[:-2] + tuple(shape))
    kernel[..., : psf.shape[-2], : psf.shape[-1]] = psf
    kernel = np.roll(kernel, (-half_y, -half_x), axis=(-2, -1))
    spectrum = fft.rfft2(kernel, axes=(-2, -1))
    if centre_y or centre_x:  # the middle sample sits at (centre_y, centre_x): move it back
        fy = fft.fftfreq(shape[0])[:, None]
        fx = fft.rfftfreq(shape[1])[None, :]
        spectrum = spectrum * np.exp(-2j * np.pi * (fy * centre_y + fx * centre_x))
    out = fft.irfft2(fft.rfft2(padded, s=shape, axes=(-2, -1)) * spectrum, s=shape,
                     axes=(-2, -1))
    return out[..., half_y: half_y + img.shape[-2], half_x: half_x + img.shape[-1]]


def _each(func, img, psf):
    """Apply a 2-D scipy routine to every broadcast pair of image and kernel."""
    img, psf = align_leading(img, 2, psf, 2)
    lead = np.broadcast_shapes(img.shape[:-2], psf.shape[:-2])
    img = np.broadcast_to(img, lead + img.shape[-2:])
    psf = np.broadcast_to(psf, lead + psf.shape[-2:])
    out = np.empty(img.shape)
    for index in np.ndindex(lead):
        out[index] = func(img[index], psf[index])
    return out


def _correlate(img, psf):
    return correlate(img, psf, mode="mirror")


def _odd(psf):
    """An even-sized kernel padded at its end to odd size: its origin n // 2 stays put."""
    return np.pad(psf, ((0, 1 - psf.shape[0] % 2), (0, 1 - psf.shape[1] % 2)))


def _pad_fft(img, psf):
    """The pad_fftconvolve of pyBSM on one image: reflect pad, correlate by FFT, middle part."""
    psf = _odd(psf)
    half_y, half_x = psf.shape[0] // 2, psf.shape[1] // 2
    padded = np.pad(img, ((half_y, half_y), (half_x, half_x)), mode="reflect")
    from scipy.signal import fftconvolve  # here: scipy.signal takes a second to import

    return fftconvolve(padded, psf[::-1, ::-1], mode="valid")


def _fft_zero(img, psf):
    """The fftconvolve of pyBSM (mode "same") on one image: zero outside the image."""
    from scipy.signal import fftconvolve

    return fftconvolve(img, _odd(psf)[::-1, ::-1], mode="same")


_PYBSM = {"correlate": _correlate, "pad_fft": _pad_fft, "fft_zero": _fft_zero}


def _pybsm_kernel(img, psf, routine):
    return _each(_PYBSM[routine], img, psf)


@contract(convolution=IMAGE_RULES["convolution"])
def blur(image: xr.DataArray, psf: xr.DataArray, convolution="fft",
         dims=("y_input", "x_input")) -> xr.DataArray:
    """Images blurred by a kernel sampled at their own sample spacing.

    Parameters
    ----------
    image : xr.DataArray
        Images over ``dims`` (rows, columns); other dims broadcast against the kernel's.
        [any]
    psf : xr.DataArray
        Kernel over (``psf_y``, ``psf_x``), summing to one, with coordinates: the
        offset of each sample from the kernel's centre in image pixels (odd or even
        sizes). [1]
    convolution : {"fft", "fft_zero", "pad_fft", "correlate"}
        See the module docstring. The pyBSM choices use the kernel as pyBSM does: its
        origin at index n // 2 whatever the coordinates, correlation not convolution.
    dims : (str, str)
        The image's row and column dims.

    Returns
    -------
    xr.DataArray
        The blurred images, on the broadcast dims, in the input's units. [any]
    """
    for dim in ("psf_y", "psf_x"):
        if dim not in psf.dims:
            raise ValueError(f"psf must have dims ('psf_y', 'psf_x'); got {psf.dims}")
    if image.chunks is not None:
        image = image.chunk({d: -1 for d in dims})
    if convolution == "fft":
        kernel, kwargs = _fft_kernel, {
            f"centre_{a}": float(psf[f"psf_{a}"][psf.sizes[f"psf_{a}"] // 2])
            if f"psf_{a}" in psf.coords else 0.0 for a in ("y", "x")}
    else:
        kernel, kwargs = _pybsm_kernel, {"routine": convolution}
    out = xr.apply_ufunc(
        kernel, image, psf, kwargs=kwargs,
        input_core_dims=[list(dims), ["psf_y", "psf_x"]], output_core_dims=[list(dims)],
        dask="parallelized", output_dtypes=[float])
    return out.assign_attrs(image.attrs)


def padded_spectrum(img, pad, size_y, size_x):
    """``rfft2`` of images (..., ny, nx) reflect-padded to size_y x size_x (``pad`` first)."""
    ny, nx = img.shape[-2:]
    lead = [(0, 0)] * (img.ndim - 2)
    padded = np.pad(img, [*lead, (pad, size_y - ny - pad), (pad, size_x - nx - pad)],
                    mode="reflect")
    return fft.rfft2(padded, axes=(-2, -1))


def cropped_inverse(spectrum, pad, shape, size_x):
    """The image part of the inverse of a :func:`padded_spectrum` product."""
    out = fft.irfft2(spectrum, s=(spectrum.shape[-2], size_x), axes=(-2, -1))
    return out[..., pad: pad + shape[0], pad: pad + shape[1]]


def _otf_kernel(img, otf, pad, size_x):
    """Images (..., ny, nx) reflect-padded to the OTF grid, multiplied, cropped back."""
    img, otf = align_leading(img, 2, otf, 2)
    spectrum = padded_spectrum(img, pad, otf.shape[-2], size_x) * otf
    return cropped_inverse(spectrum, pad, img.shape[-2:], size_x)


def blur_by_otf(image: xr.DataArray, otf: xr.DataArray, pad: int, size_x: int,
                dims=("y_input", "x_input")) -> xr.DataArray:
    """Images blurred by an OTF sampled on their own (reflect-padded) Fourier grid.

    Parameters
    ----------
    image : xr.DataArray
        Images over ``dims``; other dims broadcast against the OTF's. [any]
    otf : xr.DataArray
        Over (``fy``, ``fx``) at the frequencies of ``rfft2`` of a grid of ``otf.sizes["fy"]``
        x ``size_x`` samples (:func:`xbsm.simulate.psf.otf_rfft_grid`). [1]
    pad : int
        Reflect padding before the image's first row and column (the rest of the grid is
        padded after its last). [pixels]
    size_x : int
        Columns of the grid.
    dims : (str, str)
        The image's row and column dims.

    Returns
    -------
    xr.DataArray
        The images convolved with the OTF's kernel, periodic over the padded grid (an
        exact convolution with the band-limited response; nothing truncated). [any]
    """
    if image.chunks is not None:
        image = image.chunk({d: -1 for d in dims})
    out = xr.apply_ufunc(
        _otf_kernel, image, otf, kwargs={"pad": pad, "size_x": size_x},
        input_core_dims=[list(dims), ["fy", "fx"]], output_core_dims=[list(dims)],
        dask="parallelized", output_dtypes=[float])
    return out.assign_attrs(image.attrs)
