"""Wavefront-error OTFs: random phase screen (IBSM 3-31) and Shannon's quadratic form."""

from __future__ import annotations

import numpy as np

from .._kernels import apply_kernel
from .._metadata import described
from ..params import Spec, Values, contract
from ._contracts import APERTURE_DIAMETER, LENGTH, WAVELENGTH

__all__ = ["random_phase_wavefront", "shannon_wavefront"]


@contract(wavelength=WAVELENGTH,
          phase_variance=Values(Spec("rad2", "phase variance", low=0.0)),
          correlation_length_x=LENGTH, correlation_length_y=LENGTH,
          phase_variance_wavelength=Values(WAVELENGTH.spec, optional=True))
def random_phase_wavefront(
    fx,
    fy,
    wavelength,
    phase_variance,
    correlation_length_x,
    correlation_length_y,
    phase_variance_wavelength=None,
):
    r"""OTF of small random wavefront errors with a Gaussian phase autocorrelation.

    Parameters
    ----------
    fx, fy : xr.DataArray
        Angular spatial frequencies, broadcast against each other. [cycles/rad]
    wavelength : float or xr.DataArray
        Wavelength, > 0. [m]
    phase_variance : float or xr.DataArray
        Pupil phase variance, >= 0, i.e. :math:`(2\pi \times \text{waves rms})^2`,
        at ``phase_variance_wavelength``. [rad^2]
    correlation_length_x, correlation_length_y : float or xr.DataArray
        Correlation lengths of the phase autocorrelation, > 0 (commonly the
        aperture diameter). [m]
    phase_variance_wavelength : float or xr.DataArray, optional
        Wavelength at which ``phase_variance`` is specified; the variance is
        scaled by :math:`(\lambda_{pv}/\lambda)^2`. ``None`` applies
        ``phase_variance`` unscaled at every wavelength. [m]

    Returns
    -------
    xr.DataArray
        Real OTF, broadcast over every input dimension. [1]

    Notes
    -----
    IBSM Eq. 3-31 (Goodman, Statistical Optics, random phase screens), with
    :math:`L_x, L_y` the correlation lengths:

    .. math:: H = \exp\left\{-\sigma^2\left[1 - \exp\left(-\lambda^2
              \left(\frac{f_x^2}{L_x^2} + \frac{f_y^2}{L_y^2}\right)\right)\right]\right\},
              \quad \sigma^2 = \sigma^2_{pv}\left(\frac{\lambda_{pv}}{\lambda}\right)^2
    """
    # the variance at its own wavelength: (lambda / lambda)^2 = 1 exactly
    reference = wavelength if phase_variance_wavelength is None else phase_variance_wavelength
    out = apply_kernel(random_phase_kernel, phase_variance, reference, wavelength, fx,
                    correlation_length_x, fy, correlation_length_y)
    return described(out, random_phase_wavefront)


def random_phase_kernel(phase_variance, phase_variance_wavelength, wavelength, fx,
                         correlation_length_x, fy, correlation_length_y):
    """IBSM Eq. 3-31 on plain arrays (arguments in the order of the result's dims)."""
    variance = phase_variance * (phase_variance_wavelength / wavelength) ** 2
    correlation = np.exp(
        -(wavelength**2) * ((fx / correlation_length_x) ** 2 + (fy / correlation_length_y) ** 2)
    )
    return np.exp(-variance * (1.0 - correlation))


def _shannon_kernel(rms_wavefront_error, fx, fy, wavelength, aperture_diameter, clip):
    """Shannon's quadratic MTF loss on plain arrays."""
    nu = np.hypot(fx, fy) * wavelength / aperture_diameter
    if clip:
        nu = np.minimum(nu, 1.0)
    return 1.0 - (rms_wavefront_error / 0.18) ** 2 * (1.0 - 4.0 * (nu - 0.5) ** 2)


@contract(wavelength=WAVELENGTH, aperture_diameter=APERTURE_DIAMETER,
          rms_wavefront_error=Values(Spec("1", "rms wavefront error in waves", 0.0, 0.18)))
def shannon_wavefront(fx, fy, wavelength, aperture_diameter, rms_wavefront_error, clip=True):
    r"""Shannon's quadratic approximation of the MTF loss from random wavefront error.

    Parameters
    ----------
    fx, fy : xr.DataArray
        Angular spatial frequencies, broadcast against each other. [cycles/rad]
    wavelength : float or xr.DataArray
        Wavelength, > 0. [m]
    aperture_diameter : float or xr.DataArray
        Effective entrance-pupil diameter, > 0. [m]
    rms_wavefront_error : float or xr.DataArray
        Root-mean-square wavefront error in waves, in [0, 0.18] (the form loses
        accuracy above about 0.18 waves and goes negative beyond). [1]
    clip : bool
        True (default): the normalised frequency is clipped to the diffraction
        cutoff, so the factor is 1 beyond :math:`D/\lambda` (where the
        aperture OTF is zero) instead of growing as a parabola. False
        reproduces pyBSM's unclipped ``wavefront_OTF_2``.

    Returns
    -------
    xr.DataArray
        Real OTF, in [0, 1] when ``clip`` is True. [1]

    Notes
    -----
    Shannon, Handbook of Optics, ch. 35, with :math:`\nu = \rho\lambda/D` and
    :math:`W` the rms error in waves:

    .. math:: H = 1 - \left(\frac{W}{0.18}\right)^2\left[1 - 4(\nu - 0.5)^2\right]
    """
    out = apply_kernel(_shannon_kernel, rms_wavefront_error, fx, fy, wavelength, aperture_diameter,
                    clip=bool(clip))
    return described(out, shannon_wavefront)
