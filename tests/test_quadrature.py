"""Tests for xbsm.quadrature: the frequency rules behind the edge response."""

from __future__ import annotations

import pathlib

import numpy as np
import pytest
import xarray as xr
from scipy.integrate import trapezoid

import xbsm
from xbsm import metrics, quadrature


def knobs(preset, **overrides):
    """The edge-quadrature knobs of a method preset (the one source of their values)."""
    return xbsm.method(preset, **overrides).edge_quadrature_knobs()

FIXTURES = pathlib.Path(__file__).parent / "fixtures"
IFOV = 1e-5  # [rad]; every test below scales with cutoff * ifov only


# ---------------------------------------------------------------- test OTFs


def annular_otf(nu, eps):
    """Diffraction OTF of an annular pupil at normalised frequency nu = f lambda / D."""
    nu = np.clip(np.asarray(nu, dtype=float), 0.0, None)

    def a(x):
        x = np.clip(x, 0.0, 1.0)
        return (2 / np.pi) * (np.arccos(x) - x * np.sqrt(1 - x**2))

    out = a(nu)
    if eps > 0:
        b = eps**2 * np.where(nu <= eps, a(nu / eps), 0.0)
        lo, hi = (1 - eps) / 2, (1 + eps) / 2
        phi = np.arccos(np.clip((1 + eps**2 - 4 * nu**2) / (2 * eps), -1, 1))
        mid = (
            -2 * eps**2
            + (2 * eps / np.pi) * np.sin(phi)
            + ((1 + eps**2) / np.pi) * phi
            - (2 * (1 - eps**2) / np.pi) * np.arctan((1 + eps) / (1 - eps) * np.tan(phi / 2))
        )
        c = np.where(nu <= lo, -2 * eps**2, np.where(nu < hi, mid, 0.0))
        out = (out + b + c) / (1 - eps**2)
    return np.where(nu >= 1, 0.0, out)


def system_case(q, eps=0.0, jitter=0.0, drift=0.0, poly=False, part="real"):
    """Aperture x detector x jitter x drift; q = lambda/(D ifov); jitter, drift in px."""
    lam0 = 0.6e-6
    diameter = lam0 / (q * IFOV)
    wls = np.linspace(0.5e-6, 0.66e-6, 17) if poly else np.array([lam0])
    cutoff = diameter / wls.min()

    def otf(f):
        ap = np.mean([annular_otf(f * w / diameter, eps) for w in wls], axis=0)
        h = ap * np.sinc(f * IFOV) * np.exp(-2 * np.pi**2 * (jitter * IFOV * f) ** 2)
        h = h * np.sinc(drift * IFOV * f)
        return np.abs(h) if part == "abs" else h

    bps = [quadrature.aperture_breakpoints(diameter, wls, eps)]
    bps.append(quadrature.detector_breakpoints(IFOV, cutoff))
    if drift > 0:
        bps.append(quadrature.detector_breakpoints(drift * IFOV, cutoff))
    return otf, cutoff, np.concatenate(bps)


def run_rule(rule, otf, cutoff, bps, positions):
    nodes, w = quadrature.edge_quadrature(cutoff=cutoff, ifov=IFOV, breakpoints=bps, **rule)
    h = xr.DataArray(otf(nodes.values), dims="frequency", coords={"frequency": nodes.values})
    return metrics.edge_response(h, IFOV, positions, w).values


CASES = [
    dict(q=q, eps=eps, jitter=jit, drift=dr, poly=poly, part=part)
    for q in (0.05, 0.25, 1.0, 2.0)
    for eps in (0.0, 0.4)
    for jit in (0.0, 0.25)
    for dr in (0.0, 1.0)
    for poly in (False, True)
    for part in ("real", "abs")
]
POSITIONS = np.concatenate([[-0.5, 0.5], metrics.EHO_POSITIONS])
REFERENCE = knobs("accurate", name="reference", panels_per_oscillation=16)


def max_errors(rule, with_breakpoints=True):
    """Largest |ER error| over POSITIONS and the case family, vs a 16x finer rule."""
    worst = 0.0
    for case in CASES:
        otf, cutoff, bps = system_case(**case)
        ref = run_rule(REFERENCE, otf, cutoff, bps, POSITIONS)
        got = run_rule(rule, otf, cutoff, bps if with_breakpoints else None, POSITIONS)
        worst = max(worst, float(np.max(np.abs(got - ref))))
    return worst


# ---------------------------------------------------------------- pybsm rule


def test_pybsm_slice_count_matches_pybsm_grids():
    # pyBSM 0.16.1 slice_otf on 101- and 1601-point grids (fixture from the recipe):
    # 50 and 801 samples -- not N // 2 = 800 for 1601.
    ref = np.load(FIXTURES / "pybsm_metrics.npz")
    for n, count in zip(ref["slice_grid_sizes"], ref["slice_counts"], strict=True):
        assert quadrature.pybsm_slice_count(int(n)) == count
    assert quadrature.pybsm_slice_count(101) == 50
    assert quadrature.pybsm_slice_count(1601) == 801


def test_uniform_trapezoid_weights_equal_numpy_trapezoid():
    nodes, w = quadrature.uniform_trapezoid_rule(37, 123.4, offset=1e-6)
    y = np.cos(nodes.values / 1000.0)
    x = w["sine_frequency"].values
    np.testing.assert_allclose(float((w * y).sum()), trapezoid(y, x), rtol=1e-14)
    np.testing.assert_array_equal(x, nodes.values + 1e-6)  # exact: the same one addition


def test_pybsm_preset_uses_pybsm_grid_step():
    cutoff = 550000.0000000001  # pyBSM case A1's D / lambda_min
    nodes, w = quadrature.edge_quadrature(cutoff=cutoff, ifov=2e-6, **knobs("pybsm"))
    assert nodes.sizes["frequency"] == 50
    # df printed by pyBSM for case A1: 11000.0
    assert nodes.values[1] - nodes.values[0] == pytest.approx(11000.0, rel=1e-14)
    assert w.attrs["quadrature_preset"] == "pybsm"
    nodes_big, _ = quadrature.edge_quadrature(
        cutoff=cutoff, ifov=2e-6, **knobs("pybsm", frequency_samples=1601))
    assert nodes_big.sizes["frequency"] == 801


# ---------------------------------------------------------------- Gauss-Legendre


def test_gauss_legendre_is_exact_for_polynomials_and_avoids_zero():
    nodes, w = quadrature.gauss_legendre_rule([0.0, 0.3, 1.0], 5)
    f = nodes.values
    assert f.min() > 0.01  # the lowest 5-point node of [0, 0.3] is 0.0141: far from rounding
    for k in range(10):  # degree 2n-1 = 9
        assert float((w * f**k).sum()) == pytest.approx(1.0 / (k + 1), rel=1e-13)


def test_panel_count_follows_oscillation_count():
    # Q = 0.05: cutoff * ifov = 20, x_max = 3 px -> 60 oscillations -> 60 panels
    gl = knobs("accurate", edge_rule="gauss_legendre", nodes_per_panel=10)
    nodes, _ = quadrature.edge_quadrature(cutoff=20 / IFOV, ifov=IFOV, **gl)
    assert nodes.sizes["frequency"] == 60 * 10
    # well sampled: min_panels wins
    nodes, _ = quadrature.edge_quadrature(cutoff=0.5 / IFOV, ifov=IFOV, **gl)
    assert nodes.sizes["frequency"] == xbsm.method("accurate").min_panels * 10


def test_kronrod_panels_are_uniform_then_graded_then_one_per_drift_lobe():
    m = xbsm.method("accurate")
    per_panel = 2 * m.nodes_per_panel + 1  # Kronrod
    # Q = 0.05: 60 uniform panels of 1/3 cycle/px; the first split by 4 down to the
    # graded frequency: ceil(log(1/3 / g) / log 4) more panels
    steps = int(np.ceil(np.log(1 / 3 / m.graded_frequency) / np.log(m.grading_ratio)))
    nodes, w = quadrature.edge_quadrature(cutoff=20 / IFOV, ifov=IFOV, **knobs("accurate"))
    assert nodes.sizes["frequency"] == (60 + steps) * per_panel
    assert float(w.sum()) == pytest.approx(20 / IFOV, rel=1e-14)
    assert nodes.values.min() < m.graded_frequency / IFOV / m.grading_ratio
    # a drift of 500 px over the exposure: one panel per sinc lobe, 500 * 0.5 = 250 lobes
    # below a cutoff of 0.5 cycle/px; the first panel, 2e-3 cycle/px, is graded no further
    # with graded_frequency=2e-3
    drift = 500 * IFOV
    nodes, w = quadrature.edge_quadrature(cutoff=0.5 / IFOV, ifov=IFOV, lobe_width=drift,
                                          **knobs("accurate", graded_frequency=2e-3))
    assert nodes.sizes["frequency"] == 250 * per_panel
    # the rule integrates the sinc's own closed form: int_0^c sinc(a f) df = Si(pi a c)/(pi a)
    from scipy.special import sici
    exact = sici(np.pi * drift * 0.5 / IFOV)[0] / (np.pi * drift)
    assert float((w * np.sinc(drift * nodes)).sum()) == pytest.approx(exact, rel=1e-12)


def test_kronrod_nodes_match_quadpack_and_integrate_to_their_degree():
    # QUADPACK qk15 (Piessens et al. 1983): the largest Kronrod node and its weight, to a
    # few ulps (numpy 1.24, the floor, rounds the weight 1.05e-15 away from numpy 2's)
    t, vk, vg = quadrature.kronrod_nodes(7)
    assert t[-1] == pytest.approx(0.991455371120812639206854697526329, abs=4e-15)
    assert vk[-1] == pytest.approx(0.022935322010529224963732008058970, abs=4e-15)
    assert vg[7] == pytest.approx(0.417959183673469387755102040816327, abs=4e-15)  # G7 centre
    for n in (3, 4, 7):
        t, vk, vg = quadrature.kronrod_nodes(n)
        for k in range(3 * n + 2):
            exact = 2.0 / (k + 1) if k % 2 == 0 else 0.0
            assert float((vk * t**k).sum()) == pytest.approx(exact, abs=1e-14)
        for k in range(2 * n):
            exact = 2.0 / (k + 1) if k % 2 == 0 else 0.0
            assert float((vg * t**k).sum()) == pytest.approx(exact, abs=1e-14)


def test_breakpoints_become_panel_edges():
    bps = [0.123, 0.777, 5.0]  # the last is beyond the cutoff and ignored
    nodes, w = quadrature.edge_quadrature(
        cutoff=1.0, ifov=0.1, breakpoints=bps,
        **knobs("accurate", edge_rule="gauss_legendre", min_panels=2, nodes_per_panel=3))
    # panels [0,.123], [.123,.5], [.5,.777], [.777,1]
    assert nodes.sizes["frequency"] == 12
    assert float(w.sum()) == pytest.approx(1.0, rel=1e-14)


def test_knobs_override_one_by_one():
    gl = dict(edge_rule="gauss_legendre")
    a, _ = quadrature.edge_quadrature(cutoff=1.0, ifov=1.0,
                                      **knobs("fast", nodes_per_panel=3, **gl))
    assert a.sizes["frequency"] == xbsm.method("fast").min_panels * 3
    b, _ = quadrature.edge_quadrature(
        cutoff=1.0, ifov=0.1, **knobs("accurate", min_panels=2, nodes_per_panel=2, **gl))
    assert b.sizes["frequency"] == 4


@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(cutoff=0.0, ifov=1.0), "cutoff"),
        (dict(cutoff=1.0, ifov=-1.0), "ifov"),
        (dict(cutoff=1.0, ifov=1.0, rule="simpson"), "rule must be one of"),
    ],
)
def test_bad_arguments_raise_value_error_naming_the_parameter(kwargs, match):
    with pytest.raises(ValueError, match=match):
        quadrature.edge_quadrature(**{**knobs("accurate"), **kwargs})


def test_bad_knob_values_are_refused_when_the_method_is_made():
    # one source of knobs: a bad quadrature knob fails in xbsm.method, naming the knob
    with pytest.raises(ValueError, match=r"nodes_per_panel must be a whole number in \[1, "):
        xbsm.method("accurate", nodes_per_panel=0)
    with pytest.raises(ValueError, match="edge_rule must be one of"):
        xbsm.method("accurate", edge_rule="simpson")


def test_aperture_breakpoints_of_obscured_pupil():
    bp = quadrature.aperture_breakpoints(0.2, [0.5e-6], 0.4)
    np.testing.assert_allclose(bp, 0.2 / 0.5e-6 * np.array([0.3, 0.4, 0.7, 1.0]))


# ---------------------------------------------------------------- convergence


def test_accurate_rule_converged_vs_16x_finer_rule():
    # Measured 4.5e-9 (docs/metrics.md) over 256 aperture/detector/jitter/drift cases,
    # Q = 0.05 .. 2, with breakpoints; 1.6e-5 without them.
    assert max_errors(knobs("accurate")) < 1e-8


def test_fast_rule_error_bound():
    # Documented bound for "fast": |ER error| < 1e-6 with breakpoints (measured 3.5e-7),
    # < 1e-4 without (measured 3.5e-5), at the RER and EHO positions.
    assert max_errors(knobs("fast")) < 1e-6
    assert max_errors(knobs("fast"), with_breakpoints=False) < 1e-4


def test_accurate_without_breakpoints_still_within_1e_4():
    assert max_errors(knobs("accurate"), with_breakpoints=False) < 1e-4
