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
