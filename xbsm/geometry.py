"""Scenario geometry over a spherical Earth (radius 6378.164 km, the paper Sec. 2.6).

Every function is plain xarray/numpy arithmetic and broadcasts over any
scenario dimensions. Heights are above the spherical Earth's surface. [m]
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from .constants import EARTH_RADIUS


def _attrs(out, units, long_name):
    if isinstance(out, xr.DataArray):
        return out.assign_attrs(units=units, long_name=long_name)
    return out


def slant_range(ground_range, sensor_altitude, target_altitude=0.0):
    r"""Slant range between target and sensor over a spherical Earth.

    Parameters
    ----------
    ground_range : float or xr.DataArray
        Great-circle distance on the ground between target and sensor nadir. [m]
    sensor_altitude : float or xr.DataArray
        Sensor height above the surface. [m]
    target_altitude : float or xr.DataArray
        Target height above the surface. [m]

    Returns
    -------
    float or xr.DataArray
        Slant range. [m]

    Notes
    -----
    Law of cosines with the central angle :math:`\theta = g / R_e`:

    .. math:: R = \sqrt{a^2 + c^2 - 2ac\cos\theta},\quad a = R_e + h_s,\ c = R_e + h_t
    """
    a = EARTH_RADIUS + sensor_altitude
    c = EARTH_RADIUS + target_altitude
    theta = ground_range / EARTH_RADIUS
    out = np.sqrt(c**2.0 + a**2.0 - 2.0 * a * c * np.cos(theta))
    return _attrs(out, "m", "slant range")


def nadir_angle(slant_range, sensor_altitude, target_altitude=0.0):
    """Angle at the sensor between nadir and the line of sight to the target.

    Parameters
    ----------
    slant_range : float or xr.DataArray
        Distance between target and sensor. [m]
    sensor_altitude : float or xr.DataArray
        Sensor height above the surface. [m]
    target_altitude : float or xr.DataArray
        Target height above the surface. [m]

    Returns
    -------
    float or xr.DataArray
        Nadir angle, 0 when looking straight down. [rad]

    Notes
    -----
    Law of cosines in the triangle (Earth centre, sensor, target). The cosine is
    clipped to [-1, 1] so that rounding at nadir cannot produce NaN.
    """
    a = EARTH_RADIUS + sensor_altitude
    c = EARTH_RADIUS + target_altitude
    cosine = -(c**2.0 - a**2.0 - slant_range**2.0) / (2.0 * a * slant_range)
    out = np.arccos(np.minimum(np.maximum(cosine, -1.0), 1.0))
    return _attrs(out, "rad", "nadir angle")


def elevation_angle(slant_range, sensor_altitude, target_altitude=0.0):
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

    Returns
    -------
    float or xr.DataArray
        Elevation angle. [rad]
    """
    out = np.pi / 2 - nadir_angle(slant_range, sensor_altitude, target_altitude)
    return _attrs(out, "rad", "elevation angle")


def altitude_along_path(distance_from_target, slant_range, sensor_altitude, target_altitude=0.0):
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

    Returns
    -------
    float or xr.DataArray
        Height above the surface at that point. [m]

    Notes
    -----
    With :math:`b` the distance from the sensor and :math:`\phi` the nadir
    angle, the distance of the point from the Earth centre is
    :math:`\sqrt{a^2 + b^2 - 2ab\cos\phi}`.
    """
    a = EARTH_RADIUS + sensor_altitude
    phi = nadir_angle(slant_range, sensor_altitude, target_altitude)
    b = slant_range - distance_from_target
    out = np.sqrt(a**2 + b**2 - 2.0 * a * b * np.cos(phi)) - EARTH_RADIUS
    return _attrs(out, "m", "altitude along the line of sight")


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
    return _attrs(pixel_pitch / focal_length, "rad", "instantaneous field of view")


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
    return _attrs(ifov * slant_range, "m", "ground sample distance")


def target_elevation_angle(slant_range, sensor_altitude, target_altitude=0.0):
    """Elevation of the sensor above the target's local horizontal.

    Parameters
    ----------
    slant_range : float or xr.DataArray
        Distance between target and sensor. [m]
    sensor_altitude : float or xr.DataArray
        Sensor height above the surface. [m]
    target_altitude : float or xr.DataArray
        Target height above the surface. [m]

    Returns
    -------
    float or xr.DataArray
        Elevation angle seen from the target; 0 at the geometric horizon. [rad]

    Notes
    -----
    The angle that projects the image-plane GSD onto the ground. It is the
    sensor look-down angle (:func:`elevation_angle`) minus the central angle
    between sensor and target.
    """
    a = EARTH_RADIUS + sensor_altitude
    c = EARTH_RADIUS + target_altitude
    cosine = (a**2.0 - c**2.0 - slant_range**2.0) / (2.0 * c * slant_range)
    out = np.arcsin(np.minimum(np.maximum(cosine, -1.0), 1.0))
    return _attrs(out, "rad", "elevation angle at the target")
