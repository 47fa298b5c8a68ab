"""Diffraction OTFs of a circular aperture: obscured (IBSM 3-20) and defocused (Hopkins 1955)."""

from __future__ import annotations

import math

import numpy as np
import xarray as xr

from .._kernels import apply_kernel
from .._metadata import described
from ..params import Spec, Values, contract
from ._contracts import APERTURE_DIAMETER, FOCAL_LENGTH, WAVELENGTH

__all__ = ["circular_aperture", "defocused_aperture", "defocus_wavefront_coefficient"]


def _diffraction_term(r, nonnegative=False):
    """(2/pi)(acos r - r sqrt(1 - r^2)) for 0 <= r <= 1, else 0 (a new array).

    In place on two temporaries (not a new array per operation, each a pass through
    memory of its own): the formula's own ufuncs on the same values, so the same bits
    as writing it out. ``nonnegative``: the caller knows r >= 0, and the clip at 0 is
    skipped.
    """
    # ufuncs: np.clip would compute dask
    rc = np.minimum(r, 1.0) if nonnegative else np.maximum(r, 0.0)
    if not nonnegative:
        np.minimum(rc, 1.0, out=rc)
    root = np.square(rc)
    np.subtract(1.0, root, out=root)
    np.sqrt(root, out=root)
    root *= rc
    np.arccos(rc, out=rc)
    rc -= root
    rc *= 2.0 / np.pi
    return rc


@contract(wavelength=WAVELENGTH, aperture_diameter=APERTURE_DIAMETER,
          obscuration_ratio=Values(Spec("1", "obscuration ratio", 0.0, 1.0, high_open=True)))
def circular_aperture(fx, fy, wavelength, aperture_diameter, obscuration_ratio=0.0):
    r"""Diffraction OTF of a circular aperture with a centred circular obscuration.

    Parameters
    ----------
    fx, fy : xr.DataArray
        Angular spatial frequencies, broadcast against each other. [cycles/rad]
    wavelength : float or xr.DataArray
        Wavelength. [m]
    aperture_diameter : float or xr.DataArray
        Effective entrance-pupil diameter, > 0. [m]
    obscuration_ratio : float or xr.DataArray
        Relative linear obscuration (obscuration diameter / aperture
        diameter), in [0, 1). [1]

    Returns
    -------
    xr.DataArray
        Real OTF, broadcast over every input dimension; 0 beyond the cutoff
        :math:`D/\lambda`. [1]

    Notes
    -----
    IBSM Eq. 3-20. With :math:`\nu = \rho\lambda/D`,
    :math:`\rho = \sqrt{f_x^2 + f_y^2}` and obscuration ratio :math:`\eta`:

    .. math::

        H = \frac{A(\nu) + \eta^2 A(\nu/\eta) + C(\nu)}{1 - \eta^2},\quad
        A(x) = \frac{2}{\pi}\left(\cos^{-1}x - x\sqrt{1 - x^2}\right)
        \ (x \le 1,\ \text{else } 0)

    with :math:`C = -2\eta^2` for :math:`\nu < (1-\eta)/2` and, for
    :math:`(1-\eta)/2 \le \nu \le (1+\eta)/2` and
    :math:`\cos\phi = (1 + \eta^2 - 4\nu^2)/(2\eta)`,

    .. math::

        C = \frac{2\eta\sin\phi}{\pi} + \frac{(1+\eta^2)\phi}{\pi} - 2\eta^2
            - \frac{2(1-\eta^2)}{\pi}
              \tan^{-1}\!\left(\frac{1+\eta}{1-\eta}\tan\frac{\phi}{2}\right)

    and 0 beyond. For :math:`\eta = 0` it reduces to :math:`A(\nu)`.
    """
    out = apply_kernel(_circular_aperture_xy_kernel, fx, fy, aperture_diameter, wavelength,
                    obscuration_ratio)
    return described(out, circular_aperture)


def _circular_aperture_xy_kernel(fx, fy, aperture_diameter, wavelength, obscuration_ratio):
    """:func:`circular_aperture_kernel` at the radial frequency of ``fx``, ``fy`` (numpy)."""
    return circular_aperture_kernel(np.hypot(fx, fy), aperture_diameter, wavelength,
                                     obscuration_ratio)


def circular_aperture_kernel(radial, aperture_diameter, wavelength, obscuration_ratio):
    """IBSM Eq. 3-20 on plain arrays: radial frequency [cycles/rad], D [m], lambda [m], eta [1].

    Entries with eta = 0 reduce to the unobscured term exactly (the obscured terms
    are set to 0 there and the divisions guarded). Each piece is evaluated only where
    it is needed: nothing at or beyond the cutoff (nu >= 1, where every term is exactly
    0), the annulus overlap's transcendentals only on (1 - eta)/2 <= nu <= (1 + eta)/2;
    every value is the one the formula gives on the whole array. With one obscuration
    ratio (every sensor but an obscuration sweep) "where" means whole rows along the
    first axis (:func:`_inside_rows`).
    """
    nu = radial / (aperture_diameter / wavelength)
    eta = np.asarray(obscuration_ratio, dtype=float)
    if eta.size == 1 or not np.any(eta > 0):
        shape = np.broadcast_shapes(np.shape(nu), eta.shape)
        nu = np.asarray(nu, dtype=float)
        nu = nu.reshape(nu.shape or (1,))
        rows, values = _inside_rows(nu, _one_ratio(eta))
        out = np.zeros(nu.shape)
        if rows is not None:
            out[rows] = values
        if out.size == math.prod(shape):
            return out.reshape(shape)
        return np.broadcast_to(out, shape).copy()  # eta's own axes (all of its values <= 0)
    nu, eta = np.broadcast_arrays(nu, eta)
    out = np.zeros(nu.shape)
    inside = ~(nu >= 1.0)  # NaN stays inside, and stays NaN
    nu, eta = nu[inside], eta[inside]
    obscured = eta > 0
    eta2 = eta**2
    inner = np.zeros(nu.shape)
    central = obscured & ~(nu >= eta)  # elsewhere nu / eta >= 1: the term is exactly 0
    inner[central] = eta2[central] * _diffraction_term(nu[central] / eta[central])
    below = nu < (1.0 - eta) / 2.0
    overlap = np.where(obscured & below, -2.0 * eta2, 0.0)
    band = obscured & ~below & (nu <= (1.0 + eta) / 2.0)
    overlap[band] = _annulus_transition(nu[band], eta[band])
    out[inside] = (_diffraction_term(nu) + inner + overlap) / (1.0 - eta2)
    return out


def circular_aperture_band_kernel(radial, aperture_diameter, wavelength, obscuration_ratio,
                                  weights):
    """:func:`circular_aperture_kernel` summed over its last (wavelength) axis with ``weights``.

    The same numbers as ``np.einsum("...k,...k->...", circular_aperture_kernel(...),
    weights)``, to the bit, without the monochromatic array: with one obscuration ratio
    only the rows (first axis, the frequency nodes in the chain) holding some nu < 1 are
    evaluated and summed, each by the same contraction; a row beyond the cutoff sums
    0 x weight, which is 0 for finite weights. Other cases (a ratio per entry, weights
    with axes of their own in front) take the plain route.
    """
    radial = np.asarray(radial, dtype=float)
    scale = np.asarray(aperture_diameter / wavelength, dtype=float)  # nu = radial / scale
    eta = np.asarray(obscuration_ratio, dtype=float)
    weights = np.asarray(weights)
    full = np.broadcast_shapes(radial.shape, scale.shape)
    shape = np.broadcast_shapes(full[:-1], weights.shape[:-1]) if full else ()
    plain = (
        len(full) < 2 or 0 in full or eta.size != 1 or eta.ndim > len(full)
        or weights.ndim > len(full) or shape[0] != full[0]
        or not np.isfinite(weights).all())
    if plain:
        mono = circular_aperture_kernel(radial, aperture_diameter, wavelength, eta)
        return np.einsum("...k,...k->...", mono, weights)
    extremes = _extremes_from_radial(radial, scale, full)
    if extremes is None:
        nu = radial / scale
        low, high = _row_extremes(nu)
        rows = _rows(~(low >= 1.0))
        nu = nu[rows] if rows is not None else None
    else:
        low, high = extremes
        rows = _rows(~(low >= 1.0))
        nu = radial[rows] / scale if rows is not None else None  # only the rows inside
    out = np.zeros(shape)
    if rows is not None:
        values = _on_rows(nu, _one_ratio(eta), low[rows], high[rows])
        if weights.ndim == len(full) and weights.shape[0] != 1:
            weights = weights[rows]
        out[rows] = np.einsum("...k,...k->...", values, weights)
    return out


def _extremes_from_radial(radial, scale, full):
    """Each row's smallest and largest nu = radial / scale without dividing them all.

    Where ``radial`` holds the rows (first axis) and is constant along the last
    (wavelength) axis, and ``scale`` = D / lambda has no row axis, is finite and > 0,
    and radial >= 0: the row's extremes are its radial values over the largest and the
    smallest scale (a correctly rounded division is monotonic), the same numbers as
    the extremes of the divided array. Else None (the caller divides everything).
    """
    if (radial.ndim != len(full) or radial.shape[0] != full[0] or radial.shape[-1] != 1
            or not 1 <= scale.ndim < radial.ndim or not radial.min() >= 0.0):
        return None
    largest, smallest = scale.max(axis=-1, keepdims=True), scale.min(axis=-1, keepdims=True)
    if not 0.0 < smallest.min() <= largest.max() < np.inf:  # (False with a NaN)
        return None
    return (_row_reduce(np.minimum, radial / largest),
            _row_reduce(np.maximum, radial / smallest))


def _row_extremes(nu):
    """The smallest and largest value of each row (first axis), NaN where it holds a NaN."""
    return _row_reduce(np.minimum, nu), _row_reduce(np.maximum, nu)


def _row_reduce(ufunc, values):
    """``ufunc`` (np.minimum or np.maximum) reduced over each row (first axis) of ``values``.

    Along the first axis of the transposed copy: numpy reduces a short last axis one row at
    a time (13 us for 195 rows of 5; 2 us this way, copy included).
    """
    flat = values.reshape(values.shape[0], -1)
    if flat.shape[1] == 1:
        return flat[:, 0]
    return ufunc.reduce(np.ascontiguousarray(flat.T), axis=0)


def _one_ratio(eta):
    """The obscuration ratio of a one-value ``eta`` as a float, or None (unobscured).

    eta <= 0 (or NaN, or no positive entry) is the unobscured aperture, as on the
    general path. The constants made from it are then Python's float arithmetic, which
    rounds as numpy's array loops do (+, -, *, /: correctly rounded; eta^2 as eta * eta,
    not a scalar pow).
    """
    if eta.size != 1 or not eta.reshape(-1)[0] > 0:
        return None
    return float(eta.reshape(-1)[0])


def _rows(mask):
    """The True entries of a row mask: a slice, their indices, or None if there are none.

    A slice if they are one run (rows of a C-ordered array are then a view, not a copy:
    sorted nodes make every piece a run), else their indices (whole-row gathers run at
    memcpy speed, unlike element masks).
    """
    (index,) = mask.nonzero()
    if not index.size:
        return None
    lo, hi = int(index[0]), int(index[-1]) + 1
    return slice(lo, hi) if hi - lo == index.size else index


def _inside_rows(nu, eta):
    """The rows of ``nu`` (first axis) holding some nu < 1 or NaN, and Eq. 3-20 on them.

    ``eta``: None (unobscured) or a float, 0 < eta < 1. Returns ``(rows, values)``,
    ``rows`` as from :func:`_rows` (None: every value is at or beyond the cutoff, where
    the OTF is exactly 0). Each term is evaluated on the rows that need it, told by the
    rows' smallest and largest nu (NaN if the row holds one, so that such a row gets
    every term): the central obscuration's eta^2 A(nu/eta) on rows with some nu < eta
    (elsewhere it is exactly 0: the clipped argument is 1), the annulus overlap on rows
    reaching into (1 - eta)/2 <= nu <= (1 + eta)/2 (within them, on the band's entries),
    -2 eta^2 on rows wholly below the band. Every value is the whole-array formula's to
    the bit: the same ufuncs on the same values, and adding an exact 0 (or not) changes
    no value, as A >= +0. No numpy calls on one-value arrays: each call costs about a
    microsecond whatever its size, and a (195 nodes, 5 scenarios) x 31 block makes about
    a hundred.
    """
    if nu.size == 0:
        return None, None
    low, high = _row_extremes(nu)
    rows = _rows(~(low >= 1.0))
    if rows is None:
        return None, None
    return rows, _on_rows(nu[rows], eta, low[rows], high[rows])


def _on_rows(nu, eta, low, high):
    """:func:`_inside_rows`'s values on rows ``nu`` with extremes ``low`` and ``high``."""
    nonnegative = bool(low.min() >= 0.0)  # then no clip at 0 (with a NaN: clipped)
    out = _diffraction_term(nu, nonnegative)
    if eta is None:
        return out
    eta2 = eta * eta
    central = _rows(~(low >= eta))
    if central is not None:
        inner = _diffraction_term(np.divide(nu[central], eta), nonnegative)
        inner *= eta2
        out[central] += inner
    lower, upper = (1.0 - eta) / 2.0, (1.0 + eta) / 2.0
    below_band = _rows(high < lower)  # no NaN there (high would be NaN)
    if below_band is not None:
        out[below_band] += -2.0 * eta2
    band_rows = _rows(~(high < lower) & ~(low > upper))
    if band_rows is not None:
        part = nu[band_rows]
        below = part < lower
        overlap = np.where(below, -2.0 * eta2, 0.0)
        band = ~below & (part <= upper)
        overlap[band] = _annulus_transition(part[band], eta)
        out[band_rows] += overlap
    out /= 1.0 - eta2
    return out


def _annulus_transition(nu, eta):
    """The overlap term C of IBSM Eq. 3-20 for (1 - eta)/2 <= nu <= (1 + eta)/2, eta > 0.

    ``eta`` broadcasts against ``nu`` (a float, or an array: one value per entry). In
    place on three temporaries, with the formula's ufuncs in its order (the same bits).
    """
    eta2 = eta * eta
    one_plus, two_eta, ratio = 1.0 + eta2, 2.0 * eta, (1.0 + eta) / (1.0 - eta)
    weight = 2.0 * (1.0 - eta2) / np.pi
    cos_phi = np.square(nu)
    cos_phi *= 4.0
    np.subtract(one_plus, cos_phi, out=cos_phi)
    cos_phi /= two_eta
    np.maximum(cos_phi, -1.0, out=cos_phi)
    np.minimum(cos_phi, 1.0, out=cos_phi)
    # sin(phi) and tan(phi / 2) from cos(phi) by square roots (phi in [0, pi]): cheaper than
    # the sine and tangent of phi, and no less accurate near phi = 0
    less, more = 1.0 - cos_phi, 1.0 + cos_phi
    out = np.multiply(less, more)
    np.sqrt(out, out=out)  # sin(phi)
    with np.errstate(divide="ignore"):  # phi = pi: tan(phi / 2) = inf, arctan(inf) = pi / 2
        np.divide(less, more, out=less)
    np.sqrt(less, out=less)  # tan(phi / 2)
    phi = np.arccos(cos_phi, out=cos_phi)
    out *= two_eta
    out /= np.pi
    phi *= one_plus
    phi /= np.pi
    out += phi
    out -= 2.0 * eta2
    less *= ratio
    np.arctan(less, out=less)
    less *= weight
    out -= less
    return out


@contract(aperture_diameter=APERTURE_DIAMETER, focal_length=FOCAL_LENGTH)
def defocus_wavefront_coefficient(focus_shift, aperture_diameter, focal_length):
    r"""Defocus wavefront coefficient W20 produced by a longitudinal focus shift.

    Parameters
    ----------
    focus_shift : float or xr.DataArray
        Distance between the detector plane and the best-focus plane. [m]
    aperture_diameter : float or xr.DataArray
        Effective entrance-pupil diameter, > 0. [m]
    focal_length : float or xr.DataArray
        Effective focal length, > 0. [m]

    Returns
    -------
    float or xr.DataArray
        Peak optical path difference at the pupil edge, W20. [m]

    Notes
    -----
    The convention of pyBSM's ``circular_aperture_OTF_with_defocus``, with the
    marginal-ray angle :math:`\sin^2\theta = 1/(1 + 4F^2)`, :math:`F = f/D`:

    .. math:: W_{20} = \frac{\delta z}{2\,(1 + 4F^2)} \approx \frac{\delta z}{8F^2}
    """
    f_number = focal_length / aperture_diameter
    out = focus_shift / (2.0 * (1.0 + 4.0 * f_number**2))
    return described(out, defocus_wavefront_coefficient, units="m")


def _hopkins_terms(a_max):
    r"""The highest Bessel order the Hopkins series need for arguments up to ``a_max``.

    Beyond ``n_max = a + 6 a^(1/3) + 30``, :math:`|J_n(a)| < 10^{-17}` for every
    :math:`a` (checked for :math:`10^{-2} \le a \le 10^3`); the backward recurrence
    starts :math:`\sqrt{40 n_{max}}` orders above it (Miller's rule, made odd), so
    truncation adds no error above rounding.
    """
    n_max = a_max + 6.0 * a_max ** (1.0 / 3.0) + 30.0
    return 2 * np.ceil((n_max + np.sqrt(40.0 * n_max)) / 2.0).astype(int) + 1


_SMALL_ARGUMENT = 1e-7
"""Below this Bessel argument a = 4 pi W20 s / lambda the OTF is the in-focus one (the
difference is of order a^2 < 1e-14)."""
_RESCALE = 1e150
"""The backward recurrence's values are scaled down when they pass this."""


def hopkins_kernel(s, waves):
    r"""Hopkins (1955) defocused OTF (numpy); s = 2 rho / rho_c in [0, 2], waves = W20 / lambda.

    Every :math:`J_n(a)` the series use comes from one backward recurrence
    :math:`J_{k-1} = (2k/a) J_k - J_{k+1}` normalised by
    :math:`J_0 + 2\sum J_{2m} = 1` (Miller's algorithm), accumulated into the two sums
    as it goes: a few multiplications per order instead of a Bessel function call
    (agrees with ``scipy.special.jv`` term by term to 2e-15).
    """
    s, waves = np.broadcast_arrays(s, waves)
    sc = np.clip(s, 0.0, 2.0)
    a = 4.0 * np.pi * np.abs(waves) * sc
    beta = np.arccos(sc / 2.0)
    small = ~(a >= _SMALL_ARGUMENT)
    a_safe = np.where(small, 1.0, a)
    # each value's recurrence starts at its own order (zeros above it), so that a value
    # does not depend on the others in its array (dask chunks)
    start = _hopkins_terms(a_safe)
    top = int(np.max(start, initial=1))
    two_over_a = 2.0 / a_safe
    # the sums as sum_k coefficient_k J_k: with c_n = (-1)^(n+1) sin(2 n beta) / (2 n),
    # c_0 = -beta, and d_n = (-1)^n sin((2n+1) beta) / (2n+1), d_-1 = 0, the series
    # multiplying cos(a s / 2) has c_(m+1) - c_m at J_(2m+1) and the one multiplying
    # sin(a s / 2) has d_m - d_(m-1) at J_(2m)
    j_above, j_k = np.zeros_like(a_safe), np.where(start == top, 1e-30, 0.0)
    even, odd, norm = np.zeros_like(a_safe), np.zeros_like(a_safe), np.zeros_like(a_safe)

    def c(n):  # c_n, n >= 1
        return (-1.0) ** (n + 1) * np.sin(2 * n * beta) / (2 * n)

    def d(n):  # d_n, n >= 0
        return (-1.0) ** n * np.sin((2 * n + 1) * beta) / (2 * n + 1)

    upper_c, upper_d = c((top + 1) // 2), d((top - 1) // 2)  # top is odd: 2M + 1
    for k in range(top, -1, -1):
        m = k // 2
        if k % 2:  # J_(2m+1): c_(m+1) - c_m
            lower = c(m) if m else -beta
            even += (upper_c - lower) * j_k
            upper_c = lower
        else:  # J_(2m): d_m - d_(m-1)
            lower = d(m - 1) if m else 0.0
            odd += (upper_d - lower) * j_k
            norm += (2.0 if k else 1.0) * j_k
            upper_d = lower
        if k == 0:
            break
        j_above, j_k = j_k, k * two_over_a * j_k - j_above
        j_k[start == k - 1] = 1e-30
        if k % 4 == 0:
            big = np.abs(j_k) > _RESCALE
            if np.any(big):
                scale = np.where(big, 1.0 / _RESCALE, 1.0)
                for values in (j_k, j_above, even, odd, norm):
                    values *= scale
    with np.errstate(divide="ignore", invalid="ignore"):
        out = (4.0 / (np.pi * a_safe * norm)
               * (np.cos(a_safe * sc / 2.0) * even - np.sin(a_safe * sc / 2.0) * odd))
    in_focus = (2.0 * beta - np.sin(2.0 * beta)) / np.pi
    out = np.where(small, in_focus, out)
    out = np.where(sc == 0.0, 1.0, out)
    return np.where(s >= 2.0, 0.0, out)


@contract(wavelength=WAVELENGTH, aperture_diameter=APERTURE_DIAMETER,
          defocus_waves=Values(Spec("1", "defocus in waves"), optional=True),
          defocus_opd=Values(Spec("m", "defocus optical path difference"), optional=True))
def defocused_aperture(fx, fy, wavelength, aperture_diameter, defocus_waves=None, defocus_opd=None):
    r"""Diffraction OTF of an unobscured circular aperture with defocus.

    Give the defocus as exactly one of ``defocus_waves`` or ``defocus_opd``.
    A longitudinal focus shift converts to ``defocus_opd`` with
    :func:`defocus_wavefront_coefficient`.

    Parameters
    ----------
    fx, fy : xr.DataArray
        Angular spatial frequencies, broadcast against each other. [cycles/rad]
    wavelength : float or xr.DataArray
        Wavelength. [m]
    aperture_diameter : float or xr.DataArray
        Effective entrance-pupil diameter, > 0. [m]
    defocus_waves : float or xr.DataArray, optional
        Defocus wavefront coefficient W20 (peak optical path difference at the
        pupil edge relative to the reference sphere) in waves at
        ``wavelength``. [1]
    defocus_opd : float or xr.DataArray, optional
        The same coefficient W20 as a length; divided by ``wavelength``. [m]

    Returns
    -------
    xr.DataArray
        Real OTF (it changes sign beyond about 0.5 waves of defocus),
        broadcast over every input dimension; 0 beyond :math:`D/\lambda`. [1]

    Notes
    -----
    Hopkins (1955), Proc. R. Soc. A 231, 91, with :math:`s = 2\rho\lambda/D`,
    :math:`\beta = \cos^{-1}(s/2)`, :math:`a = 4\pi W_{20} s/\lambda`:

    .. math::

        H = \frac{4}{\pi a}\cos\frac{as}{2}\Big[\beta J_1(a)
            + \sum_{n\ge1} (-1)^{n+1}\frac{\sin 2n\beta}{2n}
              \big(J_{2n-1}(a) - J_{2n+1}(a)\big)\Big]
          - \frac{4}{\pi a}\sin\frac{as}{2}\sum_{n\ge0} (-1)^n
              \frac{\sin(2n+1)\beta}{2n+1}\big(J_{2n}(a) - J_{2n+2}(a)\big)

    Both sums run to Bessel order :math:`a + 6a^{1/3} + 30` (each value's own
    :math:`a`), past which the terms are below 1e-17, with every :math:`J_n`
    from one backward recurrence (:func:`hopkins_kernel`): the series is
    converged to rounding (checked against the pupil autocorrelation to 1e-13
    up to 10 waves). Below :math:`a = 10^{-7}` the in-focus limit
    :math:`(2\beta - \sin 2\beta)/\pi` is used. Obscured pupils and the
    chain's defocus: :func:`xbsm.otf.defocus.defocused_aperture_otf`.
    pyBSM 0.16.1 writes :math:`\sin(2n\beta(J - J))` for
    :math:`\sin(2n\beta)(J - J)`, uses :math:`2/(\pi a)` for
    :math:`4/(\pi a)` and stops after four terms (-27 % at
    :math:`\rho/\rho_c = 0.3` for 0.25 waves).
    """
    if (defocus_waves is None) == (defocus_opd is None):
        raise ValueError("give exactly one of defocus_waves or defocus_opd")
    waves = defocus_waves if defocus_opd is None else defocus_opd / wavelength
    s = 2.0 * np.hypot(fx, fy) * wavelength / aperture_diameter
    if not isinstance(waves, xr.DataArray):
        waves = xr.DataArray(waves)
    out = xr.apply_ufunc(hopkins_kernel, s, waves, dask="parallelized", output_dtypes=[float])
    return described(out, defocused_aperture)
