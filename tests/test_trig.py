"""The half-angle sine, cosine and sinc against the C library's, through long doubles."""

from __future__ import annotations

import numpy as np
import pytest

from xbsm._trig import sinc, sine, sine_cosine

# the reference: numpy's sine and cosine in 80-bit long double (x86), whose rounding error
# is 2^11 times below float64's; where long double is float64 (other platforms) the check
# is against the library's float64 values, with the library's own error added
# tan is rounded differently by each numpy (SVML's vectorised one on AVX-512, the C
# library's elsewhere): measured 2.2e-16 with numpy 2.4 and 3.6e-16 with numpy 1.24 (the
# CI's floor) against the long double; the bound is 4.5 units of 1e-16, a few ulp of 1
LONG = np.finfo(np.longdouble).eps < np.finfo(float).eps
BOUND = 4.5e-16 if LONG else 6.5e-16


def _values():
    rng = np.random.default_rng(22)
    x = rng.uniform(0.0, 60.0, 1 << 18)  # the phases of the edge tables and sincs
    # and the awkward points: zeros and poles of the half-angle tangent, tiny and negative
    k = np.arange(-40, 41)
    return np.concatenate([x, -x[:1000], k * np.pi, k * np.pi / 2, [0.0, 1e-300, 5e-324,
                                                                    1e-8, -1e-8]])


def test_sine_and_cosine_agree_with_the_library_to_a_few_ulp():
    x = _values()
    s, c = sine_cosine(x)
    ref_s, ref_c = np.sin(x.astype(np.longdouble)), np.cos(x.astype(np.longdouble))
    assert float(np.max(np.abs(s - ref_s))) <= BOUND
    assert float(np.max(np.abs(c - ref_c))) <= BOUND
    assert np.array_equal(sine(x), s) or float(np.max(np.abs(sine(x) - ref_s))) <= BOUND
    # relative where the sine is not tiny (near its zeros both are rounding of x itself)
    big = np.abs(ref_s) > 1e-3
    assert float(np.max(np.abs(s[big] - ref_s[big]) / np.abs(ref_s[big]))) <= 2 * BOUND


def test_sine_keeps_the_sign_and_size_of_tiny_arguments():
    for x in (1e-300, 1e-8, -1e-8):
        assert sine(x) == pytest.approx(x, rel=1e-15)
    # the smallest subnormal's half underflows to 0: its sine is 0, off by 5e-324 absolute
    assert sine(5e-324) == 0.0
    assert sine(0.0) == 0.0


def test_sinc_is_numpys_normalised_sinc():
    x = np.concatenate([_values() / np.pi, [0.0, 1.0, -2.0, 0.5]])
    # absolute: sinc <= 1, and numpy's own (sin(pi x) / (pi x) in float64, itself a few
    # ulp from the true value) is the reference: 3.3e-16 (numpy 2.4), 4.4e-16 (numpy 1.24)
    assert np.max(np.abs(sinc(x) - np.sinc(x))) <= 6.5e-16
    assert sinc(0.0) == 1.0
    assert np.shape(sinc(np.zeros((3, 2)))) == (3, 2)
