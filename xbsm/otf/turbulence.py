"""Atmospheric turbulence: Hufnagel-Valley Cn2, coherence diameter r0, OTFs (IBSM 3-3, 3-9)."""

from __future__ import annotations

import functools
import math

import numpy as np

from .._kernels import apply_kernel
from .._metadata import described
from ..geometry import altitude_along_path_kernel
from ..params import Spec, Values, cn2_table, contract, table_values
from ..quadrature import legendre_nodes
from ._contracts import (
    APERTURE_DIAMETER,
    CN2,
    CN2_SCALE,
    DURATION,
    LENGTH,
    SPEED,
    UNIT_INTERVAL,
    WAVELENGTH,
    Weights,
)
from .spectral import (
    _spectral,
    normalised_weights,
    weighted_sum_kernel,
)

__all__ = [
    "hufnagel_valley",
    "path_coherence_diameter",
    "slant_path_coherence_diameter",
    "scale_coherence_diameter",
    "band_coherence_diameter",
    "turbulence",
    "wind_blended_turbulence",
    "polychromatic_turbulence",
]

REFERENCE_WAVELENGTH = 1.0e-6
"""Wavelength at which the slant-path r0 is integrated before scaling. [m]"""

PATH_RULES = ("trapezoid", "gauss-legendre")

#: Values of the result (frequency x scenario) that the polychromatic OTF evaluates at a
#: time. A block holds whole, where it can, the axes along which the OTF's exponents do not
#: vary (a visibility or integration-time axis: the exponentials are taken once for all of
#: them) and cuts the others first (:func:`_blocks`). An optics study's chunk of
#: 195 nodes x 24,000 scenarios x 31 wavelengths was cut into 2 columns of its last
#: (visibility) axis before: each wavelength's temporaries held 2.3 million values (18 MB,
#: memory-bound) and the exponentials were taken once per visibility.
_BLOCK = 1 << 15
#: Values along the innermost varying axes that a block keeps whole before anything else
#: (:func:`_blocks`): a visibility sweep of 10^4 scenarios (195 nodes each) was cut into
#: blocks of 3 nodes x 10^4 visibilities, every loop three values long (91 -> 113 us a
#: scenario against the column blocks before).
_INNER = 64
#: Values of the (frequency x scenario x wavelength) temporaries inside a block: 2^14
#: (128 KiB each), so that the kernel's temporaries stay in the 1 MiB L2 cache of
#: this machine's cores: one mwir_narrow call (1,680 nodes x 61 wavelengths, one block)
#: 2.4 -> 1.3 ms of CPU against 2^16. Neither size changes a value (the sum runs in band
#: order).
_STEP = 1 << 14
#: Scenarios sharing their exponentials (the block's axes along which only the exposure,
#: the wind or the spectral weights vary: an integration-time or visibility sweep) from
#: which a block's sums over the wavelength are matrix products (:func:`_shared_sums`)
#: rather than a multiply-add per wavelength and value.
_SHARED_ROWS = 4
#: Rows of one such product: small enough that OpenBLAS runs it on the calling thread
#: (one large product on its thread pool serialises two threads' calls).
_SHARED_ROWS_PER_PRODUCT = 32


@contract(cn2_at_1m=CN2, cn2_tropopause=CN2, cn2_upper_air=CN2, cn2_multiplier=CN2_SCALE)
def hufnagel_valley(altitude, high_altitude_wind_speed=21.0, cn2_at_1m=1.7e-14,
                    cn2_tropopause=5.94e-53, cn2_upper_air=2.7e-16, cn2_multiplier=1.0):
    r"""Hufnagel-Valley refractive-index structure parameter profile.

    Parameters
    ----------
    altitude : float or xr.DataArray
        Height above the ground. [m]
    high_altitude_wind_speed : float or xr.DataArray
        Root-mean-square upper-air wind speed :math:`v` (21 for HV 5/7). [m/s]
    cn2_at_1m : float or xr.DataArray
        Coefficient :math:`A` of the surface term, >= 0 (1.7e-14 for HV 5/7). [m^(-2/3)]
    cn2_tropopause : float or xr.DataArray
        Coefficient :math:`T` of the tropopause term, >= 0 (5.94e-53 for HV 5/7, with
        :math:`h` in metres). [m^(-2/3)]
    cn2_upper_air : float or xr.DataArray
        Coefficient :math:`U` of the 1.5 km scale-height term, >= 0 (2.7e-16 for HV 5/7).
        [m^(-2/3)]
    cn2_multiplier : float or xr.DataArray
        Factor :math:`M` of the whole profile, >= 0 (1 for HV 5/7). [1]

    Returns
    -------
    float or xr.DataArray
        :math:`C_n^2` at ``altitude``. [m^(-2/3)]

    Notes
    -----
    Replaces IBSM Eqs. 3-6 to 3-8 (Roggemann and Welsh, Imaging Through
    Turbulence, 1996), with :math:`h` the altitude in metres and :math:`v` the wind
    speed in m/s:

    .. math:: C_n^2(h) = M\left[T\left(\frac{v}{27}\right)^2 h^{10} e^{-h/1000}
              + U e^{-h/1500} + A e^{-h/100}\right]

    At the defaults (HV 5/7) the zenith plane-wave r0 is 5.3 cm and the isoplanatic
    angle 7.0 urad at 0.5 um (``docs/atmosphere.md``).
    """
    out = apply_kernel(_hufnagel_valley_kernel, high_altitude_wind_speed, altitude, cn2_at_1m,
                       cn2_tropopause, cn2_upper_air, cn2_multiplier)
    return described(out, hufnagel_valley, units="m-2/3")


def _hufnagel_valley_kernel(high_altitude_wind_speed, altitude, cn2_at_1m,
                            cn2_tropopause=5.94e-53, cn2_upper_air=2.7e-16, cn2_multiplier=1.0):
    """Hufnagel-Valley Cn2 on plain arrays (arguments in the order of the result's dims).

    At the defaults every operation is the one of HV 5/7 (the multiplier 1 is exact).
    """
    h = altitude
    return (
        cn2_tropopause * (high_altitude_wind_speed / 27.0) ** 2 * h**10 * np.exp(-h / 1000.0)
        + cn2_upper_air * np.exp(-h / 1500.0)
        + cn2_at_1m * np.exp(-h / 100.0)
    ) * cn2_multiplier


def _r0_from_integral(integral, wavelength):
    """Spherical-wave r0 from the weighted path integral of Cn2."""
    k = 2.0 * np.pi / wavelength
    return (0.423 * k**2 * integral) ** (-3.0 / 5.0)


@contract(wavelength=WAVELENGTH)
def path_coherence_diameter(cn2, wavelength=REFERENCE_WAVELENGTH, path_dim="path"):
    r"""Spherical-wave coherence diameter from sampled Cn2 along a path (trapezoid rule).

    Parameters
    ----------
    cn2 : xr.DataArray
        Structure parameter sampled along ``path_dim``, whose coordinate is the
        distance from the target (0 at the target, the path length at the
        sensor), increasing. [m^(-2/3)]
    wavelength : float or xr.DataArray
        Wavelength, > 0. [m]
    path_dim : str
        Name of the path dimension. Default ``"path"``.

    Returns
    -------
    xr.DataArray
        Fried coherence diameter r0, broadcast over every other input dimension. [m]

    Notes
    -----
    Schmidt (2010) Eq. 9.64 for a spherical wave, replacing IBSM Eq. 3-5,
    with :math:`z` measured from the target and :math:`L` the path length:

    .. math:: r_0 = \left[0.423\,k^2 \int_0^L C_n^2(z)
              \left(\frac{z}{L}\right)^{5/3} dz\right]^{-3/5},\quad k = 2\pi/\lambda

    The integral is the trapezoid rule over the given samples, as pyBSM's
    ``coherence_diameter``.
    """
    if path_dim not in cn2.dims or path_dim not in cn2.coords:
        raise ValueError(f"cn2 must have a {path_dim!r} dimension with a distance coordinate")
    z = cn2[path_dim]
    integral = (cn2 * (z / z.max()) ** (5.0 / 3.0)).integrate(path_dim)
    out = _r0_from_integral(integral, wavelength)
    return described(out, path_coherence_diameter, units="m")


@functools.lru_cache(maxsize=16)
def path_nodes(path_samples, rule):
    """Nodes t in [0, 1] and weights of the normalised path integral (read-only, cached)."""
    if rule == "trapezoid":
        t = np.linspace(0.0, 1.0, path_samples)
        w = np.full(path_samples, 1.0 / (path_samples - 1))
        w[[0, -1]] *= 0.5
    else:
        # Gauss-Legendre in u with z = L u^2: the substitution makes the
        # (z/L)^(5/3) weight and the near-target boundary layer smooth in u.
        x, w = legendre_nodes(path_samples)
        u = 0.5 * (x + 1.0)
        t, w = u**2, w * u  # dz/L = 2u du, du = dx/2
    for a in (t, w):
        a.flags.writeable = False
    return t, w


@contract(slant_range=LENGTH,
          cn2_at_1m=Values(Spec("m-2/3", "refractive-index structure parameter", low=0.0,
                                low_open=True)),
          cn2_tropopause=CN2, cn2_upper_air=CN2,
          cn2_multiplier=Values(Spec("1", "multiplier of the Cn2 profile", low=0.0,
                                     low_open=True)),
          wavelength=WAVELENGTH,
          path_samples=Spec("1", "samples along the path", low=2.0, whole=True))
def slant_path_coherence_diameter(
    slant_range,
    sensor_altitude,
    target_altitude=0.0,
    high_altitude_wind_speed=21.0,
    cn2_at_1m=1.7e-14,
    wavelength=REFERENCE_WAVELENGTH,
    path_samples=64,
    rule="gauss-legendre",
    geometry_form="stable",
    cn2_tropopause=5.94e-53,
    cn2_upper_air=2.7e-16,
    cn2_multiplier=1.0,
    cn2_profile=None,
):
    r"""Spherical-wave coherence diameter on a curved-Earth slant path, Hufnagel-Valley Cn2.

    Parameters
    ----------
    slant_range : float or xr.DataArray
        Distance between target and sensor, > 0. [m]
    sensor_altitude : float or xr.DataArray
        Sensor height above the surface. [m]
    target_altitude : float or xr.DataArray
        Target height above the surface. [m]
    high_altitude_wind_speed : float or xr.DataArray
        Hufnagel-Valley wind speed. [m/s]
    cn2_at_1m : float or xr.DataArray
        Hufnagel-Valley structure parameter near the ground, > 0. [m^(-2/3)]
    wavelength : float or xr.DataArray
        Wavelength, > 0 (default 1 um). [m]
    path_samples : int
        Number of quadrature nodes along the path. [1]
    rule : {"gauss-legendre", "trapezoid"}
        ``"trapezoid"`` with 10000 samples reproduces pyBSM 0.16.1 (which
        also assumes a target on the ground); its error is about 3e-9
        relative. ``"gauss-legendre"`` (default) uses Gauss-Legendre nodes in
        :math:`u = \sqrt{z/L}`, which smooths the :math:`(z/L)^{5/3}` weight;
        32 nodes are within 1e-12 of a 10^6-sample trapezoid and of 2000
        nodes for paths from 100 m to 300 km (``docs/otf.md``).
    geometry_form : {"stable", "law-of-cosines"}
        Formulas of the path heights (:data:`xbsm.geometry.FORMS`).
    cn2_tropopause, cn2_upper_air : float or xr.DataArray
        The other Hufnagel-Valley coefficients (:func:`hufnagel_valley`). [m^(-2/3)]
    cn2_multiplier : float or xr.DataArray
        Factor of the whole profile (Hufnagel-Valley or ``cn2_profile``), > 0. [1]
    cn2_profile : xr.DataArray, optional
        A table of :math:`C_n^2` over a ``height`` coordinate in place of
        Hufnagel-Valley (:func:`xbsm.params.cn2_table`; the Hufnagel-Valley parameters are then
        unused). [m^(-2/3)]

    Returns
    -------
    xr.DataArray
        Fried coherence diameter r0, broadcast over the scenario dimensions. [m]

    Notes
    -----
    Schmidt (2010) Eq. 9.64 for a spherical wave (replacing IBSM Eq. 3-5) with
    :math:`C_n^2(h(z))` from :func:`hufnagel_valley` (or the table) and :math:`h(z)`
    the height above the spherical Earth at distance :math:`z` from the target
    (:func:`xbsm.geometry.altitude_along_path`):

    .. math:: r_0 = \left[0.423\,k^2 L \int_0^1 C_n^2(h(tL))\, t^{5/3}\, dt\right]^{-3/5}
    """
    if rule not in PATH_RULES:
        raise ValueError(f"rule must be one of {PATH_RULES}; got {rule!r}")
    table = None if cn2_profile is None else table_values(cn2_table(cn2_profile))
    out = apply_kernel(slant_path_kernel, wavelength, high_altitude_wind_speed, slant_range,
                       sensor_altitude, target_altitude, cn2_at_1m, cn2_tropopause,
                       cn2_upper_air, cn2_multiplier,
                       nodes=path_nodes(int(path_samples), rule), form=geometry_form,
                       profile=table)
    return described(out, slant_path_coherence_diameter, units="m")


def slant_path_kernel(wavelength, high_altitude_wind_speed, slant_range, sensor_altitude,
                      target_altitude, cn2_at_1m, cn2_tropopause=5.94e-53,
                      cn2_upper_air=2.7e-16, cn2_multiplier=1.0, *, nodes, form,
                      profile=None):
    """Slant-path r0 on plain arrays; ``nodes`` = (t, weights) of :func:`path_nodes`.

    Arguments in the order of the result's dims. The path runs along a new first axis.
    ``profile``: (heights, Cn2) of a table (:func:`xbsm.params.table_values`) in place of
    Hufnagel-Valley, or None.
    """
    t, w = nodes
    ndim = max(np.ndim(a) for a in (  # of the broadcast result (np.broadcast_shapes: 8 us)
        wavelength, high_altitude_wind_speed, slant_range, sensor_altitude, target_altitude,
        cn2_at_1m, cn2_tropopause, cn2_upper_air, cn2_multiplier))
    along = (slice(None),) + (None,) * ndim

    def on_path(a):
        return np.asarray(a, dtype=float)[None, ...]

    heights = altitude_along_path_kernel(on_path(sensor_altitude), on_path(slant_range),
                                         t[along] * slant_range, on_path(target_altitude),
                                         form)
    if profile is None:
        cn2 = _hufnagel_valley_kernel(on_path(high_altitude_wind_speed), heights,
                                      on_path(cn2_at_1m), on_path(cn2_tropopause),
                                      on_path(cn2_upper_air), on_path(cn2_multiplier))
    else:
        cn2 = table_kernel(heights, *profile) * on_path(cn2_multiplier)
    integral = np.einsum("k...,k->...", cn2, w * t ** (5.0 / 3.0)) * slant_range
    return _r0_from_integral(integral, wavelength)


def table_kernel(altitude, heights, cn2):
    """Cn2 of a table at ``altitude``, log-linear between heights (linear next to a 0).

    Raises ValueError where ``altitude`` is above the table's last height.
    """
    altitude = np.asarray(altitude, dtype=float)
    # the path's heights are computed; a sensor at the last height may exceed it by rounding
    if np.any(altitude > heights[-1] + 1e-9 * max(abs(heights[-1]), 1.0)):
        raise ValueError(
            f"cn2_profile must cover the path: its last height is {heights[-1]:g} m but the "
            f"path reaches {float(np.nanmax(altitude)):g} m; extend the table")
    i = np.clip(np.searchsorted(heights, altitude, side="right") - 1, 0, heights.size - 2)
    w = np.clip((altitude - heights[i]) / (heights[i + 1] - heights[i]), 0.0, 1.0)
    lo, hi = cn2[i], cn2[i + 1]
    both = (lo > 0.0) & (hi > 0.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        logs = np.exp(np.log(np.where(both, lo, 1.0)) * (1.0 - w)
                      + np.log(np.where(both, hi, 1.0)) * w)
    return np.where(both, logs, lo + (hi - lo) * w)


@contract(coherence_diameter=LENGTH, wavelength=WAVELENGTH,
          reference_wavelength=WAVELENGTH)
def scale_coherence_diameter(
    coherence_diameter, wavelength, reference_wavelength=REFERENCE_WAVELENGTH
):
    r"""Coherence diameter r0 scaled from a reference wavelength.

    Parameters
    ----------
    coherence_diameter : float or xr.DataArray
        r0 at ``reference_wavelength``, > 0. [m]
    wavelength : float or xr.DataArray
        Wavelength, > 0. [m]
    reference_wavelength : float or xr.DataArray
        Wavelength at which ``coherence_diameter`` is given (default 1 um). [m]

    Returns
    -------
    float or xr.DataArray
        r0 at ``wavelength``. [m]

    Notes
    -----
    .. math:: r_0(\lambda) = r_0(\lambda_0)\,(\lambda/\lambda_0)^{6/5}
    """
    out = apply_kernel(_scale_kernel, coherence_diameter, wavelength, reference_wavelength)
    return described(out, scale_coherence_diameter, units="m")


def _scale_kernel(coherence_diameter, wavelength, reference_wavelength):
    """r0 scaled as lambda^(6/5) on plain arrays."""
    return coherence_diameter * (wavelength / reference_wavelength) ** (6.0 / 5.0)


@contract(coherence_diameter=LENGTH, wavelength=WAVELENGTH, weights=Weights(),
          reference_wavelength=WAVELENGTH)
def band_coherence_diameter(
    coherence_diameter, wavelength, weights, reference_wavelength=REFERENCE_WAVELENGTH
):
    r"""Spectrally weighted coherence diameter over a band (pyBSM's r0_band).

    Parameters
    ----------
    coherence_diameter : float or xr.DataArray
        r0 at ``reference_wavelength``, > 0. [m]
    wavelength : xr.DataArray
        Wavelengths of the band, dimension ``wavelength``. [m]
    weights : xr.DataArray
        Spectral weights over ``wavelength``, normalised here. [any]
    reference_wavelength : float or xr.DataArray
        Wavelength at which ``coherence_diameter`` is given (default 1 um). [m]

    Returns
    -------
    xr.DataArray
        Weighted mean of :math:`r_0(\lambda)`. [m]

    Notes
    -----
    Paper Eq. 3 applied to :math:`r_0(\lambda) = r_0(\lambda_0)(\lambda/\lambda_0)^{6/5}`:

    .. math:: \bar r_0 = \sum_\lambda w(\lambda)\, r_0(\lambda)
    """
    out = _spectral(band_kernel, coherence_diameter, reference_wavelength, wavelength, weights)
    return described(out, band_coherence_diameter, units="m")


def band_kernel(coherence_diameter, reference_wavelength, wavelength, weights):
    """Weighted mean of r0(lambda) over the last (wavelength) axis, on plain arrays."""
    r0 = _scale_kernel(coherence_diameter[..., None], wavelength,
                       np.asarray(reference_wavelength)[..., None])
    return weighted_sum_kernel(r0, weights)


@contract(wavelength=WAVELENGTH, aperture_diameter=APERTURE_DIAMETER,
          coherence_diameter=LENGTH, exposure_coefficient=UNIT_INTERVAL)
def turbulence(fx, fy, wavelength, aperture_diameter, coherence_diameter, exposure_coefficient=0.0):
    r"""Long- or short-exposure atmospheric turbulence OTF.

    Parameters
    ----------
    fx, fy : xr.DataArray
        Angular spatial frequencies, broadcast against each other. [cycles/rad]
    wavelength : float or xr.DataArray
        Wavelength, > 0. [m]
    aperture_diameter : float or xr.DataArray
        Effective entrance-pupil diameter, > 0. [m]
    coherence_diameter : float or xr.DataArray
        Fried coherence diameter r0 at ``wavelength``, > 0. [m]
    exposure_coefficient : float or xr.DataArray
        0 for long exposure, 0.5 for short exposure (tilt removed), in [0, 1]. [1]

    Returns
    -------
    xr.DataArray
        Real OTF, broadcast over every input dimension. [1]

    Notes
    -----
    IBSM Eq. 3-3, with :math:`\alpha` the exposure coefficient:

    .. math:: H = \exp\left\{-3.44\left(\frac{\lambda\rho}{r_0}\right)^{5/3}
              \left[1 - \alpha\left(\frac{\lambda\rho}{D}\right)^{1/3}\right]\right\}

    The short-exposure form is meant for :math:`\rho \le D/\lambda`; beyond
    :math:`\rho = D/(\alpha^3\lambda)` it exceeds 1 (not clipped, as in pyBSM;
    the aperture OTF is zero there).
    """
    out = apply_kernel(_turbulence_xy_kernel, wavelength, coherence_diameter, fx, fy,
                    exposure_coefficient, aperture_diameter)
    return described(out, turbulence)


def _turbulence_xy_kernel(wavelength, coherence_diameter, fx, fy, exposure_coefficient,
                          aperture_diameter):
    """:func:`_turbulence_kernel` at hypot(fx, fy) (arguments in the order of the dims)."""
    return _turbulence_kernel(np.hypot(fx, fy), wavelength, aperture_diameter,
                              coherence_diameter, exposure_coefficient)


def _turbulence_kernel(radial, wavelength, aperture_diameter, coherence_diameter,
                       exposure_coefficient, long_exposure=None):
    """IBSM Eq. 3-3 on plain arrays, at radial frequency ``radial`` >= 0 [cycles/rad].

    ``long_exposure`` is the exponent of the long-exposure OTF,
    :func:`_long_exposure_exponent` (computed here if not given).
    """
    if long_exposure is None:
        long_exposure = _long_exposure_exponent(radial, wavelength, coherence_diameter)
    return np.exp(long_exposure * (1.0 - exposure_coefficient
                                   * (wavelength / aperture_diameter * radial) ** (1.0 / 3.0)))


def _long_exposure_exponent(radial, wavelength, coherence_diameter):
    """``-3.44 (lambda f / r0)^(5/3)``, the logarithm of the long-exposure turbulence OTF."""
    return -3.44 * (wavelength / coherence_diameter * radial) ** (5.0 / 3.0)


@contract(wavelength=WAVELENGTH, aperture_diameter=APERTURE_DIAMETER,
          coherence_diameter=LENGTH, integration_time=DURATION, wind_speed=SPEED)
def wind_blended_turbulence(
    fx, fy, wavelength, aperture_diameter, coherence_diameter, integration_time, wind_speed
):
    r"""Turbulence OTF blended between short and long exposure by the wind-driven decorrelation.

    Parameters
    ----------
    fx, fy : xr.DataArray
        Angular spatial frequencies, broadcast against each other. [cycles/rad]
    wavelength : float or xr.DataArray
        Wavelength, > 0. [m]
    aperture_diameter : float or xr.DataArray
        Effective entrance-pupil diameter, > 0. [m]
    coherence_diameter : float or xr.DataArray
        Fried coherence diameter r0 at ``wavelength``, > 0. [m]
    integration_time : float or xr.DataArray
        Dwell (integration) time, >= 0 (times the TDI stages for TDI). [s]
    wind_speed : float or xr.DataArray
        Apparent transverse wind speed across the path (e.g. the platform
        speed), >= 0. [m/s]

    Returns
    -------
    xr.DataArray
        Real OTF, broadcast over every input dimension. [1]

    Notes
    -----
    IBSM Eq. 3-9, with :math:`H_\alpha` from :func:`turbulence`:

    .. math:: H = w H_{0.5} + (1 - w) H_0,\quad w = e^{-v t / r_0}
    """
    out = apply_kernel(_wind_blended_xy_kernel, wind_speed, integration_time, coherence_diameter,
                    wavelength, fx, fy, aperture_diameter)
    return described(out, wind_blended_turbulence)


def _wind_blended_xy_kernel(wind_speed, integration_time, coherence_diameter, wavelength, fx, fy,
                            aperture_diameter):
    """:func:`_wind_blended_kernel` at hypot(fx, fy) (arguments in the order of the dims)."""
    return _wind_blended_kernel(np.hypot(fx, fy), wavelength, aperture_diameter,
                                coherence_diameter, integration_time, wind_speed)


def _wind_blended_kernel(radial, wavelength, aperture_diameter, coherence_diameter,
                         integration_time, wind_speed):
    """IBSM Eq. 3-9 on plain arrays, at radial frequency ``radial`` >= 0 [cycles/rad]."""
    weight = np.exp(-wind_speed * integration_time / coherence_diameter)
    exponent = _long_exposure_exponent(radial, wavelength, coherence_diameter)
    short = _turbulence_kernel(radial, wavelength, aperture_diameter, coherence_diameter, 0.5,
                               exponent)
    long = np.exp(exponent)  # Eq. 3-3 at exposure coefficient 0: its factor is exactly 1
    return weight * short + (1.0 - weight) * long


@contract(aperture_diameter=APERTURE_DIAMETER, coherence_diameter=LENGTH,
          reference_wavelength=WAVELENGTH, integration_time=DURATION, wind_speed=SPEED)
def polychromatic_turbulence(
    fx,
    fy,
    wavelength,
    weights,
    aperture_diameter,
    coherence_diameter,
    integration_time,
    wind_speed,
    reference_wavelength=REFERENCE_WAVELENGTH,
):
    r"""Spectrally weighted wind-blended turbulence OTF.

    Parameters
    ----------
    fx, fy : xr.DataArray
        Angular spatial frequencies, broadcast against each other. [cycles/rad]
    wavelength : xr.DataArray
        Wavelengths of the band, dimension ``wavelength``. [m]
    weights : xr.DataArray
        Spectral weights over ``wavelength``, normalised here. [any]
    aperture_diameter : float or xr.DataArray
        Effective entrance-pupil diameter, > 0. [m]
    coherence_diameter : float or xr.DataArray
        r0 at ``reference_wavelength`` (e.g. from
        :func:`slant_path_coherence_diameter`), > 0. [m]
    integration_time : float or xr.DataArray
        Dwell (integration) time, >= 0. [s]
    wind_speed : float or xr.DataArray
        Apparent transverse wind speed, >= 0. [m/s]
    reference_wavelength : float or xr.DataArray
        Wavelength at which ``coherence_diameter`` is given (default 1 um). [m]

    Returns
    -------
    xr.DataArray
        Real OTF with ``wavelength`` reduced. [1]

    Notes
    -----
    Paper Eq. 3 over IBSM Eq. 3-9, with :math:`r_0(\lambda) \propto \lambda^{6/5}`:

    .. math:: H = \sum_\lambda w(\lambda)\, H_{3\text{-}9}\big(\lambda, r_0(\lambda)\big)

    pyBSM's ``polychromatic_turbulence_OTF`` also integrates r0 on the path;
    here that is :func:`slant_path_coherence_diameter` and the band r0 is
    :func:`band_coherence_diameter`.
    """
    out = _spectral(_polychromatic_xy_kernel, fx, fy, coherence_diameter, integration_time,
                    wind_speed, aperture_diameter, reference_wavelength, wavelength, weights)
    return described(out, polychromatic_turbulence)


def _polychromatic_xy_kernel(fx, fy, r0_ref, exposure, speed, diameter, reference, wl, w):
    """:func:`polychromatic_kernel` at hypot(fx, fy) (arguments in the order of the dims)."""
    return polychromatic_kernel(np.hypot(fx, fy), r0_ref, exposure, speed, diameter, reference,
                                 wl, w)


def polychromatic_kernel(radial, r0_ref, exposure, speed, diameter, reference, wl, w):
    """Weighted sum over the last (wavelength) axis (numpy).

    ``w`` is normalised here. The OTFs are evaluated a block at a time, at most about
    :data:`_BLOCK` values (:func:`_blocks`), then as many wavelengths as make
    :data:`_STEP` values (a few for one scenario, one at a time for a large sweep), so
    temporaries stay in cache and memory at one block; every value is summed wavelength
    by wavelength in band order whatever the block. Inside a block the wavelength is the
    outermost axis, so that every ufunc runs along the long contiguous axis of the other
    inputs (with wavelength innermost, a step of a few wavelengths made numpy's inner loops a
    few values long: twice the time on one scenario of 1,680 nodes x 61 wavelengths).
    Each (frequency, wavelength) value costs one exponential, the short-exposure OTF; the
    long-exposure one is it times a factor that does not depend on the wavelength
    (:func:`_tilt_exponent`).
    """
    w = normalised_weights(w)
    inputs = [np.asarray(a)[..., None] for a in (radial, r0_ref, exposure, speed, diameter,
                                                 reference)] + [np.asarray(wl), w]
    # every input ends in the wavelength axis (or 1): the result's shape is the rest
    # (np.broadcast of the arrays: np.broadcast_shapes of their shapes costs 5 us more)
    shape = np.broadcast(*inputs).shape[:-1]
    total = np.zeros(shape or (1,))  # a 0-d result is computed as one value
    ndim = total.ndim + 1
    inputs = [a.reshape((1,) * (ndim - a.ndim) + a.shape) for a in inputs]
    # The axes along which the exponents vary (frequency, r0, aperture) go innermost, so
    # that every ufunc runs along them and the exponentials broadcast over the others (a
    # visibility axis of 2 innermost made numpy's loops two values long); :func:`_blocks`
    # says which axes a block keeps whole.
    varies = [n > 1 for n in np.broadcast(*(inputs[i] for i in (0, 1, 4, 5))).shape[:-1]]
    order = ([i for i, v in enumerate(varies) if not v]
             + [i for i, v in enumerate(varies) if v])
    # every input as a view with the wavelength axis first, the result's axes in ``order``
    # after it (one transpose: moveaxis and transpose cost 5 us an input on one scenario)
    axes = (ndim - 1, *order)
    radial, r0_ref, exposure, speed, diameter, reference, wl, w = (
        a.transpose(axes) for a in inputs)
    # what does not depend on the frequency, once per (wavelength, scenario), not per block:
    # the long-exposure exponent's factor and Eq. 3-9's weights of short and long exposure
    r0 = _scale_kernel(r0_ref, wl, reference)
    exponent = -3.44 * (wl / r0) ** (5.0 / 3.0)
    short_share = np.exp(-speed * exposure / r0)
    # the weights of the short- and the long-exposure sums, stacked on a new axis after the
    # wavelength so that one multiply-add per wavelength makes both sums
    shares = np.stack(np.broadcast_arrays(w * short_share, w * (1.0 - short_share)), axis=1)
    total = np.transpose(total, order)
    n_shared = varies.count(False)  # the first axes in ``order``
    whole = (slice(None),) * total.ndim
    for index in _kernel_blocks(total.shape, [varies[i] for i in order], shares.shape, n_shared):
        if index == whole:  # one block (a single scenario): the inputs as they are
            radial_, r0_ref_, diameter_, reference_, exponent_, shares_ = (
                radial, r0_ref, diameter, reference, exponent, shares)
        else:
            radial_, r0_ref_, diameter_, reference_, exponent_ = (
                _block_of(a, index) for a in (radial, r0_ref, diameter, reference, exponent))
            shares_ = _block_of(shares, index, lead=2)
        # the frequency's power once per block, not once per wavelength and scenario
        radial_5_3 = radial_ ** (5.0 / 3.0)
        tilt = _tilt_exponent(radial_, r0_ref_, diameter_, reference_)
        block = total[index].shape
        if math.prod(block[:n_shared]) >= _SHARED_ROWS:
            sums = _shared_sums(np.exp(exponent_ * radial_5_3 + tilt), shares_, n_shared)
        else:
            sums = _sums_by_wavelength(exponent_, radial_5_3, tilt, shares_, block)
        total[index] = sums[0] + np.exp(-tilt) * sums[1]
    back = sorted(range(len(order)), key=order.__getitem__)  # np.argsort of ``order``
    return np.ascontiguousarray(total.transpose(back)).reshape(shape)


def _kernel_blocks(shape, varies, shares_shape, n_shared):
    """The blocks :func:`polychromatic_kernel` cuts its (transposed) result ``shape`` into.

    ``varies`` says along which axes the exponents vary; the first ``n_shared`` axes do
    not (they share their exponentials). With at least :data:`_SHARED_ROWS` such rows the
    sums become matrix products (:func:`_shared_sums`): blocks keep whole the columns
    (axes along which the exponents vary but the weights ``shares_shape`` do not: the
    frequency), then the shared axes (the rows), and cut the axes along which both vary (a
    product for each). Otherwise :func:`_blocks` decides.
    """
    if math.prod(shape[:n_shared]) < _SHARED_ROWS:
        return _blocks(shape, varies)
    weighted = [shares_shape[2 + a] > 1 for a in range(len(shape))]
    columns = [a for a in reversed(range(n_shared, len(shape))) if not weighted[a]]
    batch = [a for a in reversed(range(n_shared, len(shape))) if weighted[a]]
    return _blocks_in(shape, columns + list(reversed(range(n_shared))) + batch)


def _sums_by_wavelength(exponent, radial_5_3, tilt, shares, block):
    """Both sums of a block, a few wavelengths at a time, added in band order (numpy).

    ``exponent`` (wavelength, block...) is the long-exposure exponent's factor, ``shares``
    (wavelength, 2, block...) the weights of the short- and long-exposure sums. Returns
    (2, block...): the short- and long-exposure parts, each over the band.
    """
    sums = np.zeros((2,) + block)
    n_wavelengths = exponent.shape[0]
    step = min(n_wavelengths, max(1, _STEP // max(1, sums[0].size)))
    # one buffer of each temporary for every step, not new ones (a fifth of the time of a
    # sweep's 31 steps of 30,000 values went to allocating and first touching them); the
    # exponentials' in their own shape, size 1 along the axes where only the weights vary
    own = np.broadcast(exponent[0], radial_5_3[0], tilt[0]).shape  # of their axes after the first
    short_buffer, terms_buffer = np.empty((step,) + own), np.empty((step, 2) + block)
    for start in range(0, n_wavelengths, step):
        n = min(step, n_wavelengths - start)
        short, terms = short_buffer[:n], terms_buffer[:n]
        # Eq. 3-3's short-exposure OTF: exp(long-exposure exponent + tilt exponent)
        np.multiply(exponent[start:start + n], radial_5_3, out=short)
        short += tilt
        np.exp(short, out=short)
        np.multiply(shares[start:start + n] if shares.shape[0] > 1 else shares, short[:, None],
                    out=terms)
        if start == 0:  # a sum over the first axis adds in its order: from 0, the same bits
            np.add.reduce(terms, axis=0, out=sums)
        else:
            for one in terms:  # band order, whatever the step
                sums += one
    return sums


def _shared_sums(short, shares, n_shared):
    """Both sums of a block whose first ``n_shared`` axes share their exponentials (numpy).

    ``short`` (wavelength, block...) is every wavelength's short-exposure OTF, size 1 on
    those axes; ``shares`` (wavelength, 2, block...) the weights of the short- and
    long-exposure sums. The sums over the wavelength are matrix products: rows the two
    sums on the shared axes, columns the axes along which the weights do not vary (the
    frequency at least), a product for each entry of the others. Returns (2, block...).
    """
    n = short.ndim - 1
    varying = range(n_shared, n)
    batch = [a for a in varying if shares.shape[2 + a] > 1]
    columns = [a for a in varying if shares.shape[2 + a] == 1]
    rows = np.transpose(shares, [2 + a for a in batch] + [1] + [2 + a for a in range(n_shared)]
                        + [0] + [2 + a for a in columns])
    values = np.transpose(short, [1 + a for a in batch] + [0]
                          + [1 + a for a in range(n_shared)] + [1 + a for a in columns])
    outer = rows.shape[:len(batch)]
    rows = np.reshape(rows, (math.prod(outer), -1, short.shape[0]))
    values = np.reshape(values, (rows.shape[0], short.shape[0], -1))
    out = np.empty((rows.shape[0], rows.shape[1], values.shape[2]))
    # stacks of rows small enough that BLAS runs each product on the calling thread
    for start in range(0, rows.shape[1], _SHARED_ROWS_PER_PRODUCT):
        stack = slice(start, start + _SHARED_ROWS_PER_PRODUCT)
        out[:, stack] = np.matmul(rows[:, stack], values)
    sizes = [short.shape[1 + a] for a in columns]
    out = np.reshape(out, (*outer, 2, *shares.shape[2:2 + n_shared], *sizes))
    where = batch + [-1] + list(range(n_shared)) + columns  # each result axis's block axis
    return np.transpose(out, np.argsort([a + 1 for a in where]))


def _block_of(a, index, lead=1):
    """Entries ``index`` of ``a``'s axes after its ``lead`` first ones; size-1 axes whole."""
    return a[(slice(None),) * lead + tuple(i if n > 1 else slice(None)
                                           for i, n in zip(index, a.shape[lead:], strict=True))]


def _tilt_exponent(radial, r0_ref, aperture_diameter, reference):
    """What removing tilt adds to the long-exposure OTF's exponent: the same at every wavelength.

    In Eq. 3-3 the short-exposure exponent is the long-exposure one,
    ``-3.44 (lambda f / r0)^(5/3)``, times ``1 - 0.5 (lambda f / D)^(1/3)``; so it adds
    ``1.72 (lambda f / r0)^(5/3) (lambda f / D)^(1/3)`` to it. With
    ``r0 = r0_ref (lambda / lambda_ref)^(6/5)`` the powers of lambda cancel
    (``lambda^(5/3 - 2 + 1/3) = 1``): the term is its value at the reference wavelength,
    ``1.72 (lambda_ref / r0_ref)^(5/3) (lambda_ref / D)^(1/3) f^2``, once per frequency and
    scenario. So each (frequency, wavelength) value needs one exponential, the short-
    exposure OTF, and the long-exposure OTF is it times ``exp(-tilt)``, which does not
    depend on the wavelength. Values move by a few units in the last place of the
    exponent against the formula written per wavelength (:func:`_wind_blended_kernel`).
    """
    scale = 1.72 * (reference / r0_ref) ** (5.0 / 3.0) * (reference / aperture_diameter) ** (
        1.0 / 3.0)
    return scale * radial**2


def _blocks(shape, varies):
    """Index tuples (slices) cutting ``shape`` into blocks of at most about :data:`_BLOCK` values.

    ``shape`` is in memory order, ``varies`` marks the axes along which the exponents vary.
    Axes are taken whole, while the block stays within :data:`_BLOCK`, in this order: the
    innermost varying axes until they hold :data:`_INNER` values (numpy's loops then run
    along at least that many), the axes along which nothing varies (their exponentials
    are shared, not taken again per block), the other varying axes; innermost first in
    each group. The first axis that does not fit is cut into steps of nearly equal length,
    every axis left after it into single entries.
    """
    inner, shared, rest, size = [], [], [], 1
    for axis in reversed(range(len(shape))):
        if not varies[axis]:
            shared.append(axis)
        elif size < _INNER:
            inner.append(axis)
            size *= shape[axis]
        else:
            rest.append(axis)
    yield from _blocks_in(shape, inner + shared + rest)


def _blocks_in(shape, order):
    """:func:`_blocks` with the axes taken whole in ``order`` (every axis once)."""
    size, k = 1, 0
    while k < len(order) and size * shape[order[k]] <= _BLOCK:
        size *= shape[order[k]]
        k += 1
    if k == len(order):
        yield (slice(None),) * len(shape)
        return
    cut, step = order[k], max(1, _BLOCK // size)
    step = -(-shape[cut] // -(-shape[cut] // step))  # steps of (nearly) equal length
    outer = order[k + 1:]
    for entries in np.ndindex(*(shape[i] for i in outer)):
        index = [slice(None)] * len(shape)
        for axis, entry in zip(outer, entries, strict=True):
            index[axis] = slice(entry, entry + 1)
        for start in range(0, shape[cut], step):
            index[cut] = slice(start, start + step)
            yield tuple(index)
