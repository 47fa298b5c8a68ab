"""How often ``blur_unresolved`` flags a long-range ground-based visible camera, and why.

Issue 23: the flag was a false alarm where it is most often hit. The camera:
aperture 0.15 m, focal length 1.5 m (F/10), band 0.4-0.7 um, pitch 3.45 um
(a common global-shutter CMOS pixel; Q = lambda_min F / p = 1.16),
integration time 2 ms, read noise 5 e-, well 10^4 e-, no jitter or drift
(a tripod), obscuration 0. Scenarios: altitude 10, 20, 50, 100 m x ground range
1, 2, 3, 5, 7, 10, 15, 20, 25, 30 km x visibility 23 and 5 km, HV 5/7
turbulence (the scenario defaults: Cn2(1 m) 1.7e-14 m^-2/3, high-altitude wind
21 m/s), platform speed 0. Cells beyond the database (below the horizon) are
left out.

For ``accurate`` and ``fast``: the share of cells flagged ``blur_unresolved``
and |NIIRS - reference| (GIQE 3, 4, 5) behind flagged and unflagged cells,
with the independent reference of ``recipes/evidence/edge_reference.py``.

Writes ``docs/benchmarks/ground_camera_flags.json`` (``--out`` to change). Run
from the repository root::

    PYTHONPATH=. .venv/bin/python recipes/evidence/ground_camera_flags.py
"""

from __future__ import annotations

import argparse
import itertools
import os
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))
sys.path.insert(0, str(HERE))

import numpy as np  # noqa: E402
import preset_error as pe  # noqa: E402
from _provenance import commit, machine  # noqa: E402

import xbsm  # noqa: E402

OUT = HERE.parents[1] / "docs" / "benchmarks" / "ground_camera_flags.json"
METHODS = ("accurate", "fast")
SENSOR = dict(aperture_diameter=0.15, focal_length=1.5, pixel_pitch_x=3.45e-6,
              wavelength_min=0.4e-6, wavelength_max=0.7e-6, integration_time=0.002,
              read_noise=5.0, max_well=1e4)
ALTITUDES = (10.0, 20.0, 50.0, 100.0)
GROUND_RANGES = (1e3, 2e3, 3e3, 5e3, 7e3, 10e3, 15e3, 20e3, 25e3, 30e3)
VISIBILITIES = (23.0, 5.0)


def cells():
    for altitude, ground, vis in itertools.product(ALTITUDES, GROUND_RANGES, VISIBILITIES):
        yield {"kind": "ground_camera", "label": f"{altitude:g} m, {ground / 1e3:g} km, "
                                                 f"vis {vis:g} km",
               "Q": 0.4e-6 * 1.5 / (0.15 * 3.45e-6), "sensor": dict(SENSOR),
               "scenario": dict(altitude=altitude, ground_range=ground, visibility=vis),
               "drift_px": [0.0, 0.0], "jitter_px": 0.0, "one_axis_drift_px": 0.0,
               "turbulence": True}


def summary(rows, name):
    """Share flagged and the error behind flagged / unflagged cells, per GIQE."""
    per = [r["methods"][name] for r in rows]
    niirs = np.array([p["niirs"] for p in per], float)
    ref = np.array([p["reference_niirs"] for p in per], float)
    flags = np.array([p["flags"] for p in per], np.int64)
    blur = (flags & pe.BLUR) != 0
    err = np.abs(niirs - ref)
    out = {"cells": len(per), "share_flagged": float(blur.any(axis=1).mean()),
           "reference_worse_rer_range": [
               float(min(min(p["reference_rer_x"], p["reference_rer_y"]) for p in per)),
               float(max(min(p["reference_rer_x"], p["reference_rer_y"]) for p in per))]}
    for group, sel in (("flagged", blur), ("unflagged", ~blur)):
        out[group] = {}
        for k, v in enumerate(pe.GIQE):
            m = sel[:, k] & np.isfinite(ref[:, k])
            fin = m & np.isfinite(niirs[:, k])
            out[group][str(v)] = {**pe._summary(err[fin, k]),
                                  "nan_cells": int((m & ~np.isfinite(niirs[:, k])).sum())}
    flagged = [min(p["reference_rer_x"], p["reference_rer_y"])
               for p, b in zip(per, blur.any(axis=1), strict=True) if b]
    out["flagged_reference_rer_range"] = [min(flagged), max(flagged)] if flagged else None
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", type=Path, default=OUT)
    args = ap.parse_args()
    t0 = time.perf_counter()
    load = os.getloadavg()
    rows, kept, rejected = pe.run(list(cells()), "ground camera", METHODS)
    tree = Path(xbsm.__file__).resolve().parents[1]  # the tree measured
    result = {"description": __doc__.split("\n\n")[0], "git": commit(tree),
              "xbsm_path": str(Path(xbsm.__file__).resolve().parent), "machine": machine(),
              "load_average_at_start": load, "sensor": SENSOR,
              "scenarios": {"altitude_m": ALTITUDES, "ground_range_m": GROUND_RANGES,
                            "visibility_km": VISIBILITIES, "cn2_at_1m": 1.7e-14,
                            "high_altitude_wind_speed": 21.0},
              "cells_kept": len(kept), "cells_rejected": rejected,
              "methods": {m: summary(rows, m) for m in METHODS},
              "cells": [c | {"results": r["methods"]} for c, r in zip(kept, rows, strict=True)]}
    for m in METHODS:
        s = result["methods"][m]
        print(f"{m}: {s['cells']} cells, flagged {100 * s['share_flagged']:.0f} % "
              f"(reference worse-slice RER of flagged cells {s['flagged_reference_rer_range']})")
        for group in ("flagged", "unflagged"):
            print(f"  {group}: " + "; ".join(
                f"GIQE {v} " + ("-" if s[group][str(v)]["cells"] == 0 else
                                f"median {s[group][str(v)]['median']:.1e} p95 "
                                f"{s[group][str(v)]['p95']:.1e} max {s[group][str(v)]['max']:.1e}")
                + f" NaN {s[group][str(v)]['nan_cells']}" for v in pe.GIQE))
    result["runtime_s"] = time.perf_counter() - t0
    pe.write_json(args.out, result)
    print(f"wrote {args.out} in {result['runtime_s']:.0f} s; xbsm {xbsm.__file__}")


if __name__ == "__main__":
    main()
