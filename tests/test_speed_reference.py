"""The speed work changes no result: xbsm now against xbsm at main's cf2fa1d (issue 22).

``tests/fixtures/speed_reference.json`` holds ``xbsm.niirs`` and ``xbsm.snr`` results of
cf2fa1d (written by ``recipes/fixtures/speed_reference.py`` through that commit's public
API): every fifth pyBSM fixture case and Olson sweeps over each optics parameter, with
each method. Where the test runs on the fixture's numpy and CPU extensions (numpy's libm
paths depend on both), ``method="pybsm"`` must agree within 1e-13 relative (the pyBSM
parity tests' tolerance: the factored turbulence powers move pyBSM's own formula by a few
units in the last place, 5.7e-16 at most on these cases) and ``"accurate"`` / ``"fast"``
within 1e-12 relative (the issue's bound for an unavoidable reassociation).
Elsewhere (another numpy, another CPU: the CI's minimum-versions job) a different libm
rounds differently, and pyBSM's law-of-cosines slant range amplifies one rounding of a
cosine on short paths (``tests/pybsm_cases.geometry_rtol``: up to about 1e-6 at 100 m), so
the check there is 1e-6 relative: loose for rounding, tight for any change of the model.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

import xbsm
from xbsm.examples import olson_sensor

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "recipes" / "fixtures"))
import speed_reference as recipe  # noqa: E402  (the cases, written once)

REFERENCE = json.loads(recipe.OUT.read_text())


def _same_environment() -> bool:
    try:
        simd = recipe.simd()
    except ImportError:  # numpy < 2 keeps the CPU features elsewhere: not the fixture's numpy
        return False
    return np.__version__ == REFERENCE["numpy"] and simd == REFERENCE["simd"]


SAME = _same_environment()


def _compute() -> dict:
    """The recipe's cases on the current code, by the recipe's own loops."""
    out = {}
    for name, s, sc in recipe.fixture_cases():
        for method in recipe.METHODS:
            out[f"{name}/niirs/{method}"] = xbsm.niirs(s, sc, method=method)
            out[f"{name}/snr/{method}"] = xbsm.snr(s, sc, method=method)
    sc = xbsm.scenario(**recipe.BASE_SCENARIO)
    for parameter, (low, high) in recipe.SWEEPS.items():
        swept = xr.DataArray(np.linspace(low, high, 12), dims=parameter)
        s = olson_sensor("nir", **{parameter: swept})
        for method in recipe.METHODS:
            try:
                out[f"olson/{parameter}/{method}"] = xbsm.niirs(s, sc, method=method)
            except ValueError as error:
                out[f"olson/{parameter}/{method}"] = {"error": str(error)}
    ranges = xr.DataArray(np.linspace(0.0, 60e3, 12), dims="ground_range")
    for method in recipe.METHODS:
        out[f"olson/ground_range/{method}"] = xbsm.niirs(olson_sensor("nir"), xbsm.scenario(
            **{**recipe.BASE_SCENARIO, "ground_range": ranges}), method=method)
        for low, high in recipe.BANDS:
            s = olson_sensor("nir", wavelength_min=low, wavelength_max=high)
            out[f"olson/band_{low:.3g}_{high:.3g}/{method}"] = xbsm.niirs(s, sc, method=method)
    return {key: value if isinstance(value, dict) else recipe.values(value)
            for key, value in out.items()}


@pytest.fixture(scope="module")
def current():
    return _compute()


def test_speed_reference_same_cases(current):
    """Every case of the fixture is computed, with the same variables."""
    assert current.keys() == REFERENCE["cases"].keys()
    for key, ref in REFERENCE["cases"].items():
        assert current[key].keys() == ref.keys(), key


@pytest.mark.parametrize("method", recipe.METHODS)
def test_speed_reference_values_unchanged(current, method):
    """pybsm within 1e-13, accurate / fast within 1e-12 relative (1e-6 on another libm)."""
    rtol = (1e-13 if method == "pybsm" else 1e-12) if SAME else 1e-6
    for key, ref in REFERENCE["cases"].items():
        if not key.endswith(f"/{method}") or "error" in ref:
            continue
        for name, expected in ref.items():
            got, expected = np.asarray(current[key][name]), np.asarray(expected, dtype=float)
            assert got.shape == expected.shape, (key, name)
            assert np.array_equal(np.isnan(got), np.isnan(expected)), (key, name)
            ok = ~np.isnan(expected)
            same = got[ok] == expected[ok]  # also the infinite ones (r0 without turbulence)
            with np.errstate(invalid="ignore"):
                relative = np.where(same, 0.0, np.abs(got[ok] - expected[ok])
                                    / np.maximum(np.abs(expected[ok]), 1e-300))
            assert np.all(relative <= rtol), (key, name, float(relative.max()))
