import dask
import dask.array
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


# ------------------------------------------------ NumPy kernels and the Dataset they fill


def test_snr_and_scene_kernels_on_plain_arrays():
    # hand calculation: brighter of 144 and 100 e-, quantization 3 e- (well 3 sqrt(12) over a
    # 1-bit ADC), read 4 e-: total sqrt(144 + 9 + 16) = 13; contrast 26 -> SNR 2, 4 frames -> 4
    well = 3 * np.sqrt(12)
    args = (np.array([26.0, 13.0]), 144.0, 100.0, well, 1.0, 4.0, 0.0)
    np.testing.assert_allclose(noise._snr_frame_kernel(*args), [2.0, 1.0], rtol=1e-15)
    np.testing.assert_allclose(noise._snr_kernel(4.0, *args), [4.0, 2.0], rtol=1e-15)
    # scene and path rates 25 and 16 e-/s over 0.5 s x 2 TDI stages: sqrt(5^2 - 4^2) = 3
    assert noise._scene_noise_kernel(25.0, 0.5, 2.0, 9.0, 16.0) == pytest.approx(3.0, rel=1e-15)


def _noise_inputs(chunks=None):
    case = xr.DataArray([1.0, 2.0, 3.0], dims="case")
    signal = xr.Dataset({
        "effective_integration_time": 0.5 * case / case, "target_photoelectrons": 144.0 * case,
        "background_photoelectrons": 100.0 * case, "contrast_photoelectrons": 26.0 * case,
        "path_rate": 16.0 * case, "target_scene_rate": 25.0 * case,
        "background_scene_rate": 9.0 * case, "sensor_rate": 4.0 * case,
    })
    sensor = xr.Dataset({
        "tdi_stages": 2.0, "max_well": 3 * np.sqrt(12), "bit_depth": 1.0, "read_noise": 4.0,
        "other_noise": 0.0, "dark_current": 100.0,
        "frame_stacks": xr.DataArray([1.0, 4.0], dims="frame_stacks"),
    })
    return (signal.chunk({"case": chunks}) if chunks else signal), sensor


def test_noise_terms_keep_each_term_on_the_dims_it_depends_on():
    out = noise.noise_terms(*_noise_inputs())
    # only the stacked SNR depends on the frame-stacking sweep; quantization on the sensor
    assert set(out.snr.dims) == {"case", "frame_stacks"}
    assert out.snr_frame.dims == out.total_noise.dims == ("case",)
    assert out.quantization_noise.dims == ()
    # hand calculation as above, case 1: total 13, SNR 2 (x sqrt(4) = 4 with 4 frames);
    # dark current 100 e-/s over 0.5 s x 2 stages: sqrt(100) = 10; scene 3; path 4
    first = out.isel(case=0)
    assert float(first.total_noise) == pytest.approx(13.0, rel=1e-15)
    assert first.snr.values.tolist() == pytest.approx([2.0, 4.0], rel=1e-15)
    assert float(first.dark_current_noise) == pytest.approx(10.0, rel=1e-15)
    assert float(first.scene_noise) == pytest.approx(3.0, rel=1e-15)
    assert float(first.path_noise) == pytest.approx(4.0, rel=1e-15)
    assert all(out[name].attrs["units"] == "count" for name in out if "noise" in name)


def test_noise_terms_dask_equals_eager_and_stays_lazy(no_compute):
    lazy = noise.noise_terms(*_noise_inputs(chunks=1))
    for name in ("snr", "snr_frame", "shot_noise", "scene_noise", "total_noise"):
        assert isinstance(lazy[name].data, dask.array.Array), name
    with dask.config.set(scheduler="sync"):
        xr.testing.assert_identical(lazy.compute(), noise.noise_terms(*_noise_inputs()))


# --- self-emission and stray light by source (issue 21 item 8) -------------------------------

# An MWIR camera with every source of its own irradiance set; max_well large enough that no
# configuration below is well-fill limited (the integration time is the same in every run)
MWIR = dict(aperture_diameter=0.2, focal_length=1.0, pixel_pitch_x=15e-6,
            wavelength_min=3e-6, wavelength_max=5e-6, integration_time=1e-3, max_well=1e9,
            cold_shield_temperature=200.0, optics_temperature=290.0, optics_emissivity=0.1,
            cold_filter_transmission=0.9, cold_filter_temperature=150.0,
            cold_filter_emissivity=0.1, stray_irradiance=1e-3)
# each source alone (the others off; a 1 K cold shield emits nothing at 3-5 um in float64)
ALONE = {
    "cold_shield_noise": dict(optics_emissivity=0.0, cold_filter_emissivity=0.0,
                              stray_irradiance=0.0),
    "optics_emission_noise": dict(cold_shield_temperature=1.0, cold_filter_emissivity=0.0,
                                  stray_irradiance=0.0),
    "cold_filter_emission_noise": dict(cold_shield_temperature=1.0, optics_emissivity=0.0,
                                       stray_irradiance=0.0),
    "stray_light_noise": dict(cold_shield_temperature=1.0, optics_emissivity=0.0,
                              cold_filter_emissivity=0.0),
}


def _snr(**overrides):
    import xbsm

    sensor = xbsm.sensor(**{**MWIR, **overrides})
    scenario = xbsm.scenario(altitude=3000.0, ground_range=5000.0, visibility=23.0)
    return sensor, xbsm.snr(sensor, scenario)


def test_self_emission_split_equals_each_source_alone():
    # Poisson variances add: each source's term equals the self-emission noise the model
    # gives with that source alone (xbsm.snr, same integration time)
    sensor, r = _snr()
    terms = noise.self_emission_noise_terms(r.self_emission_noise, sensor, r.wavelength)
    assert set(terms.data_vars) == set(noise.SELF_EMISSION_SOURCES)
    for name, off in ALONE.items():
        _, alone = _snr(**off)
        assert float(alone.effective_integration_time) == float(r.effective_integration_time)
        assert float(terms[name]) == pytest.approx(float(alone.self_emission_noise), rel=1e-9)
        assert float(terms[name]) > 0
    # and they add in quadrature to the total
    total = np.sqrt(sum(float(terms[name]) ** 2 for name in terms.data_vars))
    assert total == pytest.approx(float(r.self_emission_noise), rel=1e-12)


def test_self_emission_split_of_a_source_that_is_off_is_zero():
    sensor, r = _snr(stray_irradiance=0.0)
    terms = noise.self_emission_noise_terms(r.self_emission_noise, sensor, r.wavelength)
    assert float(terms.stray_light_noise) == 0.0
    assert float(terms.cold_shield_noise) > 0
