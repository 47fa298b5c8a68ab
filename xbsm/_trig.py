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
    return _scalar_if_0d(_sine_of_half_tangent(t))


def _sine_of_half_tangent(t):
    """2 t / (1 + t^2), written into ``t`` (a new array of ours): one temporary, not four.

    The same operations as the expression, so the same bits; a study chunk's drift sinc
    is 156 MB an array.
    """
    denominator = t * t
    denominator += 1.0
    t *= 2.0
    t /= denominator
    return t


def _scalar_if_0d(a):
    """A 0-d array as numpy's scalar (what the arithmetic expressions returned)."""
    return a[()] if isinstance(a, np.ndarray) and a.ndim == 0 else a


def sine_cosine(x):
    """(sin(x), cos(x)) of a float array, from one tan(x / 2)."""
    t = np.tan(0.5 * np.asarray(x, dtype=float))
    t2 = t * t
    return 2.0 * t / (1.0 + t2), (1.0 - t2) / (1.0 + t2)


#: Values per block of a large sinc: its temporaries stay in cache, and its memory is the
#: argument and the result (a study chunk's drift sinc: 156 MB each, where the whole-array
#: expression held four such arrays at once).
BLOCK = 1 << 15


def sinc(x):
    """sin(pi x) / (pi x), 1 at x = 0 (numpy's normalised ``sinc``), from tan(pi x / 2)."""
    x = np.asarray(x, dtype=float)
    if x.size <= BLOCK:
        return _sinc_block(x)
    # in memory order: the blocks of a product whose axes are permuted (a drift OTF's
    # argument) are views, and the result keeps the argument's layout
    out = np.empty_like(x)
    flat, flat_out = x.ravel(order="K"), out.ravel(order="K")
    if not (np.shares_memory(flat, x) and np.shares_memory(flat_out, out)):
        flat, out = x.reshape(-1), np.empty(x.shape)  # not dense: C order, copied
        flat_out = out.reshape(-1)
    for start in range(0, flat.size, BLOCK):
        flat_out[start:start + BLOCK] = _sinc_block(flat[start:start + BLOCK])
    return out


def _sinc_block(x):
    y = np.pi * x
    out = np.asarray(_sine_of_half_tangent(np.tan(0.5 * y)))
    with np.errstate(invalid="ignore", divide="ignore"):
        out /= y
    out[y == 0.0] = 1.0
    return out
