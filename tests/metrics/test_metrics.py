"""Tests for xbsm.metrics: edge response, RER, EHO, GRD and GIQE 3 / 4 / 5."""

from __future__ import annotations

import pathlib

import dask
import dask.array as da
import numpy as np
import pytest
import xarray as xr
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.integrate import trapezoid
from scipy.special import erf, ndtr, struve

import xbsm
from xbsm import flags, metrics, quadrature

FIXTURES = pathlib.Path(__file__).resolve().parents[1] / "fixtures"
REF = np.load(FIXTURES / "pybsm_metrics.npz")
IFOV = 1e-5  # [rad]


def slice_da(values, nodes, lead_dim="case"):
    values = np.asarray(values)
    dims = ("frequency",) if values.ndim == 1 else (lead_dim, "frequency")
    return xr.DataArray(values, dims=dims, coords={"frequency": np.asarray(nodes)})


def accurate_er(otf, cutoff, positions, breakpoints=None, ifov=IFOV, method="accurate"):
    nodes, w = quadrature.edge_quadrature(cutoff=cutoff, ifov=ifov, breakpoints=breakpoints,
                                          **xbsm.method(method).edge_quadrature_knobs())
    h = slice_da(otf(nodes.values), nodes.values)
    return metrics.edge_response(h, ifov, positions, w)


def rer_of(otf, cutoff, breakpoints=None, method="accurate"):
    nodes, w = quadrature.edge_quadrature(cutoff=cutoff, ifov=IFOV, breakpoints=breakpoints,
                                          **xbsm.method(method).edge_quadrature_knobs())
    h = slice_da(otf(nodes.values), nodes.values)
    return float(metrics.relative_edge_response(h, IFOV, w))


def raising_scheduler(*args, **kwargs):
    raise RuntimeError("computed before it was asked to")


# ------------------------------------------------ pybsm_test_cases.md, section C


def test_edge_response_c11_pybsm_rule():
    # pybsm_test_cases.md C11 [T]: edge_response(pixel_pos=2.0, mtf_slice=[0.5, 0.5],
    # df=1.0, ifov=pi/4) = 1.2511552058098858 (sensitive to the +1e-6 offset)
    nodes, w = quadrature.uniform_trapezoid_rule(2, 1.0)
    er = metrics.edge_response(slice_da([0.5, 0.5], nodes), np.pi / 4, 2.0, w)
    assert float(er) == pytest.approx(1.2511552058098858, rel=1e-14)
    assert er.attrs["units"] == "1" and er.attrs["long_name"] == "edge response"


def test_relative_edge_response_c12_pybsm_rule():
    # pybsm_test_cases.md C12 [T]: relative_edge_response(mtf_slice=[1, 2], df=5,
    # ifov=pi/2) = 7.5720829278734385
    nodes, w = quadrature.uniform_trapezoid_rule(2, 5.0)
    rer = metrics.relative_edge_response(slice_da([1.0, 2.0], nodes), np.pi / 2, w)
    assert float(rer) == pytest.approx(7.5720829278734385, rel=1e-14)


def test_edge_response_rejects_slice_off_the_nodes():
    nodes, w = quadrature.uniform_trapezoid_rule(3, 1.0)
    with pytest.raises(ValueError, match="quadrature nodes"):
        metrics.edge_response(slice_da([1.0, 0.5, 0.0], nodes + 0.5), 1.0, 0.5, w)
    with pytest.raises(ValueError, match="frequency"):
        metrics.edge_response(xr.DataArray([1.0, 0.5, 0.0], dims="f"), 1.0, 0.5, w)


# ------------------------------------------------ pybsm_test_cases.md, section B


def test_giqe5_b7_nga_test_case():
    # NGA GIQE 5 (2015) Fig. 1 test case, pybsm_test_cases.md B7 [T]:
    # GSD 20.8 in, RER 0.35, SNR 50, nadir -> NIIRS 5.015165370148328 (the report: 5.0)
    out = metrics.giqe5(rer_x=0.35, rer_y=0.35, gsd=20.8 * 0.0254, snr=50, elevation=np.pi / 2)
    assert float(out.niirs) == pytest.approx(5.015165370148328, rel=1e-13)
    assert float(out.gsd_w) == pytest.approx(0.52832, rel=1e-15)
    assert float(out.rer) == pytest.approx(0.35, rel=1e-15)
    # the report's own example is outside its validation data only in SNR (4.1-26.7)
    assert int(out.flags) == flags.flag("snr_out_of_range")
    assert out.niirs.attrs["units"] == "1"


def test_giqe5_b8():
    # pybsm_test_cases.md B8 [T]: giqe5(1, 1, gsd=1, snr=2, elev_angle=20.0 rad)
    out = metrics.giqe5(rer_x=1, rer_y=1, gsd=1, snr=2, elevation=20.0)
    assert float(out.niirs) == pytest.approx(3.341217068150002, rel=1e-13)
    assert float(out.gsd_w) == pytest.approx(1.0230310532914486, rel=1e-13)
    assert float(out.rer) == 1.0
    # 20 rad is outside GIQE 5's 8.5-90 deg; GSD_W 1.023 m = 40.3 in is outside
    # its validation data's 3.3-34.4 in (NGA GIQE 5 report, 2015)
    assert bool(flags.has_flag(out.flags, "elevation_out_of_range"))
    assert bool(flags.has_flag(out.flags, "gsd_out_of_range"))


def test_giqe3_b9():
    # pybsm_test_cases.md B9 [T]
    a = metrics.giqe3(rer=1, gsd=1, eho=1, noise_gain=2, snr=2)
    b = metrics.giqe3(rer=2, gsd=2, eho=2, noise_gain=1, snr=1)
    assert float(a.niirs) == pytest.approx(4.034047939178196, rel=1e-13)
    assert float(b.niirs) == pytest.approx(2.5540479391781954, rel=1e-13)


def test_giqe4_b10_with_pybsm_noise_coefficient():
    # pybsm_test_cases.md B10 [T]: pyBSM uses 0.334 for the G/SNR coefficient
    out = metrics.giqe4(
        rer=2, gsd=2, eho=2, noise_gain=1, snr=1, elevation=np.pi / 2, noise_coefficient=0.334
    )
    assert float(out.niirs) == pytest.approx(2.778934116813923, rel=1e-13)
    assert float(out.gsd_gp) == 2.0
    # Leachtenauer et al. 1997's 0.344 lowers it by 0.01 * G / SNR
    pub = metrics.giqe4(rer=2, gsd=2, eho=2, noise_gain=1, snr=1, elevation=np.pi / 2)
    assert float(pub.niirs) == pytest.approx(2.778934116813923 - 0.01, rel=1e-13)


def test_giqe4_at_zero_elevation_is_nan_and_flagged_not_minus_inf():
    # pyBSM 0.16.1 returns (-inf, +inf) here (pybsm_test_cases.md B10)
    out = metrics.giqe4(rer=2, gsd=2, eho=2, snr=1, elevation=0.0)
    assert np.isnan(float(out.niirs)) and np.isnan(float(out.gsd_gp))
    assert bool(flags.has_flag(out.flags, "elevation_out_of_range"))


def test_giqe4_coefficients_switch_at_rer_0p9():
    lo = metrics.giqe4(rer=0.9 - 1e-12, gsd=0.3, eho=1, snr=50, elevation=1.0)
    hi = metrics.giqe4(rer=0.9, gsd=0.3, eho=1, snr=50, elevation=1.0)
    # the published fit is discontinuous there (pybsm_0.16.1_notes.md 2.6: 0.11 NIIRS)
    assert abs(float(hi.niirs - lo.niirs)) == pytest.approx(0.11, abs=0.01)


# ------------------------------------------------ GIQE 5 report smear table


@pytest.mark.parametrize(
    "snr, expected",
    [
        (50, [0.0, -0.03, -0.11, -0.33, -0.87]),
        (5, [0.0, -0.05, -0.19, -0.51, -1.19]),
    ],
)
def test_giqe5_smear_table(snr, expected):
    # NGA GIQE 5 report, Table 6: RER_cross 0.329, RER_along as below
    along = xr.DataArray([0.329, 0.302, 0.247, 0.169, 0.100], dims="smear")
    out = metrics.giqe5(rer_x=0.329, rer_y=along, gsd=0.5, snr=snr, elevation=np.pi / 2)
    delta = out.niirs - out.niirs.isel(smear=0)
    np.testing.assert_allclose(delta.values, expected, atol=0.01)
    assert out.niirs.dims == ("smear",)


# ------------------------------------------------ SNR <= 0 and other failure modes


@pytest.mark.parametrize("snr", [0.0, -3.0])
def test_nonpositive_snr_gives_nan_and_flag(snr):
    for out in (
        metrics.giqe3(rer=0.5, gsd=0.3, eho=1.0, snr=snr),
        metrics.giqe4(rer=0.5, gsd=0.3, eho=1.0, snr=snr, elevation=1.0),
        metrics.giqe5(rer_x=0.5, rer_y=0.5, gsd=0.3, snr=snr, elevation=1.0),
    ):
        assert np.isnan(float(out.niirs))
        assert bool(flags.has_flag(out.flags, "snr_nonpositive"))
        assert bool(flags.has_flag(out.flags, "snr_out_of_range"))


def test_tiny_snr_is_finite_but_flagged():
    # pyBSM returns GIQE 5 = -175 at SNR 0.01 with no warning (notes 2.6)
    out = metrics.giqe5(rer_x=0.5, rer_y=0.5, gsd=0.3, snr=0.01, elevation=1.0)
    assert float(out.niirs) < -100
    assert bool(flags.has_flag(out.flags, "snr_out_of_range"))
    assert bool(flags.has_flag(out.flags, "niirs_out_of_scale"))
    assert not bool(flags.has_flag(out.flags, "snr_nonpositive"))


def test_giqe_flags_inside_calibration_range_are_clear():
    fl = metrics.giqe_flags(snr=50, rer=0.5, gsd=0.5, elevation=1.2, niirs=5.0)
    assert int(fl) == 0
    assert fl.attrs["flag_meanings"].split()[0] == "beyond_database"
    fl = metrics.giqe_flags(snr=200, rer=1.5, gsd=0.01, elevation=0.2, niirs=11)
    for name in (
        "snr_out_of_range",
        "rer_out_of_range",
        "gsd_out_of_range",
        "elevation_out_of_range",
        "niirs_out_of_scale",
    ):
        assert bool(flags.has_flag(fl, name)), name


# ------------------------------------------------ parity with pyBSM 0.16.1


def _rel(a, b):
    return np.max(np.abs(a - b) / np.maximum(np.abs(b), 1e-300))


@pytest.mark.parametrize("group", [0, 1, 2, 3])
def test_edge_response_parity_with_pybsm(group):
    # tests/fixtures/pybsm_metrics.npz, written by recipes/fixtures/pybsm_reference_metrics.py
    slices = REF[f"er{group}_slices"]
    nodes, w = quadrature.uniform_trapezoid_rule(slices.shape[1], float(REF[f"er{group}_df"]))
    h = slice_da(slices, nodes)
    ifov = xr.DataArray(REF[f"er{group}_ifov"], dims="case")
    pos = xr.DataArray(REF[f"er{group}_pos"], dims="case")
    er = metrics.edge_response(h, ifov, pos, w)
    assert er.dims == ("case",)
    assert _rel(er.values, REF[f"er{group}_value"]) < 1e-12


@pytest.mark.parametrize("kind", ["smooth", "noisy"])
def test_rer_eho_grd_parity_with_pybsm(kind):
    slices = REF[f"{kind}_slices"]
    nodes, w = quadrature.edge_quadrature(cutoff=float(REF[f"{kind}_cutoff"]), ifov=1.0,
                                          **xbsm.method("pybsm").edge_quadrature_knobs())
    # exact: pyBSM's step is one IEEE division of the same two doubles
    assert nodes.values[1] == float(REF[f"{kind}_df"])
    h = slice_da(slices, nodes)
    ifov = xr.DataArray(REF[f"{kind}_ifov"], dims="case")
    terms = metrics.edge_terms(h, ifov, w)
    assert _rel(terms.rer.values, REF[f"{kind}_rer"]) < 1e-12
    assert _rel(terms.eho.values, REF[f"{kind}_eho"]) < 1e-12
    eho = metrics.edge_height_overshoot(h, ifov, w)
    assert _rel(eho.values, REF[f"{kind}_eho"]) < 1e-12
    grd = metrics.ground_resolved_distance(
        h,
        xr.DataArray(REF[f"{kind}_snr"], dims="case"),
        ifov,
        xr.DataArray(REF[f"{kind}_slant_range"], dims="case"),
        method="pybsm",
    )
    assert _rel(grd.values, REF[f"{kind}_grd"]) < 1e-12
    assert grd.attrs["units"] == "m"


def test_giqe_parity_with_pybsm():
    c = {
        k: xr.DataArray(REF[f"giqe_{k}"], dims="case")
        for k in ("rer", "rer2", "gsd", "eho", "ng", "snr", "elev")
    }
    g3 = metrics.giqe3(rer=c["rer"], gsd=c["gsd"], eho=c["eho"], noise_gain=c["ng"], snr=c["snr"])
    assert _rel(g3.niirs.values, REF["giqe3"]) < 1e-12
    g4 = metrics.giqe4(
        rer=c["rer"],
        gsd=c["gsd"],
        eho=c["eho"],
        noise_gain=c["ng"],
        snr=c["snr"],
        elevation=c["elev"],
        noise_coefficient=0.334,
    )
    assert _rel(g4.niirs.values, REF["giqe4"]) < 1e-12
    assert _rel(g4.gsd_gp.values, REF["giqe4_gsd_gp"]) < 1e-12
    g5 = metrics.giqe5(
        rer_x=c["rer"], rer_y=c["rer2"], gsd=c["gsd"], snr=c["snr"], elevation=c["elev"]
    )
    assert _rel(g5.niirs.values, REF["giqe5"]) < 1e-12
    assert _rel(g5.gsd_w.values, REF["giqe5_gsd_w"]) < 1e-12
    assert _rel(g5.rer.values, REF["giqe5_rer"]) < 1e-12


# ------------------------------------------------ analytic edge responses


def gaussian_otf(sigma_px):
    return lambda f: np.exp(-2 * np.pi**2 * (sigma_px * IFOV) ** 2 * f**2)


@pytest.mark.parametrize("sigma_px", [0.2, 0.6, 1.5])
def test_gaussian_edge_response_is_normal_cdf(sigma_px):
    # MTF exp(-2 pi^2 s^2 f^2) <-> Gaussian LSF: ER(x) = Phi(x ifov / s)
    cutoff = 8 / (sigma_px * IFOV)  # the OTF is below 1e-54 there
    x = np.array([-0.5, 0.5, 1.0, 1.25, 2.0, 3.0])
    er = accurate_er(gaussian_otf(sigma_px), cutoff, x)
    np.testing.assert_allclose(er.values, ndtr(x / sigma_px), rtol=0, atol=1e-9)
    rer = rer_of(gaussian_otf(sigma_px), cutoff)
    assert rer == pytest.approx(erf(1 / (2 * np.sqrt(2) * sigma_px)), abs=1e-9)


def test_rect_detector_edge_response_is_a_ramp_with_otf_not_with_mtf():
    # A rect pixel alone: ER is the linear ramp 1/2 + x on [-1/2, 1/2], so RER = 1.
    # The integral is truncated at 2000 / ifov; the tail costs 2.5e-5 per edge value.
    cutoff = 2000 / IFOV
    bps = quadrature.detector_breakpoints(IFOV, cutoff)
    x = np.array([-0.5, -0.25, 0.0, 0.25, 0.5, 1.0])
    er = accurate_er(lambda f: np.sinc(f * IFOV), cutoff, x, bps)
    np.testing.assert_allclose(er.values, np.clip(0.5 + x, 0, 1), atol=5e-5)
    # |sinc| (pyBSM's |OTF|) gives RER 0.8669 whatever the cutoff (docs/metrics.md)
    er_abs = accurate_er(lambda f: np.abs(np.sinc(f * IFOV)), cutoff, [-0.5, 0.5], bps)
    assert float(er_abs[1] - er_abs[0]) == pytest.approx(0.86689, abs=1e-4)


def test_rect_times_gaussian_closed_form_needs_real_otf():
    # LSF = rect(1 px) * Gaussian(s): ER(x) = G(x + 1/2) - G(x - 1/2),
    # G(t) = t Phi(t/s) + s phi(t/s)   (closed form in the spatial domain)
    s = 0.3

    def exact(x):
        g = lambda t: t * ndtr(t / s) + s * np.exp(-0.5 * (t / s) ** 2) / np.sqrt(2 * np.pi)  # noqa: E731
        return g(x + 0.5) - g(x - 0.5)

    cutoff = 40 / (s * IFOV)
    bps = quadrature.detector_breakpoints(IFOV, cutoff)
    x = np.array([-0.5, 0.5, 1.25, 2.0])

    def otf(f):
        return np.sinc(f * IFOV) * gaussian_otf(s)(f)

    er = accurate_er(otf, cutoff, x, bps)
    np.testing.assert_allclose(er.values, exact(x), atol=1e-9)
    er_abs = accurate_er(lambda f: np.abs(otf(f)), cutoff, x, bps)
    assert np.max(np.abs(er_abs.values - exact(x))) > 1e-3  # measured 1.5e-3


def test_aperture_detector_rer_matches_spatial_convolution_with_real_otf():
    # Q = 0.25 unobscured aperture x rect pixel. Reference: the edge convolved in
    # the spatial domain with the aperture LSF (Struve H1(z)/z^2, z = 2 pi x / Q)
    # and the pixel: RER 0.85507 (docs/metrics.md). Re(OTF): 0.85506; |OTF|: 0.80249.
    q = 0.25
    xs = np.linspace(-4000, 4000, 4_000_001)
    z = 2 * np.pi * np.abs(xs) / q
    lsf = struve(1, np.where(z == 0, 1e-12, z)) / np.where(z == 0, 1e-12, z) ** 2
    dx = xs[1] - xs[0]
    cdf = np.cumsum(lsf) * dx
    cdf = cdf / cdf[-1]
    cdf = cdf - np.interp(0.0, xs, cdf) + 0.5

    def er_spatial(x):
        u = np.linspace(x - 0.5, x + 0.5, 4001)
        return trapezoid(np.interp(u, xs, cdf), u)

    rer_spatial = er_spatial(0.5) - er_spatial(-0.5)
    cutoff = 1 / (q * IFOV)

    def otf(f):
        nu = np.clip(f * q * IFOV, 0, 1)
        return (2 / np.pi) * (np.arccos(nu) - nu * np.sqrt(1 - nu**2)) * np.sinc(f * IFOV)

    bps = quadrature.detector_breakpoints(IFOV, cutoff)
    rer_re = rer_of(otf, cutoff, bps)
    rer_abs = rer_of(lambda f: np.abs(otf(f)), cutoff, bps)
    assert rer_re == pytest.approx(rer_spatial, abs=2e-4)
    assert rer_re == pytest.approx(0.855060, abs=1e-6)
    assert rer_abs == pytest.approx(0.802490, abs=1e-6)
    assert rer_spatial - rer_abs > 0.05


def test_complex_otf_with_linear_phase_shifts_the_edge():
    # A pure shift of d px multiplies the OTF by exp(-2 pi i f ifov d): ER(x) -> ER(x - d)
    s, d = 0.5, 0.3
    cutoff = 8 / (s * IFOV)

    def otf(f):
        return gaussian_otf(s)(f) * np.exp(-2j * np.pi * f * IFOV * d)

    x = np.array([-0.5, 0.0, 0.5, 1.25])
    er = accurate_er(otf, cutoff, x)
    np.testing.assert_allclose(er.values, ndtr((x - d) / s), atol=1e-9)


def test_pybsm_rule_fails_for_undersampled_system_accurate_does_not():
    # Q = 0.05 (lambda F / p): cutoff * ifov = 20, 60 oscillations over [0, cutoff]
    # at 3 px; the 50-sample pyBSM rule cannot resolve them.
    q = 0.05
    cutoff = 1 / (q * IFOV)

    def mtf(f):
        nu = np.clip(f * q * IFOV, 0, 1)
        return np.abs((2 / np.pi) * (np.arccos(nu) - nu * np.sqrt(1 - nu**2)) * np.sinc(f * IFOV))

    bps = quadrature.detector_breakpoints(IFOV, cutoff)
    out = {}
    for method in ("pybsm", "accurate"):
        nodes, w = quadrature.edge_quadrature(cutoff=cutoff, ifov=IFOV, breakpoints=bps,
                                              **xbsm.method(method).edge_quadrature_knobs())
        out[method] = metrics.edge_terms(slice_da(mtf(nodes.values), nodes.values), IFOV, w)
    # converged (|OTF| as pyBSM uses): the edge has settled by 1 px, EHO 1.00858
    assert float(out["accurate"].eho) == pytest.approx(1.00858, abs=1e-5)
    # pyBSM's 50-sample rule: EHO 1.927, 0.92 too high; its RER is still close
    assert float(out["pybsm"].eho) == pytest.approx(1.9269, abs=1e-4)
    assert float(out["pybsm"].rer) == pytest.approx(float(out["accurate"].rer), abs=5e-4)


# ------------------------------------------------ EHO rule


def test_eho_rule_monotonic_uses_er_at_1p25_else_max():
    x = xr.DataArray(metrics.EHO_POSITIONS, dims="position")
    x = x.assign_coords(position=metrics.EHO_POSITIONS)
    rising = 1 - 0.5 * np.exp(-x)
    overshoot = rising + 0.1 * np.exp(-((x - 1.5) ** 2) * 4)
    # the NumPy kernel: edge responses at EHO_POSITIONS along the last axis
    eho = metrics.edge._eho_kernel(np.stack([rising.values, overshoot.values]))
    assert eho[0] == pytest.approx(float(rising.sel(position=1.25)))
    assert eho[1] == pytest.approx(float(overshoot.max()))


# ------------------------------------------------ ground resolved distance


def test_grd_first_crossing_on_non_monotonic_mtf():
    # MTF falls to 0 at f = 2, then a lobe back up to 0.4 at f = 3: 3/SNR = 0.3 is
    # first reached at f = 1.4 (linear between (1, 0.5) and (2, 0)); GRD = R / 1.4.
    f = np.array([0.0, 1.0, 2.0, 3.0, 4.0])
    mtf = slice_da([1.0, 0.5, 0.0, 0.4, 0.0], f)
    grd = metrics.ground_resolved_distance(mtf, snr=10.0, ifov=0.01, slant_range=1.0)
    assert float(grd) == pytest.approx(1 / 1.4, rel=1e-14)
    # pyBSM's np.interp on the reversed curve lands on the later lobe instead
    grd_pybsm = metrics.ground_resolved_distance(
        mtf, snr=10.0, ifov=0.01, slant_range=1.0, method="pybsm"
    )
    expected = 1 / (np.interp(0.3, mtf.values[::-1], f[::-1]) + 1e-12)
    assert float(grd_pybsm) == pytest.approx(expected, rel=1e-14)
    assert float(grd_pybsm) != pytest.approx(float(grd), rel=1e-3)


def test_grd_detector_limit_and_low_snr():
    f = np.linspace(0, 10, 11)
    mtf = slice_da(np.clip(1 - f / 10, 0, 1), f)
    # SNR high enough that 1/u_r < 2 ifov: GRD = 2 GSD
    grd = metrics.ground_resolved_distance(mtf, snr=1e6, ifov=0.2, slant_range=100.0)
    assert float(grd) == pytest.approx(40.0)
    snr = xr.DataArray([3.0, 2.0, 0.0, -1.0], dims="snr")
    grd = metrics.ground_resolved_distance(mtf, snr=snr, ifov=0.01, slant_range=1.0)
    assert np.isinf(grd.values[:2]).all()  # 3/SNR >= 1: nothing is resolved
    assert np.isnan(grd.values[2:]).all()


@pytest.mark.parametrize("method", ["first_crossing", "pybsm"])
def test_grd_where_nothing_is_resolved_carries_grd_unresolved(method):
    # 3/SNR >= 1 for SNR <= 3: the MTF (at most 1) never falls to the threshold, so no
    # square wave is resolved (IBSM Eq. 3-54); docs/flags.md: grd_unresolved where
    # SNR <= 3 or NaN, snr_nonpositive where SNR <= 0
    f = np.linspace(0, 10, 11)
    mtf = slice_da(np.clip(1 - f / 10, 0, 1), f)
    snr = xr.DataArray([50.0, 3.0, 2.0, 1e-12, 0.0, np.nan], dims="snr")
    grd = metrics.ground_resolved_distance(mtf, snr=snr, ifov=0.01, slant_range=1.0,
                                           method=method)
    bits = flags.decode(grd["grd_flags"])
    assert bits.grd_unresolved.values.tolist() == [False, True, True, True, True, True]
    assert bits.snr_nonpositive.values.tolist() == [False, False, False, False, True, False]
    assert bool(bits.invalid[1:].all()) and not bool(bits.invalid[0])
    assert np.isfinite(float(grd[0]))
    if method == "pybsm":  # pyBSM's own finite value is kept, and flagged
        assert np.isfinite(grd.values[1:4]).all()
    else:
        assert np.isinf(grd.values[1:4]).all()


def test_grd_on_gauss_nodes_uses_implicit_unit_otf_at_zero():
    nodes, _ = quadrature.gauss_legendre_rule([0.0, 1.0], 4)
    mtf = slice_da(1 - nodes.values, nodes.values)  # linear, crosses 0.5 at f = 0.5
    grd = metrics.ground_resolved_distance(mtf, snr=6.0, ifov=0.0, slant_range=1.0)
    assert float(grd) == pytest.approx(2.0, rel=1e-12)
    mtf = slice_da(1 - 0.01 * nodes.values, nodes.values)  # first node already below 0.9999
    grd = metrics.ground_resolved_distance(mtf, snr=3.0003, ifov=0.0, slant_range=1.0)
    assert float(grd) == pytest.approx(1 / (1 - 3 / 3.0003) * 0.01, rel=1e-9)


@settings(max_examples=60, deadline=None)
@given(
    values=st.lists(st.floats(0.0, 1.0), min_size=5, max_size=40),
    snr=st.floats(0.5, 500.0),
)
def test_grd_pybsm_rule_reproduces_numpy_interp(values, snr):
    # NumPy's search on non-monotonic data is emulated; check against np.interp itself
    mtf = np.array([1.0, *values])
    f = np.arange(mtf.size) * 7.0
    got = metrics.ground_resolved_distance(
        slice_da(mtf, f), snr=snr, ifov=1e-9, slant_range=1.0, method="pybsm"
    )
    expected = 1 / (np.interp(3.0 / snr, mtf[::-1], f[::-1]) + 1e-12)
    assert float(got) == pytest.approx(expected, rel=1e-12)


# ------------------------------------------------ vectorisation, dask, broadcasting


def test_sweep_dims_broadcast_and_ifov_sweep():
    nodes, w = quadrature.edge_quadrature(cutoff=4 / IFOV, ifov=2 * IFOV,
                                          **xbsm.method("accurate").edge_quadrature_knobs())
    sig = xr.DataArray([0.3, 0.6, 0.9], dims="blur", coords={"blur": [0.3, 0.6, 0.9]})
    h = np.exp(-2 * np.pi**2 * (sig * IFOV) ** 2 * slice_da(nodes.values, nodes.values) ** 2)
    ifov = xr.DataArray([IFOV, 2 * IFOV], dims="pitch", coords={"pitch": [1, 2]})
    terms = metrics.edge_terms(h, ifov, w)
    assert set(terms.rer.dims) == {"blur", "pitch"}
    assert list(terms.rer["blur"].values) == [0.3, 0.6, 0.9]
    assert terms.rer.attrs["units"] == "1"
    # doubling the IFOV is the same as halving the blur in pixels
    s = sig / ifov * IFOV
    np.testing.assert_allclose(
        terms.rer.transpose("blur", "pitch").values,
        erf(1 / (2 * np.sqrt(2) * s)).transpose("blur", "pitch").values,
        atol=1e-6,
    )


def test_dask_equals_eager_and_stays_lazy():
    nodes, w = quadrature.edge_quadrature(cutoff=4 / IFOV, ifov=IFOV,
                                          **xbsm.method("fast").edge_quadrature_knobs())
    rng = np.random.default_rng(0)
    s = rng.uniform(0.2, 1.0, 12)
    values = np.exp(-2 * np.pi**2 * (s[:, None] * IFOV) ** 2 * nodes.values**2)
    eager = slice_da(values, nodes.values)
    lazy = eager.copy(data=da.from_array(values, chunks=(4, -1)))
    snr = xr.DataArray(rng.uniform(5, 100, 12), dims="case")
    with dask.config.set(scheduler=raising_scheduler):
        t = metrics.edge_terms(lazy, IFOV, w)
        g5 = metrics.giqe5(rer_x=t.rer, rer_y=t.rer, gsd=0.3, snr=snr, elevation=1.0)
        g4 = metrics.giqe4(rer=t.rer, gsd=0.3, eho=t.eho, snr=snr, elevation=1.0)
        grd = metrics.ground_resolved_distance(lazy, snr, IFOV, 1e4)
        grd_p = metrics.ground_resolved_distance(lazy, snr, IFOV, 1e4, method="pybsm")
        for x in (t.rer, t.eho, g5.niirs, g5.flags, g4.niirs, grd, grd_p):
            assert isinstance(x.data, da.Array)
    te = metrics.edge_terms(eager, IFOV, w)
    xr.testing.assert_allclose(t.compute(), te)
    g5e = metrics.giqe5(rer_x=te.rer, rer_y=te.rer, gsd=0.3, snr=snr, elevation=1.0)
    xr.testing.assert_allclose(g5.compute(), g5e)
    xr.testing.assert_allclose(
        grd.compute(), metrics.ground_resolved_distance(eager, snr, IFOV, 1e4)
    )
    xr.testing.assert_allclose(
        grd_p.compute(),
        metrics.ground_resolved_distance(eager, snr, IFOV, 1e4, method="pybsm"),
    )


@settings(max_examples=80, deadline=None)
@given(
    rer=st.floats(-0.5, 3.0),
    rer2=st.floats(-0.5, 3.0),
    gsd=st.floats(1e-3, 20.0),
    eho=st.floats(0.0, 3.0),
    snr=st.floats(-10.0, 1e4),
    elevation=st.floats(-0.5, np.pi / 2),
)
def test_giqe_outputs_are_finite_or_flagged(rer, rer2, gsd, eho, snr, elevation):
    outs = [
        metrics.giqe3(rer=rer, gsd=gsd, eho=eho, snr=snr),
        metrics.giqe4(rer=rer, gsd=gsd, eho=eho, snr=snr, elevation=elevation),
        metrics.giqe5(rer_x=rer, rer_y=rer2, gsd=gsd, snr=snr, elevation=elevation),
    ]
    for out in outs:
        value = float(out.niirs)
        assert not np.isinf(value)
        if np.isnan(value):
            assert int(out.flags) != 0
        if snr <= 0:
            assert np.isnan(value) and bool(flags.has_flag(out.flags, "snr_nonpositive"))
        if np.isfinite(value) and not 0 <= value <= 10:
            assert bool(flags.has_flag(out.flags, "niirs_out_of_scale"))


@settings(max_examples=40, deadline=None)
@given(q=st.floats(0.05, 3.0), sigma=st.floats(0.0, 1.0), x=st.floats(-3.0, 3.0))
def test_edge_response_of_valid_systems_is_finite_and_odd(q, sigma, x):
    cutoff = 1 / (q * IFOV)

    def otf(f):
        nu = np.clip(f * q * IFOV, 0, 1)
        ap = (2 / np.pi) * (np.arccos(nu) - nu * np.sqrt(1 - nu**2))
        return ap * np.sinc(f * IFOV) * np.exp(-2 * np.pi**2 * (sigma * IFOV * f) ** 2)

    er = accurate_er(otf, cutoff, [x, -x], method="fast")
    assert np.isfinite(er.values).all()
    # a symmetric PSF gives ER(x) + ER(-x) = 1
    assert float(er.sum()) == pytest.approx(1.0, abs=1e-12)


# ------------------------------------------------ per-version GIQE calibration
# Limits: NGA, "General Image Quality Equation (GIQE) Version 5.0" (Harrington et
# al., 16 Sep 2015), as summarised with sources in docs/flags.md.


def test_giqe5_at_8p9_deg_elevation_is_not_flagged_for_elevation():
    # GIQE 5 report: validation data span elevation 8.9-87.3 deg (conclusions
    # 8.5-90); every other input inside the report's validation spans
    out = metrics.giqe5(rer_x=0.4, rer_y=0.4, gsd=10 * metrics.INCH, snr=20,
                        elevation=np.deg2rad(8.9), q=1.5)
    assert not bool(flags.has_flag(out.flags, "elevation_out_of_range"))
    assert int(out.flags) == 0


def test_giqe4_at_28_deg_elevation_is_not_flagged_for_elevation():
    # GIQE 5 report's summary of GIQE 4: fitted on images at elevation 25-90 deg
    # (xbsm flagged below 30 deg before)
    out = metrics.giqe4(rer=0.5, gsd=0.3, eho=1.0, snr=50, elevation=np.deg2rad(28.0))
    assert not bool(flags.has_flag(out.flags, "elevation_out_of_range"))
    assert int(out.flags) == 0


def test_giqe4_at_20_deg_elevation_is_flagged():
    # below GIQE 4's 25-90 deg fitting range (GIQE 5 report's summary of GIQE 4)
    out = metrics.giqe4(rer=0.5, gsd=0.3, eho=1.0, snr=50, elevation=np.deg2rad(20.0))
    assert int(out.flags) == flags.flag("elevation_out_of_range")
    assert np.isfinite(float(out.niirs))
    assert bool(flags.is_outside_calibration(out.flags))
    assert not bool(flags.is_invalid(out.flags))


def test_giqe5_at_snr_4_is_flagged():
    # GIQE 5 report: validation SNR 4.1-26.7, and SNR below 5 "should be used
    # with caution"; SNR 4 is outside the calibration, but not a wrong number
    out = metrics.giqe5(rer_x=0.4, rer_y=0.4, gsd=10 * metrics.INCH, snr=4.0,
                        elevation=np.pi / 2, q=1.5)
    assert int(out.flags) == flags.flag("snr_out_of_range")
    assert np.isfinite(float(out.niirs))
    assert bool(flags.is_outside_calibration(out.flags))
    assert not bool(flags.is_invalid(out.flags))


def test_giqe5_at_q_2p5_is_flagged():
    # GIQE 5 report: the equation assumes 1 <= Q = lambda N / p <= 2, and Q > 2
    # is "a pure extrapolation"
    kwargs = dict(rer_x=0.4, rer_y=0.4, gsd=10 * metrics.INCH, snr=20, elevation=np.pi / 2)
    out = metrics.giqe5(**kwargs, q=2.5)
    assert int(out.flags) == flags.flag("q_out_of_range")
    # one orientation outside is enough
    q = xr.DataArray([1.5, 2.5], dims="orientation", coords={"orientation": ["x", "y"]})
    assert int(metrics.giqe5(**kwargs, q=q).flags) == flags.flag("q_out_of_range")
    assert int(metrics.giqe5(**kwargs, q=2.0).flags) == 0
    # Q only flags: the prediction is the same with or without it
    assert float(out.niirs) == float(metrics.giqe5(**kwargs).niirs)


def test_sampling_q_is_lambda_f_number_over_pitch():
    # hand calculation: 0.7 um x (4 m / 0.275 m) / 8 um = 1.2727...
    q = metrics.sampling_q(0.7e-6, 0.275, 8e-6 / 4.0)
    assert float(q) == pytest.approx(0.7e-6 * (4.0 / 0.275) / 8e-6, rel=1e-15)
    assert q.attrs["units"] == "1"


def test_each_giqe_version_has_its_own_calibration():
    cal = metrics.GIQE_CALIBRATIONS
    assert cal[3] is metrics.GIQE3_CALIBRATION and cal[5] is metrics.GIQE5_CALIBRATION
    # GIQE 4: 25-90 deg; GIQE 5: 8.5-90 deg, SNR 4.1-26.7, Q 1-2 (NGA 2015)
    assert cal[4].elevation == pytest.approx((np.deg2rad(25), np.pi / 2))
    assert cal[5].elevation == pytest.approx((np.deg2rad(8.5), np.pi / 2))
    assert cal[5].snr == (4.1, 26.7) and cal[5].rer == (0.31, 0.54) and cal[5].q == (1.0, 2.0)
    assert cal[5].gsd == pytest.approx((3.3 * 0.0254, 34.4 * 0.0254))
    assert cal[5].gsd_ground_plane == pytest.approx((3.3 * 0.0254, 55.3 * 0.0254))
    assert cal[3].elevation is None and cal[4].q is None


def test_calibration_table_is_immutable():
    with pytest.raises(TypeError):
        metrics.GIQE_CALIBRATIONS[5] = metrics.GIQE4_CALIBRATION
    with pytest.raises(AttributeError):  # dataclasses.FrozenInstanceError
        metrics.GIQE5_CALIBRATION.snr = (2.0, 130.0)


def test_calibration_override_changes_flags_not_niirs():
    kwargs = dict(rer_x=0.35, rer_y=0.35, gsd=20.8 * 0.0254, snr=50, elevation=np.pi / 2)
    default = metrics.giqe5(**kwargs)
    wide = metrics.giqe5(**kwargs, calibration=metrics.GIQE5_CALIBRATION.replace(snr=(4.1, 60)))
    assert int(default.flags) == flags.flag("snr_out_of_range")
    assert int(wide.flags) == 0
    assert float(wide.niirs) == float(default.niirs)
    # a GIQE 3 elevation range is tested once set (the default has none)
    g3 = metrics.GIQE3_CALIBRATION.replace(elevation=(np.deg2rad(25), np.pi / 2))
    low = dict(rer=0.5, gsd=0.3, eho=1.0, snr=50, elevation=np.deg2rad(20.0))
    assert int(metrics.giqe3(**low).flags) == 0
    assert int(metrics.giqe3(**low, calibration=g3).flags) == flags.flag("elevation_out_of_range")


@pytest.mark.parametrize("change, match", [
    (dict(elevation=(25.0, 90.0)), "elevation must be None or a \\(low, high\\) pair in "
     "\\[0, 1.5708\\] rad"),
    (dict(snr=(5.0, 4.0)), "snr must be None or a \\(low, high\\) pair"),
    (dict(rer=0.3), "rer must be None or a \\(low, high\\) pair"),
    (dict(gsd=(np.nan, 1.0)), "gsd must be None"),
    (dict(q=(-1.0, 2.0)), "q must be None or a \\(low, high\\) pair in \\[0, inf\\) 1"),
    (dict(snr=(1, 2, 3)), "snr must be None"),
    (dict(nirs=(0, 10)), "unknown GiqeCalibration field"),
])
def test_invalid_calibration_is_rejected(change, match):
    with pytest.raises(ValueError, match=match):
        metrics.GIQE5_CALIBRATION.replace(**change)


def test_invalid_calibration_argument_is_rejected():
    with pytest.raises(ValueError, match="calibration must be an xbsm.metrics.GiqeCalibration"):
        metrics.giqe5(rer_x=0.4, rer_y=0.4, gsd=0.3, snr=20, elevation=1.0,
                      calibration={"snr": (2, 130)})
    with pytest.raises(ValueError, match="version"):
        metrics.giqe_calibrations({6: metrics.GIQE5_CALIBRATION})
    with pytest.raises(ValueError, match="GiqeCalibration"):
        metrics.giqe_calibrations({5: (4.1, 26.7)})
    with pytest.raises(ValueError, match="GIQE 5 only"):
        metrics.giqe_calibrations({4: metrics.GIQE4_CALIBRATION.replace(q=(1, 2))})


def test_every_flag_is_in_exactly_one_group():
    groups = flags.INVALID + flags.CALIBRATION + flags.NOTICE
    assert sorted(groups) == sorted(flags.FLAGS)
    assert flags.INVALID_MASK & flags.CALIBRATION_MASK == 0
    fl = xr.DataArray(np.int32([0, 4, 8, 512, 8 | 512]))
    assert flags.is_invalid(fl).values.tolist() == [False, False, False, True, True]
    assert flags.is_outside_calibration(fl).values.tolist() == [False, False, True, False, True]


# ------------------------------------------------ NumPy kernels (plain arrays, no xarray)


def test_giqe_kernels_on_plain_arrays():
    from xbsm.metrics import giqe as g

    # pybsm_test_cases.md B9: giqe3(rer=1, gsd=1, eho=1, ng=2, snr=2) and (2, 2, 2, 1, 1);
    # arguments in the kernel's order (rer, gsd, eho, noise_gain, snr), GSD in m
    one_two = np.array([1.0, 2.0])
    niirs3 = g._giqe3_kernel(one_two, one_two, one_two, one_two[::-1], one_two[::-1])
    np.testing.assert_allclose(niirs3, [4.034047939178196, 2.5540479391781954], rtol=1e-13)
    # B10 with pyBSM's 0.334: rer = gsd = eho = 2, ng 1, SNR 1, nadir; B8: GIQE 5 of
    # rer 1 x 1, gsd 1, SNR 2, elevation 20 rad
    niirs4 = g._giqe4_kernel(2.0, 2.0, np.pi / 2, 2.0, 1.0, 1.0, 0.334)
    niirs5 = g._giqe5_kernel(1.0, 20.0, 2.0, 1.0, 1.0)
    assert niirs4 == pytest.approx(2.778934116813923, rel=1e-13)
    assert niirs5 == pytest.approx(3.341217068150002, rel=1e-13)


def test_giqe_by_version_kernel_broadcasts_size_one_axes_like_apply_ufunc():
    from xbsm.metrics import giqe as g

    # apply_ufunc hands kernels arrays with size-1 axes for missing dims: rer on a first
    # axis, snr on a second; the result spans both with the versions on a last axis
    rer, snr = np.array([[0.3], [0.6]]), np.array([5.0, 20.0, 50.0])
    out = g._niirs_of_terms(g._giqe_terms(0.3, 0.3, 1.0, rer, rer), rer, 0.3, 1.0, 1.0, snr,
                            noise_coefficient=0.344)
    assert out.shape == (2, 3, 3)
    # each column is that version's own kernel (definition)
    np.testing.assert_array_equal(out[..., 0], g._giqe3_kernel(rer, 0.3, 1.0, 1.0, snr))
    np.testing.assert_array_equal(
        out[..., 1], g._giqe4_kernel(rer, 0.3, 1.0, 1.0, 1.0, snr, 0.344))
    np.testing.assert_array_equal(out[..., 2], g._giqe5_kernel(0.3, 1.0, snr, rer, rer))


def test_flags_kernel_bits_and_nan_rules():
    from xbsm.metrics import giqe as g

    snr = np.array([-1.0, 10.0, 50.0, np.nan])
    tests = ((0, flags.flag("snr_nonpositive"), "nonpositive", 0.0, 0.0, 0, None),
             (0, flags.flag("snr_out_of_range"), "outside", 4.1, 26.7, 0, None))
    bits = g._flags_kernel(snr, tests=tests, versions=None)
    # xbsm.flags: snr_nonpositive = 512, snr_out_of_range = 8; NaN is out of range but not
    # "nonpositive" (giqe_flags' rule)
    assert bits.dtype == np.int32
    assert bits.tolist() == [512 | 8, 0, 8, 8]
    # two versions along a last axis; q's test is "any orientation" over its last axis
    q = np.array([[1.5, 2.5], [1.5, 1.8]])
    tests = ((1, flags.flag("q_out_of_range"), "any_outside", 1.0, 2.0, 0, None),)
    assert g._flags_kernel(q, tests=tests, versions=2).tolist() == [[0, 1024], [0, 0]]


def _giqe_inputs(chunks=None):
    rng = np.random.default_rng(1)
    case = xr.DataArray(rng.uniform(0.2, 1.2, 6), dims="case")
    gsd_x = xr.DataArray([0.2, 0.3, 0.5], dims="range")
    snr = xr.DataArray(rng.uniform(-1.0, 60.0, 6), dims="case")
    if chunks:
        case, snr = case.chunk(chunks), snr.chunk(chunks)
    q = xr.DataArray([1.2, 2.2], dims="orientation", coords={"orientation": ["x", "y"]})
    return dict(rer=case, eho=case + 0.5, rer_x=case, rer_y=0.9 * case, gsd_x=gsd_x,
                gsd_y=1.1 * gsd_x, snr=snr, elevation=xr.DataArray(1.0), noise_gain=1.0, q=q,
                noise_coefficient=0.344, calibration=metrics.GIQE_CALIBRATIONS)


def test_giqe_by_version_keeps_each_output_on_the_dims_it_depends_on():
    out = metrics.giqe_by_version(**_giqe_inputs())
    # GSDs depend on the range sweep only; NIIRS and flags on both, versions first
    assert out.gsd.dims == out.gsd_gp.dims == out.gsd_w.dims == ("range",)
    assert out.rer_giqe5.dims == ("case",)
    assert out.niirs.dims == ("giqe", "case", "range") and out.flags.dims[0] == "giqe"
    assert out.giqe.values.tolist() == [3, 4, 5] and out.flags.dtype == np.int32
    # the same numbers as each version's own function (definition)
    inputs = _giqe_inputs()
    gsd = np.sqrt(inputs["gsd_x"] * inputs["gsd_y"])
    g4 = metrics.giqe4(rer=inputs["rer"], gsd=gsd, eho=inputs["eho"], snr=inputs["snr"],
                       elevation=1.0)
    xr.testing.assert_equal(out.niirs.sel(giqe=4, drop=True), g4.niirs)


def test_giqe_by_version_dask_equals_eager_and_stays_lazy():
    with dask.config.set(scheduler=raising_scheduler):
        lazy = metrics.giqe_by_version(**_giqe_inputs(chunks=2))
        for name in ("niirs", "flags", "rer_giqe5"):
            assert isinstance(lazy[name].data, da.Array), name
    xr.testing.assert_identical(lazy.compute(), metrics.giqe_by_version(**_giqe_inputs()))


def test_edge_terms_kernel_gaussian_closed_form():
    from xbsm.metrics import edge

    # a Gaussian PSF of sigma px has ER = normal CDF, so RER = erf(1 / (2 sqrt(2) sigma))
    nodes, w = quadrature.edge_quadrature(cutoff=4 / IFOV, ifov=IFOV,
                                          **xbsm.method("accurate").edge_quadrature_knobs())
    f = nodes.values
    # (sigma >= 0.45 px: at 0.3 px ER(2.5 ... 3 px) = 1 - 1e-17 ... 1 - 1e-23, whose strict
    # increase, which the EHO rule tests, is below rounding and left to chance)
    sigma = np.array([0.45, 0.6, 0.9])
    otf = np.exp(-2 * np.pi**2 * (sigma[:, None] * IFOV) ** 2 * f**2)
    rer, eho = edge._edge_terms_kernel(otf, w.values, w["sine_frequency"].values, IFOV)
    np.testing.assert_allclose(rer, erf(1 / (2 * np.sqrt(2) * sigma)), atol=1e-6)
    # no overshoot: the response rises monotonically, so EHO is ER(1.25 px) (IBSM Eq. 3-60)
    np.testing.assert_allclose(eho, ndtr(1.25 / sigma), atol=1e-6)


@pytest.mark.parametrize("rer_x", [-0.01, 0.0, np.nan])
def test_giqe5_with_a_nonpositive_slice_is_nan_and_flagged(rer_x):
    # GIQE 5's RER is (max * min^2)^(1/3): squaring the poorer slice would turn the
    # sign of a slice at -0.01 into a finite -4.87 NIIRS (issue 23). The equation is
    # undefined there, as GIQE 3/4's geometric mean is; docs/flags.md says
    # rer_nonpositive is set where either slice is not positive.
    out = metrics.giqe5(rer_x=rer_x, rer_y=0.3, gsd=0.3, snr=20, elevation=np.pi / 2)
    assert np.isnan(float(out.niirs)) and np.isnan(float(out.rer))
    assert int(out.flags) & flags.flag("rer_nonpositive")
    assert bool(flags.is_invalid(out.flags))
    # the order of the slices does not matter
    swapped = metrics.giqe5(rer_x=0.3, rer_y=rer_x, gsd=0.3, snr=20, elevation=np.pi / 2)
    assert np.isnan(float(swapped.niirs))


@pytest.mark.parametrize("filtered_complex", [False, True])
def test_slice_terms_share_one_sine_table_without_changing_a_bit(filtered_complex):
    """With an embedded error rule the filtered and unfiltered OTFs share one sine (and
    cosine) table (issue 22's speed work): every output equals that of the kernel run on
    each OTF alone, to the bit."""
    from xbsm.metrics.edge import _edge_terms_error_kernel, slice_terms_arrays

    rng = np.random.default_rng(5)
    n = 90
    abscissa = np.sort(rng.uniform(1.0, 3e5, (4, n)), axis=-1)
    weights, error = rng.uniform(0.0, 2.0, (4, n)), rng.uniform(-0.1, 0.1, (4, n))
    ifov = rng.uniform(2e-6, 8e-6, (4, 2))
    unfiltered = rng.uniform(0.0, 1.0, (4, n, 2))
    filtered = unfiltered * (1.0 + 0.2j * rng.uniform(-1, 1, (4, n, 2)) if filtered_complex
                             else rng.uniform(0.5, 1.5, (4, n, 2)))
    out = slice_terms_arrays(filtered, unfiltered, weights, abscissa, ifov, "real",
                             error_weights=error)

    def alone(otf):
        return _edge_terms_error_kernel(np.swapaxes(otf, -1, -2), weights[..., None, :],
                                        error[..., None, :], abscissa[..., None, :], ifov)

    rer, eho, *_ = alone(filtered)
    rer_unfiltered = alone(unfiltered)[0]
    assert np.array_equal(out["rer_x"], rer[..., 0]) and np.array_equal(out["rer_y"], rer[..., 1])
    assert np.array_equal(out["eho_x"], eho[..., 0]) and np.array_equal(out["eho_y"], eho[..., 1])
    assert np.array_equal(out["rer_unfiltered_x"], rer_unfiltered[..., 0])
    assert np.array_equal(out["rer_unfiltered_y"], rer_unfiltered[..., 1])
