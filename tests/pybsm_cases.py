"""Load the pyBSM 0.16.1 reference fixture (written by recipes/pybsm_reference.py)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

import xbsm.pybsm_compat as compat

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
