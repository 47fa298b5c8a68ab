"""Turbulence profiles: every Hufnagel-Valley parameter, a whole-profile multiplier and a
user table of Cn2(h), checked against independent integrals and published HV 5/7 values."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr
from otf_helpers import check_lazy
from scipy.integrate import quad

import xbsm
from xbsm.examples import olson_scenario, olson_sensor
from xbsm.otf import turbulence as t

# Earth radius of xbsm (xbsm.constants.EARTH_RADIUS, the pyBSM value), written out here so
# that the geometry below is independent of xbsm.geometry.
EARTH_RADIUS = 6378.164e3


def _height_along(z, slant_range, sensor_altitude):
    """Height above a spherical Earth at distance z from a target on the ground (law of
    cosines in the triangle Earth centre - target - point, written independently)."""
    re = EARTH_RADIUS
    sin_elevation = ((re + sensor_altitude) ** 2 - re**2 - slant_range**2) / (2 * re * slant_range)
    return np.sqrt(re**2 + z**2 + 2 * re * z * sin_elevation) - re


def _hv(h, v=21.0, a=1.7e-14, tropo=5.94e-53, upper=2.7e-16, m=1.0):
    """Hufnagel-Valley written out from Roggemann and Welsh (1996), not from xbsm."""
    return m * (tropo * (v / 27) ** 2 * h**10 * np.exp(-h / 1000) + upper * np.exp(-h / 1500)
                + a * np.exp(-h / 100))


def _quad_r0(cn2_of_h, slant_range, sensor_altitude, wavelength=1e-6, breaks=()):
    """Spherical-wave r0 (Schmidt 2010 Eq. 9.64) by adaptive quadrature along the path."""
    k = 2 * np.pi / wavelength
    edges = [0.0, *sorted(b for b in breaks if 0 < b < slant_range), slant_range]
    integral = sum(
        quad(lambda z: cn2_of_h(_height_along(z, slant_range, sensor_altitude))
             * (z / slant_range) ** (5 / 3), lo, hi, epsabs=0, epsrel=1e-12, limit=400)[0]
        for lo, hi in zip(edges[:-1], edges[1:], strict=True))
    return (0.423 * k**2 * integral) ** (-3 / 5)


@pytest.mark.parametrize("altitude,slant", [(9000.0, 12000.0), (3000.0, 40000.0),
                                            (20000.0, 21000.0)])
@pytest.mark.parametrize("hv", [
    {},
    {"high_altitude_wind_speed": 40.0, "cn2_at_1m": 5e-14},
    {"cn2_tropopause": 2e-52, "cn2_upper_air": 1e-15, "cn2_multiplier": 3.0},
    {"cn2_at_1m": 1e-16, "cn2_upper_air": 0.0, "cn2_multiplier": 0.3},
])
def test_hufnagel_valley_r0_matches_an_independent_integral(altitude, slant, hv):
    mine = float(t.slant_path_coherence_diameter(slant, altitude, **hv))
    ref = _quad_r0(lambda h: _hv(h, **{
        "v": hv.get("high_altitude_wind_speed", 21.0), "a": hv.get("cn2_at_1m", 1.7e-14),
        "tropo": hv.get("cn2_tropopause", 5.94e-53), "upper": hv.get("cn2_upper_air", 2.7e-16),
        "m": hv.get("cn2_multiplier", 1.0)}), slant, altitude)
    assert mine == pytest.approx(ref, rel=1e-6)


def _table():
    heights = np.array([0.0, 50.0, 300.0, 1000.0, 3000.0, 8000.0, 12000.0, 20000.0, 30000.0])
    cn2 = np.array([3e-14, 8e-15, 1e-15, 2e-16, 0.0, 4e-17, 6e-17, 5e-18, 1e-18])
    return xr.DataArray(cn2, dims="height", coords={"height": heights}), heights, cn2


def _table_cn2(h, heights, cn2):
    """Log-linear between table heights, linear next to a zero: written independently."""
    i = min(max(int(np.searchsorted(heights, h, side="right")) - 1, 0), len(heights) - 2)
    w = (h - heights[i]) / (heights[i + 1] - heights[i])
    lo, hi = cn2[i], cn2[i + 1]
    if lo > 0 and hi > 0:
        return lo * (hi / lo) ** w
    return lo + (hi - lo) * w


@pytest.mark.parametrize("altitude,slant", [(9000.0, 12000.0), (25000.0, 60000.0)])
def test_table_r0_matches_an_independent_integral(altitude, slant):
    table, heights, cn2 = _table()
    # the table's kinks slow Gauss-Legendre: 2000 nodes for 1e-6 (64 give about 1e-4)
    mine = float(t.slant_path_coherence_diameter(slant, altitude, cn2_profile=table,
                                                 cn2_multiplier=2.0, path_samples=2000))
    # kinks at the table heights: split the integral there (z of each height on this path)
    zs = np.linspace(0, slant, 200001)
    hz = _height_along(zs, slant, altitude)
    breaks = [float(np.interp(h, hz, zs)) for h in heights if 0 < h < altitude]
    ref = _quad_r0(lambda h: 2.0 * _table_cn2(h, heights, cn2), slant, altitude, breaks=breaks)
    assert mine == pytest.approx(ref, rel=1e-6)


def test_hv57_defaults_give_the_published_r0_and_isoplanatic_angle():
    # "HV 5/7" is named for r0 = 5 cm and isoplanatic angle 7 urad at 0.5 um, zenith
    # (plane wave): Andrews and Phillips, Laser Beam Propagation through Random Media,
    # 2nd ed. (SPIE 2005) Sec. 12.2.1; Roggemann and Welsh (1996) Sec. 3.5. The values are
    # published to one digit. Integrals of xbsm's profile: r0 = 4.96 cm, theta0 = 6.89 urad.
    k = 2 * np.pi / 0.5e-6
    pieces = [(0, 1000), (1000, 5000), (5000, 30000), (30000, 200000)]

    def cn2(h):
        return float(t.hufnagel_valley(h))

    moment0 = sum(quad(cn2, a, b, epsrel=1e-12, limit=400)[0] for a, b in pieces)
    moment53 = sum(quad(lambda h: cn2(h) * h ** (5 / 3), a, b, epsrel=1e-12, limit=400)[0]
                   for a, b in pieces)
    r0 = (0.423 * k**2 * moment0) ** (-3 / 5)
    theta0 = (2.914 * k**2 * moment53) ** (-3 / 5)
    assert round(r0 * 100) == 5
    assert round(theta0 * 1e6) == 7
    assert r0 == pytest.approx(0.0496, abs=5e-5)
    assert theta0 == pytest.approx(6.89e-6, abs=5e-9)


def test_defaults_are_hv57_to_the_bit():
    h = np.linspace(0, 30000, 301)
    explicit = t.hufnagel_valley(h, 21.0, 1.7e-14, 5.94e-53, 2.7e-16, 1.0)
    literal = (5.94e-53 * (21.0 / 27.0) ** 2 * h**10 * np.exp(-h / 1000.0)
               + 2.7e-16 * np.exp(-h / 1500.0) + 1.7e-14 * np.exp(-h / 100.0))
    np.testing.assert_array_equal(np.asarray(explicit), literal)


MULTIPLIERS = [0.3, 0.5, 1.0, 2.0, 3.0, 5.0, 10.0]


@pytest.mark.parametrize("method", ["accurate", "pybsm"])
def test_niirs_falls_monotonically_as_the_profile_multiplier_grows(method):
    m = xr.DataArray(MULTIPLIERS, dims="cn2_multiplier")
    sc = olson_scenario(ground_range=xr.DataArray([5000.0, 15000.0, 30000.0], dims="ground_range"),
                        visibility=23.0, cn2_multiplier=m)
    out = xbsm.niirs(olson_sensor("nir"), sc, method=method)
    niirs = out["niirs"].transpose(..., "cn2_multiplier").values  # every GIQE version
    r0 = out["coherence_diameter"].transpose("ground_range", "cn2_multiplier").values
    assert np.all(np.diff(niirs, axis=-1) < 0)
    assert np.all(np.diff(r0, axis=-1) < 0)
    # r0 scales as the profile's strength to the -3/5
    np.testing.assert_allclose(r0[:, -1] / r0[:, 2], 10.0 ** (-0.6), rtol=1e-12)


def test_multiplier_sweep_stays_lazy_and_equals_eager():
    m = xr.DataArray(MULTIPLIERS, dims="cn2_multiplier")
    # the path r0 stays lazy; the model doors compute a dask sweep as for any parameter
    check_lazy(lambda multiplier: t.slant_path_coherence_diameter(2e4, 9e3,
                                                                  cn2_multiplier=multiplier),
               (m.chunk(2),), (m,))
    s = olson_sensor("nir")
    eager = xbsm.niirs(s, olson_scenario(ground_range=20000.0, visibility=23.0,
                                         cn2_multiplier=m))
    lazy = xbsm.niirs(s, olson_scenario(ground_range=20000.0, visibility=23.0,
                                        cn2_multiplier=m.chunk(3)))
    np.testing.assert_allclose(lazy["niirs"].values, eager["niirs"].values, rtol=1e-12)


def test_zero_multiplier_switches_turbulence_off_like_zero_cn2():
    s = olson_sensor("nir")
    off = xbsm.niirs(s, olson_scenario(ground_range=20000.0, visibility=23.0,
                                       cn2_multiplier=0.0))
    zero = xbsm.niirs(s, olson_scenario(ground_range=20000.0, visibility=23.0, cn2_at_1m=0.0))
    np.testing.assert_array_equal(off["niirs"].values, zero["niirs"].values)
    assert np.isinf(float(off["coherence_diameter"]))


def test_a_table_equal_to_hv57_gives_the_hv57_niirs():
    heights = np.concatenate([np.linspace(0, 1000, 2001), np.linspace(1010, 12000, 1100)])
    table = xr.DataArray(_hv(heights), dims="height", coords={"height": heights})
    s = olson_sensor("nir")
    hv = xbsm.niirs(s, olson_scenario(ground_range=20000.0, visibility=23.0))
    tab = xbsm.niirs(s, olson_scenario(ground_range=20000.0, visibility=23.0,
                                       cn2_profile=table))
    assert float(tab["coherence_diameter"]) == pytest.approx(float(hv["coherence_diameter"]),
                                                             rel=1e-4)
    np.testing.assert_allclose(tab["niirs"].values, hv["niirs"].values, rtol=0, atol=1e-4)


def _sc(**kw):
    return dict(altitude=9000.0, ground_range=10000.0, visibility=23.0, **kw)


@pytest.mark.parametrize(("kw", "match"), [
    ({"cn2_profile": xr.DataArray([1e-14, 1e-15], dims="h", coords={"h": [0.0, 1e4]})},
     "cn2_profile must be a 1-D xr.DataArray over dim 'height'"),
    ({"cn2_profile": xr.DataArray([1e-14, 1e-15, 1e-16], dims="height",
                                  coords={"height": [0.0, 2e4, 1e4]})},
     "cn2_profile heights must be finite and strictly increasing"),
    ({"cn2_profile": xr.DataArray([1e-14, -1e-15], dims="height",
                                  coords={"height": [0.0, 2e4]})},
     r"cn2_profile values must lie in \[0, inf\)"),
    ({"cn2_profile": xr.DataArray([1e-14, 1e-15], dims="height",
                                  coords={"height": [10.0, 2e4]})},
     "cn2_profile heights must start at or below 0 m"),
    ({"cn2_profile": xr.DataArray([1e-14, 1e-15], dims="height",
                                  coords={"height": [0.0, 5e3]})},
     "cn2_profile must cover the path"),
    ({"cn2_profile": xr.DataArray([1e-14, 1e-15], dims="height",
                                  coords={"height": [0.0, 2e4]}), "cn2_at_1m": 1e-15},
     "cn2_at_1m is a Hufnagel-Valley parameter and cn2_profile replaces"),
    ({"cn2_multiplier": -1.0}, "cn2_multiplier"),
    ({"cn2_tropopause": -1.0}, "cn2_tropopause"),
    ({"cn2_upper_air": float("nan")}, "cn2_upper_air"),
])
def test_bad_profiles_are_refused_naming_the_parameter(kw, match):
    with pytest.raises(ValueError, match=match):
        xbsm.scenario(**_sc(**kw))


def test_a_study_file_sweeps_the_multiplier_lazily(tmp_path):
    from xbsm import study

    path = tmp_path / "cn2.toml"
    path.write_text('[sensor]\npreset = "olson"\nband = "nir"\n[scenario]\n'
                    "platform_speed = 100.0\naltitude = 9000.0\nvisibility = 23.0\n"
                    "ground_range = 15000.0\n[sweep]\ncn2_multiplier = [0.3, 1.0, 10.0]\n")
    result = study.run(study.load(path))
    assert result["niirs"].chunks is not None
    niirs = result["niirs"].transpose(..., "cn2_multiplier").values
    assert np.all(np.diff(niirs, axis=-1) < 0)
