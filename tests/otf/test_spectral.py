"""Spectral weighting (paper Eq. 3)."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr
from otf_helpers import check_lazy, polar

import xbsm
from xbsm.examples import olson_scenario, olson_sensor
from xbsm.otf.aperture import circular_aperture
from xbsm.otf.spectral import normalised_weights, spectral_average

WL = xr.DataArray([0.5e-6, 0.6e-6, 0.7e-6], dims="wavelength")


def test_weights_are_normalised_and_extra_dims_kept():
    fx, fy = polar(np.linspace(0, 4e5, 9))
    mono = circular_aperture(fx, fy, WL, 0.275)
    w = xr.DataArray([[1.0, 2.0, 1.0], [0.0, 1.0, 0.0]], dims=("scene", "wavelength"))
    out = spectral_average(mono, w)
    assert set(out.dims) == {"frequency", "orientation", "scene"}
    xr.testing.assert_allclose(out.isel(scene=1, drop=True), mono.isel(wavelength=1, drop=True))
    np.testing.assert_allclose(out.isel(frequency=0), 1.0, rtol=1e-15)
    xr.testing.assert_allclose(spectral_average(mono, 7 * w), out)


@pytest.mark.parametrize("weights", [
    np.array([0.3, 1.7, 2.9]),
    np.array([[1.0, np.nan, 2.0], [np.nan, np.nan, np.nan], [0.0, 0.0, 0.0]]),
    np.array([[3, 1, 2]]),  # integers, as numpy's nansum takes them
    np.random.default_rng(5).random((4, 7, 31)).transpose(2, 0, 1)[..., ::2],  # strided
])
def test_normalised_weights_are_nansums_bits(weights):
    # numpy's own np.nansum is the reference: the kernel repeats its steps without its
    # wrappers, so every value (NaN included) must be the same to the bit
    with np.errstate(divide="ignore", invalid="ignore"):  # a row of NaN or 0: 0 / 0
        expected = weights / np.nansum(weights, axis=-1, keepdims=True)
        np.testing.assert_array_equal(normalised_weights(weights), expected, strict=True)


def test_complex_otfs_are_averaged():
    otf = xr.DataArray([1j, 1.0, -1j], dims="wavelength")
    assert complex(spectral_average(otf, xr.DataArray([1.0, 2.0, 1.0], dims="wavelength"))) == 0.5


def test_dask_stays_lazy():
    fx, fy = polar(np.linspace(0, 4e5, 20))
    mono = circular_aperture(fx, fy, WL, 0.275)
    w = xr.DataArray([1.0, 2.0, 1.0], dims="wavelength")
    check_lazy(spectral_average, (mono.chunk({"frequency": 5}), w), (mono, w))


@pytest.mark.parametrize(
    ("weights", "match"),
    [
        (xr.DataArray([1.0, -1.0, 1.0], dims="wavelength"), "weights"),
        (xr.DataArray([0.0, 0.0, 0.0], dims="wavelength"), "weights"),
        (xr.DataArray([1.0, 1.0, 1.0], dims="band"), "weights"),
        (np.ones(3), "weights"),
    ],
)
def test_bad_weights_raise(weights, match):
    with pytest.raises(ValueError, match=match):
        spectral_average(xr.DataArray(np.ones(3), dims="wavelength"), weights)


@pytest.mark.parametrize(("method", "optics"), [
    ("accurate", {}), ("pybsm", {}), ("fast", {}), ("accurate", {"obscuration_ratio": 0.3}),
    ("pybsm", {"obscuration_ratio": 0.3}),
    ("accurate", {"defocus_opd": 0.2e-6, "obscuration_ratio": 0.2})])  # pybsm: no defocus
@pytest.mark.parametrize("swept", [("focal_length", 1.5, 5.0), ("pixel_pitch_x", 4e-6, 16e-6)])
def test_states_sharing_frequency_columns_equal_small_sweeps_of_them(method, optics, swept):
    # A focal-length or pixel-pitch sweep moves each optical state's frequency nodes, but
    # a few node columns serve all its states (4-12 here): in a sweep this large the
    # polychromatic aperture OTF is evaluated once per distinct column and each state's
    # weighted sum taken from the values gathered. Sweeps of three states are too small for
    # that (each state's OTF is evaluated and summed as it is); every element of the large
    # sweep equals theirs bit for bit (a gather of the wrong column, or of another state's
    # weights, fails it). Elements of an optics sweep need not equal single calls to the
    # bit (the edge contraction of a sweep pads its node grids; 5.6e-17 in rer_giqe5 seen).
    name, low, high = swept
    values = np.linspace(low, high, 90)
    sc = olson_scenario(ground_range=20000.0, visibility=5.0)

    def niirs(part):
        s = olson_sensor("red", **optics, **{name: xr.DataArray(part, dims="case")})
        return xbsm.niirs(s, sc, method=method)

    whole = niirs(values)
    parts = [niirs(values[i:i + 3]) for i in range(0, values.size, 3)]
    names = [v for v in whole.data_vars if "case" in whole[v].dims]
    assert {"rer", "niirs", "eho"} <= set(names)
    for v in names:
        joined = xr.concat([p[v] for p in parts], "case").transpose(*whole[v].dims)
        assert np.array_equal(whole[v].values, joined.values), v
