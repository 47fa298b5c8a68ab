"""Defocus: the defocused aperture OTF (Hopkins 1955, exact), its geometrical-optics
disk, and IBSM's Gaussian approximation (IBSM 3-25 to 3-27).

One component, :func:`defocused_aperture_otf` (on plain arrays
:func:`defocused_aperture_kernel`), gives the aperture's OTF with a defocus wavefront
coefficient W020 by one of :data:`DEFOCUS_MODELS`; the NIIRS chain (the ``aperture``
component of :func:`xbsm.otf.system.system_components`, both slices) and image
simulation (through the same system components) use it with the sensor's
``defocus_opd`` and the method knob ``defocus_otf``.
"""

from __future__ import annotations

import numpy as np
from scipy.special import j1

from .._kernels import apply_kernel
from .._metadata import described
from ..methods import KNOB_CHOICES
from ..params import NONNEGATIVE, POSITIVE, Choice, Spec, Values, contract
from .aperture import circular_aperture_kernel, hopkins_kernel
from .spectral import _nonnegative, _positive

__all__ = ["DEFOCUS_MODELS", "IBSM_GAUSSIAN_FRACTION", "blur_circle_diameter",
           "defocused_aperture_kernel", "defocused_aperture_otf", "gaussian_defocus",
           "geometric_defocus", "image_domain_defocus_radius", "object_domain_defocus_radius"]

#: The defocus models of :func:`defocused_aperture_otf` (the method knob ``defocus_otf``).
DEFOCUS_MODELS = tuple(c for c in KNOB_CHOICES["defocus_otf"] if c is not None)

IBSM_GAUSSIAN_FRACTION = 0.62
"""IBSM's Gaussian size w over the geometric blur-circle diameter d (IBSM Eqs. 3-26 and
3-27: w = 0.62 D dz / f^2, and d = D dz / f^2 is the paraxial blur circle). [1]"""

_OPD = Values(Spec("m", "defocus wavefront coefficient W020", **NONNEGATIVE))
_DIAMETER = Values(Spec("m", "effective aperture diameter", **POSITIVE))


@contract(defocus_opd=_OPD, aperture_diameter=_DIAMETER)
def blur_circle_diameter(defocus_opd, aperture_diameter):
    r"""Angular diameter of the geometrical-optics blur circle of a defocus W020.

    Parameters
    ----------
    defocus_opd : float or xr.DataArray
        Defocus wavefront coefficient W020: the optical path difference at the pupil
        edge from the reference sphere, >= 0. [m]
    aperture_diameter : float or xr.DataArray
        Effective entrance-pupil diameter D, > 0. [m]

    Returns
    -------
    float or xr.DataArray
        The blur circle's angular diameter d, >= 0. [rad]

    Notes
    -----
    The transverse ray aberration of :math:`W = W_{020}\rho^2` at the pupil edge is
    :math:`2 W_{020} f / (D / 2)`, so the blur circle on the detector has diameter
    :math:`8 W_{020} f / D` and subtends

    .. math:: d = \frac{8 W_{020}}{D}

    (paraxially :math:`W_{020} = \Delta z\,D^2 / (8 f^2)` for a focus shift
    :math:`\Delta z`, so :math:`d = D\,\Delta z / f^2`, the blur of IBSM Eq. 3-27
    without its 0.62). In Hopkins' series the Bessel argument is then
    :math:`a = \pi d \rho` at angular frequency :math:`\rho`.
    """
    out = 8.0 * defocus_opd / aperture_diameter
    return described(out, blur_circle_diameter, units="rad")


def _disk_kernel(x):
    """2 J1(x) / x, 1 at x = 0 (numpy)."""
    x = np.asarray(x, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        out = 2.0 * j1(x) / x
    return np.where(x == 0.0, 1.0, out)


@contract(blur_diameter=Values(Spec("rad", "blur-circle angular diameter", **NONNEGATIVE)))
def geometric_defocus(fx, fy, blur_diameter):
    r"""Geometrical-optics defocus OTF: the transform of a uniform blur disk.

    Parameters
    ----------
    fx, fy : xr.DataArray
        Angular spatial frequencies, broadcast against each other. [cycles/rad]
    blur_diameter : float or xr.DataArray
        Angular diameter d of the blur circle, >= 0 (:func:`blur_circle_diameter`). [rad]

    Returns
    -------
    xr.DataArray
        Real OTF (negative lobes beyond the first zero at
        :math:`\rho = 1.22 / d`), broadcast over every input dimension. [1]

    Notes
    -----
    .. math:: H = \frac{2 J_1(\pi d \rho)}{\pi d \rho},\quad \rho = \sqrt{f_x^2 + f_y^2}

    The limit of Hopkins' defocused OTF for W020 much larger than the wavelength, at
    frequencies well below the cutoff (``tests/otf/test_defocus.py``).
    """
    out = apply_kernel(_geometric_kernel, fx, fy, blur_diameter)
    return described(out, geometric_defocus)


def _geometric_kernel(fx, fy, blur_diameter):
    return _disk_kernel(np.pi * blur_diameter * np.hypot(fx, fy))


def defocused_aperture_kernel(radial, aperture_diameter, wavelength, obscuration_ratio,
                              defocus_opd, model):
    """The aperture OTF with defocus on plain arrays (numpy; arguments broadcast).

    ``radial`` [cycles/rad], D [m], lambda [m], eta [1], W020 [m], ``model`` one of
    :data:`DEFOCUS_MODELS`. Where W020 = 0 the result is
    :func:`xbsm.otf.aperture.circular_aperture_kernel` exactly (to the bit).
    """
    in_focus = circular_aperture_kernel(radial, aperture_diameter, wavelength,
                                        obscuration_ratio)
    opd = np.asarray(defocus_opd, dtype=float)
    if not np.any(opd):
        return in_focus + np.zeros(np.shape(opd))
    d = 8.0 * opd / aperture_diameter  # blur-circle diameter [rad]
    if model == "gaussian":
        w = IBSM_GAUSSIAN_FRACTION * d
        factor = np.exp((-(np.pi**2) / 4.0) * (w * radial) ** 2)
    elif model == "geometric":
        factor = _disk_kernel(np.pi * d * radial)
    elif model == "hopkins":
        s = 2.0 * radial * wavelength / aperture_diameter
        exact = hopkins_kernel(s, opd / wavelength)
        eta = np.asarray(obscuration_ratio, dtype=float)
        if not np.any(eta > 0):
            return np.where(opd == 0.0, in_focus, exact)
        clear = circular_aperture_kernel(radial, aperture_diameter, wavelength, 0.0)
        # an obscured pupil: Hopkins' factor over the clear pupil's OTF (an approximation,
        # docs/otf.md); both are 0 at and beyond the cutoff
        with np.errstate(divide="ignore", invalid="ignore"):
            factor = np.where(clear > 0.0, exact / clear, 1.0)
        return np.where(opd == 0.0, in_focus, np.where(eta > 0, in_focus * factor, exact))
    else:
        raise ValueError(f"model must be one of {', '.join(map(repr, DEFOCUS_MODELS))}; "
                         f"got {model!r}")
    return np.where(opd == 0.0, in_focus, in_focus * factor)


@contract(wavelength=Values(Spec("m", "wavelength", **POSITIVE)),
          aperture_diameter=_DIAMETER,
          defocus_opd=_OPD,
          obscuration_ratio=Values(Spec("1", "relative linear obscuration", 0.0, 1.0,
                                        high_open=True)),
          model=Choice(DEFOCUS_MODELS))
def defocused_aperture_otf(fx, fy, wavelength, aperture_diameter, defocus_opd,
                           obscuration_ratio=0.0, model="hopkins"):
    r"""Diffraction OTF of a circular aperture with defocus: the one defocus component.

    Parameters
    ----------
    fx, fy : xr.DataArray
        Angular spatial frequencies, broadcast against each other. [cycles/rad]
    wavelength : float or xr.DataArray
        Wavelength, > 0. [m]
    aperture_diameter : float or xr.DataArray
        Effective entrance-pupil diameter D, > 0. [m]
    defocus_opd : float or xr.DataArray
        Defocus wavefront coefficient W020, the peak optical path difference at the
        pupil edge from the reference sphere, >= 0 (a focus shift converts with
        :func:`xbsm.otf.aperture.defocus_wavefront_coefficient`). [m]
    obscuration_ratio : float or xr.DataArray
        Relative linear obscuration, in [0, 1). [1]
    model : {"hopkins", "geometric", "gaussian"}
        "hopkins": the exact OTF of the defocused clear pupil (Hopkins 1955,
        :func:`xbsm.otf.aperture.defocused_aperture`); "geometric": the in-focus
        aperture OTF times the blur disk's :func:`geometric_defocus` with
        :math:`d = 8 W_{020} / D`; "gaussian": the in-focus aperture OTF times IBSM's
        :func:`gaussian_defocus` with IBSM's size :math:`w = 0.62\,d` (Eq. 3-27).

    Returns
    -------
    xr.DataArray
        Real OTF, broadcast over every input dimension; equal to
        :func:`xbsm.otf.aperture.circular_aperture` to the bit where W020 = 0. [1]

    Notes
    -----
    Hopkins' series is exact for a clear pupil. For an obscured pupil
    (``obscuration_ratio`` > 0) "hopkins" multiplies the obscured aperture's OTF by the
    ratio of the defocused to the in-focus clear-pupil OTF: an approximation whose
    error docs/otf.md states (``recipes/evidence/defocus_models.py``). The Gaussian's
    size against Hopkins is tabulated there too.
    """
    out = apply_kernel(_defocused_xy_kernel, fx, fy, aperture_diameter, wavelength,
                       obscuration_ratio, defocus_opd, model=model)
    return described(out, defocused_aperture_otf)


def _defocused_xy_kernel(fx, fy, aperture_diameter, wavelength, obscuration_ratio,
                         defocus_opd, *, model):
    return defocused_aperture_kernel(np.hypot(fx, fy), aperture_diameter, wavelength,
                                     obscuration_ratio, defocus_opd, model)


def gaussian_defocus(fx, fy, blur_radius_x, blur_radius_y):
    r"""Gaussian approximation of the defocus OTF near the optical axis.

    Parameters
    ----------
    fx, fy : xr.DataArray
        Angular spatial frequencies, broadcast against each other. [cycles/rad]
    blur_radius_x, blur_radius_y : float or xr.DataArray
        IBSM's "1/e blur spot radius" w along x and y, >= 0 (pyBSM's names ``w_x``,
        ``w_y``). Despite the name, w is the PSF's 1/e *diameter*: the PSF of this OTF
        is proportional to exp(-4 x^2 / w^2), which falls to 1/e at x = w / 2. [rad]

    Returns
    -------
    xr.DataArray
        Real OTF, broadcast over every input dimension. [1]

    Notes
    -----
    IBSM Eq. 3-25:

    .. math:: H = \exp\left[-\frac{\pi^2}{4}\left(w_x^2 f_x^2 + w_y^2 f_y^2\right)\right]

    IBSM's approximation of defocus: :func:`defocused_aperture_otf` with
    ``model="gaussian"`` uses it with IBSM's size w = 0.62 d (d the blur-circle
    diameter, :func:`blur_circle_diameter`); docs/otf.md compares it with Hopkins'
    exact OTF (``model="hopkins"``).
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
