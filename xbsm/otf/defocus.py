"""Defocus: the exact defocused aperture OTF, the geometric disk and IBSM's Gaussian.

Hopkins (1955) for the clear pupil, the annular pupil's autocorrelation built from it,
the geometrical-optics blur disk, and IBSM's Gaussian approximation (IBSM 3-25 to 3-27).

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
from ..params import Choice, Spec, Values, contract
from ._contracts import APERTURE_DIAMETER, FOCAL_LENGTH
from .aperture import circular_aperture_kernel, hopkins_kernel

__all__ = ["DEFOCUS_MODELS", "IBSM_GAUSSIAN_FRACTION", "annular_defocus_kernel",
           "blur_circle_diameter", "defocused_aperture_kernel", "defocused_aperture_otf",
           "gaussian_defocus", "geometric_defocus", "image_domain_defocus_radius",
           "object_domain_defocus_radius"]

#: The defocus models of :func:`defocused_aperture_otf` (the method knob ``defocus_otf``).
DEFOCUS_MODELS = tuple(c for c in KNOB_CHOICES["defocus_otf"] if c is not None)

IBSM_GAUSSIAN_FRACTION = 0.62
"""IBSM's Gaussian size w over the geometric blur-circle diameter d (IBSM Eqs. 3-26 and
3-27: w = 0.62 D dz / f^2, and d = D dz / f^2 is the paraxial blur circle). [1]"""

_OPD = Values(Spec("m", "defocus wavefront coefficient W020", low=0.0))
_GAUSSIAN_SIZE = Values(Spec("rad", "Gaussian defocus size w (PSF 1/e diameter)", low=0.0))
_RANGE = Values(Spec("m", "range", low=0.0, low_open=True), infinite=True)


@contract(defocus_opd=_OPD, aperture_diameter=APERTURE_DIAMETER)
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


@contract(blur_diameter=Values(Spec("rad", "blur-circle angular diameter", low=0.0)))
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
        waves = opd / wavelength
        exact = hopkins_kernel(s, waves)
        eta = np.asarray(obscuration_ratio, dtype=float)
        if np.any(eta > 0):
            exact = np.where(eta > 0, annular_defocus_kernel(s, waves, eta, clear=exact),
                             exact)
        return np.where(opd == 0.0, in_focus, exact)
    else:
        raise ValueError(f"model must be one of {', '.join(map(repr, DEFOCUS_MODELS))}; "
                         f"got {model!r}")
    return np.where(opd == 0.0, in_focus, in_focus * factor)


def annular_defocus_kernel(s, waves, obscuration_ratio, *, clear=None):
    r"""Defocused OTF of an annular pupil on plain arrays (numpy; arguments broadcast).

    ``s`` = 2 rho lambda / D in [0, 2], ``waves`` = W020 / lambda, ``obscuration_ratio``
    eta in [0, 1). The pupil is the clear disk less the disk of radius eta; with the
    defocus phase :math:`2\pi W_{020} r^2` the same function on both, its
    autocorrelation is (Goodman's shear form; the sheared phases differ by
    :math:`a x`, :math:`a = 4\pi W_{020} s`)

    .. math::

        H = \frac{H_H(s; W_{020}) - 2 C / \pi + \eta^2 H_H(s/\eta; \eta^2 W_{020})}
                 {1 - \eta^2}

    with :math:`H_H` Hopkins' clear-pupil OTF (:func:`xbsm.otf.aperture.hopkins_kernel`)
    and :math:`C = \int \cos(a x)\,dA` over the overlap of the unit disk centred at
    :math:`-s/2` and the disk of radius eta centred at :math:`+s/2`: the transform of
    the small disk, :math:`\pi\eta^2 \cos(as/2)\,2J_1(a\eta)/(a\eta)`, where it lies
    inside the large one (:math:`s \le 1 - \eta`), 0 where they are apart
    (:math:`s \ge 1 + \eta`), and between, the lens split at the radical line
    :math:`x^* = (1 - \eta^2)/(2s)` into two circular segments, each integrated in its
    polar angle (:math:`x = c + R\cos\theta`: smooth integrands
    :math:`2R^2\sin^2\theta\cos(a(c + R\cos\theta))`) by Gauss-Legendre with
    at least :math:`a/2 + 40` nodes, converged to rounding (against an adaptive integral of the
    pupil overlap's chords, ``tests/otf/test_defocus.py``). ``clear``: Hopkins' OTF at
    (s, waves) if the caller has it.
    """
    s, waves, eta = np.broadcast_arrays(np.asarray(s, dtype=float),
                                        np.asarray(waves, dtype=float),
                                        np.asarray(obscuration_ratio, dtype=float))
    s = np.clip(s, 0.0, 2.0)
    a = 4.0 * np.pi * waves * s
    with np.errstate(divide="ignore", invalid="ignore"):
        small = hopkins_kernel(np.where(eta > 0, s / eta, 2.0), waves * eta**2)
        inner = np.pi * eta**2 * np.cos(a * s / 2.0) * _disk_kernel(a * eta)
        radical = (1.0 - eta**2) / (2.0 * s)
    lens = (s > 1.0 - eta) & (s < 1.0 + eta)
    cross = np.where(s <= 1.0 - eta, inner, 0.0)
    if np.any(lens):
        sl, al, el, xr_ = s[lens], a[lens], eta[lens], radical[lens]
        # the small disk's segment left of the radical line: theta from theta1 to pi
        theta1 = np.arccos(np.clip((xr_ - sl / 2.0) / el, -1.0, 1.0))
        # the large disk's segment right of it: theta from 0 to theta2
        theta2 = np.arccos(np.clip(xr_ + sl / 2.0, -1.0, 1.0))
        # nodes: at least a / 2 + 40, a power of two per value (so that a value does not
        # depend on the others in its array)
        nodes = 2 ** np.ceil(np.log2(0.5 * np.abs(al) + 40.0)).astype(int)
        part = np.empty(sl.shape)
        for n in np.unique(nodes):
            t, wt = np.polynomial.legendre.leggauss(int(n))
            i = nodes == n
            part[i] = (_segment(theta1[i], np.pi, el[i], sl[i] / 2.0, al[i], t, wt)
                       + _segment(0.0, theta2[i], 1.0, -sl[i] / 2.0, al[i], t, wt))
        cross[lens] = part
    if clear is None:
        clear = hopkins_kernel(s, waves)
    return (clear - 2.0 * cross / np.pi + eta**2 * small) / (1.0 - eta**2)


def _segment(lo, hi, radius, centre, a, t, wt):
    """Integral of 2 R^2 sin^2(theta) cos(a (c + R cos theta)) over [lo, hi] (Gauss-Legendre)."""
    lo, hi, radius, centre, a = (np.asarray(v, dtype=float)[..., None]
                                 for v in (lo, hi, radius, centre, a))
    half = (hi - lo) / 2.0
    theta = lo + half * (t + 1.0)
    f = 2.0 * radius**2 * np.sin(theta) ** 2 * np.cos(a * (centre + radius * np.cos(theta)))
    return np.sum(half * f * wt, axis=-1)


@contract(wavelength=Values(Spec("m", "wavelength", low=0.0, low_open=True)),
          aperture_diameter=APERTURE_DIAMETER,
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
    "hopkins" is exact for clear and obscured pupils: Hopkins' series for a clear pupil,
    and for an obscured one the annular pupil's autocorrelation built from it
    (:func:`annular_defocus_kernel`). "geometric" and "gaussian" are approximations
    whose errors against Hopkins docs/otf.md tabulates
    (``recipes/evidence/defocus_models.py``), with the Gaussian size that fits best.
    """
    out = apply_kernel(_defocused_xy_kernel, fx, fy, aperture_diameter, wavelength,
                       obscuration_ratio, defocus_opd, model=model)
    return described(out, defocused_aperture_otf)


def _defocused_xy_kernel(fx, fy, aperture_diameter, wavelength, obscuration_ratio,
                         defocus_opd, *, model):
    return defocused_aperture_kernel(np.hypot(fx, fy), aperture_diameter, wavelength,
                                     obscuration_ratio, defocus_opd, model)


@contract(blur_radius_x=_GAUSSIAN_SIZE, blur_radius_y=_GAUSSIAN_SIZE)
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
    out = np.exp((-(np.pi**2) / 4.0) * (blur_radius_x**2 * fx**2 + blur_radius_y**2 * fy**2))
    return described(out, gaussian_defocus)


@contract(aperture_diameter=APERTURE_DIAMETER, object_range=_RANGE, focus_range=_RANGE)
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
    out = 0.62 * aperture_diameter * np.abs(1.0 / object_range - 1.0 / focus_range)
    return described(out, object_domain_defocus_radius, units="rad")


@contract(aperture_diameter=APERTURE_DIAMETER, focal_length=FOCAL_LENGTH)
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
    out = 0.62 * aperture_diameter * np.abs(focus_shift) / focal_length**2
    return described(out, image_domain_defocus_radius, units="rad")
