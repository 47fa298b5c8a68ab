"""Gaussian approximation of defocus blur (IBSM 3-25 to 3-27)."""

from __future__ import annotations

import numpy as np

from .._metadata import described
from .spectral import _nonnegative, _positive

__all__ = ["gaussian_defocus", "object_domain_defocus_radius", "image_domain_defocus_radius"]


def gaussian_defocus(fx, fy, blur_radius_x, blur_radius_y):
    r"""Gaussian approximation of the defocus OTF near the optical axis.

    Parameters
    ----------
    fx, fy : xr.DataArray
        Angular spatial frequencies, broadcast against each other. [cycles/rad]
    blur_radius_x, blur_radius_y : float or xr.DataArray
        IBSM's "1/e blur spot radius" w along x and y, >= 0; the PSF of this OTF is
        proportional to exp(-4 x^2 / w^2), so it falls to 1/e at w / 2 (w is the
        spot's 1/e diameter). [rad]

    Returns
    -------
    xr.DataArray
        Real OTF, broadcast over every input dimension. [1]

    Notes
    -----
    IBSM Eq. 3-25:

    .. math:: H = \exp\left[-\frac{\pi^2}{4}\left(w_x^2 f_x^2 + w_y^2 f_y^2\right)\right]

    For an exact treatment of defocus use
    :func:`xbsm.otf.aperture.defocused_aperture`.
    """
    _nonnegative("blur_radius_x", blur_radius_x)
    _nonnegative("blur_radius_y", blur_radius_y)
    out = np.exp((-(np.pi**2) / 4.0) * (blur_radius_x**2 * fx**2 + blur_radius_y**2 * fy**2))
    return described(out, gaussian_defocus)


def object_domain_defocus_radius(aperture_diameter, object_range, focus_range):
    r"""Angular defocus blur size w (IBSM's "1/e radius") for an object away from focus.

    Parameters
    ----------
    aperture_diameter : float or xr.DataArray
        Effective entrance-pupil diameter, > 0. [m]
    object_range : float or xr.DataArray
        Range to the object, > 0. [m]
    focus_range : float or xr.DataArray
        Range at which the focus is set, > 0 (``inf`` for focus at infinity). [m]

    Returns
    -------
    float or xr.DataArray
        Blur size w as :func:`gaussian_defocus` takes it (the PSF's 1/e radius is w / 2),
        >= 0. [rad]

    Notes
    -----
    IBSM Eq. 3-26 (pyBSM returns the signed value; only its square is used):

    .. math:: w = 0.62\,D\,\left|\frac{1}{R} - \frac{1}{R_0}\right|
    """
    _positive("aperture_diameter", aperture_diameter)
    _positive("object_range", object_range)
    _positive("focus_range", focus_range)
    out = 0.62 * aperture_diameter * np.abs(1.0 / object_range - 1.0 / focus_range)
    return described(out, object_domain_defocus_radius, units="rad")


def image_domain_defocus_radius(aperture_diameter, focus_shift, focal_length):
    r"""Angular defocus blur size w (IBSM's "1/e radius") for a focus shift at the detector.

    Parameters
    ----------
    aperture_diameter : float or xr.DataArray
        Effective entrance-pupil diameter, > 0. [m]
    focus_shift : float or xr.DataArray
        Axial distance between the detector and the image plane. [m]
    focal_length : float or xr.DataArray
        Effective focal length, > 0. [m]

    Returns
    -------
    float or xr.DataArray
        Blur size w as :func:`gaussian_defocus` takes it (the PSF's 1/e radius is w / 2),
        >= 0. [rad]

    Notes
    -----
    IBSM Eq. 3-27 (pyBSM returns the signed value; only its square is used):

    .. math:: w = 0.62\,D\,\frac{|\Delta z|}{f^2}
    """
    _positive("aperture_diameter", aperture_diameter)
    _positive("focal_length", focal_length)
    out = 0.62 * aperture_diameter * np.abs(focus_shift) / focal_length**2
    return described(out, image_domain_defocus_radius, units="rad")
