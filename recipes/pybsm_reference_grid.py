"""pyBSM 0.16.1's NIIRS on a 1601-point frequency grid instead of its hard-coded 101.

``pybsm.metrics.functional.niirs`` and ``niirs5`` build their OTF on a fixed
101 x 101 grid over +-D/lambda_min (``metrics/functional.py:426``, ``:616``),
which leaves 50 samples from 0 to the optics cutoff. To test xbsm's
``method("pybsm", frequency_samples=N)`` for N other than 101, this recipe
re-runs the steps ``niirs()`` and ``niirs5()`` take, with pyBSM's own public
functions and nothing else (``load_database_atmosphere_no_interp``,
``giqe_radiance``, ``photon_detector_SNR``, ``common_OTFs``,
``giqe_edge_terms``, ``giqe3``, ``giqe4``, ``giqe5_RER``, ``giqe5``,
``noise_gain``), with the grid size as a parameter. pyBSM itself is not
modified.

Two details keep the re-run identical to pyBSM:

- ``niirs5`` computes a second ``common_OTFs`` with the filter kernel replaced
  by ``[1]``, whose filter OTF is ones. Here the unfiltered system OTF is the
  product of the same component arrays in the same order (aperture,
  turbulence, detector, jitter, drift, wavefront), so the second 1601^2 OTF
  evaluation is not needed and the product is bit-identical.
- The scene-noise bookkeeping of ``niirs()`` does not enter the NIIRS and is
  skipped.

The recipe first asserts that the re-run with N = 101 gives exactly (bit for
bit) what ``niirs()`` / ``niirs5()`` give on every chosen case, then runs
N = 1601 and writes ``tests/fixtures/pybsm_grid1601.npz`` (one entry per case;
``case_index`` points into ``tests/fixtures/pybsm_cases.json``) and
``tests/fixtures/pybsm_grid1601.json`` (the case indices and provenance).

Run from the repository root with the pyBSM environment (about 1.5 min on a
2-core machine; how to make it: ``recipes/README.md``)::

    NUMBA_NUM_THREADS=1 recipes/_cache/pybsm-venv/bin/python recipes/pybsm_reference_grid.py
"""

from __future__ import annotations

import copy
import json
import sys
import time
from pathlib import Path

import numpy as np
from _pybsm_env import pybsm_required

with pybsm_required():
    from pybsm import geospatial, noise, radiance, utils
    from pybsm.metrics import functional as metrics
    from pybsm.otf import functional as otf_functional
    from pybsm.simulation import Scenario, Sensor

HERE = Path(__file__).resolve().parent
FIXTURES = HERE.parent / "tests" / "fixtures"
GRID_SIZE = 1601

CASES = {
    6: "Olson NIR (paper Table 2), 0.55-0.85 um, Q = 1.0, HV 5/7 turbulence",
    2: "Olson red, 0.50-0.66 um, Q = 0.91, 60 km ground range",
    28: "random NIR, Q = 0.73, weak turbulence",
    42: "random MWIR 3.6-4.2 um (emissive), Q = 1.3, HV 5/7 turbulence",
    32: "random MWIR 3.6-4.2 um (emissive), Q = 1.07, sharpening filter",
    167: "random red, Q = 0.068 (undersampled), HV 5/7 turbulence",
    145: "random blue, Q = 0.030 (undersampled), weak turbulence",
    55: "random blue, Q = 0.27, no turbulence",
}
"""Indices into tests/fixtures/pybsm_cases.json (interp=False cases on database nodes)."""

ETA_SCALE = {6: 1.0 + 1e-9}
"""Cases run a second time with the obscuration ratio scaled by this factor.

On the 1601 grid of case 6 (Olson NIR, obscuration 0.4) some grid points fall
exactly on an annular-pupil breakpoint rho = (1 - eta)/2 * D/lambda of a band
wavelength (0.8 um at 0.20625 D/lambda_min, 0.85 um at 0.275). There pyBSM's
``circular_aperture_OTF`` kernel tests ``rho < (1 - eta) r0 / 2`` strictly and
``|phi_inner| <= 1`` after rounding; on one side of the grid both fail and the
-2 eta^2 term is dropped, so the 2-D OTF is not symmetric under u -> -u (0.013
in the weighted aperture OTF) and rer_0 != rer_90 for a symmetric system. The
copy with eta scaled by 1 + 1e-9 has no exact coincidence: it separates that
floating-point artefact from the quadrature."""


def build(case, eta_scale=1.0):
    """pyBSM Sensor and Scenario from a fixture case (as recipes/pybsm_reference.py)."""
    kw = copy.deepcopy(case["sensor"])
    if eta_scale != 1.0:
        kw["eta"] = kw.get("eta", 0.0) * eta_scale
    for key in ("opt_trans_wavelengths", "qe", "qe_wavelengths"):
        if key in kw:
            kw[key] = np.asarray(kw[key], dtype=float)
    sensor = Sensor(**kw)
    for key, value in case["post"].items():
        setattr(sensor, key, np.asarray(value, dtype=float) if isinstance(value, list) else value)
    return sensor, Scenario(**case["scenario"])


def niirs_on_grid(case, grid_size, eta_scale=1.0):
    """GIQE 3, 4 (``niirs``) and 5 (``niirs5``) as pyBSM computes them, on an N x N grid."""
    sensor, scenario = build(case, eta_scale)
    slant_range = geospatial.curved_earth_slant_range(
        h_target=0.0, h_sensor=scenario.altitude, ground_range=scenario.ground_range)
    atm = utils.load_database_atmosphere_no_interp(
        altitude=scenario.altitude, ground_range=scenario.ground_range, ihaze=scenario.ihaze)
    atm = atm[atm[:, 0] >= sensor.opt_trans_wavelengths[0], :]
    atm = atm[atm[:, 0] <= sensor.opt_trans_wavelengths[-1], :]
    is_emissive = 1 if sensor.opt_trans_wavelengths[0] >= 2.9e-6 else 0
    target, background = radiance.giqe_radiance(atm=atm, is_emissive=is_emissive)
    wavelengths = atm[:, 0]
    snr = radiance.photon_detector_SNR(sensor=sensor, radiance_wavelengths=wavelengths,
                                       target_radiance=target, background_radiance=background)
    mtf_wavelengths = wavelengths[snr.weights > 0.0]
    mtf_weights = snr.weights[snr.weights > 0.0]

    cutoff = sensor.D / np.min(mtf_wavelengths)
    u_rng = np.linspace(-1.0, 1.0, grid_size) * cutoff
    v_rng = np.linspace(1.0, -1.0, grid_size) * cutoff
    uu, vv = np.meshgrid(u_rng, v_rng)
    df = u_rng[1] - u_rng[0]
    otf = otf_functional.common_OTFs(
        sensor=sensor, scenario=scenario, uu=uu, vv=vv, mtf_wavelengths=mtf_wavelengths,
        mtf_weights=mtf_weights, slant_range=slant_range, int_time=snr.int_time)
    # niirs5's system OTF: the same product without the filter (its filter OTF is ones)
    unfiltered = otf.ap_OTF.copy()
    for part in (otf.turb_OTF, otf.det_OTF, otf.jit_OTF, otf.drft_OTF, otf.wav_OTF):
        np.multiply(unfiltered, part, out=unfiltered)
    del uu, vv

    ifov_x, ifov_y = sensor.p_x / sensor.f, sensor.p_y / sensor.f
    gsd_x, gsd_y = ifov_x * slant_range, ifov_y * slant_range
    gsd_gm = np.sqrt(gsd_x * gsd_y)
    rer_gm, eho_gm = metrics.giqe_edge_terms(mtf=np.abs(otf.system_OTF), df=df,
                                              ifov_x=ifov_x, ifov_y=ifov_y)
    ng = noise.noise_gain(kernel=sensor.filter_kernel)
    stacked = np.sqrt(sensor.frame_stacks) * snr.snr
    niirs3 = metrics.giqe3(rer=rer_gm, gsd=gsd_gm, eho=eho_gm, ng=ng, snr=stacked)
    elevation = np.pi / 2 - geospatial.nadir_angle(
        h_target=0.0, h_sensor=scenario.altitude, slant_range=slant_range)
    niirs4, _ = metrics.giqe4(rer=rer_gm, gsd=gsd_gm, eho=eho_gm, ng=ng, snr=stacked,
                              elev_angle=elevation)
    rer_0, rer_90 = metrics.giqe5_RER(mtf=np.abs(unfiltered), df=df, ifov_x=ifov_x,
                                      ifov_y=ifov_y)
    niirs5, _, rer5 = metrics.giqe5(rer_1=rer_0, rer_2=rer_90, gsd=gsd_x, snr=stacked,
                                    elev_angle=elevation)
    return {"niirs3": niirs3, "niirs4": niirs4, "niirs5": niirs5, "rer_gm": rer_gm,
            "eho_gm": eho_gm, "rer_0": rer_0, "rer_90": rer_90, "rer_giqe5": rer5, "df": df,
            "cutoff_frequency": cutoff}


def pybsm_niirs(case, eta_scale=1.0):
    """pyBSM's own niirs() and niirs5() (each on fresh objects: niirs5 mutates the sensor)."""
    sensor, scenario = build(case, eta_scale)
    n = metrics.niirs(sensor=sensor, scenario=scenario, interp=False)
    sensor5, scenario5 = build(case, eta_scale)
    n5 = metrics.niirs5(sensor=sensor5, scenario=scenario5, interp=False)
    return {"niirs3": n.niirs, "niirs4": n.niirs_4, "niirs5": n5.niirs, "rer_gm": n.rer_gm,
            "eho_gm": n.eho_gm, "rer_0": n5.rer_0, "rer_90": n5.rer_90, "rer_giqe5": n5.rer}


def main():
    cases = json.loads((FIXTURES / "pybsm_cases.json").read_text())
    runs = [(i, 1.0) for i in CASES] + list(ETA_SCALE.items())
    indices = [i for i, _ in runs]
    t_start = time.perf_counter()
    for i, scale in runs:
        mine, theirs = niirs_on_grid(cases[i], 101, scale), pybsm_niirs(cases[i], scale)
        for key, value in theirs.items():
            # bit for bit: the re-run is pyBSM's own computation
            assert float(mine[key]) == float(value), (i, key, float(mine[key]), float(value))
    print(f"N = 101 re-run equals pyBSM niirs()/niirs5() bit for bit on {runs}")

    rows = []
    for i, scale in runs:
        t0 = time.perf_counter()
        rows.append({k: float(v) for k, v in niirs_on_grid(cases[i], GRID_SIZE, scale).items()})
        print(f"case {i:3d} (eta x {scale!r}): N = {GRID_SIZE}: GIQE 3/4/5 = "
              f"{rows[-1]['niirs3']:.6f} {rows[-1]['niirs4']:.6f} {rows[-1]['niirs5']:.6f}"
              f"  ({time.perf_counter() - t0:.1f} s)", flush=True)
    arrays = {key: np.array([r[key] for r in rows]) for key in rows[0]}
    arrays["case_index"] = np.array(indices)
    arrays["eta_scale"] = np.array([scale for _, scale in runs])
    arrays["grid_size"] = np.array(GRID_SIZE)
    np.savez_compressed(FIXTURES / f"pybsm_grid{GRID_SIZE}.npz", **arrays)
    meta = {
        "description": (
            f"pyBSM 0.16.1 NIIRS with a {GRID_SIZE}-point frequency grid (niirs()/niirs5() "
            "hard-code 101), re-run from pyBSM's public functions by "
            "recipes/pybsm_reference_grid.py; case_index points into pybsm_cases.json"),
        "grid_size": GRID_SIZE,
        "case_index": indices,
        "cases": {str(i): CASES[i] for i in CASES},
        "eta_scale": [scale for _, scale in runs],
        "eta_scale_note": (
            "the last entries repeat a case with the obscuration ratio scaled, so that no "
            "grid point falls exactly on an annular-pupil breakpoint (see ETA_SCALE in the "
            "recipe)"),
        "check": "the same re-run with N = 101 equals niirs()/niirs5() bit for bit",
        "runtime_s": round(time.perf_counter() - t_start, 1),
        "python": sys.version.split()[0],
    }
    (FIXTURES / f"pybsm_grid{GRID_SIZE}.json").write_text(json.dumps(meta, indent=1) + "\n")
    print(f"wrote {FIXTURES / f'pybsm_grid{GRID_SIZE}.npz'} in {meta['runtime_s']} s")


if __name__ == "__main__":
    main()
