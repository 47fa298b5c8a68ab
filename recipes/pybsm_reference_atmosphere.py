"""pyBSM 0.16.1 ``load_database_atmosphere`` outputs for the "linear" parity test.

Run from the repository root with the pyBSM environment (pyBSM 0.16.1, NumPy 2;
how to make it: ``recipes/README.md``)::

    NUMBA_NUM_THREADS=1 recipes/_cache/pybsm-venv/bin/python recipes/pybsm_reference_atmosphere.py

Writes ``tests/fixtures/atmosphere_pybsm_linear.json``: for a handful of off-node
(altitude, ground range, ihaze) points, the values pyBSM returns at a few wavelength
rows, for all five columns, as exact float hex strings. Only points that pyBSM can
interpolate are used: altitudes in [75, 20000] m (pyBSM fails in (2, 75) m and clamps
above 20 km) whose four bracketing tables exist.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
from _pybsm_env import pybsm_required

with pybsm_required():
    import pybsm
    from pybsm.utils import load_database_atmosphere

OUT = Path(__file__).resolve().parents[1] / "tests" / "fixtures" / "atmosphere_pybsm_linear.json"

# (altitude [m], ground range [m], ihaze): off-node in altitude, ground range or both
POINTS = [
    (1500.0, 10500.0, 1),
    (3700.0, 45300.0, 2),
    (12500.0, 87000.0, 1),
    (80.0, 300.0, 2),
    (9000.5, 20500.25, 1),
    (7300.0, 250000.0, 2),
    (19000.0, 299000.0, 1),
    (4000.0, 12345.0, 2),  # altitude on a node, ground range off
    (650.0, 5000.0, 1),  # ground range on a node, altitude off
]
# wavelength rows: 0.30, 0.45, 0.60, 1.00, 2.00, 4.00, 7.30, 10.30, 14.00 um
ROWS = [0, 15, 30, 70, 170, 370, 700, 1000, 1370]


def main() -> int:
    records = []
    for altitude, ground_range, ihaze in POINTS:
        atm = load_database_atmosphere(altitude=altitude, ground_range=ground_range,
                                       ihaze=ihaze)
        records.append({
            "altitude": altitude, "ground_range": ground_range, "ihaze": ihaze,
            "values_hex": [[float(atm[r, c]).hex() for c in range(1, 6)] for r in ROWS],
        })
    fixture = {
        "comment": "pybsm.utils.load_database_atmosphere(altitude, ground_range, ihaze) of "
                   f"pyBSM {pybsm.__version__ if hasattr(pybsm, '__version__') else '0.16.1'} "
                   f"with NumPy {np.__version__} (made by "
                   "recipes/pybsm_reference_atmosphere.py). values_hex[i][c]: row "
                   "wavelength_index[i] of the returned array, column c + 1 (TRANS, PTH_THRML, "
                   "SURF_EMIS, SOL_SCAT, GRND_RFLT; radiances in W/(sr m^2 m)), float.hex.",
        "python": sys.version.split()[0],
        "wavelength_index": ROWS,
        "points": records,
    }
    OUT.write_text(json.dumps(fixture, indent=1) + "\n")
    print(f"wrote {OUT}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
