"""The edge response where the old uniform panels failed (issue 23), against references
none of the package's quadrature computes: a dense uniform trapezoid with Richardson
extrapolation on the system OTF (``xbsm.system_otf``), and closed forms (a linear smear of
L px has RER = 1/L; a Gaussian blur of sigma px has RER = erf(1 / (2 sqrt(2) sigma))).

The flag ``blur_unresolved`` must be set where a method fails and absent where it is fine.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest
import xarray as xr
from dense_edge import dense_rer  # tests/dense_edge.py, shared
from scipy.special import erf

import xbsm
from xbsm import quadrature
from xbsm.examples import olson_sensor
from xbsm.flags import has_flag
from xbsm.metrics import edge

IFOV = 2e-6  # Olson NIR: 8 um / 4 m [rad]
SCENARIO = dict(altitude=9000.0, ground_range=20e3, visibility=23.0, platform_speed=100.0)


def niirs_quiet(sensor, scenario, method):
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no RuntimeWarning reaches the user
        return xbsm.niirs(sensor, scenario, method=method)


def unresolved(out):
    return bool(has_flag(out.flags, "blur_unresolved").any())


@pytest.mark.parametrize("pixels", [10.0, 109.0, 1000.0])
@pytest.mark.parametrize("method, rel", [("accurate", 1e-7), ("fast", 1e-6)])
def test_one_axis_drift_matches_the_dense_reference_unflagged(pixels, method, rel):
    # Measured (recipes/evidence/edge_rule_comparison.py): accurate within 2e-8 relative,
    # fast within 5e-7 (its reference is its own 24-bin OTF); the old uniform panels
    # were off by up to 30 % at 1000 px (rer_x 0.00125 for 0.00183).
    sensor = olson_sensor("nir", drift_rate_x=pixels * IFOV / 0.03, drift_rate_y=0.0)
    scenario = xbsm.scenario(**SCENARIO)
    out = niirs_quiet(sensor, scenario, method)
    reference = dense_rer(sensor, scenario, method)
    got = np.array([float(out.rer_x), float(out.rer_y)])
    np.testing.assert_allclose(got, reference, rtol=rel)
    assert not unresolved(out)


def test_long_one_axis_drift_gives_the_closed_form_one_over_length():
    # a linear smear of L px convolved with a PSF P: in the middle of the ramp the edge
    # response rises at (1/L) x (the mass of P within L/2 of the point), so RER = 1/L up
    # to P's mass beyond L/2 px: the diffraction line spread falls as 1/x^2, its tail mass
    # beyond 300 px is about 1e-3 here. L from the exposure the well-fill limit leaves.
    sensor = olson_sensor("nir", drift_rate_x=1000 * IFOV / 0.03, drift_rate_y=0.0)
    scenario = xbsm.scenario(**SCENARIO)
    out = niirs_quiet(sensor, scenario, "accurate")
    length = 1000 * IFOV / 0.03 * float(out.effective_integration_time) / IFOV
    assert float(out.rer_x) * length == pytest.approx(1.0, abs=2e-3)
    # twice as long a smear halves the tail's share
    longer = olson_sensor("nir", drift_rate_x=2000 * IFOV / 0.03, drift_rate_y=0.0)
    out2 = niirs_quiet(longer, scenario, "accurate")
    deficit = 1 - float(out.rer_x) * length, 1 - float(out2.rer_x) * 2 * length
    assert deficit[1] == pytest.approx(deficit[0] / 2, rel=0.1)


@pytest.mark.parametrize("sigma", [5.0, 20.0, 40.0])
def test_gaussian_blur_to_rer_001_matches_the_erf_edge(sigma):
    # The rule of each preset on a Gaussian OTF alone: ER is the normal CDF.
    # (measured: accurate 9e-11, fast 7e-9; at RER 0.01 a 1e-9 error is 2e-6 NIIRS)
    for name, tol in (("accurate", 1e-9), ("fast", 1e-7)):
        nodes, w = quadrature.edge_quadrature(cutoff=1.0 / IFOV, ifov=IFOV,
                                              **xbsm.method(name).edge_quadrature_knobs())
        otf = np.exp(-2 * np.pi**2 * (sigma * IFOV) ** 2 * nodes.values**2)
        rer, _ = edge._edge_terms_kernel(otf, w.values, w["sine_frequency"].values, IFOV)
        assert float(rer) == pytest.approx(erf(1 / (2 * np.sqrt(2) * sigma)), abs=tol)


@pytest.mark.parametrize("sigma", [5.0, 40.0])
def test_jitter_limited_system_matches_the_dense_reference_unflagged(sigma):
    sensor = olson_sensor("nir", jitter_x=sigma * IFOV, jitter_y=sigma * IFOV)
    scenario = xbsm.scenario(**SCENARIO)
    for method in ("accurate", "fast"):
        out = niirs_quiet(sensor, scenario, method)
        reference = dense_rer(sensor, scenario, method)
        np.testing.assert_allclose([float(out.rer_x), float(out.rer_y)], reference,
                                   rtol=1e-6)
        assert not unresolved(out), method


@pytest.mark.parametrize("method, rel", [("accurate", 1e-6), ("fast", 2e-5)])
def test_strong_defocus_matches_the_dense_reference_unflagged(method, rel):
    # a defocus W020 of 8 waves at the NIR band's centre (0.7 um): the OTF has a lobe about
    # every D / (8 W020) cycles/rad (the blur disk of diameter 8 W020 / D), some 60 below
    # the cutoff, and the rule puts a panel on each. The dense reference needs 2^14 steps
    # (over 200 a lobe; Hopkins' OTF at 2^16 takes a minute). Measured: within 3e-6 NIIRS
    # (accurate) of a 4x finer rule over 1-16 waves; before the lobes had panels, 8 waves
    # was 0.17 NIIRS off (accurate, flagged) and fast 1.9
    sensor = olson_sensor("nir", defocus_opd=8 * 0.7e-6)
    scenario = xbsm.scenario(**SCENARIO)
    out = niirs_quiet(sensor, scenario, method)
    reference = dense_rer(sensor, scenario, method, samples=2**14)
    got = np.array([float(out.rer_x), float(out.rer_y)])
    np.testing.assert_allclose(got, reference, rtol=rel)
    assert not unresolved(out)


def ground_camera(**overrides):
    """The issue's long-range ground camera: D 0.15 m, f 1.5 m, visible."""
    return xbsm.sensor(**{**dict(
        aperture_diameter=0.15, focal_length=1.5, pixel_pitch_x=5e-6, wavelength_min=0.4e-6,
        wavelength_max=0.7e-6, optics_transmission=0.8, quantum_efficiency=0.6,
        integration_time=0.01, read_noise=10.0, max_well=20000.0, bit_depth=12.0),
        **overrides})


def test_turbulence_limited_long_path_is_resolved_and_unflagged():
    # 10 m above the ground, 30 km away, HV 5/7 turbulence: RER about 0.02. Flagged
    # blur_unresolved before issue 23 (a fixed RER threshold of 0.05) with at most
    # 0.2 NIIRS at stake; now within 1e-8 relative of the reference.
    scenario = xbsm.scenario(altitude=10.0, ground_range=30e3, visibility=23.0)
    for method in ("accurate", "fast"):
        out = niirs_quiet(ground_camera(), scenario, method)
        reference = dense_rer(ground_camera(), scenario, method)
        assert reference.max() < 0.05  # the case the test is about
        np.testing.assert_allclose([float(out.rer_x), float(out.rer_y)], reference,
                                   rtol=1e-6)
        assert not unresolved(out), method


def test_the_flag_is_set_where_the_rule_fails():
    scenario = xbsm.scenario(**SCENARIO)
    fine = xbsm.method("accurate", nodes_per_panel=12, min_panels=64, grading_ratio=2.0,
                       graded_frequency=1e-6)
    # jitter of 2000 px (RER 2e-4) is below the graded panels: off by 2.4 NIIRS, flagged
    sensor = olson_sensor("nir", jitter_x=2000 * IFOV, jitter_y=2000 * IFOV)
    for method in ("accurate", "fast"):
        out = niirs_quiet(sensor, scenario, method)
        assert unresolved(out), method
    assert float(abs(niirs_quiet(sensor, scenario, "accurate").niirs
                     - niirs_quiet(sensor, scenario, fine).niirs).max()) > 0.1
    # an OTF the panels do not follow (no grading: a 40 px jitter in one uniform panel)
    sensor = olson_sensor("nir", jitter_x=40 * IFOV, jitter_y=40 * IFOV)
    for method in ("accurate", "fast"):
        m = xbsm.method(method, graded_frequency=0.9)
        assert float(abs(niirs_quiet(sensor, scenario, m).niirs
                         - niirs_quiet(sensor, scenario, fine).niirs).max()) > 0.1
        assert unresolved(niirs_quiet(sensor, scenario, m)), method
    # a drift sinc whose lobes the node limit does not let the rule follow
    sensor = olson_sensor("nir", drift_rate_x=1000 * IFOV / 0.03, drift_rate_y=0.0)
    out = niirs_quiet(sensor, scenario, xbsm.method("accurate", max_frequency_nodes=600))
    assert unresolved(out)
    # ... and absent where the same rule is fine
    assert not unresolved(niirs_quiet(sensor, scenario, "accurate"))


def test_flags_agree_between_single_calls_and_sweeps():
    # the labelled (sweep) and direct (single scenario) appliers set the same bits; the
    # sweep uses the rule of its longest drift for every drift (one rule for the sweep)
    pixels = xr.DataArray([10.0, 109.0, 1000.0], dims="pixels")
    jitter = xr.DataArray([0.25 * IFOV, 2000 * IFOV], dims="blur")
    sensor = olson_sensor("nir", drift_rate_x=pixels * IFOV / 0.03, drift_rate_y=0.0,
                          jitter_x=jitter)
    scenario = xbsm.scenario(**SCENARIO)
    swept = niirs_quiet(sensor, scenario, "fast")
    flagged = has_flag(swept.flags, "blur_unresolved").any("giqe")
    assert flagged.sel(blur=1).all() and not flagged.sel(blur=0).any()
    for i in range(3):
        for j in range(2):
            single = niirs_quiet(sensor.isel(pixels=i, blur=j), scenario, "fast")
            cell = swept.isel(pixels=i, blur=j)
            np.testing.assert_array_equal(single.flags.values, cell.flags.values)
            if j == 0:  # resolved: the two rules agree to fast's accuracy (1e-7 relative)
                np.testing.assert_allclose(single.rer_x, cell.rer_x, rtol=1e-6)


def test_annular_aperture_kinks_are_panel_edges():
    # The one cell of recipes/evidence/preset_error.py the kink-blind panels missed (an
    # annular MWIR system sampled far finer than its optics resolve, Q about 70, four
    # uniform panels): accurate was off by 4.5e-5 relative in RER (1.8e-3 NIIRS, GIQE 5),
    # fast by 1.5e-4. With the aperture OTF's kinks at both band ends as panel edges,
    # measured against the dense trapezoid: accurate 1.3e-7, fast 1.3e-6.
    sensor = xbsm.sensor(aperture_diameter=0.0548, focal_length=9.28, pixel_pitch_x=6.96e-6,
                         wavelength_min=3e-6, wavelength_max=5e-6, obscuration_ratio=0.49,
                         integration_time=1e-3, read_noise=10.0, max_well=1e5,
                         jitter_x=5.8e-8, jitter_y=5.8e-8, drift_rate_x=1e-4,
                         drift_rate_y=4.5e-6)
    scenario = xbsm.scenario(altitude=15000.0, ground_range=54e3, visibility=23.0)
    for method, rel in (("accurate", 1e-6), ("fast", 1e-5)):
        out = niirs_quiet(sensor, scenario, method)
        reference = dense_rer(sensor, scenario, method)
        np.testing.assert_allclose([float(out.rer_x), float(out.rer_y)], reference, rtol=rel)


def test_aperture_kink_fractions_are_the_annular_pupil_pieces_at_both_band_ends():
    eps, ratio = 0.4, 0.55 / 0.85  # Olson: obscuration 0.4, band 0.55-0.85 um
    pieces = np.array([eps, (1 - eps) / 2, (1 + eps) / 2])
    expected = np.sort(np.concatenate([pieces, [ratio], ratio * pieces]))
    got = quadrature.aperture_kink_fractions(eps, ratio)
    np.testing.assert_allclose(got, expected, rtol=1e-15)
    # a clear pupil: the longest wavelength's cutoff alone; one wavelength: no kink at all
    clear = quadrature.aperture_kink_fractions(0.0, ratio)
    assert np.isfinite(clear).sum() == 1 and np.nanmax(clear) == pytest.approx(ratio)
    assert np.isnan(quadrature.aperture_kink_fractions(0.0, 1.0)).all()
    # a kink repeated (eps = 1/3 is also (1 - eps) / 2) counts once; over sensors at once
    both = quadrature.aperture_kink_fractions(np.array([1 / 3, 0.4]), np.array([1.0, ratio]))
    assert np.isfinite(both[:, 0]).sum() == 2 and np.isfinite(both[:, 1]).sum() == 7


def test_kinks_move_the_nearest_panel_edge_and_add_panels_only_where_needed():
    knobs = xbsm.method("accurate").edge_quadrature_knobs()
    knobs.pop("name", None), knobs.pop("rule")
    cutoff, ifov = np.array(1.0 / IFOV), np.array(IFOV)
    plain = quadrature._kronrod_sensors(cutoff, ifov, np.array(0.0), **knobs)[0]
    kinks = quadrature.aperture_kink_fractions(0.4, 0.55 / 0.85)
    nodes = quadrature._kronrod_sensors(cutoff, ifov, np.array(0.0), kinks, **knobs)[0]
    per_panel = 2 * knobs["nodes_per_panel"] + 1
    added = (nodes.size - plain.size) // per_panel
    assert 0 <= added < np.isfinite(kinks).sum()  # some kinks took a uniform edge's place
    # every kink is a panel edge: no node of a panel lies on both sides of it
    edges_between = nodes.reshape(-1, per_panel)
    for k in kinks[np.isfinite(kinks)] * cutoff:
        straddles = (edges_between.min(axis=1) < k) & (edges_between.max(axis=1) > k)
        assert not straddles.any()


def _with_kinks_row_by_row(edges, cutoffs, count, steps, kinks):
    """The kink rule as its docstring says it, one kink row at a time (the reference)."""
    edges, taken = edges.copy(), np.zeros((count + 1, cutoffs.size), dtype=bool)
    added = np.full(kinks.shape, np.nan)
    for row, fraction in enumerate(kinks):
        for column, f in enumerate(fraction):
            if not np.isfinite(f):
                continue
            near = int(np.rint(f * count))
            if 1 <= near <= count - 1 and not taken[near, column]:
                edges[steps + near, column] = f * cutoffs[column]
                taken[near, column] = True
            else:
                added[row, column] = f * cutoffs[column]
    return edges, np.sort(added, axis=0), np.isfinite(added).sum(axis=0)


@pytest.mark.parametrize("seed", range(5))
def test_kink_edges_equal_the_rule_applied_one_kink_at_a_time(seed):
    # kinks of 300 sensors: sorted and unsorted columns, several near one edge, in the
    # first and last panel, NaN (no kink); the rule on every row at once must give the
    # rule kink by kink exactly (the same edges, the same added ones)
    rng = np.random.default_rng(seed)
    count, steps, n = 6, 2, 300
    cutoffs = rng.uniform(1e4, 1e6, n)
    kinks = rng.choice([0.01, 0.16, 0.17, 0.18, 0.5, 0.52, 0.97, np.nan], size=(7, n))
    kinks[:, ::2] = np.sort(kinks[:, ::2] * rng.uniform(0.9, 1.1, (7, 1)), axis=0)
    edges = quadrature._graded_edges(cutoffs, count, steps, 0.5)
    got = quadrature._with_kinks(edges, cutoffs, count, steps, kinks)
    expected = _with_kinks_row_by_row(edges, cutoffs, count, steps, kinks)
    for g, e in zip(got, expected, strict=True):
        np.testing.assert_array_equal(g, e)
    assert (expected[2] > 0).any() and (expected[2] < 7).any()  # both cases occur


def test_fast_flags_where_its_wavelength_bins_may_cost_more_than_its_tolerance():
    # The one cell of recipes/evidence/preset_error.py where fast's error passed its 1e-2
    # bound (docs/speed_accuracy.md): the annular MWIR system at Q 73, RER 0.0058, where
    # GIQE 5 moves 40 NIIRS per unit relative RER error. Its error is fast's 24
    # wavelength bins, not its quadrature: the same rule with every wavelength is within
    # 2.4e-5 of accurate; binned, 1.2e-2 (GIQE 5). The Kronrod - Gauss estimate cannot see
    # that; the bins' own error in the band's mean 1/lambda (binning_error_kernel) does.
    sensor = xbsm.sensor(aperture_diameter=0.05477, focal_length=9.276, pixel_pitch_x=6.96e-6,
                         wavelength_min=3e-6, wavelength_max=5e-6, obscuration_ratio=0.4895,
                         integration_time=9.97e-4, read_noise=10.0, max_well=1e5,
                         jitter_x=5.836e-8, jitter_y=5.836e-8, drift_rate_x=0.010683,
                         drift_rate_y=0.000483)
    scenario = xbsm.scenario(altitude=15056.0, ground_range=54180.0, visibility=23.0)
    accurate = niirs_quiet(sensor, scenario, "accurate")
    fast = niirs_quiet(sensor, scenario, "fast")
    every = niirs_quiet(sensor, scenario, xbsm.method(xbsm.method("fast"), otf_wavelengths=0))
    assert np.abs(fast.niirs - accurate.niirs).max() > 1e-2 and unresolved(fast)
    assert np.abs(every.niirs - accurate.niirs).max() < 1e-4 and not unresolved(every)
    assert not unresolved(accurate)


def test_binning_error_is_the_bins_error_in_the_mean_inverse_wavelength():
    from xbsm.otf.system import binning_error_kernel
    wavelength = np.linspace(3e-6, 5e-6, 201)
    weights = wavelength**4  # rising across the band, as a thermal MWIR target's
    full = np.sum(weights / wavelength) / np.sum(weights)
    labels = np.minimum(np.arange(201) * 24 // 201, 23)
    centres = np.array([wavelength[labels == b].mean() for b in range(24)])
    summed = np.array([weights[labels == b].sum() for b in range(24)])
    expected = abs(np.sum(summed / centres) / np.sum(weights) / full - 1)
    got = binning_error_kernel(weights, wavelength, count=24)
    assert float(got) == pytest.approx(expected, rel=1e-9) and expected > 0
    assert float(binning_error_kernel(weights, wavelength, count=0)) == 0.0
    assert float(binning_error_kernel(np.zeros(201), wavelength, count=24)) == 0.0
    both = binning_error_kernel(np.stack([weights, 2 * weights]), wavelength, count=24)
    np.testing.assert_allclose(both, [expected, expected], rtol=1e-9)  # e ~ 1e-4: cancellation
