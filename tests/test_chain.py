"""The model chain's two appliers (xbsm/_chain.py) against each other.

The labelled applier (each stage's labelled door) is what the pyBSM parity and
physics tests check; the direct applier (each stage's array orchestrator on plain
arrays, labelled once from the declarations) must agree with it on every pyBSM
reference case of tests/fixtures/pybsm_cases.json (200 sensors and scenarios:
visible to LWIR, curves, filters, turbulence, stacking, beyond the database), in
structure exactly (variables, dims, dtypes, coordinates, attributes) and in values to
1e-12 relative (the kernels are the same; only the OTF's wavelength bins are summed by
another routine).
"""

from __future__ import annotations

import dask.array  # noqa: F401  (the dask test)
import numpy as np
import pytest
import xarray as xr
from pybsm_cases import datasets, load_cases

import xbsm
from xbsm import _chain, metrics
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


def both(chain, s, sc, *args):
    """``chain`` (``_chain._snr_chain`` or ``_niirs_chain``) through each applier."""
    out = []
    for ap in (_chain.Labelled(s, sc), _chain.Direct(s, sc, _chain.single_scenario(s, sc))):
        with ap.errors():
            if chain is _chain._snr_chain:
                values, atm, _ = chain(ap, *args)
                out.append(ap.result(values, atm, *args[:1], targets=args[1]))
            else:
                out.append(ap.result(chain(ap, *args), None, args[0],
                                     flags="NIIRS validity flags"))
    return out


def _cases(step):
    return [pytest.param(i, id=CASES[i]["sensor"]["name"]) for i in range(0, len(CASES), step)]


@pytest.mark.parametrize("index", _cases(1))
def test_niirs_and_snr_of_every_reference_case(index):
    s, sc = datasets(CASES[index])
    m = method("accurate")
    assert_same(*both(_chain._niirs_chain, s, sc, m, metrics.giqe_calibrations(None)))
    assert_same(*both(_chain._snr_chain, s, sc, m, "giqe"))


@pytest.mark.parametrize("name", ["pybsm", "fast"])
@pytest.mark.parametrize("index", _cases(10))
def test_other_presets(index, name):
    s, sc = datasets(CASES[index])
    assert_same(*both(_chain._niirs_chain, s, sc, method(name),
                      metrics.giqe_calibrations(None)))


@pytest.mark.parametrize("index", _cases(10))
def test_scenario_targets(index):
    s, sc = datasets(CASES[index])
    assert_same(*both(_chain._snr_chain, s, sc, method("accurate"), "scenario"))


def test_knobs_and_calibration_reach_the_direct_applier():
    """Binned OTF wavelengths, the uniform edge rule (its undersampling flag), abs OTF, a
    calibration of one's own."""
    s, sc = olson_sensor("nir"), olson_scenario(ground_range=30000.0, visibility=5.0)
    m = method("accurate", otf_wavelengths=4, edge_rule="uniform_trapezoid", edge_otf="abs",
               frequency_samples=40)
    calibration = metrics.giqe_calibrations({5: metrics.GIQE5_CALIBRATION.replace(snr=(2, 30))})
    labelled, direct = both(_chain._niirs_chain, s, sc, m, calibration)
    assert_same(labelled, direct)
    assert_same(labelled, xbsm.niirs(s, sc, method=m, calibration={5: calibration[5]}))


def test_single_calls_take_the_direct_applier():
    s, sc = olson_sensor("red"), olson_scenario(ground_range=20000.0, visibility=5.0)
    assert isinstance(_chain.applier(s, sc), _chain.Direct)
    wider = s.assign(wavelength_max=s["wavelength_max"] + 2e-8)  # two more samples
    assert_same(*both(_chain._niirs_chain, wider, sc, method("accurate"),
                      metrics.giqe_calibrations(None)))
    assert_same(both(_chain._niirs_chain, wider, sc, method("accurate"),
                     metrics.giqe_calibrations(None))[0], xbsm.niirs(wider, sc))


def test_sweeps_dask_and_bad_values_take_the_labelled_applier():
    s, sc = olson_sensor("red"), olson_scenario(ground_range=20000.0, visibility=5.0)
    swept = sc.assign(ground_range=xr.DataArray([1e4, 2e4], dims="range_sweep"))
    assert isinstance(_chain.applier(s, swept), _chain.Labelled)
    assert xbsm.niirs(s, swept)["niirs"].dims == ("giqe", "range_sweep")
    lazy = sc.assign(altitude=xr.DataArray(dask.array.from_array(np.array(9000.0))))
    assert isinstance(_chain.applier(s, lazy), _chain.Labelled)
    assert xbsm.snr(s, lazy)["snr"].chunks is not None
    with pytest.raises(ValueError, match="aperture_diameter must lie in"):
        xbsm.niirs(s.assign(aperture_diameter=-1.0), sc)
    narrow = s.assign(wavelength_min=0.5015e-6, wavelength_max=0.5085e-6)  # no sample inside
    with pytest.raises(ValueError, match="must contain a database wavelength"):
        xbsm.niirs(narrow, sc, method="pybsm")  # exact band edges: no database sample


@pytest.mark.parametrize("name", ["accurate", "pybsm"])
def test_each_element_of_a_sweep_equals_its_single_call(name):
    # a sweep over the scenario's own target reflectance and the ground range, with a swept
    # dark current: every element equals the direct applier's single call bit for bit (the
    # band integrals sum each scenario's contiguous spectrum, whatever the sweep's layout;
    # with one door per kernel, before the signal stage ran as one orchestrator, this test
    # failed: numpy summed some spectra in another order, up to 1.4e-12 in the contrast SNR)
    s, sc = olson_sensor("nir"), olson_scenario(visibility=5.0)
    reflectances, ranges, darks = [0.05, 0.3], [0.0, 2e4, 6e4], [10.0, 1e4]
    sweep = xbsm.snr(
        s.assign(dark_current=xr.DataArray(darks, dims="dark")),
        sc.assign(target_reflectance=xr.DataArray(reflectances, dims="reflectances"),
                  ground_range=xr.DataArray(ranges, dims="ranges")),
        method=name, targets="scenario")
    for i, r in enumerate(reflectances):
        for j, g in enumerate(ranges):
            for k, d in enumerate(darks):
                one = xbsm.snr(s.assign(dark_current=d),
                               sc.assign(target_reflectance=r, ground_range=g),
                               method=name, targets="scenario")
                for variable in ("snr", "contrast_photoelectrons", "scene_noise"):
                    assert (float(sweep[variable].isel(reflectances=i, ranges=j, dark=k))
                            == float(one[variable])), (variable, r, g, d)


def test_editing_a_result_leaves_later_results_alone():
    s, sc = olson_sensor("red"), olson_scenario(ground_range=20000.0, visibility=5.0)
    first = xbsm.niirs(s, sc)
    first.attrs["note"] = "mine"
    first["niirs"].attrs["units"] = "edited"
    second = xbsm.niirs(s, sc)
    assert "note" not in second.attrs
    assert second["niirs"].attrs["units"] == "1"
    second["snr"].attrs["long_name"] = "edited"
    assert xbsm.niirs(s, sc)["snr"].attrs["long_name"] != "edited"


def test_declared_outputs_keep_only_the_sweep_dims_they_carry():
    """A sensor sweep and a scenario sweep: each output keeps the dims of what it carries."""
    s, sc = olson_sensor("red"), olson_scenario(visibility=5.0)
    s = s.assign(aperture_diameter=xr.DataArray([0.15, 0.2], dims="aperture_sweep"))
    sc = sc.assign(ground_range=xr.DataArray([1e4, 2e4], dims="range_sweep"))
    out = xbsm.niirs(s, sc)
    sweeps = {"sensor": "aperture_sweep", "scenario": "range_sweep"}
    checked = 0
    for name, output in _chain._DECLARED.items():
        if name not in out:
            continue
        for carried, dim in sweeps.items():
            if carried not in output.carries:
                assert dim not in out[name].dims, (name, out[name].dims)
                checked += 1
    assert checked >= 6


def test_dataset_of_equals_the_public_constructor():
    """The direct applier's Dataset constructor gives what ``xr.Dataset`` gives."""
    from xbsm._metadata import dataset_of

    wavelength = np.linspace(0.5e-6, 0.6e-6, 5)
    variables = {"a": xr.Variable((), 1.0, {"units": "1"}),
                 "b": xr.Variable("wavelength", wavelength * 2, {"units": "m"})}
    coords = {"wavelength": xr.Variable("wavelength", wavelength, {"units": "m"})}
    got = dataset_of(variables, coords, {"method": "accurate"})
    expected = xr.Dataset(variables, coords=coords, attrs={"method": "accurate"})
    xr.testing.assert_identical(got, expected)
    assert list(got.variables) == list(expected.variables)
    assert got.indexes["wavelength"].equals(expected.indexes["wavelength"])
