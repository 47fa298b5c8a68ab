"""The numpy kernels under the OTF functions: plain arrays in, plain arrays out."""

from __future__ import annotations

import numpy as np
import pytest

from xbsm.otf import aperture, turbulence
from xbsm.otf.system import _product_kernel


def test_aperture_kernel_takes_plain_arrays_and_matches_the_unobscured_closed_form():
    nu = np.linspace(0.0, 1.2, 13)
    out = aperture.circular_aperture_kernel(nu * 0.1 / 0.5e-6, 0.1, 0.5e-6, 0.0)
    # closed form, IBSM Eq. 3-20 with eta = 0: (2/pi)(acos nu - nu sqrt(1 - nu^2)), 0 beyond 1
    c = np.minimum(nu, 1.0)
    expected = (2 / np.pi) * (np.arccos(c) - c * np.sqrt(1 - c**2))
    assert isinstance(out, np.ndarray)
    np.testing.assert_allclose(out, expected, rtol=1e-14, atol=1e-15)


def test_polychromatic_kernel_of_one_wavelength_is_the_wind_blended_closed_form():
    radial = np.linspace(0.0, 4e5, 9)
    lam, r0_ref, t, v, d = 0.6e-6, 0.05, 0.01, 100.0, 0.275
    out = turbulence.polychromatic_kernel(radial, r0_ref, t, v, d, 1e-6,
                                           np.array([lam]), np.array([3.0]))
    # closed form, IBSM Eqs. 3-3 and 3-9 with r0 scaled as lambda^(6/5) from 1 um
    r0 = r0_ref * (lam / 1e-6) ** 1.2
    w = np.exp(-v * t / r0)
    long = np.exp(-3.44 * (lam * radial / r0) ** (5 / 3))
    tilt = 1 - 0.5 * (lam * radial / d) ** (1 / 3)
    short = np.exp(-3.44 * (lam * radial / r0) ** (5 / 3) * tilt)
    # atol: the OTF is <= 1; its tail falls to 1e-26 at the highest frequency
    np.testing.assert_allclose(out, w * short + (1 - w) * long, rtol=1e-14, atol=1e-16)


@pytest.mark.parametrize(("block", "step"), [(1, None), (7, None), (64, None),
                                           (1 << 16, None), (1 << 16, 1), (1 << 16, 4)])
def test_polychromatic_kernel_does_not_depend_on_its_blocks(monkeypatch, block, step):
    # reference: the weighted sum written out one wavelength at a time, in band order
    rng = np.random.default_rng(3)
    radial = rng.uniform(0.0, 4e5, (5, 1))
    r0_ref, weights = rng.uniform(0.02, 0.2, 11), rng.uniform(0.0, 1.0, (11, 6))
    wl = np.linspace(0.5e-6, 0.9e-6, 6)
    t, v, d = 0.01, 100.0, 0.275
    norm = weights / weights.sum(axis=-1, keepdims=True)
    expected = np.zeros((5, 11))
    for i, lam in enumerate(wl):
        expected += norm[:, i] * turbulence._wind_blended_kernel(
            radial, lam, d, turbulence._scale_kernel(r0_ref, lam, 1e-6), t, v)
    monkeypatch.setattr(turbulence, "_BLOCK", block)
    if step is not None:  # wavelengths a step over the one block of 55 values: 4 + 2 for 4
        monkeypatch.setattr(turbulence, "_STEP", 55 * step)
    out = turbulence.polychromatic_kernel(radial, r0_ref, t, v, d, 1e-6, wl, weights)
    # a few ulp: numpy's vector and scalar loops of pow and exp may round differently
    # (1.5e-15 seen with numpy 1.24), and the kernel takes the frequency's powers apart from
    # the wavelength's, a few ulp in the exponent, which exp multiplies by |exponent|
    # (1.1e-14 relative where the OTF is 5e-22): atol for that tail, as in the test above
    np.testing.assert_allclose(out, expected, rtol=1e-14, atol=1e-16)


def test_polychromatic_kernel_of_scalars_is_a_scalar():
    # one frequency, one scenario: the two-wavelength sum written out
    wl, w = np.array([0.5e-6, 0.6e-6]), np.array([1.0, 2.0])
    out = turbulence.polychromatic_kernel(np.float64(1e5), 0.05, 0.01, 100.0, 0.1, 1e-6, wl, w)
    expected = sum(w[i] / 3.0 * turbulence._wind_blended_kernel(
        1e5, lam, 0.1, turbulence._scale_kernel(0.05, lam, 1e-6), 0.01, 100.0)
        for i, lam in enumerate(wl))
    assert np.shape(out) == ()
    np.testing.assert_allclose(out, expected, rtol=1e-14)  # a few ulp, as above


def test_product_kernel_broadcasts_plain_arrays():
    a, b = np.array([[1.0], [2.0]]), np.array([3.0, 4.0])
    # closed form: the outer product
    np.testing.assert_array_equal(_product_kernel(a, b), [[3.0, 4.0], [6.0, 8.0]])
