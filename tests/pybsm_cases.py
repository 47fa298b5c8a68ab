"""Load the pyBSM 0.16.1 reference fixture (written by recipes/fixtures/pybsm_reference.py)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

import xbsm.pybsm_compat as compat
from xbsm.constants import EARTH_RADIUS

FIXTURES = Path(__file__).parent / "fixtures"


def load_cases():
    """The cases (pyBSM keyword arguments) and outputs, indexed alike."""
    cases = json.loads((FIXTURES / "pybsm_cases.json").read_text())
    with np.load(FIXTURES / "pybsm_outputs.npz") as data:
        outputs = {key: data[key] for key in data.files}
    return cases, outputs


def datasets(case):
    """xbsm sensor and scenario datasets for one fixture case, through pybsm_compat."""
    sensor_kw = {k: v for k, v in case["sensor"].items()}
    sensor_kw.update(case["post"])
    scenario_kw = dict(case["scenario"])
    return compat.sensor(**sensor_kw), compat.scenario(**scenario_kw)


def geometry_rtol(case, slant_range, floor=1e-9):
    """Relative tolerance for parity on quantities that come from the slant range.

    pyBSM's law-of-cosines slant range ``s**2 = a**2 + c**2 - 2*a*c*cos(theta)`` (a, c the
    radii of sensor and target) cancels catastrophically on short paths: one rounding of
    ``cos(theta)``, which differs between libm builds (numpy 1.24 vs 2.x), moves ``s`` by
    about ``a * c * eps / s**2`` relative. Parity "to floating-point rounding" is within a
    few times that, or ``floor`` where the formula is well conditioned.
    """
    a = EARTH_RADIUS + case["scenario"]["altitude"]
    condition = a * EARTH_RADIUS / slant_range**2
    return max(floor, 4.0 * np.finfo(float).eps * condition)
