"""The optical-depth cubic of ``"optical-depth-cubic"`` and ``"extinction-profile"``.

Numpy kernels: a monotone cubic Hermite (PCHIP slopes, scipy's formulas) through four
tables in the line-of-sight rules' optical-path coordinate. Names without an underscore
are used by the package's other modules.
"""

from __future__ import annotations

import numpy as np


def pchip_interior_slope(h_left, h_right, s_left, s_right):
    """PCHIP derivative at a node between two intervals (numpy kernel).

    The Fritsch-Butland weighted harmonic mean of the secants (scipy's); 0 at a local
    extremum.
    """
    w1, w2 = 2.0 * h_right + h_left, h_right + 2.0 * h_left
    d = (w1 + w2) / (w1 / s_left + w2 / s_right)
    return np.where(s_left * s_right > 0.0, d, 0.0)  # same sign, neither zero


def pchip_end_slope(h_near, h_far, s_near, s_far):
    """PCHIP derivative at the end node of two intervals (numpy kernel).

    scipy's shape-preserving three-point formula.
    """
    d = ((2.0 * h_near + h_far) * s_near - h_near * s_far) / (h_near + h_far)
    d = np.where(d * s_near > 0.0, d, 0.0)  # against the secant's sign, or zero: 0
    # where the far secant changes sign (or is 0), at most 3 times the near one
    overshoot = (s_near * s_far <= 0.0) & (np.abs(d) > 3.0 * np.abs(s_near))
    return np.where(overshoot, 3.0 * s_near, d)


def cubic_increment(y, x, t, left, right):
    """Monotone cubic Hermite increment over ``y[1]`` at weight ``t`` of [x1, x2] (numpy).

    ``y`` and ``x`` are the four nodes (below, lower bracket, upper bracket, above);
    PCHIP slopes from the outer nodes where ``left`` / ``right``, one-sided where only
    one of them is, the secant without either. All arguments broadcast together.
    """
    h0, h1, h2 = x[1] - x[0], x[2] - x[1], x[3] - x[2]
    rise = y[2] - y[1]
    s0, s1, s2 = (y[1] - y[0]) / h0, rise / h1, (y[3] - y[2]) / h2
    if left.all() and right.all():  # every outer node usable (the common case): the
        # interior slopes, without the one-sided ones that would be selected away
        d1, d2 = pchip_interior_slope(h0, h1, s0, s1), pchip_interior_slope(h1, h2, s1, s2)
    else:
        d1 = np.where(left, pchip_interior_slope(h0, h1, s0, s1),
                      np.where(right, pchip_end_slope(h1, h2, s1, s2), s1))
        d2 = np.where(right, pchip_interior_slope(h1, h2, s1, s2),
                      np.where(left, pchip_end_slope(h1, h0, s1, s0), s1))
    t2, t3 = t * t, t * t * t
    return (t3 - 2.0 * t2 + t) * h1 * d1 + (-2.0 * t3 + 3.0 * t2) * rise + (t3 - t2) * h1 * d2


#: Which of the components along the path (``_sight.ALONG_PATH``: TRANS, SURF_EMIS,
#: GRND_RFLT) is TRANS, on (component, wavelength) axes.
_TRANS_FIRST = np.array([True, False, False])[:, None]
_TRANS_FIRST.flags.writeable = False


@np.errstate(divide="ignore", invalid="ignore", over="ignore")
def optical_depth_cubic(base, low, high, beyond, sight, on_node, scale=None):
    """The cubic rules' values of TRANS, SURF_EMIS, GRND_RFLT (numpy kernel).

    ``base`` is ``"same-elevation"``'s result (scenario, component, wavelength); ``low``
    and ``high`` the bracketing tables' same-elevation spectra, ``beyond`` the
    logarithms of the outer tables' (below, above); ``sight`` the scenarios'
    :class:`~xbsm.atmosphere._sight.Sight` (its ``outer``, ``x`` and ``weight``).

    The logarithm of each value (-ln TRANS is the line of sight's optical depth, 0 at
    the ground) is a monotone cubic Hermite (PCHIP) between the brackets with slopes
    from the outer nodes: one-sided where an outer node is missing, unusable or has a
    zero value (TRANS at the database floor), the secant without either. For TRANS the
    ground is the lower outer node below the lowest table; SURF_EMIS and GRND_RFLT have
    no ground node. ``scale`` (scenario, wavelength), if given, multiplies the increment
    (``"extinction-profile"``). Returns ``low * exp(increment)``; on an altitude node,
    and where the result is not finite and positive (a zero bracketing value), ``base``.
    """
    usable = sight.outer
    ground = usable[:, 2, None, None]
    y0 = np.where(ground & _TRANS_FIRST, 0.0, beyond[0])
    left = np.where(_TRANS_FIRST, usable[:, 0, None, None] | ground,
                    usable[:, 0, None, None]) & np.isfinite(y0)
    right = usable[:, 1, None, None] & np.isfinite(beyond[1])
    step = cubic_increment((y0, np.log(low), np.log(high), beyond[1]),
                           [sight.x[:, k, None, None] for k in range(4)],
                           sight.weight[:, None, None], left, right)
    if scale is not None:
        step *= scale[:, None, :]
    value = low * np.exp(step)
    good = ~on_node[:, None, None] & np.isfinite(value) & (value > 0.0)
    return np.where(good, value, base)
