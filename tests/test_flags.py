"""xbsm.flags: decoding reads each flag variable's own CF table."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
import xarray as xr
from dense_edge import dense_rer  # tests/dense_edge.py, shared

import xbsm
from xbsm import flags, study


def _rising():
    # NIIRS 4, 6, 8 over three apertures: 5 is met between the first and the second
    d = np.array([0.1, 0.2, 0.3])
    return xr.DataArray([4.0, 6.0, 8.0], dims="aperture_diameter",
                        coords={"aperture_diameter": ("aperture_diameter", d, {"units": "m"})})


def test_decode_reads_goal_flags_by_their_own_meanings():
    # NIIRS 6 is met at the first aperture already: bound_at_grid_edge, value 2
    # (xbsm.study.goals.GOAL_FLAGS); the model's bit 2 is atmosphere_sparse (xbsm.flags.FLAGS),
    # which a decoder that ignores the variable's attributes reports instead
    goal = study.min_parameter(_rising(), 3.0, "aperture_diameter")
    assert int(goal.goal_flags) == 2
    bits = flags.decode(goal.goal_flags)
    assert bool(bits.bound_at_grid_edge)
    assert not bool(bits.never_meets) and not bool(bits.invalid_cell)
    assert "atmosphere_sparse" not in bits


def test_decode_reads_goal_flags_written_to_netcdf(tmp_path):
    # the attributes survive a NetCDF round trip (flag_masks comes back as an array)
    goal = study.max_range(_rising().rename(aperture_diameter="ground_range"), 9.0,
                           dim="ground_range")
    goal.to_netcdf(tmp_path / "goal.nc")
    with xr.open_dataset(tmp_path / "goal.nc") as back:
        bits = flags.decode(back.goal_flags)
        # 9 is never met on the grid: never_meets, value 1 (GOAL_FLAGS)
        assert bool(bits.never_meets) and not bool(bits.bound_at_grid_edge)


def test_decode_refuses_a_variable_without_a_flag_table():
    with pytest.raises(ValueError, match="flag_masks and flag_meanings"):
        flags.decode(xr.DataArray([0, 2], dims="case"))


def test_decode_refuses_unpaired_masks_and_meanings():
    bad = xr.DataArray([1]).assign_attrs(flag_masks=np.array([1, 2]), flag_meanings="one")
    with pytest.raises(ValueError, match="one to one"):
        flags.decode(bad)


def test_decode_of_the_model_flags_keeps_the_groups():
    # 4 | 512: well_fill_limited (a notice) and snr_nonpositive (invalid) (xbsm.flags.FLAGS)
    raw = xr.DataArray([0, 4 | 512], dims="case").assign_attrs(flags.flag_attrs())
    bits = flags.decode(raw)
    assert bits.well_fill_limited.values.tolist() == [False, True]
    assert bits.invalid.values.tolist() == [False, True]
    assert bits.outside_calibration.values.tolist() == [False, False]
    assert set(flags.FLAGS) <= set(bits.data_vars)


def test_decode_of_every_flag_variable_of_a_niirs_result():
    n = xbsm.niirs(xbsm.examples.olson_sensor(), xbsm.examples.olson_scenario())
    for name in [v for v in n.data_vars if v == "flags" or v.endswith("_flags")]:
        bits = flags.decode(n[name])
        assert set(bits.data_vars) >= set(n[name].attrs["flag_meanings"].split())


def test_a_one_axis_drift_with_a_negative_slice_is_nan_flagged_and_silent():
    # issue 23: the uniform-panel Gauss-Legendre rule of the old `fast` preset on a one-axis
    # drift of 170-180 pixels (Olson NIR, IFOV 2 urad, 30 ms) gives rer_x slightly below
    # zero. Every GIQE is undefined there: NaN with rer_nonpositive ("either slice",
    # docs/flags.md), both appliers, and no numpy RuntimeWarning reaching the user.
    from xbsm.examples import olson_scenario, olson_sensor
    old_fast = xbsm.method("fast", edge_rule="gauss_legendre", nodes_per_panel=6)
    pixels = xr.DataArray(np.arange(170.0, 180.0), dims="drift_pixels")
    sensor = olson_sensor("nir", drift_rate_x=pixels * 2e-6 / 0.03)
    scenario = olson_scenario(ground_range=0.0).isel(visibility=0)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        swept = xbsm.niirs(sensor, scenario, method=old_fast)
        negative = swept.rer_x < 0
        assert negative.any()  # the case the test is about
        single = xbsm.niirs(sensor.isel(drift_pixels=int(np.argmax(negative.values))), scenario,
                            method=old_fast)
        # the Kronrod rule of today's presets resolves the drift: positive, unflagged
        fast = xbsm.niirs(sensor, scenario, method="fast")
    for out in (swept.where(negative, drop=True), single):
        assert np.isnan(out.niirs).all()
        assert np.isnan(out.rer).all()
        assert (out.flags.astype(np.int64) & flags.flag("rer_nonpositive")).all()
    assert (fast.rer_x > 0).all()
    assert not (fast.flags & flags.flag("rer_nonpositive")).any()


def test_a_one_axis_smear_is_flagged_unresolved_on_its_own_slice():
    # issue 23: Olson NIR with a drift of 109 pixels along x (IFOV 2 urad, 30 ms; the well
    # fill shortens the exposure to 20.4 ms here: 74 px). The old uniform-panel rule gives
    # a wrong rer_x with the geometric mean above its threshold: the flag looks at the
    # worse slice. The Kronrod rule of `accurate` resolves it: within 1e-9 of a dense
    # trapezoid on the same system OTF, and unflagged.
    from xbsm.examples import olson_scenario, olson_sensor
    from xbsm.quadrature import UNRESOLVED_RER

    sensor = olson_sensor("nir", drift_rate_x=109 * 2e-6 / 0.03)
    scenario = olson_scenario(ground_range=0.0).isel(visibility=0)
    old = xbsm.niirs(sensor, scenario, method=xbsm.method("accurate", edge_rule="gauss_legendre",
                                                          nodes_per_panel=10))
    assert float(old.rer) > UNRESOLVED_RER > float(old.rer_x)  # the case the test is about
    assert (old.flags & flags.flag("blur_unresolved")).all()
    out = xbsm.niirs(sensor, scenario, method="accurate")
    reference = dense_rer(sensor, scenario, "accurate")
    assert abs(float(out.rer_x) - reference[0]) < 1e-9
    assert abs(float(old.rer_x) / reference[0] - 1) > 5e-4  # the old rule: 1e-3 relative
    assert not (out.flags & flags.flag("blur_unresolved")).any()
    # a symmetric, well-resolved system stays unflagged
    plain = xbsm.niirs(olson_sensor("nir"), olson_scenario(ground_range=0.0).isel(visibility=0))
    assert not (plain.flags & flags.flag("blur_unresolved")).any()


