"""Circular-aperture diffraction OTFs: obscured (IBSM 3-20) and defocused (Hopkins 1955)."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr
from otf_helpers import check_lazy, polar
from scipy.integrate import quad

from xbsm.otf.aperture import (
    circular_aperture,
    defocus_wavefront_coefficient,
    defocused_aperture,
)

D, LAM = 0.1, 0.5e-6
CUTOFF = D / LAM


def lens_area(r1, r2, d):
    """Intersection area of two circles of radii r1, r2 with centres d apart."""
    if d >= r1 + r2:
        return 0.0
    if d <= abs(r1 - r2):
        return np.pi * min(r1, r2) ** 2
    a1 = r1**2 * np.arccos((d**2 + r1**2 - r2**2) / (2 * d * r1))
    a2 = r2**2 * np.arccos((d**2 + r2**2 - r1**2) / (2 * d * r2))
    k = 0.5 * np.sqrt((-d + r1 + r2) * (d + r1 - r2) * (d - r1 + r2) * (d + r1 + r2))
    return a1 + a2 - k


def annulus_otf(nu, eta):
    """Geometric overlap of two annular pupils (radius 1, hole eta) shifted by 2 nu, per area."""
    d = 2 * nu
    area = lens_area(1, 1, d) - 2 * lens_area(1, eta, d) + lens_area(eta, eta, d)
    return area / (np.pi * (1 - eta**2))


def defocus_autocorrelation(s, waves):
    """Pupil autocorrelation of a unit circular pupil with phase 2 pi W20 r^2, shift s (in radii).

    The phase difference of the sheared pupils is 2 pi W20 (2 s x): linear in x, so the
    y-integral over the lens-shaped overlap is its height 2 sqrt(1 - (|x| + s/2)^2).
    """
    if s >= 2:
        return 0.0
    if s == 0:
        return 1.0

    def height(x):
        return 2 * np.sqrt(max(0.0, 1 - (x + s / 2) ** 2))

    omega = 4 * np.pi * waves * s
    integral = quad(height, 0, 1 - s / 2, weight="cos", wvar=omega, epsabs=1e-15, limit=200)[0]
    return 2 * integral / np.pi


def test_zero_frequency_is_one_for_every_obscuration():
    eta = xr.DataArray([0.0, 0.1, 0.5, 0.95], dims="obscuration")
    out = circular_aperture(xr.DataArray([0.0]), xr.DataArray([0.0]), LAM, D, eta)
    np.testing.assert_allclose(out, 1.0, rtol=1e-14)


def test_unobscured_equals_closed_form():
    nu = np.linspace(0, 1.2, 61)
    fx, fy = polar(nu * CUTOFF)
    out = circular_aperture(fx, fy, LAM, D)
    r = np.clip(nu, 0, 1)
    expected = (2 / np.pi) * (np.arccos(r) - r * np.sqrt(1 - r**2))
    np.testing.assert_allclose(
        out.transpose("frequency", ...), np.repeat(expected[:, None], 3, 1), atol=1e-15
    )


@pytest.mark.parametrize("eta", [0.0, 0.05, 0.3, 0.6, 0.9])
def test_obscured_equals_geometric_pupil_overlap(eta):
    nu = np.linspace(0, 1.05, 43)
    fx, fy = polar(nu * CUTOFF, orientation=[0.3])
    out = circular_aperture(fx, fy, LAM, D, eta).squeeze("orientation")
    expected = [annulus_otf(n, eta) for n in nu]
    np.testing.assert_allclose(out, expected, atol=2e-14)


def test_vanishes_at_and_beyond_cutoff_and_is_bounded():
    fx, fy = polar(np.linspace(0, 2, 201) * CUTOFF)
    wl = xr.DataArray([0.4e-6, LAM], dims="wavelength")
    eta = xr.DataArray([0.0, 0.4], dims="obscuration")
    out = circular_aperture(fx, fy, wl, D, eta)
    assert float(np.abs(out).max()) <= 1 + 1e-15
    beyond = np.hypot(fx, fy) >= D / wl
    assert float(np.abs(out.where(beyond, 0)).max()) == 0.0


def test_obscuration_sweep_including_zero_matches_scalar_calls():
    fx, fy = polar(np.linspace(0, 1.1, 12) * CUTOFF)
    eta = xr.DataArray([0.0, 0.25], dims="obscuration")
    swept = circular_aperture(fx, fy, LAM, D, eta)
    for i, e in enumerate(eta.values):
        xr.testing.assert_allclose(
            swept.isel(obscuration=i, drop=True),
            circular_aperture(fx, fy, LAM, D, float(e)),
            rtol=1e-15,
            atol=1e-16,
        )


def test_defocus_values_quoted_in_the_brief():
    # pybsm_test_cases.md section F: pupil autocorrelation and the correctly bracketed
    # Hopkins series give [0.8389, 0.6587, 0.5016, 0.2875, 0.1525] at W20 = 0.25 waves,
    # D = 0.1 m, lambda = 0.5 um, f = 1 m. (The autocorrelation gives 0.65858 for the
    # second value, so the quoted 0.6587 is off in its last digit: tolerance 2e-4.)
    ratio = xr.DataArray([0.1, 0.2, 0.3, 0.5, 0.7], dims="frequency")
    out = defocused_aperture(ratio * CUTOFF, 0 * ratio, LAM, D, defocus_waves=0.25)
    np.testing.assert_allclose(out, [0.8389, 0.6587, 0.5016, 0.2875, 0.1525], atol=2e-4)


@pytest.mark.parametrize("waves", [0.05, 0.25, 1.0, 3.0, 10.0])
def test_defocus_equals_numerical_pupil_autocorrelation(waves):
    ratio = np.array([0.0, 0.01, 0.05, 0.1, 0.2, 0.3, 0.45, 0.5, 0.7, 0.9, 0.999, 1.0, 1.2])
    fx, fy = polar(ratio * CUTOFF, orientation=[1.0])
    out = defocused_aperture(fx, fy, LAM, D, defocus_waves=waves).squeeze("orientation")
    expected = [defocus_autocorrelation(2 * r, waves) for r in ratio]
    np.testing.assert_allclose(out, expected, atol=2e-13)


def test_defocus_agrees_with_a_sampled_two_dimensional_pupil_autocorrelation():
    # Brute force: sample the pupil with 2 pi W20 r^2 phase on a 512^2 grid
    # (radius 100 px) and correlate it with itself shifted by whole pixels.
    n, radius, waves = 512, 100, 0.25
    y, x = (np.mgrid[:n, :n] - n / 2 + 0.5) / radius
    r2 = x**2 + y**2
    pupil = np.where(r2 <= 1, np.exp(2j * np.pi * waves * r2), 0)
    shifts = np.array([20, 60, 100, 140])  # pixels = 2 rho/rho_c * radius
    numeric = [
        np.sum(np.roll(pupil, -s // 2, axis=1) * np.conj(np.roll(pupil, s // 2, axis=1))).real
        / np.sum(np.abs(pupil) ** 2)
        for s in shifts
    ]
    ratio = xr.DataArray(shifts / (2 * radius), dims="frequency")
    out = defocused_aperture(ratio * CUTOFF, 0 * ratio, LAM, D, defocus_waves=waves)
    np.testing.assert_allclose(out, numeric, atol=4e-3)


def test_zero_defocus_equals_circular_aperture():
    fx, fy = polar(np.linspace(0, 1.1, 23) * CUTOFF)
    xr.testing.assert_allclose(
        defocused_aperture(fx, fy, LAM, D, defocus_waves=0.0),
        circular_aperture(fx, fy, LAM, D),
        atol=1e-15,
    )


def test_defocus_opd_is_waves_times_wavelength_and_sign_symmetric():
    fx, fy = polar(np.linspace(0, 1, 11) * CUTOFF)
    wl = xr.DataArray([0.5e-6, 0.8e-6], dims="wavelength")
    by_opd = defocused_aperture(fx, fy, wl, D, defocus_opd=0.3e-6)
    by_waves = defocused_aperture(fx, fy, wl, D, defocus_waves=0.3e-6 / wl)
    xr.testing.assert_allclose(by_opd, by_waves, rtol=1e-14)
    xr.testing.assert_allclose(by_opd, defocused_aperture(fx, fy, wl, D, defocus_opd=-0.3e-6))


def test_pybsm_defocus_is_wrong_by_the_documented_amount(pybsm_otf):
    # pyBSM 0.16.1 circular_aperture_OTF_with_defocus on the case above (fixture):
    # [0.7655, 0.5066, 0.3649, 0.1840, 0.0962], i.e. -27 % at rho/rho_c = 0.3.
    theirs = pybsm_otf["defocus_aperture_pybsm/otf"].ravel()
    np.testing.assert_allclose(theirs, [0.7655, 0.5066, 0.3649, 0.1840, 0.0962], atol=1e-4)
    dz = float(pybsm_otf["defocus_aperture_pybsm/defocus"])
    w20 = defocus_wavefront_coefficient(dz, D, 1.0)
    ratio = xr.DataArray([0.1, 0.2, 0.3, 0.5, 0.7], dims="frequency")
    ours = defocused_aperture(ratio * CUTOFF, 0 * ratio, LAM, D, defocus_opd=w20)
    np.testing.assert_allclose(theirs[2] / ours[2] - 1, -0.27, atol=0.005)


def test_defocus_wavefront_coefficient_convention():
    # W20 = dz / (2 (1 + 4 F^2)): F = 10, dz = 1 mm -> 1e-3 / 802
    assert defocus_wavefront_coefficient(1e-3, 0.1, 1.0) == pytest.approx(1e-3 / 802, rel=1e-15)


def test_sweeps_give_exactly_the_input_dims():
    fx, fy = polar(np.linspace(0, 1, 5) * CUTOFF)
    wl = xr.DataArray([0.5e-6, 0.6e-6], dims="wavelength")
    d = xr.DataArray([0.1, 0.2, 0.3], dims="sweep_d")
    out = circular_aperture(fx, fy, wl, d, 0.2)
    assert set(out.dims) == {"frequency", "orientation", "wavelength", "sweep_d"}
    w = xr.DataArray([0.1, 1.0], dims="sweep_w")
    out = defocused_aperture(fx, fy, wl, d, defocus_waves=w)
    assert set(out.dims) == {"frequency", "orientation", "wavelength", "sweep_d", "sweep_w"}
    assert out.attrs["units"] == "1"
    assert out.attrs["long_name"].startswith("Diffraction OTF of an unobscured")


def test_dask_inputs_stay_lazy_and_equal_eager():
    fx, fy = polar(np.linspace(0, 1.1, 40) * CUTOFF)
    wl = xr.DataArray([0.5e-6, 0.6e-6], dims="wavelength")
    lazy = (fx.chunk({"frequency": 10}), fy.chunk({"frequency": 10}), wl, D, 0.3)
    check_lazy(circular_aperture, lazy, (fx, fy, wl, D, 0.3))
    check_lazy(
        defocused_aperture,
        lazy[:4],
        (fx, fy, wl, D),
        defocus_waves=xr.DataArray([0.2, 2.0], dims="w"),
    )


@pytest.mark.parametrize(
    ("kwargs", "name"),
    [
        ({"obscuration_ratio": 1.0}, "obscuration_ratio"),
        ({"obscuration_ratio": -0.1}, "obscuration_ratio"),
        ({"aperture_diameter": 0.0}, "aperture_diameter"),
        ({"wavelength": -1e-6}, "wavelength"),
    ],
)
def test_impossible_aperture_input_raises(kwargs, name):
    args = {"wavelength": LAM, "aperture_diameter": D, "obscuration_ratio": 0.0} | kwargs
    with pytest.raises(ValueError, match=name):
        circular_aperture(xr.DataArray([0.0]), xr.DataArray([0.0]), **args)


def test_defocus_needs_exactly_one_defocus_argument():
    f = xr.DataArray([0.0])
    with pytest.raises(ValueError, match="defocus_waves or defocus_opd"):
        defocused_aperture(f, f, LAM, D)
    with pytest.raises(ValueError, match="defocus_waves or defocus_opd"):
        defocused_aperture(f, f, LAM, D, defocus_waves=0.1, defocus_opd=1e-7)
    with pytest.raises(ValueError, match="defocus_waves"):
        defocused_aperture(f, f, LAM, D, defocus_waves=np.nan)


@pytest.mark.parametrize("eta", [0.05, 0.4, 0.9])
def test_one_obscuration_ratio_equals_the_general_path_to_the_bit(eta):
    """The one-ratio path (no gathers, issue 22's speed work) gives the general path's
    values to the bit: the same formula, each term's zero region exact (nu/eta >= 1 clips
    to an argument of 1, whose term is exactly 0). The general path is the one a sweep
    over the ratio takes (one ratio per entry)."""
    from xbsm.otf.aperture import circular_aperture_kernel

    rng = np.random.default_rng(7)
    radial = rng.uniform(-0.01, 1.3, (40, 3, 31)) * CUTOFF
    # the pieces' boundaries exactly: nu = eta, (1 -+ eta)/2, 1, and one step either side
    edges = np.array([eta, (1 - eta) / 2, (1 + eta) / 2, 1.0, 0.0])
    radial.flat[:15] = np.concatenate([edges, np.nextafter(edges, 2), np.nextafter(edges, -1)]
                                      ) * CUTOFF
    radial.flat[15] = np.nan
    one = circular_aperture_kernel(radial, D, LAM, eta)
    general = circular_aperture_kernel(radial, D, LAM, np.full(radial.shape, eta))
    assert one.shape == general.shape
    assert np.array_equal(one, general, equal_nan=True)
    assert np.array_equal(np.signbit(one), np.signbit(general))
    assert np.isnan(one.flat[15]) and np.all(one[radial >= CUTOFF] == 0.0)


def _eq_3_20(nu, eta):
    """IBSM Eq. 3-20 written out on whole arrays: every term everywhere, np.where, no gathers.

    The formula as the docstring of ``circular_aperture`` gives it (A(x) clipped to [0, 1],
    C with sin(phi) and tan(phi / 2) from cos(phi)), in the kernel's order of operations.
    """
    nu, eta = np.broadcast_arrays(nu, eta)

    def term(x):
        c = np.minimum(np.maximum(x, 0.0), 1.0)
        return (2.0 / np.pi) * (np.arccos(c) - c * np.sqrt(1.0 - c**2))

    with np.errstate(all="ignore"):
        obscured = eta > 0
        safe = np.where(obscured, eta, 0.5)
        eta2 = eta**2
        inner = np.where(obscured, eta2 * term(nu / safe), 0.0)
        cos_phi = np.minimum(np.maximum((1.0 + eta2 - 4.0 * nu**2) / (2.0 * safe), -1.0), 1.0)
        phi = np.arccos(cos_phi)
        sin_phi = np.sqrt((1.0 - cos_phi) * (1.0 + cos_phi))
        tan_half = np.sqrt((1.0 - cos_phi) / (1.0 + cos_phi))
        annulus = (2.0 * safe * sin_phi / np.pi + (1.0 + eta2) * phi / np.pi - 2.0 * eta2
                   - (2.0 * (1.0 - eta2) / np.pi)
                   * np.arctan((1.0 + safe) / (1.0 - safe) * tan_half))
        below = nu < (1.0 - eta) / 2.0
        overlap = np.where(below, -2.0 * eta2, np.where(nu <= (1.0 + eta) / 2.0, annulus, 0.0))
        out = (term(nu) + inner + np.where(obscured, overlap, 0.0)) / (1.0 - eta2)
    return np.where(nu >= 1.0, 0.0, out)


@pytest.mark.parametrize("order", ["random", "sorted"])
@pytest.mark.parametrize("eta", [0.0, 0.4, "per scenario"])
def test_kernels_equal_eq_3_20_written_out_to_the_bit(order, eta):
    """The row-wise kernels (each term on the rows of nodes that need it, in place; the
    polychromatic one summing row by row) give Eq. 3-20 written out on whole arrays to
    the bit, and its weighted sum by the same contraction: unsorted and sorted nodes,
    eta = 0, one eta, one per scenario; NaN, negative nu, nu >= 1 and the pieces'
    boundaries included."""
    from xbsm.otf.aperture import circular_aperture_band_kernel, circular_aperture_kernel

    rng = np.random.default_rng(11)
    scenarios, wavelengths = 4, 31
    wl = np.linspace(0.45e-6, 0.55e-6, wavelengths)
    wl[wavelengths // 2] = LAM
    diameter = rng.uniform(0.09, 0.11, (scenarios, 1))
    radial = rng.uniform(-0.02, 1.4, (60, scenarios, 1)) * CUTOFF
    ratio = 0.4 if eta == "per scenario" else eta
    edges = np.array([ratio, (1 - ratio) / 2, (1 + ratio) / 2, 1.0, 0.0])
    radial[:15, 0, 0] = np.concatenate(
        [edges, np.nextafter(edges, 2), np.nextafter(edges, -1)]) * diameter[0, 0] / LAM
    radial[rng.integers(60, size=3), rng.integers(scenarios, size=3), 0] = np.nan
    radial[50:, :, 0] = rng.uniform(1.5, 3.0, (10, scenarios)) * CUTOFF  # beyond the cutoff
    if order == "sorted":  # the chain's nodes: ascending in each scenario, NaN last
        radial = np.sort(radial, axis=0)
    if eta == "per scenario":
        eta = np.array([[0.0], [0.05], [0.4], [0.9]])  # (scenarios, 1): the general path
    weights = rng.uniform(0.0, 1.0, (scenarios, wavelengths))
    weights /= weights.sum(axis=-1, keepdims=True)

    expected = _eq_3_20(radial / (diameter / wl), eta)
    mono = circular_aperture_kernel(radial, diameter, wl, eta)
    assert mono.shape == expected.shape
    assert np.array_equal(mono, expected, equal_nan=True)
    assert np.array_equal(np.signbit(mono), np.signbit(expected))
    band = circular_aperture_band_kernel(radial, diameter, wl, eta, weights)
    summed = np.einsum("...k,...k->...", expected, weights)
    assert band.shape == summed.shape == (60, scenarios)
    assert np.array_equal(band, summed, equal_nan=True)
    assert np.array_equal(np.signbit(band), np.signbit(summed))
    assert np.any(np.isnan(band)) and np.all(band[50:][~np.isnan(band[50:])] == 0.0)
    # one node row at a time (a block of one row, and the rows' order reversed)
    assert np.array_equal(circular_aperture_band_kernel(radial[::-1], diameter, wl, eta, weights),
                          summed[::-1], equal_nan=True)
    assert np.array_equal(circular_aperture_band_kernel(radial[7:8], diameter, wl, eta, weights),
                          summed[7:8], equal_nan=True)
