"""Detector OTFs: pixel (IBSM 3-36), aggregation, charge transfer (3-39), diffusion (3-40)."""

from __future__ import annotations

import numpy as np

from .._kernels import apply_kernel
from .._metadata import described
from .._trig import sinc
from ..params import Spec, Values, contract
from ._contracts import COUNT, FOCAL_LENGTH, LENGTH, POSITIVE_NUMBER, UNIT_INTERVAL

__all__ = ["detector", "aggregated_detector", "charge_transfer", "diffusion"]


@contract(detector_width_x=LENGTH, detector_width_y=LENGTH, focal_length=FOCAL_LENGTH)
def detector(fx, fy, detector_width_x, detector_width_y, focal_length):
    r"""OTF of the spatial integration over a rectangular detector.

    Parameters
    ----------
    fx, fy : xr.DataArray
        Angular spatial frequencies, broadcast against each other. [cycles/rad]
    detector_width_x, detector_width_y : float or xr.DataArray
        Active detector width along x and y, > 0. [m]
    focal_length : float or xr.DataArray
        Effective focal length, > 0. [m]

    Returns
    -------
    xr.DataArray
        Real OTF with its negative lobes, broadcast over every input dimension. [1]

    Notes
    -----
    IBSM Eq. 3-36 (simplified: rectangular detector, no aggregation):

    .. math:: H = \operatorname{sinc}\left(\frac{w_x f_x}{F}\right)
              \operatorname{sinc}\left(\frac{w_y f_y}{F}\right)
    """
    out = apply_kernel(detector_kernel, detector_width_x, focal_length, fx, detector_width_y, fy)
    return described(out, detector)


def detector_kernel(detector_width_x, focal_length, fx, detector_width_y, fy):
    """IBSM Eq. 3-36 on plain arrays (arguments in the order of the result's dims)."""
    return (sinc(detector_width_x / focal_length * fx)
            * sinc(detector_width_y / focal_length * fy))


def _aggregation_factor(frequency, pitch, focal_length, n):
    """(1/n) sum_i cos(2 pi (i - (n-1)/2) p f / F) for i = 0 .. n-1."""
    phase = 2.0 * np.pi * pitch * frequency / focal_length
    total = 0.0
    for i in range(n):
        total = total + np.cos(phase * (i - (n - 1.0) / 2.0))
    return total / n


@contract(detector_width_x=LENGTH, detector_width_y=LENGTH, pixel_pitch_x=LENGTH,
          pixel_pitch_y=LENGTH, focal_length=FOCAL_LENGTH,
          aggregation=Spec("1", "pixels aggregated along each axis", low=1.0, whole=True))
def aggregated_detector(
    fx,
    fy,
    detector_width_x,
    detector_width_y,
    pixel_pitch_x,
    pixel_pitch_y,
    focal_length,
    aggregation=1,
):
    r"""OTF of a rectangular detector whose signal is summed over n x n pixels.

    Parameters
    ----------
    fx, fy : xr.DataArray
        Angular spatial frequencies, broadcast against each other. [cycles/rad]
    detector_width_x, detector_width_y : float or xr.DataArray
        Active detector width along x and y, > 0. [m]
    pixel_pitch_x, pixel_pitch_y : float or xr.DataArray
        Detector centre-to-centre spacing along x and y, > 0. [m]
    focal_length : float or xr.DataArray
        Effective focal length, > 0. [m]
    aggregation : int
        Number of pixels aggregated along each axis, >= 1. [1]

    Returns
    -------
    xr.DataArray
        Real OTF, broadcast over every input dimension. [1]

    Notes
    -----
    The pixel-aperture OTF (IBSM Eq. 3-36) times the transform of ``n``
    equally spaced samples about their centre (M. Howard's form in pyBSM's
    ``detector_OTF_with_aggregation``); it matters most for fill factors below
    one (:math:`p > w`):

    .. math:: H = \operatorname{sinc}\frac{w_x f_x}{F}\operatorname{sinc}\frac{w_y f_y}{F}
              \prod_{k\in\{x, y\}} \frac{1}{n}\sum_{i=0}^{n-1}
              \cos\left[2\pi\left(i - \frac{n-1}{2}\right)\frac{p_k f_k}{F}\right]
    """
    out = apply_kernel(_aggregated_detector_kernel, pixel_pitch_x, fx, focal_length, pixel_pitch_y,
                    fy, detector_width_x, detector_width_y, aggregation=int(aggregation))
    return described(out, aggregated_detector)


def _aggregated_detector_kernel(pixel_pitch_x, fx, focal_length, pixel_pitch_y, fy,
                                detector_width_x, detector_width_y, aggregation):
    """Aggregated pixel OTF on plain arrays (arguments in the order of the result's dims)."""
    pixel = detector_kernel(detector_width_x, focal_length, fx, detector_width_y, fy)
    return (_aggregation_factor(fx, pixel_pitch_x, focal_length, aggregation)
            * _aggregation_factor(fy, pixel_pitch_y, focal_length, aggregation)
            * pixel)


@contract(pixel_pitch_x=LENGTH, pixel_pitch_y=LENGTH, focal_length=FOCAL_LENGTH,
          transfers_x=COUNT, transfers_y=COUNT, transfer_efficiency=UNIT_INTERVAL,
          phases=POSITIVE_NUMBER)
def charge_transfer(
    fx,
    fy,
    pixel_pitch_x,
    pixel_pitch_y,
    focal_length,
    transfers_x,
    transfers_y,
    transfer_efficiency,
    phases=1,
):
    r"""OTF of charge-transfer inefficiency in a CCD.

    Parameters
    ----------
    fx, fy : xr.DataArray
        Angular spatial frequencies, broadcast against each other. [cycles/rad]
    pixel_pitch_x, pixel_pitch_y : float or xr.DataArray
        Detector centre-to-centre spacing along x and y, > 0. [m]
    focal_length : float or xr.DataArray
        Effective focal length, > 0. [m]
    transfers_x, transfers_y : float or xr.DataArray
        Number of charge transfers along x and y, >= 0. [1]
    transfer_efficiency : float or xr.DataArray
        Charge-transfer efficiency per phase, in [0, 1]. [1]
    phases : int or xr.DataArray
        Clock phases per transfer, > 0. [1]

    Returns
    -------
    xr.DataArray
        Real OTF, broadcast over every input dimension. [1]

    Notes
    -----
    IBSM Eq. 3-39, with :math:`N_\phi` phases, :math:`\epsilon` the efficiency:

    .. math:: H = \prod_{k\in\{x, y\}} \exp\left\{-N_\phi N_k (1 - \epsilon)
              \left[1 - \cos\left(\frac{2\pi p_k f_k}{F}\right)\right]\right\}
    """
    out = apply_kernel(_charge_transfer_kernel, phases, transfer_efficiency, transfers_x,
                    pixel_pitch_x, fx, focal_length, transfers_y, pixel_pitch_y, fy)
    return described(out, charge_transfer)


def _charge_transfer_kernel(phases, transfer_efficiency, transfers_x, pixel_pitch_x, fx,
                            focal_length, transfers_y, pixel_pitch_y, fy):
    """IBSM Eq. 3-39 on plain arrays (arguments in the order of the result's dims)."""
    loss = phases * (1.0 - transfer_efficiency)

    def axis(transfers, pitch, frequency):
        return np.exp(
            -loss * transfers * (1.0 - np.cos(2.0 * np.pi * pitch * frequency / focal_length))
        )

    return axis(transfers_x, pixel_pitch_x, fx) * axis(transfers_y, pixel_pitch_y, fy)


@contract(absorption_coefficient=Values(Spec("m-1", "absorption coefficient", low=0.0,
                                             low_open=True)),
          depletion_width=Values(Spec("m", "depletion width", low=0.0)),
          diffusion_length=LENGTH, focal_length=FOCAL_LENGTH)
def diffusion(fx, fy, absorption_coefficient, depletion_width, diffusion_length, focal_length):
    r"""OTF of minority-carrier diffusion in a front-illuminated CCD.

    Parameters
    ----------
    fx, fy : xr.DataArray
        Angular spatial frequencies, broadcast against each other. [cycles/rad]
    absorption_coefficient : float or xr.DataArray
        Spectral absorption coefficient of the detector material, > 0
        (IBSM Table 3-4 for silicon; usually a function of ``wavelength``). [1/m]
    depletion_width : float or xr.DataArray
        Depletion layer width, >= 0. [m]
    diffusion_length : float or xr.DataArray
        Minority-carrier diffusion length, > 0. [m]
    focal_length : float or xr.DataArray
        Effective focal length, > 0. [m]

    Returns
    -------
    xr.DataArray
        Real OTF, broadcast over every input dimension. [1]

    Notes
    -----
    IBSM Eq. 3-40, with :math:`\rho = \sqrt{f_x^2 + f_y^2}`, :math:`L_D` the
    depletion width and :math:`L_0` the diffusion length:

    .. math:: H = \frac{g(L(\rho))}{g(L_0)},\quad
              g(L) = 1 - \frac{e^{-\alpha L_D}}{1 + \alpha L},\quad
              L(\rho) = \left[L_0^{-2} + (2\pi\rho/F)^2\right]^{-1/2}

    A demonstration model: it does not describe modern detector structures.
    """
    out = apply_kernel(_diffusion_kernel, absorption_coefficient, depletion_width, diffusion_length,
                    fx, fy, focal_length)
    return described(out, diffusion)


def _diffusion_kernel(absorption_coefficient, depletion_width, diffusion_length, fx, fy,
                      focal_length):
    """IBSM Eq. 3-40 on plain arrays (arguments in the order of the result's dims)."""
    rho = np.hypot(fx, fy)
    length = (1.0 / diffusion_length**2 + (2.0 * np.pi * rho / focal_length) ** 2) ** -0.5
    depletion = np.exp(-absorption_coefficient * depletion_width)

    def collected(diffusion_len):
        return 1.0 - depletion / (1.0 + absorption_coefficient * diffusion_len)

    return collected(length) / collected(diffusion_length)
