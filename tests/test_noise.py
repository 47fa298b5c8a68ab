import numpy as np
import pytest
import xarray as xr

from xbsm import noise


def test_quantization_noise_reference():
    # pybsm_test_cases.md D26: quantization_noise(pe_range=1, bit_depth=1) = 1/sqrt(12)
    assert noise.quantization_noise(1.0, 1.0) == pytest.approx(0.2886751345948129, rel=1e-15)


def test_noise_gain_reference():
    # pybsm_test_cases.md D26: noise_gain([[0.5],[0.5]]) = sqrt(0.5)
    k = xr.DataArray([[0.5], [0.5]], dims=("kernel_y", "kernel_x"))
    assert float(noise.noise_gain(k)) == pytest.approx(0.7071067811865476, rel=1e-15)


def test_noise_gain_of_identity_is_one():
    k = xr.DataArray([[1.0]], dims=("kernel_y", "kernel_x"))
    assert float(noise.noise_gain(k)) == 1.0


def test_total_noise_is_root_sum_square():
    assert float(noise.total_noise(xr.DataArray(9.0), 4.0, 12.0, 0.0)) == pytest.approx(13.0)


def test_stacking_grows_snr_as_square_root():
    assert float(noise.stacked_snr(xr.DataArray(3.0), 16)) == 12.0


def test_dark_current_noise_counts_every_tdi_stage():
    assert noise.dark_current_noise(100.0, 0.01, 4) == pytest.approx(np.sqrt(4.0))
