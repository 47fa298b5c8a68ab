"""The TTP metric's kernels (xbsm.metrics.ttp) against closed forms, quadrature and
published values."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.integrate import quad
from scipy.optimize import brentq
from scipy.special import erf

from xbsm.metrics import eye, ttp

# ---- the probability of a task ------------------------------------------------------------


@settings(max_examples=300, deadline=None)
@given(v=st.floats(0.0, 200.0), v50=st.floats(0.1, 50.0))
def test_task_probability_equals_the_published_form_evaluated_independently(v, v50):
    # P = (V/V50)^E / (1 + (V/V50)^E), E = 1.51 + 0.24 V / V50, literally (the kernel
    # evaluates it as 1 / (1 + exp(-E ln(V/V50))))
    e = 1.51 + 0.24 * v / v50
    try:
        power = (v / v50) ** e
        expected = power / (1.0 + power)
    except OverflowError:
        expected = 1.0
    got = float(ttp.task_probability(v, v50))
    assert got == pytest.approx(expected, abs=1e-12)
    assert 0.0 <= got <= 1.0


def test_task_probability_is_one_half_at_v50_and_rises_with_cycles():
    assert ttp.task_probability(13.0, 13.0) == 0.5
    p = ttp.task_probability(np.linspace(0.0, 100.0, 1001), 7.5)
    assert p[0] == 0.0 and np.all(np.diff(p) > 0) and p[-1] < 1.0
    assert ttp.task_probability(1e300, 1.0) == 1.0  # overflow saturates, never NaN


def test_johnson_probability_uses_e_2_7_plus_0_7_n_over_n50():
    # N = 2 N50: E = 4.1, P = 2^4.1 / (1 + 2^4.1) = 0.94489
    assert ttp.johnson_probability(2.0, 1.0) == pytest.approx(2 ** 4.1 / (1 + 2 ** 4.1))
    assert ttp.johnson_probability(6.4, 6.4) == 0.5


def test_cycles_for_probability_inverts_the_probability_to_1e_9():
    p = np.array([0.1, 0.5, 0.8, 0.9, 0.99])
    for criterion in ("ttp", "johnson"):
        cycles = ttp.cycles_for_probability(p, 7.5, criterion)
        law = ttp.johnson_probability if criterion == "johnson" else ttp.task_probability
        assert law(cycles, 7.5) == pytest.approx(p, abs=1e-9)


def test_johnson_cycles_at_70_and_90_percent_against_the_drs_white_paper_table():
    # J. Love, "The truth about range data", DRS Technologies white paper (Table: cycles
    # across the critical dimension for P = 50 / 70 / 90 %): detection 0.75 / 0.94 / 1.34,
    # recognition 3.0 / 3.75 / 5.37, identification 6.0 / 7.5 / 10.7. The classic TTPF
    # (E = 2.7 + 0.7 N / N50) gives 0.95 / 1.31, 3.80 / 5.25, 7.60 / 10.50: within 1.4 %
    # at 70 % and 2.3 % at 90 % (the paper's figures are rounded multipliers of N50).
    published = {0.75: (0.94, 1.34), 3.0: (3.75, 5.37), 6.0: (7.5, 10.7)}
    for n50, (at70, at90) in published.items():
        ours = ttp.cycles_for_probability([0.7, 0.9], n50, "johnson")
        assert ours[0] == pytest.approx(at70, rel=0.014)
        assert ours[1] == pytest.approx(at90, rel=0.023)


def test_johnson_range_reproduces_the_drs_white_paper_worked_example():
    # same paper: a 1.8 m x 0.5 m person (critical dimension sqrt(0.9) = 0.95 m), 17 um
    # pixels behind a 16.75 mm lens (IFOV 1.01 mrad), recognition at 3 cycles = 6 pixels:
    # 6.3 pixels per metre, range 157 m. Exact arithmetic gives 155.8 m (the paper
    # rounds the IFOV and the pixels per metre): within 1 %.
    r = ttp.johnson_range(math.sqrt(1.8 * 0.5), 3.0, 17e-6 / 16.75e-3)
    assert r == pytest.approx(157.0, rel=0.01)


# ---- the TTP integral -----------------------------------------------------------------


def _threshold(xi, c0=0.01, xi0=2000.0, xi1=300.0):
    """An analytic system CTF: infinite at 0 (like the eye's), growing with frequency."""
    return c0 * (xi1 / xi + np.exp(xi / xi0))


def test_ttp_integral_equals_an_adaptive_quadrature_to_1e_6():
    contrast = 0.2
    lo = brentq(lambda x: _threshold(x) - contrast, 1.0, 2000.0)
    hi = brentq(lambda x: _threshold(x) - contrast, 2000.0, 20000.0)
    reference = quad(lambda x: math.sqrt(contrast / _threshold(x)), lo, hi,
                     epsabs=0, epsrel=1e-13)[0]
    grid = np.linspace(0.0, 12000.0, 20001)[1:]
    ctf = _threshold(grid)[None, :]
    value, limit = ttp.ttp_kernel(grid, ctf, contrast)
    assert value[0] == pytest.approx(reference, rel=1e-6)
    assert limit[0] == pytest.approx(hi, rel=1e-6)


def test_ttp_integral_is_zero_where_the_target_never_beats_the_threshold():
    grid = np.linspace(0.0, 1e4, 101)[1:]
    value, limit = ttp.ttp_kernel(grid, np.full((1, 100), 0.5), 0.2)
    assert value[0] == 0.0 and limit[0] == 0.0
    value, _ = ttp.ttp_kernel(grid, np.full((1, 100), np.inf), 0.2)
    assert value[0] == 0.0


def test_aliasing_ratio_of_a_gaussian_mtf_against_its_closed_form():
    # H = exp(-(f/s)^2): |H|^2 integrates to s sqrt(pi / 8) erf(sqrt(2) f / s)
    spacing, s = 1e-4, 6000.0
    nyquist = 0.5 / spacing
    grid = np.linspace(0.0, 2.0 * nyquist, 40001)[1:]
    ratio = ttp.aliasing_ratio(grid, np.exp(-(grid / s) ** 2), spacing)
    c = math.sqrt(2.0) / s
    expected = (erf(c * 2 * nyquist) - erf(c * nyquist)) / erf(c * nyquist)
    assert float(ratio) == pytest.approx(expected, rel=1e-6)


def test_noise_bandwidths_equal_an_adaptive_quadrature_to_1e_6():
    spacing, magnification, luminance = 75e-6, 6.67, 34.26
    frequency = np.array([200.0, 1000.0, 5000.0, 12000.0])
    channel, full = ttp.noise_bandwidths(frequency, spacing, magnification, luminance)

    def gain(n):
        return (np.sinc(spacing * n)
                * eye.eye_mtf(n / magnification * math.pi / 180.0, luminance)) ** 2

    assert float(full) == pytest.approx(
        quad(gain, 0, 1 / spacing, epsabs=0, epsrel=1e-13, limit=500)[0], rel=1e-6)
    for f, value in zip(frequency, np.ravel(channel), strict=True):
        reference = quad(lambda n, f=f: eye.visual_channel(n, f) ** 2 * gain(n), 0,
                         1 / spacing, points=[f], epsabs=0, epsrel=1e-13, limit=1000)[0]
        assert value == pytest.approx(reference, rel=1e-6)


# ---- the system CTF ---------------------------------------------------------------------

KNOBS = {"luminance": 34.26, "contrast": 0.2, "eye": "vollmerhausen", "eyes": 2,
         "noise_constant": 169.6, "eye_integration_time": 0.1, "frame_rate": 30.0}


def _block(snr, aliasing=0.0, frequency=None):
    spacing = np.array([75e-6, 75e-6])
    magnification = 5e-4 / spacing
    frequency = np.linspace(0.0, 1 / 75e-6, 97)[1:] if frequency is None else frequency
    mtf = np.stack([np.exp(-(frequency / 8000.0) ** 2)] * 2)
    channel, full = ttp.noise_bandwidths(frequency, spacing, magnification, 34.26)
    ctf = ttp.system_ctf_kernel(frequency, mtf, spacing, magnification, channel, full,
                                snr, 1.5, aliasing, **KNOBS)
    return frequency, mtf, spacing, magnification, channel, full, ctf


def test_system_ctf_without_noise_is_the_eye_ctf_over_the_system_and_display_mtf():
    f, mtf, spacing, magnification, *_, ctf = _block(np.inf)
    eye_ctf = eye.ctf_vollmerhausen(f / magnification[0] * math.pi / 180.0, 34.26, 1.5)
    expected = eye_ctf / (mtf[0] * np.sinc(spacing[0] * f))
    finite = np.isfinite(expected) & (expected > 0)
    assert ctf[0][finite] == pytest.approx(expected[finite], rel=1e-12)
    # the display's sinc is 0 at the sampling frequency (4e-17 in floating point)
    assert ctf[0][-1] > 1e10


def test_system_ctf_noise_factor_against_an_independent_evaluation():
    snr, aliasing = 4.0, 0.3
    f, mtf, spacing, magnification, channel, full, ctf = _block(snr, aliasing)
    _, *_, quiet = _block(np.inf)
    area = spacing[0] * spacing[1]
    density = (0.4 / snr) ** 2 * area / 30.0 + 0.04 * aliasing * area * 0.1
    factor = np.sqrt(1.0 + 169.6 ** 2 * density * channel[0] * full[1])
    finite = np.isfinite(quiet[0])
    assert ctf[0][finite] == pytest.approx(quiet[0][finite] * factor[finite], rel=1e-12)
    assert np.all(ctf[0][finite] > quiet[0][finite])


@settings(max_examples=40, deadline=None)
@given(low=st.floats(0.5, 50.0), factor=st.floats(1.05, 10.0))
def test_ttp_rises_with_snr(low, factor):
    f, mtf, spacing, magnification, channel, full, _ = _block(1.0)
    out = [ttp.targeting_arrays(f, mtf, spacing, magnification, channel, full, snr, 2000.0,
                                2.5, aliasing=True, **KNOBS)[0] for snr in (low, low * factor)]
    assert out[1] > out[0] > 0.0
