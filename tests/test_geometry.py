import dask
import dask.array as da
import numpy as np
import pytest
import xarray as xr

from xbsm import geometry
from xbsm.constants import EARTH_RADIUS


def test_slant_range_reference_case():
    # pybsm_test_cases.md D25: pyBSM 0.16.1's curved_earth_slant_range(0, 1, 1) gives
    # sqrt(2) = 1.4142135623730951, but its law of cosines cancels 13 digits there; the
    # exact value (50-digit mpmath, same formula) is sqrt(2 + 1/R_e) = 1.41421361780493704
    assert geometry.slant_range(1.0, 1.0, 0.0) == pytest.approx(1.414213617804937, rel=1e-14)
    assert geometry.slant_range(1.0, 1.0, 0.0) == pytest.approx(1.4142135623730951, rel=1e-7)


def test_nadir_angle_reference_case():
    # pybsm_test_cases.md D25: nadir_angle(h_target=1, h_sensor=1, slant_range=1)
    assert geometry.nadir_angle(1.0, 1.0, 1.0) == pytest.approx(1.5707962484024436, rel=1e-12)


def test_olson_slant_range_and_elevation():
    # pybsm_test_cases.md A5 (pyBSM 0.16.1): 9 km altitude, 20 km ground range
    # 50-digit mpmath of the same geometry: 21944.568747966005055 m and 0.42415759925679397 rad
    # (pyBSM's rounded law of cosines and arccos: 21944.568747898647 and 0.42415759925816854)
    r = geometry.slant_range(20000.0, 9000.0)
    assert r == pytest.approx(21944.568747966005, rel=1e-15)
    assert r == pytest.approx(21944.568747898647, rel=1e-11)
    assert geometry.elevation_angle(r, 9000.0) == pytest.approx(0.42415759925679397, rel=1e-14)
    assert geometry.elevation_angle(r, 9000.0) == pytest.approx(0.42415759925816854, rel=1e-9)


def test_nadir_angle_is_exact_near_nadir():
    # 0.1 m from nadir at 9 km: pyBSM's arccos gives 1.388e-5 rad; the exact angle for this
    # (double-rounded) slant range is 1.1111113585886088e-5 (50-digit mpmath), and
    # 1.1111111110652896e-5 for the exact slant range
    r = geometry.slant_range(0.1, 9000.0)
    assert geometry.nadir_angle(r, 9000.0) == pytest.approx(1.1111113585886088e-5, rel=1e-12)
    assert geometry.nadir_angle(r, 9000.0) == pytest.approx(1.1111111110652896e-5, rel=1e-6)
    assert float(geometry.target_elevation_angle(r, 9000.0)) == pytest.approx(
        np.pi / 2 - 1.1111113585886088e-5 - 0.1 / EARTH_RADIUS, rel=1e-14)


def test_nadir_look_is_vertical_without_nan():
    r = geometry.slant_range(0.0, 9000.0)
    assert r == pytest.approx(9000.0, rel=1e-12)
    assert geometry.elevation_angle(r, 9000.0) == pytest.approx(np.pi / 2, abs=1e-7)


def test_flat_earth_limit_for_short_ranges():
    # for ground range << R_e the slant range tends to sqrt(h^2 + g^2)
    r = geometry.slant_range(1000.0, 1000.0)
    assert r == pytest.approx(np.hypot(1000.0, 1000.0), rel=1e-4)


def test_altitude_along_path_ends():
    r = geometry.slant_range(50e3, 10e3)
    assert geometry.altitude_along_path(0.0, r, 10e3) == pytest.approx(0.0, abs=1e-6)
    assert geometry.altitude_along_path(r, r, 10e3) == pytest.approx(10e3, rel=1e-12)


def test_horizon_geometry():
    # at the geometric horizon the line of sight grazes the target: the look angle below the
    # sensor's horizontal equals the central angle theta, cos(theta) = R / (R + h)
    h = 10e3
    theta = np.arccos(EARTH_RADIUS / (EARTH_RADIUS + h))
    r = geometry.slant_range(theta * EARTH_RADIUS, h)
    assert geometry.elevation_angle(r, h) == pytest.approx(theta, rel=1e-6)


def test_broadcasts_over_sweep_dims():
    gr = xr.DataArray(np.linspace(0, 1e5, 5), dims="ground_range")
    h = xr.DataArray([1e3, 1e4], dims="altitude")
    r = geometry.slant_range(gr, h)
    assert set(r.dims) == {"ground_range", "altitude"}
    assert r.attrs["units"] == "m"


def test_gsd_and_ifov():
    ifov = geometry.ifov(8e-6, 4.0)
    assert ifov == pytest.approx(2e-6)
    gsd = geometry.ground_sample_distance(ifov, 21944.568747898647)
    # pybsm_test_cases.md A5: GIQE-5 gsd_w = gsd / sin(elevation)^(1/4) = 0.05479621447912214
    gsd_w = gsd / np.sin(0.42415759925816854) ** 0.25
    assert gsd_w == pytest.approx(0.05479621447912214, rel=1e-12)


def test_target_elevation_zero_at_horizon_and_vertical_at_nadir():
    h = 10e3
    theta = np.arccos(EARTH_RADIUS / (EARTH_RADIUS + h))
    r = geometry.slant_range(theta * EARTH_RADIUS, h)
    assert geometry.target_elevation_angle(r, h) == pytest.approx(0.0, abs=1e-6)
    assert geometry.target_elevation_angle(h, h) == pytest.approx(np.pi / 2, abs=1e-7)


def test_target_elevation_is_look_down_minus_central_angle():
    g, h = 80e3, 9e3
    r = geometry.slant_range(g, h)
    expected = geometry.elevation_angle(r, h) - g / EARTH_RADIUS
    assert geometry.target_elevation_angle(r, h) == pytest.approx(expected, rel=1e-9)


def test_slant_and_elevation_kernel_on_plain_arrays():
    # pybsm_test_cases.md A5, 9 km altitude, 20 km ground range: 50-digit mpmath gives
    # 21944.568747966005 m and a look-down angle of 0.42415759925679397 rad; pyBSM's law of
    # cosines 21944.568747898647 m and 0.42415759925816854 rad
    h, g = np.array([9000.0]), np.array([20000.0, 0.1])
    slant, angle = geometry.slant_and_elevation_kernel(h, g, "stable", "look-down")
    assert slant[0] == pytest.approx(21944.568747966005, rel=1e-15)
    assert angle[0] == pytest.approx(0.42415759925679397, rel=1e-14)
    slant, angle = geometry.slant_and_elevation_kernel(h, g, "law-of-cosines", "look-down")
    assert slant[0] == pytest.approx(21944.568747898647, rel=1e-11)
    assert angle[0] == pytest.approx(0.42415759925816854, rel=1e-9)
    # at the target the elevation is the look-down angle less the central angle g / R_e
    _, target = geometry.slant_and_elevation_kernel(h, g, "stable", "target")
    np.testing.assert_allclose(target[0], 0.42415759925679397 - 20000.0 / EARTH_RADIUS,
                               rtol=1e-13)


def test_viewing_geometry_keeps_each_output_on_its_dims_and_dask_lazy(no_compute):
    gr = xr.DataArray([1e4, 2e4, 4e4, 8e4], dims="ground_range")
    f = xr.DataArray([3.0, 4.0], dims="focal_length")
    eager = geometry.viewing_geometry(gr, 9e3, 8e-6, 1e-5, f)
    assert eager.slant_range.dims == eager.elevation_angle.dims == ("ground_range",)
    assert eager.ifov_x.dims == ("focal_length",)
    assert set(eager.gsd_y.dims) == {"ground_range", "focal_length"}
    # GSD = IFOV x slant range (IBSM Eq. 3-62), IFOV = pitch / focal length
    np.testing.assert_allclose(eager.gsd_y.isel(focal_length=1), 1e-5 / 4.0 * eager.slant_range,
                               rtol=1e-15)
    lazy = geometry.viewing_geometry(gr.chunk(2), 9e3, 8e-6, 1e-5, f)
    assert all(isinstance(lazy[n].data, da.Array) for n in ("slant_range", "gsd_x"))
    with dask.config.set(scheduler="sync"):
        xr.testing.assert_identical(lazy.compute(), eager)


# ---- zero and impossible slant ranges (issue 20) -------------------------------------

@pytest.mark.parametrize("form", geometry.FORMS)
@pytest.mark.parametrize("height", [0.0, 9000.0])
def test_zero_slant_range_between_equal_heights_looks_along_the_horizontal(form, height):
    # sensor and target coincide: the limit of ground range g -> 0 at equal heights, where
    # the chord's nadir angle is pi/2 - g / (2 R_e) (closed form) and the point's own
    # height is the path's. pyBSM's law of cosines divides by zero here
    near = geometry.nadir_angle(geometry.slant_range(1e-3, height, height), height, height,
                                form="stable")
    assert float(near) == pytest.approx(np.pi / 2 - 0.5e-3 / EARTH_RADIUS, abs=1e-12)
    assert float(geometry.nadir_angle(0.0, height, height, form=form)) == np.pi / 2
    assert float(geometry.elevation_angle(0.0, height, height, form=form)) == 0.0
    assert float(geometry.target_elevation_angle(0.0, height, height, form=form)) == 0.0
    assert float(geometry.altitude_along_path(0.0, 0.0, height, height, form=form)) == height


@pytest.mark.parametrize("form", geometry.FORMS)
@pytest.mark.parametrize("slant", [0.0, 8999.0])
def test_a_slant_range_shorter_than_the_height_difference_is_nan(form, slant):
    # no triangle: the line of sight is at least the 9 km vertical distance (it returned
    # 0 rad and the sensor altitude, or raised ZeroDivisionError for law-of-cosines)
    assert np.isnan(geometry.nadir_angle(slant, 9000.0, form=form))
    assert np.isnan(geometry.elevation_angle(slant, 9000.0, form=form))
    assert np.isnan(geometry.target_elevation_angle(slant, 9000.0, form=form))
    assert np.isnan(geometry.altitude_along_path(0.0, slant, 9000.0, form=form))


@pytest.mark.parametrize("form", geometry.FORMS)
def test_the_vertical_slant_range_is_nadir_not_nan(form):
    # the shortest line of sight, straight down; an altitude whose R_e + h rounds up
    # (0.1 m: (R_e + 0.1) - R_e = 0.0999999996 m) is still a triangle
    for height in (9000.0, 0.1):
        assert float(geometry.nadir_angle(height, height, form=form)) == pytest.approx(
            0.0, abs=1e-3)


def test_ground_range_at_elevation_inverts_slant_range_and_target_elevation():
    # closed form: slant_range then target_elevation_angle of (ground range, altitude);
    # the inverse returns the ground range, labelled
    g = xr.DataArray([0.0, 100.0, 5e3, 60e3, 150e3], dims="g")
    e = geometry.target_elevation_angle(geometry.slant_range(g, 20e3), 20e3)
    back = geometry.ground_range_at_elevation(e, 20e3)
    np.testing.assert_allclose(back, g, rtol=1e-9, atol=1e-6)
    assert back.attrs["units"] == "m" and back.dims == ("g",)
