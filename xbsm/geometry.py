"""Scenario geometry over a spherical Earth (radius 6378.164 km, the paper Sec. 2.6).

Every function broadcasts over any scenario dimensions; its arithmetic is a NumPy kernel
under one ``xr.apply_ufunc``. Heights are above the spherical Earth's surface. [m]
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from ._kernels import apply_kernel, apply_orchestrator, dataset
from ._metadata import Output, outputs
from .constants import EARTH_RADIUS
from .params import Choice, contract

#: Formulas of the curved-earth triangle: "stable" (default: no cancellation near nadir or
#: on short paths) or "law-of-cosines" (pyBSM 0.16.1's, for number-for-number parity).
FORMS = ("stable", "law-of-cosines")
#: The GIQE elevation angle: "look-down" (pyBSM's, at the sensor) or "target" (the sensor's
#: elevation above the target's horizon).
ELEVATIONS = ("look-down", "target")
_FORM = Choice(FORMS)
_EPSILON = float(np.finfo(float).eps)  # read once: np.finfo costs 0.4 us a call


# ---------------------------------------------------------------------------- kernels
# Plain NumPy in and out, no checks. Each formula takes its arguments in the order in which
# its arithmetic first meets their dimensions, so that ``xr.apply_ufunc`` labels the result
# with the dimension order the formula has always given. Like xarray's arithmetic, the
# kernels give IEEE results (inf, NaN) without floating-point warnings.


def _slant_range_stable(sensor_altitude, target_altitude, ground_range):
    with np.errstate(all="ignore"):
        a = EARTH_RADIUS + sensor_altitude
        c = EARTH_RADIUS + target_altitude
        half = np.sin(ground_range / (2.0 * EARTH_RADIUS))
        return np.sqrt((a - c) ** 2 + 4.0 * a * c * half**2)


def _slant_range_cosines(target_altitude, sensor_altitude, ground_range):
    with np.errstate(all="ignore"):
        a = EARTH_RADIUS + sensor_altitude
        c = EARTH_RADIUS + target_altitude
        return np.sqrt(c**2.0 + a**2.0 - 2.0 * a * c * np.cos(ground_range / EARTH_RADIUS))


def _degenerate(angle, slant_range, a, c, coincident):
    """``angle`` where the triangle (Earth centre, sensor, target) exists, else its limit.

    NaN where the slant range is shorter than the height difference (beyond rounding:
    8 ulp of ``a^2 + c^2`` on the squares, the law of cosines' own error);
    ``coincident`` at zero slant range between equal heights.
    """
    d = np.abs(a - c)
    no_triangle = (d - slant_range) * (d + slant_range) > 8.0 * _EPSILON * (a * a + c * c)
    coincide = (slant_range == 0.0) & (d == 0.0)
    return np.where(no_triangle, np.nan, np.where(coincide, coincident, angle))[()]


def _nadir_angle_stable(target_altitude, slant_range, sensor_altitude):
    with np.errstate(all="ignore"):
        a = EARTH_RADIUS + sensor_altitude
        c = EARTH_RADIUS + target_altitude
        sine, _, two_half_sq = _central_angle_legs(slant_range, a, c)
        angle = np.arctan2(c * sine, (a - c) + c * two_half_sq)
        return _degenerate(angle, slant_range, a, c, np.pi / 2)


def _nadir_angle_cosines(target_altitude, sensor_altitude, slant_range):
    with np.errstate(all="ignore"):
        a = EARTH_RADIUS + sensor_altitude
        c = EARTH_RADIUS + target_altitude
        slant_range = np.asarray(slant_range, dtype=float)  # 0 gives inf, not an exception
        cosine = -(c**2.0 - a**2.0 - slant_range**2.0) / (2.0 * a * slant_range)
        angle = np.arccos(np.minimum(np.maximum(cosine, -1.0), 1.0))
        return _degenerate(angle, slant_range, a, c, np.pi / 2)


def _target_elevation_kernel(sensor_altitude, target_altitude, slant_range, form):
    with np.errstate(all="ignore"):
        a = EARTH_RADIUS + sensor_altitude
        c = EARTH_RADIUS + target_altitude
        slant_range = np.asarray(slant_range, dtype=float)
        if form == "law-of-cosines":
            cosine = (a**2.0 - c**2.0 - slant_range**2.0) / (2.0 * c * slant_range)
            angle = np.arcsin(np.minimum(np.maximum(cosine, -1.0), 1.0))
        else:
            sine, _, two_half_sq = _central_angle_legs(slant_range, a, c)
            angle = np.arctan2((a - c) - a * two_half_sq, a * sine)
        return _degenerate(angle, slant_range, a, c, 0.0)


def _nadir_angle_kernel(slant_range, sensor_altitude, target_altitude, form):
    if form == "law-of-cosines":
        return _nadir_angle_cosines(target_altitude, sensor_altitude, slant_range)
    return _nadir_angle_stable(target_altitude, slant_range, sensor_altitude)


def slant_and_elevation_kernel(altitude, ground_range, form, elevation):
    """Slant range and GIQE elevation angle of a target on the ground (numpy kernel).

    ``elevation`` is ``"target"`` (:func:`target_elevation_angle`) or ``"look-down"``
    (:func:`elevation_angle`); ``form`` one of :data:`FORMS`.
    """
    if form == "law-of-cosines":
        slant = _slant_range_cosines(0.0, altitude, ground_range)
    else:
        slant = _slant_range_stable(altitude, 0.0, ground_range)
    if elevation == "look-down":
        angle = np.pi / 2 - _nadir_angle_kernel(slant, altitude, 0.0, form)
    else:
        angle = _target_elevation_kernel(altitude, 0.0, slant, form)
    return slant, angle


def ground_range_at_elevation_kernel(sin_elevation, cos_elevation, sensor_altitude):
    """Ground range at which a sensor sees a target on the ground at an elevation (numpy kernel).

    The inverse of :func:`slant_and_elevation_kernel` (``"stable"``, ``"target"``) in the
    ground range, from the sine and cosine of the elevation angle at the target; see
    :func:`ground_range_at_elevation`. [m]
    """
    above = sensor_altitude * (2.0 * EARTH_RADIUS + sensor_altitude)
    rise = EARTH_RADIUS * sin_elevation
    slant = above / (np.sqrt(rise * rise + above) + rise)
    return EARTH_RADIUS * np.arctan2(slant * cos_elevation,
                                     EARTH_RADIUS + slant * sin_elevation)


def altitude_along_path_kernel(sensor_altitude, slant_range, distance_from_target,
                               target_altitude, form):
    """Height above the Earth at a point on the line of sight (numpy kernel).

    :func:`altitude_along_path` on plain arrays (the slant-path r0's kernel calls it);
    ``form`` one of :data:`FORMS`. [m]
    """
    with np.errstate(all="ignore"):
        a = EARTH_RADIUS + sensor_altitude
        phi = _nadir_angle_kernel(slant_range, sensor_altitude, target_altitude, form)
        b = slant_range - distance_from_target
        return np.sqrt(a**2 + b**2 - 2.0 * a * b * np.cos(phi)) - EARTH_RADIUS


def _ratio_kernel(numerator, denominator):
    with np.errstate(all="ignore"):
        return numerator / denominator


def _product_kernel(a, b):
    with np.errstate(all="ignore"):
        return a * b




@contract(Output("slant_range", "m", "slant range"), form=_FORM)
def slant_range(ground_range, sensor_altitude, target_altitude=0.0, *, form="stable"):
    r"""Slant range between target and sensor over a spherical Earth.

    Parameters
    ----------
    ground_range : float or xr.DataArray
        Great-circle distance on the ground between target and sensor nadir. [m]
    sensor_altitude : float or xr.DataArray
        Sensor height above the surface. [m]
    target_altitude : float or xr.DataArray
        Target height above the surface. [m]
    form : {"stable", "law-of-cosines"}
        See :data:`FORMS`.

    Returns
    -------
    float or xr.DataArray
        Slant range. [m]

    Notes
    -----
    Law of cosines with the central angle :math:`\theta = g / R_e`, in the form that
    does not cancel on short paths (:math:`1 - \cos\theta = 2\sin^2(\theta/2)`):

    .. math:: R = \sqrt{(a - c)^2 + 4ac\sin^2(\theta/2)},\quad a = R_e + h_s,\ c = R_e + h_t

    pyBSM's :math:`\sqrt{a^2 + c^2 - 2ac\cos\theta}` loses about
    :math:`\log_{10}(ac/R^2)` digits (7 on a 1 km path).
    """
    if form == "law-of-cosines":
        out = apply_kernel(_slant_range_cosines, target_altitude, sensor_altitude, ground_range)
    else:
        out = apply_kernel(_slant_range_stable, sensor_altitude, target_altitude, ground_range)
    return out


def _central_angle_legs(slant_range, a, c):
    """Sine and cosine of the central angle, and 2 sin^2(theta / 2), from the three sides.

    ``s^2 = (a - c)^2 + 4 a c sin^2(theta/2)`` solved for the half angle as a product
    of sums, which keeps every digit near nadir (no ``arccos`` of a value near 1).
    """
    d = a - c
    half_sq = np.maximum((slant_range - d) * (slant_range + d) / (4.0 * a * c), 0.0)
    at_most_one = np.minimum(half_sq, 1.0)
    two_half_sq = 2.0 * at_most_one
    sine = 2.0 * np.sqrt(at_most_one * np.maximum(1.0 - half_sq, 0.0))
    return sine, 1.0 - two_half_sq, two_half_sq


@contract(Output("nadir_angle", "rad", "nadir angle"), form=_FORM)
def nadir_angle(slant_range, sensor_altitude, target_altitude=0.0, *, form="stable"):
    r"""Angle at the sensor between nadir and the line of sight to the target.

    Parameters
    ----------
    slant_range : float or xr.DataArray
        Distance between target and sensor. [m]
    sensor_altitude : float or xr.DataArray
        Sensor height above the surface. [m]
    target_altitude : float or xr.DataArray
        Target height above the surface. [m]
    form : {"stable", "law-of-cosines"}
        See :data:`FORMS`.

    Returns
    -------
    float or xr.DataArray
        Nadir angle, 0 when looking straight down. [rad]

    Notes
    -----
    Two geometries have no triangle. At zero slant range between equal heights
    (sensor and target coincide) the result is :math:`\pi/2`, the limit of the
    chord's nadir angle :math:`\pi/2 - \theta/2` as the ground range goes to 0:
    the line of sight becomes the local horizontal (pyBSM divides by zero). A
    slant range shorter than the height difference (beyond rounding) is NaN:
    no line of sight is that short.

    In the triangle (Earth centre, sensor, target) with central angle :math:`\theta`,
    the two legs of the line of sight seen from the sensor give

    .. math:: \alpha = \operatorname{atan2}\big(c\sin\theta,\ (a - c) + 2c\sin^2(\theta/2)\big)

    which is exact to rounding at and near nadir (pyBSM's ``arccos`` of the law of
    cosines loses half the digits there: 1.388e-5 rad for an exact 1.111e-5 at 0.1 m
    from nadir at 9 km).
    """
    if form == "law-of-cosines":
        out = apply_kernel(_nadir_angle_cosines, target_altitude, sensor_altitude, slant_range)
    else:
        out = apply_kernel(_nadir_angle_stable, target_altitude, slant_range, sensor_altitude)
    return out


@contract(Output("elevation_angle", "rad", "elevation angle"), form=_FORM)
def elevation_angle(slant_range, sensor_altitude, target_altitude=0.0, *, form="stable"):
    r"""Look-down angle of the line of sight below the sensor's horizontal.

    :math:`\pi/2` minus the nadir angle: the GIQE "elevation angle" in pyBSM's
    convention. Measured at the sensor, it equals the sensor's elevation seen
    from the target only over a flat Earth (at the horizon it is the central
    angle, not 0).

    Parameters
    ----------
    slant_range : float or xr.DataArray
        Distance between target and sensor. [m]
    sensor_altitude : float or xr.DataArray
        Sensor height above the surface. [m]
    target_altitude : float or xr.DataArray
        Target height above the surface. [m]
    form : {"stable", "law-of-cosines"}
        See :data:`FORMS`.

    Returns
    -------
    float or xr.DataArray
        Elevation angle; 0 at zero slant range between equal heights (the limit),
        NaN for a slant range shorter than the height difference
        (:func:`nadir_angle`). [rad]
    """
    return np.pi / 2 - nadir_angle(slant_range, sensor_altitude, target_altitude, form=form)


@contract(Output("altitude", "m", "altitude along the line of sight"), form=_FORM)
def altitude_along_path(distance_from_target, slant_range, sensor_altitude, target_altitude=0.0,
                        *, form="stable"):
    r"""Height above the spherical Earth at a point on the line of sight.

    Parameters
    ----------
    distance_from_target : float or xr.DataArray
        Distance along the line of sight measured from the target, 0 to
        ``slant_range``. [m]
    slant_range : float or xr.DataArray
        Distance between target and sensor. [m]
    sensor_altitude : float or xr.DataArray
        Sensor height above the surface. [m]
    target_altitude : float or xr.DataArray
        Target height above the surface. [m]
    form : {"stable", "law-of-cosines"}
        Of the nadir angle; see :data:`FORMS`.

    Returns
    -------
    float or xr.DataArray
        Height above the surface at that point. [m]

    Notes
    -----
    With :math:`b` the distance from the sensor and :math:`\phi` the nadir
    angle, the distance of the point from the Earth centre is
    :math:`\sqrt{a^2 + b^2 - 2ab\cos\phi}`.

    At zero slant range between equal heights the path is one point and the
    result is that height, the limit as the path shrinks (pyBSM divides by zero
    in its nadir angle). A slant range shorter than the height difference is
    NaN (:func:`nadir_angle`).
    """
    out = apply_kernel(altitude_along_path_kernel, sensor_altitude, slant_range,
                       distance_from_target, target_altitude, form=form)
    return out


@contract(Output("ifov", "rad", "instantaneous field of view"))
def ifov(pixel_pitch, focal_length):
    """Instantaneous field of view of one detector pitch.

    Parameters
    ----------
    pixel_pitch : float or xr.DataArray
        Detector centre-to-centre spacing. [m]
    focal_length : float or xr.DataArray
        Effective focal length. [m]

    Returns
    -------
    float or xr.DataArray
        Angular sample spacing. [rad]
    """
    return apply_kernel(_ratio_kernel, pixel_pitch, focal_length)


@contract(Output("gsd", "m", "ground sample distance"))
def ground_sample_distance(ifov, slant_range):
    """Ground sample distance in the plane normal to the line of sight (IBSM Eq. 3-62).

    Parameters
    ----------
    ifov : float or xr.DataArray
        Angular sample spacing. [rad]
    slant_range : float or xr.DataArray
        Distance between target and sensor. [m]

    Returns
    -------
    float or xr.DataArray
        Ground sample distance. [m]
    """
    return apply_kernel(_product_kernel, ifov, slant_range)


@contract(Output("elevation_angle", "rad", "elevation angle at the target"),
          form=_FORM)
def target_elevation_angle(slant_range, sensor_altitude, target_altitude=0.0, *, form="stable"):
    r"""Elevation of the sensor above the target's local horizontal.

    Parameters
    ----------
    slant_range : float or xr.DataArray
        Distance between target and sensor. [m]
    sensor_altitude : float or xr.DataArray
        Sensor height above the surface. [m]
    target_altitude : float or xr.DataArray
        Target height above the surface. [m]
    form : {"stable", "law-of-cosines"}
        See :data:`FORMS`.

    Returns
    -------
    float or xr.DataArray
        Elevation angle seen from the target; 0 at the geometric horizon, and at
        zero slant range between equal heights (the limit: the chord becomes the
        horizon); NaN for a slant range shorter than the height difference. [rad]

    Notes
    -----
    The angle that projects the image-plane GSD onto the ground. It is the
    sensor look-down angle (:func:`elevation_angle`) minus the central angle
    between sensor and target. From the legs of the line of sight at the target:

    .. math:: \epsilon = \operatorname{atan2}\big((a - c) - 2a\sin^2(\theta/2),\ a\sin\theta\big)
    """
    out = apply_kernel(_target_elevation_kernel, sensor_altitude, target_altitude, slant_range,
                 form=form)
    return out


@contract(Output("ground_range", "m", "ground range"))
def ground_range_at_elevation(elevation_angle, sensor_altitude):
    r"""Ground range at which a sensor sees a target on the ground at a given elevation.

    The inverse of :func:`slant_range` followed by :func:`target_elevation_angle` in the
    ground range (target on the surface).

    Parameters
    ----------
    elevation_angle : float or xr.DataArray
        Elevation of the sensor above the target's local horizontal, 0 to :math:`\pi/2`.
        [rad]
    sensor_altitude : float or xr.DataArray
        Sensor height above the surface. [m]

    Returns
    -------
    float or xr.DataArray
        Great-circle distance on the ground between target and sensor nadir. [m]

    Notes
    -----
    The slant range solves :math:`(R + h)^2 = R^2 + s^2 + 2 R s \sin e` in the form
    without cancellation,

    .. math:: s = \frac{h (2R + h)}{\sqrt{R^2 \sin^2 e + h (2R + h)} + R \sin e}

    and the central angle is :math:`\operatorname{atan2}(s \cos e,\ R + s \sin e)`.
    """
    return apply_kernel(_ground_range_at_angle, elevation_angle, sensor_altitude)


def _ground_range_at_angle(elevation_angle, sensor_altitude):
    return ground_range_at_elevation_kernel(np.sin(elevation_angle), np.cos(elevation_angle),
                                            sensor_altitude)


@contract(form=_FORM, elevation=Choice(ELEVATIONS))
def viewing_geometry(ground_range, altitude, pixel_pitch_x, pixel_pitch_y, focal_length, *,
                     elevation="target", form="stable") -> xr.Dataset:
    """Slant range, GIQE elevation angle, IFOVs and GSDs of every scenario.

    Parameters
    ----------
    ground_range, altitude : float or xr.DataArray
        Scenario geometry (target on the ground). [m]
    pixel_pitch_x, pixel_pitch_y, focal_length : float or xr.DataArray
        [m]
    elevation : {"target", "look-down"}
        The GIQE elevation angle: :func:`target_elevation_angle` or
        :func:`elevation_angle` (pyBSM's look-down angle at the sensor).
    form : {"stable", "law-of-cosines"}
        See :data:`FORMS`.

    Returns
    -------
    xr.Dataset
        ``slant_range`` [m], ``elevation_angle`` [rad], ``ifov_x``, ``ifov_y`` [rad],
        ``gsd_x``, ``gsd_y`` [m].
    """
    out = apply_orchestrator(viewing_arrays, VIEW_OUTPUTS, altitude, ground_range,
                             pixel_pitch_x, pixel_pitch_y, focal_length, elevation=elevation,
                             form=form)
    return dataset(out)


_SCENE = ("altitude", "ground_range")
VIEW_OUTPUTS = outputs(
    Output("slant_range", "m", "slant range", carries=("scenario",), inputs=_SCENE),
    Output("elevation_angle", "rad", "GIQE elevation angle", carries=("scenario",),
           inputs=_SCENE),
    Output("ifov_x", "rad", "instantaneous field of view along x", carries=("sensor",),
           inputs=("pixel_pitch_x", "focal_length")),
    Output("gsd_x", "m", "ground sample distance along x",
           inputs=("pixel_pitch_x", "focal_length", *_SCENE)),
    Output("ifov_y", "rad", "instantaneous field of view along y", carries=("sensor",),
           inputs=("pixel_pitch_y", "focal_length")),
    Output("gsd_y", "m", "ground sample distance along y",
           inputs=("pixel_pitch_y", "focal_length", *_SCENE)),
)
"""What :func:`viewing_arrays` and :func:`viewing_geometry` return."""


def viewing_arrays(altitude, ground_range, pixel_pitch_x, pixel_pitch_y, focal_length, *,
                   elevation="target", form="stable") -> dict:
    """:data:`VIEW_OUTPUTS` on plain arrays (one eager scenario; no checks)."""
    slant, angle = slant_and_elevation_kernel(altitude, ground_range, form=form,
                                               elevation=elevation)
    out = {"slant_range": slant, "elevation_angle": angle}
    for axis, pitch in (("x", pixel_pitch_x), ("y", pixel_pitch_y)):
        out[f"ifov_{axis}"] = _ratio_kernel(pitch, focal_length)
        out[f"gsd_{axis}"] = _product_kernel(out[f"ifov_{axis}"], slant)
    return out
