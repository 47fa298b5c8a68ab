"""Motion OTFs: jitter (IBSM 3-28), drift (3-29), TDI (3-38)."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr
from otf_helpers import check_lazy, polar

from xbsm.otf.motion import drift, drift_kernel, drift_slices_kernel, jitter, tdi

ONE = xr.DataArray([[1.0]], dims=("fy", "fx"))


def test_jitter_reference_case_17():
    # pybsm_test_cases.md C-17 [T]: jitter_OTF(u=[[1]], v=[[1]], s_x=1, s_y=0) = exp(-2 pi^2)
    np.testing.assert_allclose(jitter(ONE, ONE, 1.0, 0.0), [[2.675287991074243e-09]], rtol=1e-13)


def test_drift_reference_case_19_keeps_the_negative_lobe():
    # pybsm_test_cases.md C-19 [T]: drift_OTF(u=[[1]], v=[[1]], a_x=0, a_y=1.07)
    np.testing.assert_allclose(drift(ONE, ONE, 0.0, 1.07), [[-0.06489453302868843]], rtol=1e-14)


def test_tdi_reference_case_21_adapted():
    # pybsm_test_cases.md C-21 [T]: tdi_OTF(u_or_v=[1], w=1000, n_tdi=0.5, phases_n=1, beta=30,
    # f=1000) = 1.996346594741599. pyBSM sums np.arange(0.5) = [0] (one term) and divides by
    # 0.5, so its OTF(0) is 2. With one stage the same single term gives half of it.
    out = tdi(xr.DataArray([1.0]), 1000.0, 1000.0, stages=1, rate_ratio=30.0, phases=1)
    np.testing.assert_allclose(out, [1.996346594741599 / 2], rtol=1e-13)
    with pytest.raises(ValueError, match="stages"):
        tdi(xr.DataArray([1.0]), 1000.0, 1000.0, stages=0.5, rate_ratio=30.0)


def test_tdi_closed_form_equals_direct_sum_including_integer_crossings():
    f = xr.DataArray(np.linspace(-4e6, 4e6, 801), dims="frequency")
    stages = xr.DataArray([1, 2, 4, 16], dims="stages").assign_coords(stages=[1, 2, 4, 16])
    beta = xr.DataArray([0.5, 0.9, 1.0, 1.05, 2.0], dims="ratio")
    beta = beta.assign_coords(ratio=beta.values)
    out = tdi(f, 8e-6, 4.0, stages, beta, phases=2)
    for s in stages.values:
        for b in beta.values:
            x = 8e-6 * f.values / (4.0 * b)
            m = 2 * s
            direct = np.sinc(x) * np.exp(-2j * np.pi * np.outer(x * (b - 1), np.arange(m))).mean(1)
            np.testing.assert_allclose(out.sel(stages=s, ratio=b), direct, atol=1e-13)


def test_tdi_is_one_at_zero_and_bounded():
    f = xr.DataArray(np.linspace(0, 1e6, 101), dims="frequency")
    out = tdi(f, 8e-6, 4.0, 8, 1.1)
    assert out.dtype.kind == "c"
    assert complex(out[0]) == 1.0
    assert float(np.abs(out).max()) <= 1.0 + 1e-15


def test_jitter_and_drift_limits_and_sweeps():
    fx, fy = polar(np.linspace(0, 1e6, 11))
    s = xr.DataArray([0.0, 1e-6], dims="jitter")
    out = jitter(fx, fy, s, 0.5e-6)
    assert set(out.dims) == {"frequency", "orientation", "jitter"}
    np.testing.assert_allclose(out.isel(frequency=0), 1.0)
    assert float(out.max()) <= 1.0
    d = drift(fx, fy, xr.DataArray([1e-6, -1e-6], dims="d"), 0.0)
    xr.testing.assert_allclose(d.isel(d=0, drop=True), d.isel(d=1, drop=True))
    assert d.attrs["long_name"] == "Blur OTF of constant line-of-sight drift during one integration"


def test_drift_on_the_slices_is_the_two_axis_kernel_on_them_to_the_bit():
    # the x slice is (fx, fy) = (f, 0) and the y slice (0, f): each other-axis factor is
    # sinc(0) = 1 exactly, so the one-sinc-per-slice kernel must give the same bits
    rng = np.random.default_rng(7)
    f = np.concatenate([[0.0], rng.uniform(0.0, 2e6, 300)])
    for drift_x, drift_y in [(3e-6, 0.0), (0.0, 7e-6), (rng.uniform(0, 1e-5, (4, 1)), 2.5e-6),
                             (np.zeros((3, 1)), np.zeros((3, 1)))]:
        slices = drift_slices_kernel(np.asarray(drift_x), np.asarray(drift_y), f)
        for k, (ux, uy) in enumerate([(1.0, 0.0), (0.0, 1.0)]):
            expected = drift_kernel(np.asarray(drift_x), f * ux, np.asarray(drift_y), f * uy)
            np.testing.assert_array_equal(slices[..., k], np.broadcast_to(expected,
                                                                          slices.shape[:-1]))


@pytest.mark.parametrize("layout", ["scenarios first", "frequency first", "two sweep axes"])
def test_drift_evaluated_once_per_distinct_value_is_the_same_to_the_bit(layout):
    # a sweep's scenarios share few exposures: their sincs are evaluated once per value
    # and gathered; each scenario alone (a scalar drift, evaluated directly) is the check
    rng = np.random.default_rng(11)
    f = np.concatenate([[0.0], rng.uniform(0.0, 2e6, 120)])
    values = np.array([0.0, -0.0, 1e-6, -1e-6, 3.3e-6, 5e-7, np.nan])
    drift_x, fx = {
        "scenarios first": (rng.choice(values, (500, 1)), f),
        "frequency first": (rng.choice(values, (1, 400)), f[:, None]),
        "two sweep axes": (rng.choice(values, (30, 1, 20)), f[:, None])}[layout]
    out = drift_kernel(drift_x, fx, 0.0, 0.0)
    assert out.shape == np.broadcast_shapes(drift_x.shape, fx.shape)
    for index in np.ndindex(drift_x.shape):
        alone = drift_kernel(drift_x[index], fx, 0.0, 0.0)  # scalar: evaluated directly
        got = out[tuple(i if n > 1 else slice(None) for i, n in zip(index, drift_x.shape,
                                                                    strict=True))]
        np.testing.assert_array_equal(got, alone.reshape(got.shape))


def test_dask_stays_lazy():
    fx, fy = polar(np.linspace(0, 1e6, 20))
    lazy = (fx.chunk(5), fy.chunk(5))
    check_lazy(jitter, (*lazy, 1e-6, 2e-6), (fx, fy, 1e-6, 2e-6))
    check_lazy(drift, (*lazy, 1e-6, 2e-6), (fx, fy, 1e-6, 2e-6))
    stages = xr.DataArray([1, 4], dims="stages")
    check_lazy(tdi, (lazy[0], 8e-6, 4.0, stages, 1.1), (fx, 8e-6, 4.0, stages, 1.1))


@pytest.mark.parametrize(
    ("call", "name"),
    [
        (lambda f: jitter(f, f, -1e-6, 0.0), "jitter_rms_x"),
        (lambda f: drift(f, f, 0.0, np.inf), "drift_y"),
        (lambda f: tdi(f, 8e-6, 4.0, 4, 0.0), "rate_ratio"),
        (lambda f: tdi(f, 8e-6, 4.0, 0, 1.0), "stages"),
        (lambda f: tdi(f, -8e-6, 4.0, 4, 1.0), "detector_width"),
    ],
)
def test_impossible_input_raises(call, name):
    with pytest.raises(ValueError, match=name):
        call(xr.DataArray([0.0]))
