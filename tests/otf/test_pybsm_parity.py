"""Parity with pyBSM 0.16.1 where pyBSM is correct.

Reference values: tests/fixtures/pybsm_otf.npz, written by
recipes/fixtures/pybsm_reference_otf.py with pyBSM 0.16.1 (rerun it to regenerate).
pyBSM's numba kernels use fastmath, so the same formulas agree to rounding,
not bit for bit: rtol 1e-12 with an absolute floor of 1e-14 for values near
zero (measured worst cases are listed in docs/otf.md).
"""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr
from otf_helpers import grid_da

from xbsm.otf import aperture, defocus, detector, filters, motion, spectral, turbulence, wavefront

RTOL, ATOL = 1e-12, 1e-14


def check(actual, expected, rtol=RTOL, atol=ATOL):
    np.testing.assert_allclose(np.asarray(actual), expected, rtol=rtol, atol=atol)


def sweep(values, dim):
    return xr.DataArray(np.asarray(values), dims=dim)


def test_circular_aperture_matches_pybsm(pybsm_otf):
    d = {k.split("/")[1]: v for k, v in pybsm_otf.items() if k.startswith("aperture/")}
    fx, fy = grid_da(d["u"], d["v"])
    out = aperture.circular_aperture(
        fx,
        fy,
        sweep(d["wavelength"], "wavelength"),
        float(d["aperture_diameter"]),
        sweep(d["obscuration_ratio"], "obscuration"),
    )
    check(out.transpose("wavelength", "obscuration", "fy", "fx"), d["otf"])


def test_spectral_average_matches_pybsm_weighted_by_wavelength(pybsm_otf):
    d = {k.split("/")[1]: v for k, v in pybsm_otf.items() if k.startswith("weighted_aperture/")}
    fx, fy = grid_da(d["u"], d["v"])
    wl = sweep(d["wavelength"], "wavelength")
    mono = aperture.circular_aperture(
        fx, fy, wl, float(d["aperture_diameter"]), float(d["obscuration_ratio"])
    )
    out = spectral.spectral_average(mono, sweep(d["weights"], "wavelength"))
    check(out.transpose("fy", "fx"), d["otf"], rtol=1e-13, atol=1e-15)


def test_detector_matches_pybsm(pybsm_otf):
    g = lambda k: pybsm_otf[f"detector/{k}"]  # noqa: E731
    fx, fy = grid_da(g("u"), g("v"))
    out = detector.detector(fx, fy, float(g("w_x")), float(g("w_y")), float(g("f")))
    check(out, g("otf"))


def test_aggregated_detector_matches_pybsm(pybsm_otf):
    g = lambda k: pybsm_otf[f"aggregation/{k}"]  # noqa: E731
    fx, fy = grid_da(g("u"), g("v"))
    for i, n in enumerate(g("n")):
        out = detector.aggregated_detector(
            fx,
            fy,
            float(g("w_x")),
            float(g("w_y")),
            float(g("p_x")),
            float(g("p_y")),
            float(g("f")),
            aggregation=int(n),
        )
        check(out, g("otf")[i])


def test_charge_transfer_matches_pybsm(pybsm_otf):
    g = lambda k: pybsm_otf[f"cte/{k}"]  # noqa: E731
    fx, fy = grid_da(g("u"), g("v"))
    out = detector.charge_transfer(
        fx,
        fy,
        float(g("p_x")),
        float(g("p_y")),
        float(g("f")),
        float(g("cte_n_x")),
        float(g("cte_n_y")),
        sweep(g("cte_eff"), "efficiency"),
        phases=int(g("phases_n")),
    )
    check(out.transpose("efficiency", "fy", "fx"), g("otf"))


def test_diffusion_matches_pybsm(pybsm_otf):
    g = lambda k: pybsm_otf[f"diffusion/{k}"]  # noqa: E731
    fx, fy = grid_da(g("u"), g("v"))
    out = detector.diffusion(
        fx, fy, sweep(g("alpha"), "wavelength"), float(g("ald")), float(g("al0")), float(g("f"))
    )
    check(out.transpose("wavelength", "fy", "fx"), g("otf"))


def test_drift_and_jitter_match_pybsm(pybsm_otf):
    g = lambda k: pybsm_otf[f"drift/{k}"]  # noqa: E731
    fx, fy = grid_da(g("u"), g("v"))
    check(motion.drift(fx, fy, float(g("a_x")), float(g("a_y"))), g("otf"))
    g = lambda k: pybsm_otf[f"jitter/{k}"]  # noqa: E731
    fx, fy = grid_da(g("u"), g("v"))
    check(motion.jitter(fx, fy, float(g("s_x")), float(g("s_y"))), g("otf"))


def test_tdi_matches_pybsm(pybsm_otf):
    g = lambda k: pybsm_otf[f"tdi/{k}"]  # noqa: E731
    freq = xr.DataArray(g("frequency"), dims="frequency")
    out = motion.tdi(
        freq,
        float(g("w")),
        float(g("f")),
        int(g("n_tdi")),
        sweep(g("beta"), "ratio"),
        phases=int(g("phases_n")),
    )
    check(out.transpose("ratio", "frequency"), g("otf"))


def test_turbulence_matches_pybsm(pybsm_otf):
    g = lambda k: pybsm_otf[f"turbulence/{k}"]  # noqa: E731
    fx, fy = grid_da(g("u"), g("v"))
    out = turbulence.turbulence(
        fx,
        fy,
        sweep(g("wavelength"), "wavelength"),
        float(g("aperture_diameter")),
        sweep(g("r0"), "r0"),
        sweep(g("alpha"), "alpha"),
    )
    check(out.transpose("wavelength", "r0", "alpha", "fy", "fx"), g("otf"))


def test_wind_blended_turbulence_matches_pybsm(pybsm_otf):
    g = lambda k: pybsm_otf[f"wind_turbulence/{k}"]  # noqa: E731
    fx, fy = grid_da(g("u"), g("v"))
    out = turbulence.wind_blended_turbulence(
        fx,
        fy,
        sweep(g("wavelength"), "wavelength"),
        float(g("aperture_diameter")),
        sweep(g("r0"), "r0"),
        float(g("t_d")),
        float(g("vel")),
    )
    check(out.transpose("wavelength", "r0", "fy", "fx"), g("otf"))


def test_hufnagel_valley_matches_pybsm(pybsm_otf):
    g = lambda k: pybsm_otf[f"hufnagel_valley/{k}"]  # noqa: E731
    out = turbulence.hufnagel_valley(
        xr.DataArray(g("h"), dims="altitude"), float(g("v")), float(g("cn2_at_1m"))
    )
    check(out, g("cn2"), atol=0)


def test_slant_path_r0_trapezoid_matches_pybsm(pybsm_otf):
    g = lambda k: pybsm_otf[f"coherence_diameter/{k}"]  # noqa: E731
    out = turbulence.slant_path_coherence_diameter(
        sweep(g("slant_range"), "scenario"),
        sweep(g("altitude"), "scenario"),
        high_altitude_wind_speed=float(g("v")),
        cn2_at_1m=float(g("cn2_at_1m")),
        path_samples=10000,
        rule="trapezoid",
    )
    check(out, g("r0"), atol=0)


def test_polychromatic_turbulence_and_band_r0_match_pybsm(pybsm_otf):
    g = lambda k: pybsm_otf[f"polychromatic_turbulence/{k}"]  # noqa: E731
    fx, fy = grid_da(g("u"), g("v"))
    wl = sweep(g("wavelength"), "wavelength")
    w = sweep(g("weights"), "wavelength")
    r0 = turbulence.slant_path_coherence_diameter(
        sweep(g("slant_range"), "scenario"),
        sweep(g("altitude"), "scenario"),
        high_altitude_wind_speed=float(g("ha_wind_speed")),
        cn2_at_1m=float(g("cn2_at_1m")),
        path_samples=10000,
        rule="trapezoid",
    )
    band = turbulence.band_coherence_diameter(r0, wl, w)
    check(band, g("r0_band"), atol=0)
    out = turbulence.polychromatic_turbulence(
        fx,
        fy,
        wl,
        w,
        float(g("aperture_diameter")),
        r0,
        float(g("int_time")),
        float(g("aircraft_speed")),
    )
    check(out.transpose("scenario", "fy", "fx"), g("otf"))


def test_random_phase_wavefront_matches_pybsm(pybsm_otf):
    g = lambda k: pybsm_otf[f"wavefront/{k}"]  # noqa: E731
    fx, fy = grid_da(g("u"), g("v"))
    out = wavefront.random_phase_wavefront(
        fx,
        fy,
        sweep(g("wavelength"), "wavelength"),
        float(g("pv")),
        float(g("L_x")),
        float(g("L_y")),
        phase_variance_wavelength=float(g("pv_wavelength")),
    )
    check(out.transpose("wavelength", "fy", "fx"), g("otf"))


def test_shannon_wavefront_unclipped_matches_pybsm(pybsm_otf):
    g = lambda k: pybsm_otf[f"wavefront_2/{k}"]  # noqa: E731
    fx, fy = grid_da(g("u"), g("v"))
    wl = sweep(g("wavelength"), "wavelength")
    out = wavefront.shannon_wavefront(
        fx, fy, wl, float(g("aperture_diameter")), float(g("w_rms")), clip=False
    )
    check(out.transpose("wavelength", "fy", "fx"), g("otf"))
    clipped = wavefront.shannon_wavefront(fx, fy, wl, float(g("aperture_diameter")), 0.1)
    inside = (np.hypot(fx, fy) * wl / float(g("aperture_diameter")) <= 1).transpose(
        "wavelength", "fy", "fx"
    )
    check(
        clipped.transpose("wavelength", "fy", "fx").values[inside.values], g("otf")[inside.values]
    )


def test_gaussian_defocus_and_gaussian_match_pybsm(pybsm_otf):
    g = lambda k: pybsm_otf[f"defocus/{k}"]  # noqa: E731
    fx, fy = grid_da(g("u"), g("v"))
    check(defocus.gaussian_defocus(fx, fy, float(g("w_x")), float(g("w_y"))), g("otf"))
    g = lambda k: pybsm_otf[f"gaussian/{k}"]  # noqa: E731
    out = filters.gaussian(fx, fy, float(g("blur_size_x")), float(g("blur_size_y")))
    check(out, g("otf"))


def test_defocus_radii_match_pybsm_in_magnitude(pybsm_otf):
    g = lambda k: pybsm_otf[f"object_defocus/{k}"]  # noqa: E731
    out = defocus.object_domain_defocus_radius(
        float(g("D")), sweep(g("R"), "range"), float(g("R0"))
    )
    check(out, np.abs(g("w")), atol=0)
    g = lambda k: pybsm_otf[f"image_defocus/{k}"]  # noqa: E731
    out = defocus.image_domain_defocus_radius(float(g("D")), sweep(g("dz"), "shift"), float(g("f")))
    check(out, g("w"), atol=0)


@pytest.mark.parametrize("name", ["row3", "col3", "pair", "sharpen3x3", "half_nyquist"])
def test_filter_pybsm_method_reproduces_filter_otf(pybsm_otf, name):
    g = lambda k: pybsm_otf[f"filter_{name}/{k}"]  # noqa: E731
    fx, fy = grid_da(g("u"), g("v"))
    out = filters.sharpening_filter(fx, fy, g("kernel"), float(g("ifov")), method="pybsm")
    check(out, g("otf"), atol=0)
