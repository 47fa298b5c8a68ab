"""The system OTF with defocus: the sensor's defocus_opd (W020) in the aperture component,
both slices, filtered and unfiltered, through the NIIRS chain."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

import xbsm
from xbsm.examples import olson_scenario, olson_sensor

SCENARIO = olson_scenario(ground_range=10e3, visibility=23.0)
LAM = 0.7e-6  # W020 in waves at the NIR band's middle


@pytest.mark.parametrize("method", ["accurate", "fast"])
@pytest.mark.parametrize("obscuration", [0.0, 0.4])
def test_niirs_falls_monotonically_with_defocus(method, obscuration):
    waves = [0.0, 0.05, 0.1, 0.25, 0.5, 0.75, 1.0, 1.5, 2.0]
    opd = xr.DataArray([w * LAM for w in waves], dims="defocus")
    s = olson_sensor("nir", obscuration_ratio=obscuration, defocus_opd=opd)
    out = xbsm.niirs(s, SCENARIO, method=method)
    for version in (3, 4, 5):
        n = out.niirs.sel(giqe=version).values
        assert np.all(np.diff(n) < 0), (version, n)
    rer = out.rer.values
    assert np.all(np.diff(rer) < 0)


def test_zero_defocus_is_every_result_to_the_bit():
    # the default and an explicit 0: every result to the bit
    base = xbsm.niirs(olson_sensor("nir"), SCENARIO)
    zero = xbsm.niirs(olson_sensor("nir", defocus_opd=0.0), SCENARIO)
    xr.testing.assert_identical(base, zero)
    # the 0 cell of a sweep with non-zero defocus beside it: the aperture OTF to the bit,
    # but the edge rule is the sweep's (one panel per lobe of its widest defocus, so that
    # the optics OTF is shared), so the edge terms agree to the rule's convergence
    # (accurate: within 1e-6 NIIRS of a 4x finer rule, docs/otf.md) and the flags exactly
    swept = xbsm.niirs(olson_sensor("nir", defocus_opd=xr.DataArray(
        [0.0, 1e-6], dims="defocus")), SCENARIO).isel(defocus=0, drop=True)
    np.testing.assert_array_equal(swept.flags.values, base.flags.values)
    np.testing.assert_allclose(swept.niirs.values, base.niirs.values, rtol=0, atol=1e-6)
    for name in ("rer_x", "rer_y", "eho_x", "eho_y"):
        # 7e-7 measured: the rule is not split at the obscured aperture's kinks
        np.testing.assert_allclose(swept[name].values, base[name].values, rtol=2e-6,
                                   err_msg=name)
    for name in ("snr", "gsd", "target_photoelectrons"):
        np.testing.assert_array_equal(swept[name].values, base[name].values, err_msg=name)


def test_zero_defocus_leaves_the_system_otf_to_the_bit():
    f = xr.DataArray(np.linspace(0, 2e5, 33), dims="frequency")
    base = xbsm.system_otf(olson_sensor("nir"), SCENARIO, f)
    zero = xbsm.system_otf(olson_sensor("nir", defocus_opd=0.0), SCENARIO, f)
    xr.testing.assert_identical(base, zero)


def test_defocus_enters_both_slices_filtered_and_unfiltered():
    kernel = [[0.0, -0.1, 0.0], [-0.1, 1.4, -0.1], [0.0, -0.1, 0.0]]
    f = xr.DataArray(np.linspace(0, 2e5, 33), dims="frequency")
    base = xbsm.system_otf(olson_sensor("nir", filter_kernel=kernel), SCENARIO, f)
    blurred = xbsm.system_otf(olson_sensor("nir", filter_kernel=kernel, defocus_opd=0.5 * LAM),
                              SCENARIO, f)
    ratio = blurred["aperture"] / base["aperture"]
    for name in ("system", "system_unfiltered"):
        for o in ("x", "y"):
            got = (blurred[name] / base[name]).sel(orientation=o).isel(frequency=slice(1, 20))
            np.testing.assert_allclose(got, ratio.isel(frequency=slice(1, 20)), rtol=1e-12)
    assert float(ratio.isel(frequency=10)) < 0.95


def test_single_scenario_and_sweep_agree_with_defocus():
    # the direct applier (one eager scenario) against the labelled one (a sweep): to the
    # edge rule's convergence, since the sweep's rule has a panel per lobe of its widest
    # defocus (7e-8 relative measured on the first cell; to the bit on the widest)
    opd = [0.3 * LAM, 1.2 * LAM]
    swept = xbsm.niirs(olson_sensor("nir", defocus_opd=xr.DataArray(opd, dims="defocus")),
                       SCENARIO)
    for i, value in enumerate(opd):
        one = xbsm.niirs(olson_sensor("nir", defocus_opd=value), SCENARIO)
        np.testing.assert_allclose(swept.niirs.isel(defocus=i).values, one.niirs.values,
                                   rtol=1e-12 if i == len(opd) - 1 else 1e-6)


def test_pybsm_refuses_defocus_and_is_unchanged_without_it():
    s = olson_sensor("nir", defocus_opd=0.2e-6)
    with pytest.raises(ValueError, match="defocus_opd is non-zero"):
        xbsm.niirs(s, SCENARIO, method="pybsm")
    # the other pyBSM numerics with a defocus model chosen explicitly
    out = xbsm.niirs(s, SCENARIO, method=xbsm.method("pybsm", defocus_otf="hopkins"))
    base = xbsm.niirs(olson_sensor("nir"), SCENARIO, method="pybsm")
    assert np.all(out.niirs.values < base.niirs.values)


@pytest.mark.parametrize("value", [-1e-7, np.nan, np.inf])
def test_bad_defocus_is_refused_naming_the_parameter(value):
    with pytest.raises(ValueError, match=r"defocus_opd must .*\[0, inf\) m"):
        olson_sensor("nir", defocus_opd=value)


def test_models_order_as_measured_and_agree_at_zero():
    # docs/otf.md: at 0.5 waves on the Olson camera geometric < gaussian < hopkins
    s = olson_sensor("nir", defocus_opd=0.5 * LAM)
    n = {m: float(xbsm.niirs(s, SCENARIO, method=xbsm.method("accurate", defocus_otf=m))
                  .niirs.sel(giqe=4)) for m in ("hopkins", "geometric", "gaussian")}
    assert n["geometric"] < n["gaussian"] < n["hopkins"]


@pytest.mark.parametrize("lengths", [(0.05, 0.05), (0.05, 0.08)])
@pytest.mark.parametrize("variance", [0.0, 0.3])
def test_wavefront_slices_equal_the_pair_kernel_to_the_bit(lengths, variance):
    """The direct applier evaluates the wavefront OTF on each slice's own 1-D nodes (and
    once for both when the correlation lengths are equal: issue 22's speed work); the
    values are those of the kernel on the (frequency, orientation) pair, to the bit."""
    from xbsm.otf.system import _wavefront_band_kernel, _wavefront_slices

    rng = np.random.default_rng(11)
    nodes = np.sort(rng.uniform(0.0, 4e5, 200))
    wl = np.linspace(3.6e-6, 4.2e-6, 61)
    w = rng.uniform(0.0, 1.0, 61)
    w = w / w.sum()
    p = {"wavefront_variance": np.float64(variance), "wavefront_wavelength": np.float64(1e-6),
         "wavefront_correlation_length_x": np.float64(lengths[0]),
         "wavefront_correlation_length_y": np.float64(lengths[1])}
    pair = _wavefront_band_kernel(p["wavefront_variance"], p["wavefront_wavelength"],
                                  nodes[:, None] * [1.0, 0.0], lengths[0],
                                  nodes[:, None] * [0.0, 1.0], lengths[1], wl, w)
    slices = _wavefront_slices(p, nodes, wl, w)
    assert slices.shape == pair.shape == (200, 2)
    assert np.array_equal(slices, pair)
