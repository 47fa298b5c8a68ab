"""xbsm.mrtd: the classic four-bar MRTD from the NETD and the system MTF (issue 25, item 1).

The expected values are recomputed here with numpy from the outputs of xbsm.netd and of
the public OTF stage (the formula written out again, not imported), and checked against
the formula's limits. No published worked MRTD value could be found with the project's
search tools (Holst's and Vollmerhausen & Driggers' books and the NVTherm manual are not
in the stored corpora), so none is compared here.
"""

import math

import dask.array as dsa
import numpy as np
import pytest
import xarray as xr
from hypothesis import given, settings
from hypothesis import strategies as st

import xbsm
from xbsm.examples import INFRARED_CAMERAS
from xbsm.flags import has_flag
from xbsm.otf import system

# the MWIR camera of tests/test_model_netd.py (the 3-5 um, f/4, 15 um pitch)
MWIR = dict(INFRARED_CAMERAS["mwir"])  # xbsm.examples
# a rectangular-pixel LWIR camera, so that the two orientations differ
LWIR = dict(aperture_diameter=0.1, focal_length=0.2, pixel_pitch_x=17e-6,
            pixel_pitch_y=25e-6, wavelength_min=8e-6, wavelength_max=12e-6,
            quantum_efficiency=0.6, optics_transmission=0.8, integration_time=1e-4,
            read_noise=500.0, max_well=2e7, bit_depth=14.0, dark_current=1e6,
            cold_shield_temperature=77.0, cold_filter_temperature=77.0)
LAB = dict(altitude=2.0, ground_range=0.0, visibility=23.0)  # a 2 m path
SCENE = dict(target_temperature=300.0, background_temperature=300.0,
             target_reflectance=0.0, background_reflectance=0.0)
FREQUENCY = np.array([1e2, 1e3, 3e3, 5e3, 6e3, 8e3])  # cycles/rad, below both cutoffs


def independent_mrtd(camera, frequency, snr=2.5, eye=0.1, rate=30.0, aspect=7.0):
    """MRTD by the formula written out in numpy, on xbsm.netd and the public OTF stage."""
    s, sc = xbsm.sensor(**camera), xbsm.scenario(**LAB, **SCENE)
    n = xbsm.netd(s, sc, temperature=300.0)
    f = xr.DataArray(frequency, dims="frequency", coords={"frequency": frequency})
    otf = system.system_components(
        s, sc, f, spectral_weights=system.otf_weights(n.spectral_weights),
        integration_time=n.effective_integration_time,
        slant_range=xbsm.geometry.slant_range(sc.ground_range, sc.altitude),
        method=xbsm.method("accurate"))
    mtf = np.abs(otf.system_unfiltered.transpose("orientation", "frequency").values)
    alpha = camera["pixel_pitch_x"] / camera["focal_length"]
    beta = camera.get("pixel_pitch_y", camera["pixel_pitch_x"]) / camera["focal_length"]
    constant = math.pi ** 2 / (4.0 * math.sqrt(aspect))
    return (constant * snr * float(n.netd_frame) * frequency
            * math.sqrt(alpha * beta / (eye * rate)) / mtf), mtf


def test_the_constant_is_the_classic_one_for_a_staring_detector():
    # pi^2 / (4 sqrt 14) sqrt(1 / (delta_f tau)), integrate-and-dump delta_f tau = 1/2
    classic = math.pi ** 2 / (4.0 * math.sqrt(14.0)) * math.sqrt(1.0 / 0.5)
    assert xbsm.metrics.acquisition.bar_constant() == pytest.approx(classic, rel=1e-15)
    assert classic == pytest.approx(0.93259, abs=1e-5)  # 9.86960 / 10.58301 by hand


@pytest.mark.parametrize("camera", [MWIR, LWIR], ids=["mwir", "lwir"])
def test_mrtd_matches_an_independent_numpy_computation(camera):
    expected, mtf = independent_mrtd(camera, FREQUENCY)
    r = xbsm.mrtd(xbsm.sensor(**camera), xbsm.scenario(**LAB), frequency=FREQUENCY)
    got = r.mrtd.transpose("orientation", "frequency").values
    np.testing.assert_allclose(got, expected, rtol=1e-6)
    np.testing.assert_allclose(r.mtf.transpose("orientation", "frequency").values, mtf,
                               rtol=1e-12)
    assert r.mrtd.attrs["units"] == "K"


def test_knobs_enter_as_the_formula_says():
    expected, _ = independent_mrtd(MWIR, FREQUENCY, snr=2.25, eye=0.2, rate=60.0, aspect=5.0)
    r = xbsm.mrtd(xbsm.sensor(**MWIR), xbsm.scenario(**LAB), frequency=FREQUENCY,
                  snr_threshold=2.25, eye_integration_time=0.2, frame_rate=60.0,
                  bar_aspect=5.0)
    np.testing.assert_allclose(r.mrtd.transpose("orientation", "frequency").values, expected,
                               rtol=1e-6)
    assert r.attrs["snr_threshold"] == 2.25 and r.attrs["bar_aspect"] == 5.0


def test_low_frequency_slope_is_the_netd_times_the_formulas_constant():
    # MRTD / f -> pi^2 / (4 sqrt 7) SNR_th NETD sqrt(alpha beta / (t_e F_R)) as f -> 0
    r = xbsm.mrtd(xbsm.sensor(**MWIR), xbsm.scenario(**LAB), frequency=[0.0, 1e-3])
    netd = float(xbsm.netd(xbsm.sensor(**MWIR), xbsm.scenario(**LAB)).netd_frame)
    ifov = 15e-6 / 0.2
    slope = math.pi ** 2 / (4 * math.sqrt(7)) * 2.5 * netd * ifov / math.sqrt(0.1 * 30.0)
    assert np.all(r.mrtd.sel(frequency=0.0).values == 0.0)
    np.testing.assert_allclose(r.mrtd.sel(frequency=1e-3).values / 1e-3, slope, rtol=1e-6)


@pytest.mark.parametrize("camera", [MWIR, LWIR], ids=["mwir", "lwir"])
def test_mrtd_rises_with_frequency_while_the_mtf_falls(camera):
    # below the first zero of the OTF (the optics cutoff D / lambda_min, or the detector
    # sinc's zero at focal length / pitch) the MTF falls and the MRTD rises; beyond it,
    # wherever the MTF falls the MRTD rises
    cutoff = camera["aperture_diameter"] / camera["wavelength_min"]
    pitch = max(camera["pixel_pitch_x"], camera.get("pixel_pitch_y", 0.0))
    first_zero = min(cutoff, camera["focal_length"] / pitch)
    f = np.linspace(0.0, 0.999 * first_zero, 200)
    r = xbsm.mrtd(xbsm.sensor(**camera), xbsm.scenario(**LAB), frequency=f)
    for o in ("x", "y"):
        mtf = r.mtf.sel(orientation=o).values
        mrtd = r.mrtd.sel(orientation=o).values
        assert (np.diff(mtf) < 0).all()
        assert (np.diff(mrtd) > 0).all()
        assert np.isfinite(mrtd).all()
        assert not has_flag(r.flags.sel(orientation=o), "bars_unresolved").any()
    wide = xbsm.mrtd(xbsm.sensor(**camera), xbsm.scenario(**LAB),
                     frequency=np.linspace(0.0, 0.999 * cutoff, 300))
    falling = (wide.mtf.diff("frequency") < 0).values
    assert falling.any() and (wide.mrtd.diff("frequency").values[falling] > 0).all()


@settings(max_examples=15, deadline=None)
@given(d=st.floats(0.02, 0.2), focal=st.floats(0.1, 0.6), pitch=st.floats(8e-6, 30e-6),
       read=st.floats(10.0, 1000.0))
def test_mrtd_is_finite_rising_and_flagged_right_over_random_cameras(d, focal, pitch, read):
    camera = {**MWIR, "aperture_diameter": d, "focal_length": focal, "pixel_pitch_x": pitch,
              "read_noise": read}
    cutoff, nyquist = d / 3e-6, 0.5 * focal / pitch
    first_zero = min(cutoff, focal / pitch)
    f = np.linspace(0.0, 0.99 * first_zero, 40)
    r = xbsm.mrtd(xbsm.sensor(**camera), xbsm.scenario(**LAB), frequency=f)
    mrtd = r.mrtd.sel(orientation="x").values
    assert np.isfinite(mrtd).all() and (np.diff(mrtd) > 0).all()
    aliased = has_flag(r.flags.sel(orientation="x"), "bars_aliased").values
    np.testing.assert_array_equal(aliased, f > nyquist * (1 + 1e-12))
    assert not has_flag(r.flags, "bars_unresolved").any()


def test_beyond_the_optics_cutoff_mrtd_is_inf_and_flagged():
    cutoff = MWIR["aperture_diameter"] / MWIR["wavelength_min"]  # 16.7 cycles/mrad
    r = xbsm.mrtd(xbsm.sensor(**MWIR), xbsm.scenario(**LAB),
                  frequency=[0.5 * cutoff, 1.01 * cutoff, 2 * cutoff])
    assert np.isfinite(r.mrtd.isel(frequency=0)).all()
    assert np.isinf(r.mrtd.isel(frequency=[1, 2])).all()
    unresolved = has_flag(r.flags, "bars_unresolved")
    assert not unresolved.isel(frequency=0).any() and unresolved.isel(frequency=[1, 2]).all()
    assert xbsm.flags.is_invalid(r.flags.isel(frequency=[1, 2])).all()


def test_bars_above_the_nyquist_frequency_are_flagged_aliased_per_orientation():
    nyquist_x, nyquist_y = 0.5 * 0.2 / 17e-6, 0.5 * 0.2 / 25e-6  # 5882, 4000 cycles/rad
    r = xbsm.mrtd(xbsm.sensor(**LWIR), xbsm.scenario(**LAB), frequency=[3000.0, 5000.0, 6000.0])
    aliased = has_flag(r.flags, "bars_aliased").transpose("orientation", "frequency").values
    assert nyquist_y < 5000.0 < nyquist_x < 6000.0
    np.testing.assert_array_equal(aliased, [[False, False, True], [False, True, True]])


def test_default_grid_ends_at_the_finer_axis_nyquist_frequency():
    r = xbsm.mrtd(xbsm.sensor(**LWIR), xbsm.scenario(**LAB))
    f = r.frequency.values
    assert f.size == 64 and f[0] > 0 and f[-1] == pytest.approx(0.5 * 0.2 / 17e-6, rel=1e-12)
    assert r.frequency.attrs["units"] == "cycles/rad"


def test_mrtd_falls_with_aperture_and_rises_with_read_noise():
    f = [2e3, 5e3]
    d = xr.DataArray([0.03, 0.05, 0.08], dims="d")
    by_d = xbsm.mrtd(xbsm.sensor(**{**MWIR, "aperture_diameter": d}), xbsm.scenario(**LAB),
                     frequency=f).mrtd
    assert (by_d.diff("d") < 0).all()
    rn = xr.DataArray([10.0, 100.0, 1000.0], dims="rn")
    by_rn = xbsm.mrtd(xbsm.sensor(**{**MWIR, "read_noise": rn}), xbsm.scenario(**LAB),
                      frequency=f).mrtd
    assert (by_rn.diff("rn") > 0).all()


def test_sweep_equals_single_scenarios():
    t = [280.0, 320.0]
    rn = xr.DataArray([20.0, 200.0], dims="read")
    swept = xbsm.mrtd(xbsm.sensor(**{**MWIR, "read_noise": rn}), xbsm.scenario(**LAB),
                      frequency=FREQUENCY, temperature=t)
    assert set(swept.mrtd.dims) == {"orientation", "frequency", "read", "temperature"}
    for i, r in enumerate((20.0, 200.0)):
        for j, temperature in enumerate(t):
            one = xbsm.mrtd(xbsm.sensor(**{**MWIR, "read_noise": r}), xbsm.scenario(**LAB),
                            frequency=FREQUENCY, temperature=temperature)
            xr.testing.assert_allclose(swept.mrtd.isel(read=i, temperature=j, drop=True),
                                       one.mrtd, rtol=1e-12)


def test_dask_sweep_stays_lazy(no_compute):
    s = xbsm.sensor(**{**MWIR, "read_noise": xr.DataArray(
        dsa.from_array(np.array([20.0, 200.0]), chunks=1), dims="read")})
    lazy = xbsm.mrtd(s, xbsm.scenario(**LAB), frequency=FREQUENCY)
    assert isinstance(lazy.mrtd.data, dsa.Array)
    assert set(lazy.mrtd.dims) == {"orientation", "frequency", "read"}


def test_a_perfect_reflector_has_infinite_mrtd_and_is_flagged():
    r = xbsm.mrtd(xbsm.sensor(**MWIR), xbsm.scenario(**LAB), frequency=FREQUENCY,
                  reflectance=1.0)
    assert np.isinf(r.mrtd).all()
    assert has_flag(r.flags, "no_thermal_signal").all()


@pytest.mark.parametrize(("kwargs", "message"), [
    ({"snr_threshold": 0.0}, r"snr_threshold must be a real number in \(0, inf\)"),
    ({"eye_integration_time": -0.1}, r"eye_integration_time must be a real number in \(0"),
    ({"frame_rate": 0.0}, r"frame_rate must be a real number in \(0, inf\)"),
    ({"bar_aspect": 0.5}, r"bar_aspect must be a real number in \[1, inf\)"),
    ({"frequency": [1e3, -1.0]}, r"frequency must be in \[0, inf\) cycles/rad"),
    ({"frequency": [np.nan]}, r"frequency must be in \[0, inf\)"),
    ({"temperature": -5.0}, "temperature must lie in"),
    ({"method": "nonsense"}, "method"),
])
def test_bad_input_names_the_parameter_and_range(kwargs, message):
    with pytest.raises(ValueError, match=message):
        xbsm.mrtd(xbsm.sensor(**MWIR), xbsm.scenario(**LAB), **kwargs)


# ---- MRC: the same threshold with the noise-equivalent contrast ------------------------

def _olson(**changes):
    from xbsm.examples import olson_scenario, olson_sensor
    return olson_sensor(), olson_scenario(ground_range=0.0, visibility=23.0, **changes)


def test_mrc_matches_an_independent_numpy_computation():
    s, sc = _olson()
    r = 0.07
    # the scene (reflectance r) against a black surface, through xbsm.snr on the scenario
    pair = sc.assign(target_reflectance=sc.background_reflectance * 0 + r,
                     background_reflectance=sc.background_reflectance * 0)
    n = xbsm.snr(s, pair, targets="scenario")
    nec = float(n.total_noise / n.contrast_photoelectrons)
    f = np.array([1e4, 5e4, 1e5, 2e5])
    fa = xr.DataArray(f, dims="frequency", coords={"frequency": f})
    otf = system.system_components(
        s, pair, fa, spectral_weights=system.otf_weights(n.spectral_weights),
        integration_time=n.effective_integration_time,
        slant_range=xbsm.geometry.slant_range(pair.ground_range, pair.altitude),
        method=xbsm.method("accurate"))
    mtf = np.abs(otf.system_unfiltered.transpose("orientation", "frequency").values)
    ifov = float(s.pixel_pitch_x / s.focal_length)  # square pixels
    expected = (math.pi ** 2 / (4 * math.sqrt(7)) * 2.5 * nec * f * ifov
                / math.sqrt(0.1 * 30.0) / mtf)
    got = xbsm.mrc(s, sc, frequency=f)
    assert float(sc.background_reflectance) == r
    np.testing.assert_allclose(got.mrc.transpose("orientation", "frequency").values,
                               expected, rtol=1e-6)
    assert float(got.noise_equivalent_contrast) == pytest.approx(nec, rel=1e-12)
    assert got.mrc.attrs["units"] == "1"


def test_mrc_reflectance_signal_is_linear_in_reflectance():
    # N(r) - N(0) = r dN/dr: doubling the scene's reflectance doubles it (well not full)
    s, _ = _olson()
    s = s.assign(integration_time=s.integration_time * 0 + 1e-3)  # the well stays below full
    one = xbsm.mrc(s, _olson(background_reflectance=0.1)[1], frequency=[1e4])
    two = xbsm.mrc(s, _olson(background_reflectance=0.2)[1], frequency=[1e4])
    assert not has_flag(one.flags, "well_fill_limited").any()
    assert not has_flag(two.flags, "well_fill_limited").any()
    assert float(two.reflectance_signal) == pytest.approx(2 * float(one.reflectance_signal),
                                                          rel=1e-9)


def test_mrc_falls_with_scene_reflectance():
    s, _ = _olson()
    r = xr.DataArray([0.05, 0.1, 0.3], dims="r")
    out = xbsm.mrc(s, _olson(background_reflectance=r)[1], frequency=[1e4, 1e5])
    assert (out.mrc.diff("r") < 0).all()


def test_mrc_without_reflected_light_is_inf_and_flagged():
    # an LWIR camera looking at a 300 K scene on a 2 m path: a black surface at the same
    # temperature emits more than the scene reflects, so there is no reflective contrast
    sc = xbsm.scenario(**LAB, background_reflectance=0.3, background_temperature=300.0)
    out = xbsm.mrc(xbsm.sensor(**LWIR), sc, frequency=FREQUENCY)
    assert np.isinf(out.mrc).all()
    assert has_flag(out.flags, "no_reflective_signal").all()


def test_mrc_dask_sweep_stays_lazy(no_compute):
    s, sc = _olson()
    s = s.assign(read_noise=xr.DataArray(dsa.from_array(np.array([20.0, 200.0]), chunks=1),
                                         dims="read").assign_attrs(s.read_noise.attrs))
    lazy = xbsm.mrc(s, sc, frequency=[1e4, 1e5])
    assert isinstance(lazy.mrc.data, dsa.Array)
    assert {"orientation", "frequency", "read"} <= set(lazy.mrc.dims)


@pytest.mark.parametrize(("kwargs", "message"), [
    ({"snr_threshold": -1.0}, r"snr_threshold must be a real number in \(0, inf\)"),
    ({"frequency": [-5.0]}, r"frequency must be in \[0, inf\)"),
])
def test_mrc_bad_input_names_the_parameter_and_range(kwargs, message):
    s, sc = _olson()
    with pytest.raises(ValueError, match=message):
        xbsm.mrc(s, sc, **kwargs)
