"""An edge-response reference independent of ``xbsm.quadrature``, shared by the tests.

RER of the x and y slices of the system OTF (``xbsm.system_otf``, the method's own
modelling) by the trapezoid rule on ``samples`` and ``samples / 2`` uniform steps over
[0, D / lambda_min], Richardson-extrapolated:
RER = (2 / pi) int_0^fc H(f) sin(pi f ifov) / f df (IBSM Eq. 3-61, 3-63).
"""

from __future__ import annotations

import numpy as np
from scipy.integrate import trapezoid  # numpy.trapezoid needs numpy 2

import xbsm


def dense_rer(sensor, scenario, method, samples=2**16):
    """Reference RER (x, y) of ``sensor`` and ``scenario`` under ``method``'s modelling."""
    cutoff = float(xbsm.niirs(sensor, scenario, method=method).cutoff_frequency)
    f = np.linspace(0.0, cutoff, samples + 1)
    otf = xbsm.system_otf(sensor, scenario, frequency=f, method=method)
    h = otf.system_unfiltered.transpose("orientation", "frequency").values.real
    ifov = np.array([float(sensor.pixel_pitch_x / sensor.focal_length),
                     float(sensor.pixel_pitch_y / sensor.focal_length)])[:, None]
    kernel = np.full((2, f.size), np.pi * ifov)  # sin(pi f ifov) / f -> pi ifov at f = 0
    kernel[:, 1:] = np.sin(np.pi * f[1:] * ifov) / f[1:]
    fine, coarse = (trapezoid(h[:, ::k] * kernel[:, ::k], f[::k], axis=-1) * 2 / np.pi
                    for k in (1, 2))
    return fine + (fine - coarse) / 3
