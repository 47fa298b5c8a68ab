"""Defocus: the exact defocused aperture (Hopkins, annular), the geometric disk, IBSM's Gaussian."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr
from otf_helpers import check_lazy, polar
from scipy.integrate import quad, trapezoid
from scipy.special import j1, jv

from xbsm.otf.aperture import circular_aperture, hopkins_kernel
from xbsm.otf.defocus import (
    DEFOCUS_MODELS,
    annular_defocus_kernel,
    blur_circle_diameter,
    defocused_aperture_otf,
    gaussian_defocus,
    geometric_defocus,
    image_domain_defocus_radius,
    object_domain_defocus_radius,
)


def test_reference_value_case_20():
    # pybsm_test_cases.md C-20 [T]: defocus_OTF(u=[1], v=[1], w_x=1, w_y=1) = 0.007191883355826368
    out = gaussian_defocus(xr.DataArray([1.0]), xr.DataArray([1.0]), 1.0, 1.0)
    np.testing.assert_allclose(out, [0.007191883355826368], rtol=1e-13)


def test_is_the_transform_of_a_gaussian_psf():
    # H = exp(-pi^2 w^2 f^2 / 4) is the Fourier transform of exp(-4 x^2 / w^2) / (w sqrt(pi) / 2).
    w = 2e-6
    x = np.linspace(-20 * w, 20 * w, 40001)
    psf = np.exp(-4 * x**2 / w**2)
    psf /= trapezoid(psf, x)
    f = np.array([0.0, 5e4, 1e5, 3e5, 6e5])
    numeric = [trapezoid(psf * np.cos(2 * np.pi * fi * x), x) for fi in f]
    out = gaussian_defocus(xr.DataArray(f, dims="frequency"), 0.0, w, 0.0)
    np.testing.assert_allclose(out, numeric, atol=1e-12)


def test_zero_frequency_is_one_and_otf_is_bounded():
    fx, fy = polar(np.linspace(0, 1e6, 21))
    out = gaussian_defocus(fx, fy, xr.DataArray([0.0, 1e-6, 5e-6], dims="blur"), 2e-6)
    assert float(out.isel(frequency=0).min()) == 1.0
    assert float(out.max()) <= 1.0
    assert set(out.dims) == {"frequency", "orientation", "blur"}


def test_object_and_image_radii_formulas():
    # IBSM 3-26: 0.62 D |1/R - 1/R0|; 3-27: 0.62 D dz / f^2
    assert object_domain_defocus_radius(0.2, 1000.0, 2000.0) == pytest.approx(0.62 * 0.2 * 0.5e-3)
    assert object_domain_defocus_radius(0.2, 2000.0, np.inf) == pytest.approx(0.62 * 0.2 / 2000)
    assert image_domain_defocus_radius(0.2, -1e-4, 2.0) == pytest.approx(0.62 * 0.2 * 1e-4 / 4)
    r = object_domain_defocus_radius(0.2, xr.DataArray([1e3, 2e3], dims="range"), 2e3)
    assert r.dims == ("range",) and r.attrs["units"] == "rad"


def test_dask_stays_lazy():
    fx, fy = polar(np.linspace(0, 1e6, 20))
    check_lazy(gaussian_defocus, (fx.chunk(5), fy.chunk(5), 1e-6, 2e-6), (fx, fy, 1e-6, 2e-6))


@pytest.mark.parametrize(
    ("call", "name"),
    [
        (lambda: gaussian_defocus(xr.DataArray([0.0]), 0.0, -1e-6, 0.0), "blur_radius_x"),
        (lambda: object_domain_defocus_radius(0.1, 0.0, 10.0), "object_range"),
        (lambda: image_domain_defocus_radius(0.1, 1e-4, 0.0), "focal_length"),
    ],
)
def test_impossible_input_raises(call, name):
    with pytest.raises(ValueError, match=name):
        call()


# ---- the defocus component (Hopkins, annular pupil, geometric disk, IBSM's Gaussian) ----

D, LAM = 0.1, 0.5e-6


def chord(x, s, eta):
    """Chord at abscissa x of the overlap of two annuli (radius 1, hole eta) centred at +-s/2."""
    high, low = np.inf, 0.0
    for u in (x + s / 2, x - s / 2):
        if abs(u) > 1:
            return 0.0
        high = min(high, np.sqrt(1 - u * u))
        low = max(low, np.sqrt(max(eta * eta - u * u, 0.0)))
    return 2 * max(0.0, high - low)


def pupil_autocorrelation(s, waves, eta=0.0):
    """Independent reference: the defocused annular pupil's autocorrelation by QUADPACK.

    With the phase 2 pi W r^2 on the pupil, the sheared copies differ by a x,
    a = 4 pi W s, so the OTF is int chord(x) cos(a x) dx / (pi (1 - eta^2)), the
    chord being the overlap's height at x (even in x); integrated piecewise between the
    chord's kinks with the cosine-weighted rule.
    """
    if s >= 2:
        return 0.0
    a = 4 * np.pi * waves * s
    cuts = {0.0, 1 - s / 2} | {c for c in (eta - s / 2, s / 2 - eta, eta + s / 2)
                               if 0 < c < 1 - s / 2}
    edges = sorted(cuts)
    total = sum(quad(chord, lo, hi, args=(s, eta), weight="cos", wvar=a, epsabs=1e-14,
                     limit=200)[0] if a else
                quad(chord, lo, hi, args=(s, eta), epsabs=1e-14, limit=200)[0]
                for lo, hi in zip(edges[:-1], edges[1:], strict=True))
    return 2 * total / (np.pi * (1 - eta * eta))


@pytest.mark.parametrize("eta", [0.0, 0.2, 0.4, 0.75])
@pytest.mark.parametrize("waves", [0.05, 0.5, 3.0])
def test_exact_defocus_equals_the_independent_pupil_autocorrelation(eta, waves):
    s = np.linspace(0.0, 1.99, 34)
    ratio = xr.DataArray(s / 2, dims="frequency")
    out = defocused_aperture_otf(ratio * D / LAM, 0 * ratio, LAM, D, waves * LAM, eta)
    expected = [pupil_autocorrelation(v, waves, eta) for v in s]
    # the reference's own error near its square-root end points is up to 2e-7
    np.testing.assert_allclose(out.values, expected, rtol=0, atol=1e-6)


def test_hopkins_recurrence_equals_the_series_with_scipy_bessel_functions():
    # Hopkins 1955 with every J_n from scipy.special.jv, summed well past convergence
    rng = np.random.default_rng(3)
    s, waves = rng.uniform(0, 2, 400), rng.uniform(0, 6, 400)
    a, beta = 4 * np.pi * waves * s, np.arccos(s / 2)
    even = beta * jv(1, a)
    odd = np.zeros_like(a)
    for n in range(0, 120):
        odd += (-1) ** n * np.sin((2 * n + 1) * beta) / (2 * n + 1) * (jv(2 * n, a)
                                                                       - jv(2 * n + 2, a))
        if n:
            even += (-1) ** (n + 1) * np.sin(2 * n * beta) / (2 * n) * (jv(2 * n - 1, a)
                                                                      - jv(2 * n + 1, a))
    series = 4 / (np.pi * a) * (np.cos(a * s / 2) * even - np.sin(a * s / 2) * odd)
    np.testing.assert_allclose(hopkins_kernel(s, waves), series, rtol=0, atol=1e-13)


@pytest.mark.parametrize("model", DEFOCUS_MODELS)
@pytest.mark.parametrize("eta", [0.0, 0.4])
def test_zero_defocus_is_the_in_focus_aperture_to_the_bit(model, eta):
    fx, fy = polar(np.linspace(0, 1.1, 45) * D / LAM)
    out = defocused_aperture_otf(fx, fy, LAM, D, 0.0, eta, model=model)
    # values, dims and coordinates to the bit (attributes name each function; and not
    # DataArray.drop_attrs: xarray 2023.12, the floor, lacks it)
    xr.testing.assert_equal(out, circular_aperture(fx, fy, LAM, D, eta))
    np.testing.assert_array_equal(out.values, circular_aperture(fx, fy, LAM, D, eta).values)


@pytest.mark.parametrize("eta", [0.0, 0.4])
def test_vanishing_defocus_tends_to_the_in_focus_aperture(eta):
    fx, fy = polar(np.linspace(0, 1.0, 41) * D / LAM)
    focus = circular_aperture(fx, fy, LAM, D, eta)
    errors = [float(abs(defocused_aperture_otf(fx, fy, LAM, D, w * LAM, eta) - focus).max())
              for w in (1e-2, 1e-3, 1e-4)]
    # the OTF is even in W020: the difference falls as W020^2
    assert errors[0] < 1e-2 and errors[1] < errors[0] / 50 and errors[2] < errors[1] / 50


def test_large_defocus_approaches_the_geometric_disk():
    # at a fixed blur-disk argument pi d rho (so rho -> 0 as W020 grows) Hopkins tends to
    # 2 J1(x) / x, the transform of the geometrical-optics blur disk
    x = np.linspace(0.0, 12.0, 61)
    errors = []
    for waves in (2.0, 8.0, 32.0, 128.0):
        s = x / (4 * np.pi * waves)  # a = 4 pi W s = pi d rho
        with np.errstate(invalid="ignore"):
            disk = np.where(x == 0, 1.0, 2 * j1(x) / x)
        errors.append(float(np.max(np.abs(hopkins_kernel(s, waves) - disk))))
    assert all(b < a / 2 for a, b in zip(errors, errors[1:], strict=False))
    assert errors[-1] < 0.01


def test_geometric_model_is_the_in_focus_aperture_times_the_disk():
    fx, fy = polar(np.linspace(0, 1.0, 21) * D / LAM)
    opd = 1.3e-6
    d = 8 * opd / D
    out = defocused_aperture_otf(fx, fy, LAM, D, opd, 0.3, model="geometric")
    rho = np.hypot(fx, fy)
    with np.errstate(invalid="ignore"):
        disk = xr.where(rho == 0, 1.0, 2 * j1(np.pi * d * rho) / (np.pi * d * rho))
    xr.testing.assert_allclose(out, circular_aperture(fx, fy, LAM, D, 0.3) * disk, rtol=1e-13)
    xr.testing.assert_allclose(geometric_defocus(fx, fy, d), disk, rtol=1e-13)


def test_gaussian_model_is_ibsm_eq_3_27_size():
    # IBSM 3-27: w = 0.62 D dz / f^2; a focus shift dz is W020 = dz D^2 / (8 f^2)
    # paraxially, so the blur circle 8 W020 / D is D dz / f^2 and w = 0.62 of it
    dz, f = 2e-4, 1.0
    opd = dz * D**2 / (8 * f**2)
    assert float(blur_circle_diameter(opd, D)) == pytest.approx(D * dz / f**2, rel=1e-14)
    w = image_domain_defocus_radius(D, dz, f)
    fx, fy = polar(np.linspace(0, 1.0, 21) * D / LAM)
    out = defocused_aperture_otf(fx, fy, LAM, D, opd, 0.2, model="gaussian")
    expected = circular_aperture(fx, fy, LAM, D, 0.2) * gaussian_defocus(fx, fy, w, w)
    xr.testing.assert_allclose(out, expected, rtol=1e-13)


def test_annular_kernel_with_a_tiny_hole_tends_to_hopkins():
    s = np.linspace(0, 1.99, 50)
    clear = hopkins_kernel(s, 0.7)
    assert np.max(np.abs(annular_defocus_kernel(s, 0.7, 1e-4) - clear)) < 1e-7


def test_defocus_component_stays_lazy_and_equals_eager():
    fx, fy = polar(np.linspace(0, 1.1, 40) * D / LAM)
    wl = xr.DataArray([0.5e-6, 0.6e-6], dims="wavelength")
    opd = xr.DataArray([0.0, 0.2e-6, 2e-6], dims="opd")
    check_lazy(defocused_aperture_otf, (fx.chunk({"frequency": 7}), fy.chunk({"frequency": 7}),
                                        wl, D, opd, 0.35), (fx, fy, wl, D, opd, 0.35))


@pytest.mark.parametrize(
    ("call", "name"),
    [
        (lambda: defocused_aperture_otf(xr.DataArray([0.0]), 0.0, LAM, D, -1e-7),
         r"defocus_opd must lie in \[0, inf\) m"),
        (lambda: defocused_aperture_otf(xr.DataArray([0.0]), 0.0, LAM, D, np.nan),
         "defocus_opd"),
        (lambda: defocused_aperture_otf(xr.DataArray([0.0]), 0.0, LAM, D, 1e-7, model="disk"),
         "model must be one of"),
        (lambda: defocused_aperture_otf(xr.DataArray([0.0]), 0.0, LAM, D, 1e-7, 1.0),
         "obscuration_ratio"),
        (lambda: blur_circle_diameter(1e-7, 0.0), "aperture_diameter"),
        (lambda: geometric_defocus(xr.DataArray([0.0]), 0.0, -1e-6), "blur_diameter"),
    ],
)
def test_bad_defocus_input_raises_naming_the_parameter(call, name):
    with pytest.raises(ValueError, match=name):
        call()
