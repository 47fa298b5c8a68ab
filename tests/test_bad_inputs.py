"""Bad input at every public entry point: a clear error naming the parameter, or a flag.

One row per case. An error row names the exception, the parameter the message must
name, and a fragment of the allowed range or choices it must state; a flag row names
the flag bit the result must carry. Built from the parameter tables, so a new
parameter is covered the day it is added, and from the hand-written rows of
``tests/bad_input_table.py``, which recipes/evidence/bad_input_sweep.py runs too.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
from bad_input_table import (  # tests/bad_input_table.py, shared with the sweep recipe
    ERROR_ROWS,
    INTERNALS,
    RESULT_ROWS,
    SC,
    SCENARIO,
    SENSOR,
    S,
)
from hypothesis import given, settings
from hypothesis import strategies as st

import xbsm
from xbsm import params
from xbsm.flags import has_flag


def _bad_values(spec: params.Spec):
    """Values outside ``spec``: below, at an open end, infinite, NaN, not a real number."""
    out = [math.inf, math.nan, "0.1", 1 + 2j, True]
    if spec.low > -math.inf:
        out.append(spec.low - 1.0)
        if spec.low_open:
            out.append(spec.low)
    if spec.high < math.inf:
        out.append(spec.high + 1.0)
    return out


def _rows(specs, make):
    for name, spec in specs.items():
        for value in _bad_values(spec):
            yield pytest.param(make, name, value, id=f"{name}={value!r}")


SPEC_ROWS = [
    *_rows(params.SENSOR_SPECS, lambda **kw: xbsm.sensor(**{**SENSOR, **kw})),
    *_rows(params.SCENARIO_SPECS, lambda **kw: xbsm.scenario(**{**SCENARIO, **kw})),
]


@pytest.mark.parametrize("make, name, value", SPEC_ROWS)
def test_out_of_range_or_non_numeric_value_names_the_parameter(make, name, value):
    with pytest.raises(ValueError) as err:
        make(**{name: value})
    message = str(err.value)
    assert name in message
    assert ("must lie in" in message or "real number" in message or "must be" in message
            or "smaller than" in message), message
    assert not [part for part in INTERNALS if part in message], message


def test_table_has_at_least_120_rows():
    assert len(SPEC_ROWS) + len(ERROR_ROWS) >= 120


@pytest.mark.parametrize("dim", params.RESERVED_DIMS)
def test_each_reserved_dimension_name_is_refused(dim):
    with pytest.raises(ValueError, match=f"swept on dimension '{dim}'"):
        xbsm.scenario(**{**SCENARIO, "ground_range": xr.DataArray([0.0, 2e4], dims=dim)})


def test_the_guide_lists_each_reserved_dimension_name():
    # docs/guide.md names every reserved dimension; the <parameter>_wavelength ones as a pattern
    guide = (Path(__file__).resolve().parent.parent / "docs" / "guide.md").read_text()
    for dim in params.RESERVED_DIMS:
        shown = "<parameter>_wavelength" if dim.endswith("_wavelength") else dim
        assert f"`{shown}`" in guide, dim





@pytest.mark.parametrize("call, error, fragment",
                         [pytest.param(c, e, f, id=i) for i, c, e, f in ERROR_ROWS])
def test_bad_call_raises_a_clear_error(call, error, fragment):
    with pytest.raises(error) as err:
        call()
    assert fragment in str(err.value), str(err.value)
    assert not [part for part in INTERNALS if part in str(err.value)], str(err.value)


# --- issue 20: the review's new inputs that give a result: flagged or documented ----------



@pytest.mark.parametrize("call, check",
                         [pytest.param(c, k, id=i) for i, c, k, _ in RESULT_ROWS])
def test_odd_input_gives_a_flagged_or_documented_result(call, check):
    assert check(call())


# --- inputs that are legitimate but odd: converted, promoted or flagged, never silent ------


def test_atmosphere_at_reads_the_units_attribute():
    km = xbsm.atmosphere_at(9000.0, xr.DataArray(20.0, attrs={"units": "km"}), 23.0)
    xr.testing.assert_identical(km.transmission, xbsm.atmosphere_at(9000.0, 20e3,
                                                                     23.0).transmission)


def test_cli_refuses_an_output_that_is_a_file(tmp_path, capsys):
    from xbsm.cli import main
    target = tmp_path / "file.txt"
    target.write_text("x")
    with pytest.raises(SystemExit) as exit_:
        main(["olson", "--out", str(target)])
    assert exit_.value.code == 2
    assert "exists and is not a directory" in capsys.readouterr().err


def test_units_attribute_is_converted():
    km = xbsm.scenario(**{**SCENARIO, "ground_range": xr.DataArray(
        [20.0], dims="g", attrs={"units": "km"})})
    assert float(km.ground_range[0]) == 20e3
    mm = xbsm.sensor(**{**SENSOR, "aperture_diameter": xr.DataArray(275.0,
                                                                     attrs={"units": "mm"})})
    assert float(mm.aperture_diameter) == pytest.approx(0.275, rel=1e-15)
    urad = xbsm.sensor(**{**SENSOR, "jitter_x": xr.DataArray(0.5, attrs={"units": "urad"})})
    assert float(urad.jitter_x) == pytest.approx(0.5e-6, rel=1e-15)


@pytest.mark.parametrize("dtype", [np.float16, np.float32, np.int64])
def test_low_precision_and_integer_inputs_are_promoted(dtype):
    altitude = xr.DataArray(np.array([9000], dtype=dtype), dims="case")
    sc = xbsm.scenario(**{**SCENARIO, "altitude": altitude, "ground_range": 0.0})
    assert sc.altitude.dtype == np.float64
    # the slant range at nadir is the altitude itself (float32 arithmetic gave 8688.9 m)
    n = xbsm.niirs(S, sc)
    assert float(n.slant_range[0]) == pytest.approx(9000.0, rel=1e-12)


def test_sweep_on_the_parameters_own_name_keeps_every_output():
    times = xr.DataArray([0.01, 0.03], dims="integration_time",
                         coords={"integration_time": [0.01, 0.03]})
    n = xbsm.niirs(xbsm.sensor(**{**SENSOR, "integration_time": times}), SC)
    assert n.sizes["integration_time"] == 2
    assert "effective_integration_time" in n


def test_beyond_the_horizon_is_flagged_not_silent():
    far = xbsm.scenario(**{**SCENARIO, "altitude": 100.0, "ground_range": 150e3})
    n = xbsm.niirs(S, far)
    assert bool(np.isnan(n.niirs).all())
    assert bool(has_flag(n.flags, "beyond_database").all())
    o = xbsm.system_otf(S, far)
    assert bool(has_flag(o.flags, "beyond_database"))


def test_a_system_blurred_over_many_pixels_is_flagged_not_trusted():
    # RER 0.019 from 20 px of jitter: the edge quadrature does not resolve the narrow OTF
    # (recipes/evidence/preset_error.py: accurate off by up to 28 NIIRS below RER 0.05)
    blurred = xbsm.sensor(**{**SENSOR, "jitter_x": 160e-6, "jitter_y": 160e-6})
    n = xbsm.niirs(blurred, SC)
    assert float(n.rer) < 0.05
    assert bool(xbsm.flags.decode(n.flags).blur_unresolved.all())
    assert bool(xbsm.flags.is_invalid(n.flags).all())
    assert not bool(xbsm.flags.decode(xbsm.niirs(S, SC).flags).blur_unresolved.any())


CURVE_BAND = dict(dims="wavelength")


@pytest.mark.parametrize("name, wavelengths", [
    ("quantum_efficiency", [0.5e-6, 0.6e-6]),      # ends inside the 0.55-0.85 um band
    ("optics_transmission", [0.6e-6, 0.9e-6]),     # starts inside it
    ("stray_irradiance", [0.6e-6, 0.7e-6]),        # inside at both ends
])
def test_a_curve_covering_part_of_the_band_is_flagged(name, wavelengths):
    # docs/flags.md: partial_spectral_coverage (a notice) on snr, niirs and system_otf
    curve = xr.DataArray([0.5, 0.5], coords={"wavelength": wavelengths}, **CURVE_BAND)
    s = xbsm.sensor(**{**SENSOR, name: curve})
    for result in (xbsm.snr(s, SC), xbsm.niirs(s, SC), xbsm.system_otf(s, SC)):
        bits = xbsm.flags.decode(result.flags)
        assert bool(bits.partial_spectral_coverage.all())
        assert not bool(bits.invalid.any())
    assert "partial_spectral_coverage" in xbsm.flags.NOTICE


def test_a_curve_covering_the_band_is_not_flagged():
    # the band edges written another way (0.55 * 1e-6) still cover the band; a curve sampled
    # only outside the band spans it and is non-zero inside (it was refused as zero before)
    curve = xr.DataArray([0.7, 0.6], coords={"wavelength": [0.55 * 1e-6, 0.85 * 1e-6]},
                         **CURVE_BAND)
    wider = xr.DataArray([0.7, 0.6], coords={"wavelength": [0.4e-6, 1.0e-6]}, **CURVE_BAND)
    for s in (xbsm.sensor(**{**SENSOR, "quantum_efficiency": curve}),
              xbsm.sensor(**{**SENSOR, "optics_transmission": wider}), S):
        assert not bool(has_flag(xbsm.niirs(s, SC).flags, "partial_spectral_coverage").any())


def test_a_sensor_without_signal_is_flagged_in_its_own_cells_of_a_sweep():
    # cold_filter_transmission = 0: no wavelength reaches the detector, so no optics cutoff
    # D / lambda_min of the signal; the call must not fail for the whole sweep (it raised
    # "cutoff must be finite"), the zero-signal cell is NaN with snr_nonpositive (flags.md)
    s = xbsm.sensor(**{**SENSOR, "cold_filter_transmission": xr.DataArray([0.0, 1.0],
                                                                          dims="cold_filter")})
    n = xbsm.niirs(s, SC)
    dark, lit = n.isel(cold_filter=0), n.isel(cold_filter=1)
    assert bool(np.isnan(dark.niirs).all()) and bool(has_flag(dark.flags, "snr_nonpositive").all())
    assert bool(np.isfinite(lit.niirs).all())
    single = xbsm.niirs(xbsm.sensor(**SENSOR), SC)
    np.testing.assert_allclose(lit.niirs, single.niirs, rtol=1e-12)


def test_an_even_pybsm_grid_is_a_valid_grid():
    # pyBSM's slice of linspace(-1, 1, N) is arange(0, 1, 2 / (N - 1)): 50 samples up to
    # 0.99 of the cutoff for N = 100 (0.98 for N = 101). The bound: undersampling_threshold
    # flags wherever the uniform rule's NIIRS error may exceed 0.01 (xbsm.methods), so an
    # unflagged even grid must agree with the converged Gauss-Legendre rule within 0.01.
    even = xbsm.niirs(S, SC, xbsm.method("pybsm", frequency_samples=100))
    converged = xbsm.niirs(S, SC, xbsm.method("pybsm", edge_rule="gauss_legendre"))
    assert not bool(has_flag(even.flags, "undersampled_grid").any())
    assert float(abs(even.niirs - converged.niirs).max()) <= 0.01
    assert float(abs(even.rer - converged.rer)) <= 1e-3


def test_method_overrides_are_recorded_in_the_result():
    n = xbsm.niirs(S, SC, xbsm.method("pybsm", frequency_samples=201))
    assert n.attrs["method"] == "pybsm (frequency_samples=201)"
    assert xbsm.snr(S, SC).attrs["method"] == "accurate"


def test_decode_gives_one_boolean_per_flag():
    n = xbsm.niirs(S, SC)
    bits = xbsm.flags.decode(n.flags)
    assert set(xbsm.flags.FLAGS) <= set(bits.data_vars)
    assert bits.invalid.dims == n.flags.dims
    np.testing.assert_array_equal(bits.well_fill_limited, has_flag(n.flags, "well_fill_limited"))


# --- random invalid values: an error naming the parameter, never a silent number ----------

_SENSOR_NAMES = [n for n in params.SENSOR_SPECS if n not in ("wavelength_min", "wavelength_max")]


@settings(max_examples=150, deadline=None)
@given(name=st.sampled_from(_SENSOR_NAMES),
       value=st.one_of(st.just(math.inf), st.just(-math.inf), st.just(math.nan),
                       st.floats(-1e12, -1e-300), st.text(max_size=3),
                       st.complex_numbers(allow_nan=False, allow_infinity=False)
                       .filter(lambda z: z.imag != 0)))
def test_random_invalid_sensor_values_raise_naming_the_parameter(name, value):
    spec = params.SENSOR_SPECS[name]
    try:
        xbsm.sensor(**{**SENSOR, name: value})
    except ValueError as err:
        assert name in str(err)
        return
    # accepted: only a real, finite value inside the allowed interval may pass
    assert isinstance(value, float) and not spec.violated(np.asarray(value)).any()
