import numpy as np
import pytest
import scipy.constants as sc
import xarray as xr

from xbsm import radiometry
from xbsm.constants import PYBSM_CODATA_2014


def test_planck_reference_value():
    # pybsm_test_cases.md D24: blackbody_radiance(lambda0=1 m, T=1) with pyBSM's constants
    value = radiometry.blackbody_radiance(1.0, 1.0, PYBSM_CODATA_2014)
    assert value == pytest.approx(8.218750924575625e-15, rel=1e-13)


def test_planck_band_integral_is_stefan_boltzmann_over_pi():
    # analytic limit: integral of B over all wavelengths = sigma T^4 / pi
    t = 300.0
    wl = xr.DataArray(np.geomspace(0.5e-6, 5e-3, 200001), dims="wavelength")
    wl = wl.assign_coords(wavelength=wl)
    total = radiometry.band_integral(radiometry.blackbody_radiance(wl, t))
    assert float(total) == pytest.approx(sc.Stefan_Boltzmann * t**4 / np.pi, rel=1e-6)


def test_planck_underflows_to_zero_without_warning():
    # pyBSM's exp overflows (with a warning) when lambda*T < ~20 um K; ours underflows cleanly
    wl = xr.DataArray([0.3e-6, 1e-6], dims="wavelength")
    out = radiometry.blackbody_radiance(wl, 10.0)
    # exactly 0: the true value, ~1e-2083, is far below the smallest subnormal double
    assert np.all(np.isfinite(out)) and float(out[0]) == 0.0


def test_planck_peak_follows_wien():
    wl = xr.DataArray(np.linspace(5e-6, 15e-6, 100001), dims="wavelength")
    peak = float(wl[int(radiometry.blackbody_radiance(wl, 300.0).argmax("wavelength"))])
    assert peak == pytest.approx(sc.Wien / 300.0, rel=1e-4)


def test_focal_plane_irradiance_reference():
    # pybsm_test_cases.md D23: at_focal_plane_irradiance(D=1, f=1, L=[1]) = pi / 5
    assert radiometry.focal_plane_irradiance(1.0, 1.0, 1.0) == pytest.approx(0.6283185307179586)


def test_photon_detection_rate_reference():
    # pybsm_test_cases.md D24: photon_detection_rate(E=[1], w=1, wavelengths=[1], qe=[1])
    e = xr.DataArray([1.0], dims="wavelength", coords={"wavelength": [1.0]})
    rate = radiometry.photon_detection_rate(e, 1.0, 1.0, 1.0, PYBSM_CODATA_2014)
    assert float(rate[0]) == pytest.approx(5.034116651114543e24, rel=1e-13)


def test_dark_current_from_density_olson():
    # paper Table 2: 1e-5 A/m^2 on an 8 um pixel = 6.4e-15 A = 39946 e-/s (CODATA q)
    assert radiometry.dark_current_from_density(1e-5, 8e-6, 8e-6) == pytest.approx(
        1e-5 * 64e-12 / sc.e, rel=1e-15)


def test_cold_shield_plus_aperture_cone_is_a_hemisphere():
    # the shield fills pi - pi/(1+4F^2) sr; with the optics cone, the full pi sr hemisphere
    wl = xr.DataArray(4e-6)
    shield = radiometry.cold_shield_self_emission(wl, 300.0, 0.1, 0.2)
    cone = radiometry.focal_plane_irradiance(radiometry.blackbody_radiance(wl, 300.0), 0.1, 0.2)
    hemisphere = np.pi * float(radiometry.blackbody_radiance(wl, 300.0))
    assert float(shield + cone) == pytest.approx(hemisphere)


def test_well_fill_scale():
    n = xr.DataArray([1e3, 1e5], dims="case")
    scale = radiometry.well_fill_scale(n, 96000.0, 0.6)
    assert list(scale.values) == [1.0, pytest.approx(57600.0 / 1e5)]


def test_resample_spectral_zero_outside_curve():
    curve = xr.DataArray([0.5, 1.0], dims="quantum_efficiency_wavelength",
                         coords={"quantum_efficiency_wavelength": [1e-6, 2e-6]})
    wl = xr.DataArray([0.5e-6, 1.5e-6, 3e-6], dims="wavelength")
    out = radiometry.resample_spectral(curve, wl, "quantum_efficiency")
    assert list(out.values) == [0.0, 0.75, 0.0]


def test_resample_spectral_refuses_an_empty_curve_naming_the_parameter():
    # issue 20: a curve with no samples raised a bare IndexError inside the kernel
    curve = xr.DataArray(np.array([]), dims="quantum_efficiency_wavelength",
                         coords={"quantum_efficiency_wavelength": np.array([])})
    wl = xr.DataArray([0.5e-6, 1.5e-6], dims="wavelength")
    with pytest.raises(ValueError, match="quantum_efficiency is an empty curve"):
        radiometry.resample_spectral(curve, wl, "quantum_efficiency")


# ---- the kernels under the xarray layer ---------------------------------------------

@pytest.mark.parametrize("size", [1, 2, 5])
def test_interp_kernel_is_numpy_interp_on_every_row(size):
    # reference: np.interp(x, xp, fp, left=0, right=0) row by row (pyBSM's resampling rule),
    # bit for bit, on the nodes, between them, at both ends and outside
    rng = np.random.default_rng(size)
    source = np.sort(rng.uniform(1e-6, 2e-6, size))
    curves = rng.uniform(0.0, 1.0, (3, 4, size))
    target = np.concatenate([source, rng.uniform(0.9e-6, 2.1e-6, 40), [0.5e-6, 3e-6]])
    out = radiometry._interp_kernel(curves, target, source=source)
    expected = np.stack([[np.interp(target, source, row, left=0.0, right=0.0) for row in block]
                         for block in curves])
    np.testing.assert_array_equal(out, expected)


def test_resample_spectral_interpolates_every_sweep_row():
    # reference: np.interp per row; the sweep dimension stays first, wavelength last
    curve = xr.DataArray([[0.5, 1.0, 0.5], [0.2, 0.4, 0.8]],
                         dims=("case", "quantum_efficiency_wavelength"),
                         coords={"quantum_efficiency_wavelength": [1e-6, 2e-6, 3e-6]},
                         attrs={"units": "1"})
    wl = xr.DataArray([0.5e-6, 1.5e-6, 2e-6, 2.25e-6, 4e-6], dims="wavelength")
    out = radiometry.resample_spectral(curve, wl, "quantum_efficiency")
    assert out.dims == ("case", "wavelength") and out.attrs == {"units": "1"}
    for i in range(2):
        np.testing.assert_array_equal(out[i].values, np.interp(
            wl.values, [1e-6, 2e-6, 3e-6], curve[i].values, left=0.0, right=0.0))


def test_band_integral_exact_on_a_linear_spectrum():
    # closed form: the trapezoid rule is exact for 2 + 3 x on [1, 4] (= 6 + 3 * 15 / 2 = 28.5),
    # on any grid and along any other dimension
    wl = np.array([1.0, 1.5, 3.0, 4.0])
    spectral = xr.DataArray(np.outer([1.0, 2.0], 2.0 + 3.0 * wl), dims=("case", "wavelength"),
                            coords={"wavelength": wl}, attrs={"units": "W m-2 m-1"})
    out = radiometry.band_integral(spectral)
    assert out.dims == ("case",) and out.attrs["units"] == "W m-2"
    np.testing.assert_allclose(out.values, [28.5, 57.0], rtol=1e-15)


def test_misaligned_inputs_join_like_xarray_arithmetic():
    # xarray arithmetic's inner join: only the shared wavelengths remain (behaviour kept)
    e = xr.DataArray([1.0, 2.0, 3.0], dims="wavelength", coords={"wavelength": [1.0, 2.0, 3.0]})
    qe = xr.DataArray([0.5, 0.5, 0.5], dims="wavelength", coords={"wavelength": [2.0, 3.0, 4.0]})
    rate = radiometry.photon_detection_rate(e, qe, 1.0, 1.0, PYBSM_CODATA_2014)
    hc = PYBSM_CODATA_2014.planck * PYBSM_CODATA_2014.speed_of_light
    assert list(rate["wavelength"].values) == [2.0, 3.0]
    # closed form: lambda / (h c) * qe * E (IBSM Eq. 3-42)
    np.testing.assert_allclose(rate.values, [2.0 / hc * 0.5 * 2.0, 3.0 / hc * 0.5 * 3.0],
                               rtol=1e-15)


def _swept_case():
    """A mid-wave sensor with curves and sweeps on sensor and scenario parameters."""
    import xbsm
    from xbsm import atmosphere

    def curve(values, wavelengths):
        return xr.DataArray(values, dims="wavelength", coords={"wavelength": wavelengths})

    s = xbsm.sensor(
        aperture_diameter=0.2, focal_length=xr.DataArray([0.6, 0.8], dims="focal_length"),
        pixel_pitch_x=15e-6, wavelength_min=3.5e-6, wavelength_max=4.5e-6,
        cold_shield_temperature=xr.DataArray([70.0, 90.0], dims="cold_shield_temperature"),
        optics_temperature=250.0, optics_emissivity=0.05, cold_filter_temperature=80.0,
        cold_filter_emissivity=0.02, cold_filter_transmission=0.9,
        quantum_efficiency=curve([0.5, 0.7, 0.6], [3.4e-6, 4.0e-6, 4.6e-6]),
        optics_transmission=curve([0.8, 0.9], [3.6e-6, 4.4e-6]),
        stray_irradiance=curve([1.0, 3.0], [3.5e-6, 4.5e-6]), integration_time=0.01,
        max_well=xr.DataArray([2e6, 5e6], dims="max_well"))
    sc = xbsm.scenario(
        altitude=9000.0, ground_range=xr.DataArray([5e3, 20e3], dims="ground_range"),
        visibility=23.0, target_reflectance=xr.DataArray([0.0, 0.3], dims="target_reflectance"))
    atm = atmosphere.atmosphere_at(sc["altitude"], sc["ground_range"], sc["visibility"],
                                   wavelength_bounds=(3.5e-6, 4.5e-6))
    return s, sc, atm


def _signal_by_xarray_arithmetic(s, sc, atm, k):
    """Paper Eq. 1-2 and IBSM Eq. 3-42 written in plain xarray arithmetic (the reference)."""
    wl = atm["wavelength"]
    h, c, kb = k.planck, k.speed_of_light, k.boltzmann

    def planck(t):
        x = h * c / (wl * kb * t)
        return (2.0 * h * c**2.0 / wl**5.0) * np.exp(-x) / -np.expm1(-x)

    def resampled(name):
        dim = f"{name}_wavelength"
        return xr.DataArray(np.interp(wl.values, s[dim].values, s[name].values, 0.0, 0.0),
                            dims="wavelength", coords={"wavelength": wl})

    def radiance(r, t):
        return (atm["path_thermal"] + (1.0 - r) * planck(t) * atm["transmission"]
                + atm["solar_scatter"] + atm["ground_reflected"] * (r / 0.15))

    cone = np.pi / (1.0 + 4.0 * (s["focal_length"] / s["aperture_diameter"]) ** 2.0)
    optics = s["cold_filter_transmission"] * (1.0 - s["obscuration_ratio"] ** 2) * resampled(
        "optics_transmission")
    own = ((np.pi - cone) * planck(s["cold_shield_temperature"])
           + s["cold_filter_transmission"] * s["optics_emissivity"] * planck(
               s["optics_temperature"]) * cone
           + s["cold_filter_emissivity"] * planck(s["cold_filter_temperature"]) * cone
           + resampled("stray_irradiance"))
    per_watt = wl / (h * c) * resampled("quantum_efficiency") * s["detector_width_x"] * s[
        "detector_width_y"]
    target = per_watt * (optics * radiance(sc["target_reflectance"], sc["target_temperature"])
                         * cone + own)
    background = per_watt * (optics * radiance(sc["background_reflectance"],
                                               sc["background_temperature"]) * cone + own)
    path = per_watt * optics * (atm["path_thermal"] + atm["solar_scatter"]) * cone
    counts = [(x.integrate("wavelength") + s["dark_current"]) * s["integration_time"]
              * s["tdi_stages"] for x in (target, background)]
    brighter = np.maximum(*counts)
    limit = s["max_well_fill"] * s["max_well"]
    scale = xr.where(brighter > limit, limit / brighter, 1.0)
    return {"spectral_weights": target, "target_photoelectrons": scale * counts[0],
            "background_photoelectrons": scale * counts[1],
            "path_rate": path.integrate("wavelength"),
            "sensor_rate": (per_watt * own).integrate("wavelength")}


def test_signal_terms_equal_the_equations_in_xarray_arithmetic():
    # reference: the equations in plain xarray arithmetic, on sweeps of sensor and scenario
    # parameters and sensor curves; each term keeps only the dimensions it depends on
    from xbsm.constants import CODATA

    s, sc, atm = _swept_case()
    target, background = radiometry.aperture_radiances(atm, sc, "scenario", 3.5e-6)
    out = radiometry.signal_terms(s, atm, target, background)
    for name, expected in _signal_by_xarray_arithmetic(s, sc, atm, CODATA).items():
        assert set(out[name].dims) == set(expected.dims), name
        np.testing.assert_allclose(out[name].transpose(*expected.dims).values,
                                   expected.values, rtol=1e-12, err_msg=name)
    assert "ground_range" not in out["sensor_rate"].dims
    assert "target_reflectance" not in out["path_rate"].dims
    assert "target_reflectance" not in out["background_scene_rate"].dims


def test_signal_terms_dask_is_lazy_and_equals_eager(no_compute):
    # dask in, dask out; nothing computes until asked; same numbers as eager
    s, sc, atm = _swept_case()
    target, background = radiometry.aperture_radiances(atm, sc, "scenario", 3.5e-6)
    lazy_atm = atm.chunk({"ground_range": 1})
    lazy = radiometry.signal_terms(
        s, lazy_atm, *radiometry.aperture_radiances(lazy_atm, sc, "scenario", 3.5e-6))
    assert lazy["target_photoelectrons"].chunks is not None
    eager = radiometry.signal_terms(s, atm, target, background)
    computed = lazy.compute(scheduler="sync")
    for name in eager.data_vars:
        assert computed[name].dims == eager[name].dims, name
        np.testing.assert_allclose(computed[name].values, eager[name].values, rtol=1e-14,
                                   err_msg=name)


def test_signal_terms_without_noise_rates_leave_the_rest_unchanged():
    # image simulation's signal stage: the same counts, weights and target rate, bit for bit,
    # without the rates only the noise terms read
    s, sc, atm = _swept_case()
    radiances = radiometry.aperture_radiances(atm, sc, "scenario", 3.5e-6)
    full = radiometry.signal_terms(s, atm, *radiances)
    short = radiometry.signal_terms(s, atm, *radiances, noise_rates=False)
    assert set(full.data_vars) - set(short.data_vars) == set(radiometry.NOISE_RATES)
    for name in short.data_vars:
        xr.testing.assert_identical(short[name], full[name])


# ---- target sets (issue 25, item 2) ----------------------------------------------------

def test_target_set_is_labelled_data_over_target():
    t = radiometry.target_set([2.3, 3.0], [1.25, 2.0], names=["a", "b"])
    assert list(t["target"].values) == ["a", "b"]
    assert t["characteristic_dimension"].attrs["units"] == "m"
    assert t["thermal_contrast"].attrs["units"] == "K"
    assert t["reflectance_contrast"].values.tolist() == [0.0, 0.0]


def test_standard_targets_carry_their_sources():
    t = radiometry.standard_targets()
    assert set(t["target"].values) == set(radiometry.TARGET_SETS)
    assert all("nippon.zaidan.info" in src or src.startswith("as ")
               for src in t["source"].values)
    # STANAG image intensifier target: 2.3 m x 2.3 m, C0 0.25 / 0.4 (para. 6)
    assert float(t["characteristic_dimension"].sel(target="nato_image_intensifier_gen3")) == 2.3
    assert float(t["reflectance_contrast"].sel(target="nato_image_intensifier_gen3")) == 0.4


@pytest.mark.parametrize(("kwargs", "message"), [
    ({"characteristic_dimension": 0.0}, "characteristic_dimension must be finite and lie in"),
    ({"characteristic_dimension": 2.0, "thermal_contrast": np.inf}, "thermal_contrast must"),
    ({"characteristic_dimension": 2.0, "reflectance_contrast": -1.5},
     "reflectance_contrast must be finite and lie in"),
    ({"characteristic_dimension": [[2.0]]}, "must be a number or a 1-D sequence"),
    ({"characteristic_dimension": [2.0, 3.0], "names": ["a"]}, "names must give one name"),
])
def test_target_set_refuses_bad_values(kwargs, message):
    with pytest.raises(ValueError, match=message):
        radiometry.target_set(**kwargs)


def test_standard_targets_refuse_unknown_names():
    with pytest.raises(ValueError, match="target set names must be among"):
        radiometry.standard_targets("nvesd_12")
