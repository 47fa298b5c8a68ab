"""Turbulence: Hufnagel-Valley, coherence diameter, OTFs (IBSM 3-3, 3-9)."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr
from otf_helpers import check_lazy, polar

from xbsm.otf import turbulence as t

ONE = xr.DataArray([[1.0]], dims=("fy", "fx"))


def test_path_coherence_diameter_reference_case_13():
    # pybsm_test_cases.md C-13 [T]: coherence_diameter(lambda0=1, z_path=[1,2], cn2=[1]) and
    # z_path=[1,2,3]; pyBSM broadcasts the one-element cn2 along the path.
    for z, expected in (([1.0, 2.0], 0.23749058343491444), ([1.0, 2.0, 3.0], 0.17546491199555045)):
        cn2 = xr.DataArray(np.ones(len(z)), dims="path", coords={"path": z})
        out = t.path_coherence_diameter(cn2, wavelength=1.0)
        assert float(out) == pytest.approx(expected, rel=1e-14)


def test_hufnagel_valley_reference_case_14():
    # pybsm_test_cases.md C-14 [T]: (h=[1], v=0, cn2_at_1m=1) and (h=[1], v=1, cn2_at_1m=0)
    assert t.hufnagel_valley(1.0, 0.0, 1.0) == pytest.approx(0.9900498337491683, rel=1e-13)
    assert t.hufnagel_valley(1.0, 1.0, 0.0) == pytest.approx(2.698200599866689e-16, rel=1e-13)


@pytest.mark.parametrize(
    ("value", "otf", "r0_band"),
    [
        # pybsm_test_cases.md C-15 [T]: every argument 1.
        (1.0, 2.7466560073027004e-09, 0.3340840371124818),
        # "every argument set to 2": the quoted (4.5961070493442145e-49, 0.14605390401093207)
        # is not what pyBSM 0.16.1 returns for that call; rerun with pyBSM 0.16.1 it gives
        # (2.0919906566378523e-54, 0.33554375855650503) [C], used here. (0.14605 is the r0_band of
        # the same call with wavelengths=[1]; its OTF, 3.6e-104, matches neither.)
        (2.0, 2.0919906566378523e-54, 0.33554375855650503),
    ],
)
def test_polychromatic_turbulence_reference_case_15(value, otf, r0_band):
    # pyBSM takes (altitude, slant_range, ...) and integrates r0 itself with a 10000-sample
    # trapezoid; here that is slant_path_coherence_diameter(rule="trapezoid").
    v = value
    wl = xr.DataArray([v], dims="wavelength")
    r0 = t.slant_path_coherence_diameter(
        v, v, high_altitude_wind_speed=v, cn2_at_1m=v, path_samples=10000, rule="trapezoid"
    )
    band = t.band_coherence_diameter(r0, wl, xr.DataArray([v], dims="wavelength"))
    assert float(band) == pytest.approx(r0_band, rel=1e-12)
    out = t.polychromatic_turbulence(
        v * ONE, v * ONE, wl, xr.DataArray([v], dims="wavelength"), v, r0, v, v
    )
    np.testing.assert_allclose(out, [[otf]], rtol=1e-12)


def test_wind_blended_reference_case_16():
    # pybsm_test_cases.md C-16 [T]: wind_speed_turbulence_OTF(u=[[1,1]], v=[[1,1]], lambda0=1,
    # D=1, r0=1, t_d=1, vel=1) = 0.02636412049677297 (both elements)
    one = xr.DataArray([[1.0, 1.0]], dims=("fy", "fx"))
    out = t.wind_blended_turbulence(one, one, 1.0, 1.0, 1.0, 1.0, 1.0)
    np.testing.assert_allclose(out, [[0.02636412049677297] * 2], rtol=1e-14)


SCENARIOS = [(9000.0, 9000.0), (9000.0, 21944.57), (1000.0, 30000.0), (20000.0, 300000.0)]


def test_gauss_legendre_r0_is_converged():
    # Reference: a 10^6-sample trapezoid (error ~3e-13 by comparison with 2000 Gauss nodes).
    alt = xr.DataArray([a for a, _ in SCENARIOS], dims="scenario")
    rng = xr.DataArray([r for _, r in SCENARIOS], dims="scenario")
    fine = t.slant_path_coherence_diameter(rng, alt, path_samples=1_000_000, rule="trapezoid")
    default = t.slant_path_coherence_diameter(rng, alt)
    pybsm_like = t.slant_path_coherence_diameter(rng, alt, path_samples=10000, rule="trapezoid")
    np.testing.assert_allclose(default, fine, rtol=5e-12)
    err = np.abs(pybsm_like / fine - 1)
    assert float(err.max()) < 1e-8  # pyBSM's 10000-sample trapezoid: ~3e-9


def test_r0_scales_as_wavelength_to_six_fifths_and_matches_direct_integration():
    wl = xr.DataArray([0.5e-6, 1e-6, 4e-6], dims="wavelength")
    wl = wl.assign_coords(wavelength=wl.values)
    direct = t.slant_path_coherence_diameter(20000.0, 9000.0, wavelength=wl)
    scaled = t.scale_coherence_diameter(t.slant_path_coherence_diameter(20000.0, 9000.0), wl)
    xr.testing.assert_allclose(direct, scaled, rtol=1e-14)
    assert float(scaled.sel(wavelength=4e-6) / scaled.sel(wavelength=1e-6)) == pytest.approx(4**1.2)


def test_r0_broadcasts_over_scenario_dims_only():
    alt = xr.DataArray([3000.0, 9000.0], dims="altitude")
    rng = xr.DataArray([10000.0, 20000.0, 40000.0], dims="ground")
    out = t.slant_path_coherence_diameter(
        rng, alt, cn2_at_1m=xr.DataArray([1e-15, 1e-14], dims="c")
    )
    assert set(out.dims) == {"altitude", "ground", "c"}
    assert out.attrs["units"] == "m"
    # Stronger ground turbulence and longer paths both shrink r0.
    assert bool((out.sel(c=0) > out.sel(c=1)).all())
    assert bool((out.diff("ground") < 0).all())


def test_turbulence_otf_limits():
    fx, fy = polar(np.linspace(0, 0.275 / 0.5e-6, 30))
    r0 = xr.DataArray([0.05, 0.2], dims="r0")
    long = t.turbulence(fx, fy, 0.5e-6, 0.275, r0, 0.0)
    short = t.turbulence(fx, fy, 0.5e-6, 0.275, r0, 0.5)
    np.testing.assert_allclose(long.isel(frequency=0), 1.0)
    assert float(long.max()) <= 1.0
    # orderings to within rounding (values in [0, 1]; both are exp(0) = 1 at f = 0)
    assert bool((short >= long - 1e-14).all())
    assert bool((long.diff("frequency") <= 1e-14).all())
    blend = t.wind_blended_turbulence(fx, fy, 0.5e-6, 0.275, r0, 0.01, 0.0)
    xr.testing.assert_allclose(blend, short)  # no wind: short exposure
    blend = t.wind_blended_turbulence(fx, fy, 0.5e-6, 0.275, r0, 1e3, 1e3)
    xr.testing.assert_allclose(blend, long)  # long dwell: long exposure
    mid = t.wind_blended_turbulence(fx, fy, 0.5e-6, 0.275, r0, 0.01, 5.0)
    assert bool(((mid >= long - 1e-15) & (mid <= short + 1e-15)).all())


def test_polychromatic_turbulence_is_the_weighted_mean():
    fx, fy = polar(np.linspace(0, 5e5, 8))
    wl = xr.DataArray([0.5e-6, 0.6e-6, 0.7e-6], dims="wavelength")
    w = xr.DataArray([1.0, 2.0, 1.0], dims="wavelength")
    out = t.polychromatic_turbulence(fx, fy, wl, w, 0.275, 0.1, 0.01, 50.0)
    r0 = t.scale_coherence_diameter(0.1, wl)
    mono = t.wind_blended_turbulence(fx, fy, wl, 0.275, r0, 0.01, 50.0)
    xr.testing.assert_allclose(out, (mono * w).sum("wavelength") / 4.0, rtol=1e-14)


def test_dask_stays_lazy():
    fx, fy = polar(np.linspace(0, 5e5, 20))
    r0 = xr.DataArray([0.05, 0.1], dims="r0")
    lazy = (fx.chunk(5), fy.chunk(5), 0.5e-6, 0.275, r0)
    check_lazy(t.turbulence, (*lazy, 0.5), (fx, fy, 0.5e-6, 0.275, r0, 0.5))
    check_lazy(
        t.wind_blended_turbulence, (*lazy, 0.01, 5.0), (fx, fy, 0.5e-6, 0.275, r0, 0.01, 5.0)
    )


def test_slant_path_r0_with_dask_scenario_stays_lazy():
    rng = xr.DataArray([9000.0, 20000.0, 50000.0], dims="range")
    check_lazy(t.slant_path_coherence_diameter, (rng.chunk(1), 9000.0), (rng, 9000.0))


@pytest.mark.parametrize(
    ("call", "name"),
    [
        (lambda: t.hufnagel_valley(10.0, 21.0, -1e-14), "cn2_at_1m"),
        (lambda: t.slant_path_coherence_diameter(0.0, 9000.0), "slant_range"),
        (lambda: t.slant_path_coherence_diameter(1e4, 9e3, rule="simpson"), "rule"),
        (lambda: t.slant_path_coherence_diameter(1e4, 9e3, path_samples=1), "path_samples"),
        (lambda: t.scale_coherence_diameter(0.0, 1e-6), "coherence_diameter"),
        (lambda: t.turbulence(ONE, ONE, 1e-6, 0.1, 0.05, 1.5), "exposure_coefficient"),
        (lambda: t.turbulence(ONE, ONE, 1e-6, 0.1, -0.05), "coherence_diameter"),
        (lambda: t.wind_blended_turbulence(ONE, ONE, 1e-6, 0.1, 0.05, -1, 1), "integration_time"),
    ],
)
def test_impossible_input_raises(call, name):
    with pytest.raises(ValueError, match=name):
        call()


@pytest.mark.parametrize("block, step", [(2**6, 2**6), (2**11, 2**14), (2**30, 2**8),
                                         (2**30, 2**30)])
def test_polychromatic_kernel_values_do_not_depend_on_the_block(monkeypatch, block, step):
    """The kernel evaluates cache-sized blocks (wavelength outermost, issue 22's speed
    work) and sums each value in band order: every block size gives the same bits, on one
    scenario and on a sweep with weights of its own per scenario."""
    rng = np.random.default_rng(3)
    wl = np.linspace(0.6e-6, 0.9e-6, 31)
    cases = [
        (np.sort(rng.uniform(0, 3e5, 300)), np.float64(0.05), 0.01, 100.0, 0.2, 1e-6, wl,
         rng.uniform(0.2, 1.0, 31)),
        (rng.uniform(0, 3e5, (50, 1)), rng.uniform(0.01, 0.2, 40), rng.uniform(1e-3, 3e-2, 40),
         100.0, 0.2, 1e-6, wl, rng.uniform(0.0, 1.0, (40, 31))),
        (rng.uniform(0, 3e5, (50, 7)), np.float64(0.08), 0.02, 100.0, rng.uniform(0.1, 0.5, 7),
         1e-6, wl, rng.uniform(0.0, 1.0, (7, 31))),
    ]
    reference = [t.polychromatic_kernel(*case) for case in cases]  # the module's own block
    monkeypatch.setattr(t, "_BLOCK", block)
    monkeypatch.setattr(t, "_STEP", step)
    for case, expected in zip(cases, reference, strict=True):
        got = t.polychromatic_kernel(*case)
        assert got.shape == expected.shape
        assert np.array_equal(got, expected)


@pytest.mark.parametrize("block", [2**6, 2**11, 2**15])
def test_polychromatic_kernel_sums_shared_scenarios_as_matrix_products(monkeypatch, block):
    """Where only the exposure, the wind or the weights vary along an axis (an
    integration-time or visibility sweep), a block's sums over the wavelength are matrix
    products (``_shared_sums``); they equal the multiply-add per wavelength to a few ulp
    (the products add in BLAS's order), on a sweep alone, crossed with a varying r0 (a
    product per r0), and with weights that vary along both."""
    rng = np.random.default_rng(5)
    wl = np.linspace(0.6e-6, 0.9e-6, 31)
    nodes = np.sort(rng.uniform(0, 3e5, 195))
    exposure = rng.uniform(1e-3, 3e-2, (40, 1, 1))  # shared: the exponentials' axis of 40
    cases = [
        (nodes, np.float64(0.05), exposure[:, 0], 100.0, 0.2, 1e-6, wl, rng.uniform(0.2, 1, 31)),
        (nodes, rng.uniform(0.01, 0.2, (7, 1)), exposure, 100.0, 0.2, 1e-6, wl,
         rng.uniform(0.2, 1.0, 31)),
        (nodes, rng.uniform(0.01, 0.2, (7, 1)), exposure, rng.uniform(50, 200, (40, 1, 1)), 0.2,
         1e-6, wl, rng.uniform(0.0, 1.0, (40, 7, 1, 31))),
    ]
    monkeypatch.setattr(t, "_BLOCK", block)
    for case in cases:
        products = t.polychromatic_kernel(*case)
        monkeypatch.setattr(t, "_SHARED_ROWS", 10**9)  # every block by multiply-adds
        expected = t.polychromatic_kernel(*case)
        monkeypatch.setattr(t, "_SHARED_ROWS", 4)
        assert products.shape == expected.shape
        # atol: the OTF's tail (as the closed-form test of the kernel)
        np.testing.assert_allclose(products, expected, rtol=1e-14, atol=1e-16)
