"""Wavefront OTFs: random phase screen (IBSM 3-31) and Shannon's form."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr
from otf_helpers import check_lazy, polar

from xbsm.otf.wavefront import random_phase_wavefront, shannon_wavefront

ONE = xr.DataArray([[1.0]], dims=("fy", "fx"))
D, LAM = 0.275, 0.5e-6


def test_random_phase_reference_case_18():
    # pybsm_test_cases.md C-18 [T]: wavefront_OTF(u=[[1]], v=[[1]], lambda0=1, pv=1, L_x=1,
    # L_y=1) = exp(-(1 - exp(-2)))
    np.testing.assert_allclose(
        random_phase_wavefront(ONE, ONE, 1.0, 1.0, 1.0, 1.0), [[0.42119274782353533]], rtol=1e-13
    )


def test_random_phase_limits_and_wavelength_scaling():
    fx, fy = polar(np.linspace(0, D / LAM, 21))
    wl = xr.DataArray([0.5e-6, 1e-6], dims="wavelength")
    pv = (2 * np.pi * 0.05) ** 2
    out = random_phase_wavefront(fx, fy, wl, pv, D, D, phase_variance_wavelength=0.633e-6)
    np.testing.assert_allclose(out.isel(frequency=0), 1.0)
    assert float(out.max()) <= 1.0
    # The floor exp(-pv (lambda_pv / lambda)^2) is reached at high frequency.
    floor = np.exp(-pv * (0.633e-6 / wl) ** 2)
    far = random_phase_wavefront(1e12 * ONE, 0 * ONE, wl, pv, D, D, 0.633e-6).squeeze()
    np.testing.assert_allclose(far, floor, rtol=1e-14)
    assert float(random_phase_wavefront(fx, fy, wl, 0.0, D, D).min()) == 1.0


def test_shannon_clipped_is_bounded_and_one_beyond_cutoff():
    fx, fy = polar(np.linspace(0, 2 * D / LAM, 41))
    out = shannon_wavefront(fx, fy, LAM, D, xr.DataArray([0.0, 0.1, 0.18], dims="w"))
    # in [0, 1] to within rounding: at 0.18 waves rms and half the cutoff the OTF is 0 exactly
    # in arithmetic, so its computed sign is rounding
    assert float(out.min()) >= -1e-14 and float(out.max()) <= 1.0 + 1e-14
    beyond = np.hypot(fx, fy) >= D / LAM
    np.testing.assert_allclose(out.where(beyond).dropna("frequency", how="all"), 1.0)
    # at nu = 0.5 the loss is (W/0.18)^2
    mid = shannon_wavefront(0.5 * D / LAM * ONE, 0 * ONE, LAM, D, 0.09)
    np.testing.assert_allclose(mid, [[0.75]], rtol=1e-14)
    unclipped = shannon_wavefront(2 * D / LAM * ONE, 0 * ONE, LAM, D, 0.1, clip=False)
    assert unclipped.item() > 1.0  # pyBSM's parabola keeps growing past the cutoff


def test_dask_stays_lazy():
    fx, fy = polar(np.linspace(0, D / LAM, 20))
    check_lazy(
        random_phase_wavefront, (fx.chunk(5), fy.chunk(5), LAM, 0.1, D, D), (fx, fy, LAM, 0.1, D, D)
    )
    check_lazy(shannon_wavefront, (fx.chunk(5), fy.chunk(5), LAM, D, 0.1), (fx, fy, LAM, D, 0.1))


@pytest.mark.parametrize(
    ("call", "name"),
    [
        (lambda: random_phase_wavefront(ONE, ONE, LAM, -0.1, D, D), "phase_variance"),
        (lambda: random_phase_wavefront(ONE, ONE, LAM, 0.1, 0.0, D), "correlation_length_x"),
        (lambda: random_phase_wavefront(ONE, ONE, LAM, 0.1, D, D, -1.0), "phase_variance_wave"),
        (lambda: shannon_wavefront(ONE, ONE, LAM, D, 0.25), "rms_wavefront_error"),
        (lambda: shannon_wavefront(ONE, ONE, 0.0, D, 0.1), "wavelength"),
    ],
)
def test_impossible_input_raises(call, name):
    with pytest.raises(ValueError, match=name):
        call()
