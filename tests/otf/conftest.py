"""Fixtures for the OTF tests."""

from __future__ import annotations

import numpy as np
import pytest
from otf_helpers import FIXTURE


@pytest.fixture(scope="session")
def pybsm_otf():
    """pyBSM 0.16.1 reference values written by recipes/fixtures/pybsm_reference_otf.py."""
    with np.load(FIXTURE) as data:
        return {key: data[key] for key in data.files}
