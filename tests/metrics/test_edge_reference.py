"""The independent edge-response reference of recipes/evidence/edge_reference.py, and the
error bounds docs/speed_accuracy.md states for unflagged cells (issue 23 item 3).

The reference integrates OTF samples by a dense trapezoid rule with Richardson
extrapolation; nothing of xbsm.quadrature or xbsm.metrics.edge is involved. It is
checked here against closed forms none of us derived numerically:

- a Gaussian PSF of rms sigma: ER(x) = (1 + erf(x ifov / (sigma sqrt 2))) / 2;
- a linear smear of L px convolved with the 1-px detector rect: the PSF is a
  trapezoid whose flat top is 1/L wide enough for the 1-px window, so RER = 1/L exactly;
- the detector rect alone, OTF sinc(ifov f) with its negative lobes kept (the real
  OTF): RER = (2/pi) [Si(2U) - sin^2(U)/U] on [0, F], U = pi ifov F, which tends to 1.
"""

from __future__ import annotations

import importlib.util
import math
from pathlib import Path

import numpy as np
import pytest
from scipy.special import erf, sici

import xbsm
from xbsm.examples import olson_sensor_parameters
from xbsm.flags import flag

ROOT = Path(__file__).resolve().parents[2]
_spec = importlib.util.spec_from_file_location(
    "edge_reference", ROOT / "recipes" / "evidence" / "edge_reference.py")
er = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(er)

IFOV = 1e-5


def _grid(f_ifov, intervals):
    fmax = f_ifov / IFOV
    return np.linspace(0.0, fmax, intervals + 1), fmax


def test_gaussian_edge_is_the_erf():
    sigma = 3.0 * IFOV  # 3 px rms
    f, fmax = _grid(4.0 * IFOV / sigma, 2**12)  # exp(-2 pi^2 16) ~ 1e-137 at fmax
    otf = np.exp(-2.0 * np.pi**2 * sigma**2 * f**2)
    fine, coarse, rich = er.edge_integrals(otf, fmax, IFOV)
    exact = 0.5 * (1.0 + erf(er.POSITIONS * IFOV / (sigma * math.sqrt(2.0))))
    assert np.max(np.abs(rich - exact)) < 1e-12
    rer, eho = er.edge_terms(rich)
    assert rer == pytest.approx(erf(0.5 / (3.0 * math.sqrt(2.0))), abs=1e-12)
    # a Gaussian edge rises monotonically: EHO is ER(1.25 px)
    assert eho == pytest.approx(0.5 * (1.0 + erf(1.25 / (3.0 * math.sqrt(2.0)))), abs=1e-12)


@pytest.mark.parametrize("length", [10.0, 100.0, 1000.0])
def test_linear_smear_rer_is_one_over_length(length):
    # PSF = rect(L px) * rect(1 px); its integrand's Fourier content ends at (L + 2)/2 px,
    # so 2^16 intervals up to 50 / ifov sample it (h ifov (L + 2) / 2 < 1 at both levels).
    # Truncation beyond F: below 1 / (pi^3 L (ifov F)^2) = 1.3e-5 / L.
    f, fmax = _grid(50.0, 2**16)
    otf = np.sinc(length * IFOV * f) * np.sinc(IFOV * f)  # np.sinc(x) = sin(pi x) / (pi x)
    fine, coarse, rich = er.edge_integrals(otf, fmax, IFOV, er.RER_POSITIONS)
    rer = rich[1] - rich[0]
    assert rer == pytest.approx(1.0 / length, rel=2e-3 / length + 1e-6)


def test_rect_detector_alone_real_otf_rer_is_one():
    f, fmax = _grid(1000.0, 2**14)
    otf = np.sinc(IFOV * f)  # negative lobes kept: the real OTF, not |OTF|
    fine, coarse, rich = er.edge_integrals(otf, fmax, IFOV, er.RER_POSITIONS)
    u = np.pi * IFOV * fmax
    truncated = 2.0 / np.pi * (sici(2.0 * u)[0] - np.sin(u) ** 2 / u)
    assert rich[1] - rich[0] == pytest.approx(truncated, abs=1e-10)
    assert abs(rich[1] - rich[0] - 1.0) < 1.0 / (np.pi * u)  # -> 1 as F grows
    # |OTF| folds the lobes up and gives a different (pyBSM's) value, 0.867 (docs/metrics.md)
    fa, ca, ra = er.edge_integrals(np.abs(otf), fmax, IFOV, er.RER_POSITIONS)
    assert ra[1] - ra[0] == pytest.approx(0.867, abs=5e-3)


def test_richardson_beats_both_levels():
    # a Gaussian cut off where it is not negligible (its derivatives at F do not vanish),
    # on a coarse grid: the two levels differ by the h^2 term, and the extrapolation lies
    # closer to a 256x denser trapezoid than the finer level does
    sigma = 1.5 * IFOV
    f, fmax = _grid(0.6, 2**10)
    otf = np.exp(-2.0 * np.pi**2 * sigma**2 * f**2)  # truncated where it is not negligible
    fine, coarse, rich = er.edge_integrals(otf, fmax, IFOV, er.RER_POSITIONS)
    f2, _ = _grid(0.6, 2**18)
    dense = er.edge_integrals(np.exp(-2.0 * np.pi**2 * sigma**2 * f2**2), fmax, IFOV,
                              er.RER_POSITIONS)[2]
    assert abs(rich[1] - rich[0] - (dense[1] - dense[0])) < abs(
        fine[1] - fine[0] - (dense[1] - dense[0]))


# ---- the package against the reference: the bounds docs/speed_accuracy.md states ------

BOUND = {"accurate": 1e-4, "fast": 1e-2}
"""docs/speed_accuracy.md ("What the flags promise"): where ``blur_unresolved`` is not set,
``accurate`` is within 1e-4 NIIRS and ``fast`` within 1e-2 NIIRS of the reference (every
GIQE version); issue 23's goal, asserted here case by case."""
BLUR = flag("blur_unresolved")
AIR = dict(altitude=9000.0, ground_range=10e3, visibility=23.0)
IFOV_OLSON = 8e-6 / 4.0


def _olson(**over):
    p = olson_sensor_parameters("nir")
    p.update(drift_rate_x=0.0, drift_rate_y=0.0)
    p.update(over)
    return p


def _with_drift(sensor, scenario, drift_px):
    """The sensor with a smear of ``drift_px`` (x, y) pixels over the effective integration
    time (after the well-fill limit), as recipes/evidence/preset_error.py sets it."""
    s, sc = xbsm.sensor(**sensor), xbsm.scenario(**scenario)
    t = float(xbsm.niirs(s, sc)["effective_integration_time"])
    ifov = sensor["pixel_pitch_x"] / sensor["focal_length"]
    dx, dy = np.broadcast_to(drift_px, 2)
    return xbsm.sensor(**{**sensor, "drift_rate_x": dx * ifov / t,
                          "drift_rate_y": dy * ifov / t}), sc


TARGETED = {
    "one_axis_drift_10px": (_olson(), AIR, 10.0),
    "one_axis_drift_30px": (_olson(), AIR, 30.0),
    "one_axis_drift_109px": (_olson(), AIR, 109.0),
    "one_axis_drift_1000px": (_olson(), AIR, 1000.0),
    "jitter_4px": (_olson(jitter_x=4 * IFOV_OLSON, jitter_y=4 * IFOV_OLSON), AIR, 0.0),
    "jitter_8px": (_olson(jitter_x=8 * IFOV_OLSON, jitter_y=8 * IFOV_OLSON), AIR, 0.0),
    "turbulence_20km": (dict(aperture_diameter=0.3, focal_length=3.0, pixel_pitch_x=5e-6,
                             wavelength_min=0.4e-6, wavelength_max=0.7e-6,
                             integration_time=0.002, read_noise=10.0, max_well=1e5),
                        dict(altitude=100.0, ground_range=20e3, visibility=23.0,
                             cn2_at_1m=1e-13), 0.0),
    "turbulence_30km": (dict(aperture_diameter=0.3, focal_length=3.0, pixel_pitch_x=5e-6,
                             wavelength_min=0.4e-6, wavelength_max=0.7e-6,
                             integration_time=0.002, read_noise=10.0, max_well=1e5),
                        dict(altitude=1000.0, ground_range=30e3, visibility=23.0,
                             cn2_at_1m=1e-13), 0.0),
    "ground_camera_50m_10km": (dict(aperture_diameter=0.15, focal_length=1.5,
                                pixel_pitch_x=3.45e-6, wavelength_min=0.4e-6,
                                wavelength_max=0.7e-6, integration_time=0.002,
                                read_noise=5.0, max_well=1e4),
                           dict(altitude=50.0, ground_range=10e3, visibility=23.0), 0.0),
    # two random systems of docs/benchmarks/preset_error.json (cases 372 and 99, seed
    # 20261124), where fast's worse slice reads above the flag threshold while the
    # reference's is below it or just above
    "random_372_swir_drift_40px": (
        dict(aperture_diameter=0.8573417444742507, focal_length=0.5502651053873485,
             pixel_pitch_x=1.7929737053002995e-05, wavelength_min=1e-06,
             wavelength_max=1.7e-06, obscuration_ratio=0.47624767493135484,
             integration_time=0.00016417289598539525, read_noise=10.0, max_well=1e5,
             wavefront_variance=0.7124595762118173),
        dict(altitude=5418.906746065363, ground_range=79692.98577616306, visibility=5.0,
             cn2_at_1m=1.1863214313176848e-16), (39.90170975055636, 0.0)),
    "random_99_visible_drift_18px": (
        dict(aperture_diameter=0.7809606876610558, focal_length=0.16085281433485607,
             pixel_pitch_x=3.6714711501595663e-06, wavelength_min=4e-07,
             wavelength_max=7e-07, obscuration_ratio=0.4449093067050437,
             integration_time=0.0001983740739202812, read_noise=10.0, max_well=1e5,
             wavefront_variance=0.1778114202293856),
        dict(altitude=8811.093291534853, ground_range=61152.17251843068, visibility=5.0,
             cn2_at_1m=1.346122437765071e-16), (18.475079107316404, 13.675018424651496)),
}
def _cases():
    # before issue 23's Gauss-Kronrod rule (3b99eb9) three of these failed: accurate on
    # turbulence_30km (2.3e-4 NIIRS on GIQE 5, unflagged), fast on random_372 (2.3: its
    # own RER read above the old 0.05 threshold where the reference's was 0.025) and on
    # random_99 (0.45)
    for name in TARGETED:
        for m in BOUND:
            yield pytest.param(name, m, id=f"{name}-{m}")


@pytest.mark.parametrize(("case", "method"), list(_cases()))
def test_unflagged_cells_within_the_documented_bound(case, method):
    sensor, scenario, drift = TARGETED[case]
    s, sc = _with_drift(sensor, scenario, drift)
    out = xbsm.niirs(s, sc, method=method)
    ref = er.reference_slices(s, sc, method, intervals=2**15)
    expected = er.reference_niirs(ref, out, method)
    assert np.isfinite(expected).all()  # inside the database, SNR > 0: a number to compare
    flagged = (out["flags"].values & BLUR) != 0
    error = np.abs(out["niirs"].values - expected)  # NaN where the method gives NaN
    unflagged_error = np.where(flagged, 0.0, np.where(np.isnan(error), np.inf, error))
    assert np.max(unflagged_error) <= BOUND[method], (
        f"{case}, {method}: |dNIIRS| {error} (GIQE 3, 4, 5), flagged {flagged}, "
        f"rer_x {float(out['rer_x']):.4g} vs {ref['rer_x']:.4g}, "
        f"rer_y {float(out['rer_y']):.4g} vs {ref['rer_y']:.4g}")


def test_chain_one_axis_drift_rer_tends_to_one_over_length():
    # the whole model through xbsm.system_otf: a 300 px smear along x dominates the Olson
    # camera's ~1 px optics blur, so the reference's rer_x is 1/300 to within a few
    # per cent (the aperture's line-spread tails, ~1/x^2, take mass out of the flat top)
    s, sc = _with_drift(_olson(), AIR, 300.0)
    ref = er.reference_slices(s, sc, "accurate", intervals=2**15)
    assert ref["rer_x"] == pytest.approx(1.0 / 300.0, rel=0.03)
    assert ref["level_difference"] < 1e-6


def test_accurate_and_fast_share_a_reference_pybsm_does_not():
    # fast differs from accurate in numerical knobs only; pybsm passes |OTF| and models
    # its own filter OTF, so the recipe gives it a reference of its own
    s, sc = xbsm.sensor(**_olson()), xbsm.scenario(**AIR)
    assert er.same_reference(s, sc, "accurate", "fast")
    assert not er.same_reference(s, sc, "accurate", "pybsm")
    assert not er.same_reference(s, sc, "accurate", xbsm.method("accurate", edge_otf="abs"))
