"""One scenario on plain arrays (xbsm/_one_scenario.py) against the labelled chain.

The expected results are the labelled chain's own (``model._snr``, ``model._niirs``),
which the pyBSM parity and physics tests check; here both paths must agree on every
pyBSM reference case of tests/fixtures/pybsm_cases.json (200 sensors and scenarios:
visible to LWIR, curves, filters, turbulence, stacking, beyond the database), in
structure exactly (variables, dims, dtypes, coordinates, attributes) and in values to
1e-12 relative (the kernels are the same; only the OTF's wavelength bins are summed by
another routine).
"""

from __future__ import annotations

import dask.array  # noqa: F401  (the dask fallback test)
import numpy as np
import pytest
import xarray as xr
from pybsm_cases import datasets, load_cases

import xbsm
from xbsm import _one_scenario, metrics, model
from xbsm.examples import olson_scenario, olson_sensor
from xbsm.methods import method

CASES, _ = load_cases()


def assert_same(labelled: xr.Dataset, single: xr.Dataset) -> None:
    assert list(single.variables) == list(labelled.variables)
    assert single.attrs == labelled.attrs
    for name, expected in labelled.variables.items():
        got = single.variables[name]
        assert got.dims == expected.dims, name
        assert got.dtype == expected.dtype, name
        assert got.attrs.keys() == expected.attrs.keys(), name
        for key, value in expected.attrs.items():
            np.testing.assert_array_equal(got.attrs[key], value, err_msg=f"{name}.{key}")
        if expected.dtype.kind in "iu":
            np.testing.assert_array_equal(got.values, expected.values, err_msg=name)
        else:
            np.testing.assert_allclose(got.values, expected.values, rtol=1e-12, atol=0,
                                       equal_nan=True, err_msg=name)
    assert set(single.indexes) == set(labelled.indexes)


def single(call, labelled):
    """``call()`` twice: the first makes the template, the second must fill it."""
    _one_scenario._TEMPLATES.clear()
    call()

    def refuse():
        raise AssertionError("the one-scenario path fell back to the labelled chain")

    original = model._niirs, model._snr
    model._niirs = model._snr = lambda *a, **k: refuse()
    try:
        return call()
    finally:
        model._niirs, model._snr = original
        assert labelled is not None


def _cases(step):
    return [pytest.param(i, id=CASES[i]["sensor"]["name"]) for i in range(0, len(CASES), step)]


@pytest.mark.parametrize("index", _cases(1))
def test_niirs_and_snr_of_every_reference_case(index):
    s, sc = datasets(CASES[index])
    m = method("accurate")
    labelled = model._niirs(s, sc, m, metrics.giqe_calibrations(None))
    assert_same(labelled, single(lambda: xbsm.niirs(s, sc), labelled))
    labelled = model._snr(s, sc, m, "giqe")[0]
    assert_same(labelled, single(lambda: xbsm.snr(s, sc), labelled))


@pytest.mark.parametrize("name", ["pybsm", "fast"])
@pytest.mark.parametrize("index", _cases(10))
def test_other_presets(index, name):
    s, sc = datasets(CASES[index])
    m = method(name)
    labelled = model._niirs(s, sc, m, metrics.giqe_calibrations(None))
    assert_same(labelled, single(lambda: xbsm.niirs(s, sc, method=m), labelled))


@pytest.mark.parametrize("index", _cases(10))
def test_scenario_targets(index):
    s, sc = datasets(CASES[index])
    labelled = model._snr(s, sc, method("accurate"), "scenario")[0]
    assert_same(labelled, single(lambda: xbsm.snr(s, sc, targets="scenario"), labelled))


def test_knobs_and_calibration_reach_the_single_path():
    """Binned OTF wavelengths, the uniform edge rule (its undersampling flag), abs OTF, a
    calibration of one's own."""
    s, sc = olson_sensor("nir"), olson_scenario(ground_range=30000.0, visibility=5.0)
    m = method("accurate", otf_wavelengths=4, edge_rule="uniform_trapezoid", edge_otf="abs",
               frequency_samples=40)
    calibration = metrics.giqe_calibrations({5: metrics.GIQE5_CALIBRATION.replace(snr=(2, 30))})
    labelled = model._niirs(s, sc, m, calibration)
    assert_same(labelled, single(
        lambda: xbsm.niirs(s, sc, method=m, calibration={5: calibration[5]}), labelled))


def test_a_new_band_gets_its_own_template():
    s, sc = olson_sensor("red"), olson_scenario(ground_range=20000.0, visibility=5.0)
    xbsm.niirs(s, sc)
    wider = s.assign(wavelength_max=s["wavelength_max"] + 2e-8)  # two more samples
    labelled = model._niirs(wider, sc, method("accurate"), metrics.giqe_calibrations(None))
    assert_same(labelled, xbsm.niirs(wider, sc))
    shifted = s.assign(wavelength_min=s["wavelength_min"] + 3e-9,
                       wavelength_max=s["wavelength_max"] + 3e-9)  # same count, other values
    xbsm.snr(s, sc)
    labelled = model._snr(shifted, sc, method("accurate"), "giqe")[0]
    assert_same(labelled, xbsm.snr(shifted, sc))


def test_sweeps_dask_and_bad_values_take_the_labelled_chain():
    s, sc = olson_sensor("red"), olson_scenario(ground_range=20000.0, visibility=5.0)
    assert _one_scenario.inputs(s, sc) is not None
    swept = sc.assign(ground_range=xr.DataArray([1e4, 2e4], dims="range_sweep"))
    assert _one_scenario.inputs(s, swept) is None
    assert xbsm.niirs(s, swept)["niirs"].dims == ("giqe", "range_sweep")
    lazy = sc.assign(altitude=xr.DataArray(dask.array.from_array(np.array(9000.0))))
    assert _one_scenario.inputs(s, lazy) is None
    assert xbsm.snr(s, lazy)["snr"].chunks is not None
    with pytest.raises(ValueError, match="aperture_diameter must lie in"):
        xbsm.niirs(s.assign(aperture_diameter=-1.0), sc)
    narrow = s.assign(wavelength_min=0.5015e-6, wavelength_max=0.5085e-6)  # no sample inside
    with pytest.raises(ValueError, match="must contain a database wavelength"):
        xbsm.niirs(narrow, sc, method="pybsm")  # exact band edges: no database sample


def test_editing_a_result_leaves_later_results_alone():
    s, sc = olson_sensor("red"), olson_scenario(ground_range=20000.0, visibility=5.0)
    _one_scenario._TEMPLATES.clear()
    first = xbsm.niirs(s, sc)  # the labelled chain's result, kept as the template
    first.attrs["note"] = "mine"
    first["niirs"].attrs["units"] = "edited"
    second = xbsm.niirs(s, sc)
    assert "note" not in second.attrs
    assert second["niirs"].attrs["units"] == "1"
    second["snr"].attrs["long_name"] = "edited"
    assert xbsm.niirs(s, sc)["snr"].attrs["long_name"] != "edited"
