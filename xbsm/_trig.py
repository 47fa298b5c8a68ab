r"""Sine, cosine and sinc of float64 arrays from the tangent of the half angle (private).

numpy's float64 ``sin`` and ``cos`` run element by element through the C library (16 ns a
value on this project's machines, measured beside the other functions in
``recipes/bench/bench_sweeps.py``), while its ``tan`` is vectorised (about 1.4 ns). With
``t = tan(x / 2)``:

.. math:: \sin x = \frac{2t}{1 + t^2},\qquad \cos x = \frac{1 - t^2}{1 + t^2}

exact in exact arithmetic for every finite x (at x = pi + 2 k pi, t is the largest double
near the pole, of order 1e16, and the formulas give the rounded sine and cosine of the
double x as the library does). In floating point they agree with the library's sine and
cosine to a few units in the last place, as numpy's tangent rounds: on 2^18 values in
[0, 60] against the 80-bit long-double sine (``tests/test_trig.py``), 2.2e-16 absolute and
3.2e-16 relative at most with numpy 2.4, 3.6e-16 absolute with numpy 1.24 (whose own
float64 sine is vectorised too). The edge response's sine tables and the detector and
drift sincs, the sines of an optics sweep, use them.
"""

from __future__ import annotations

import numpy as np

__all__ = ["sine", "sine_cosine", "sinc"]


def sine(x):
    """sin(x) of a float array, from tan(x / 2)."""
    t = np.tan(0.5 * np.asarray(x, dtype=float))
    return 2.0 * t / (1.0 + t * t)


def sine_cosine(x):
    """(sin(x), cos(x)) of a float array, from one tan(x / 2)."""
    t = np.tan(0.5 * np.asarray(x, dtype=float))
    t2 = t * t
    return 2.0 * t / (1.0 + t2), (1.0 - t2) / (1.0 + t2)


def sinc(x):
    """sin(pi x) / (pi x), 1 at x = 0 (numpy's normalised ``sinc``), from tan(pi x / 2)."""
    y = np.pi * np.asarray(x, dtype=float)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(y == 0.0, 1.0, sine(y) / y)
