"""Write the pyBSM 0.16.1 reference fixture for xbsm's parity tests.

Run from the repository root with the pyBSM environment (never a dependency
of xbsm; how to make it: ``recipes/README.md``)::

    NUMBA_NUM_THREADS=1 recipes/_cache/pybsm-venv/bin/python recipes/pybsm_reference.py
    NUMBA_NUM_THREADS=1 recipes/_cache/pybsm-venv/bin/python recipes/pybsm_reference.py --all

It draws random but reproducible sensors and scenarios covering visible to
LWIR bands, self-emission, TDI, frame stacks, well-fill limits, sharpening,
jitter, drift, wavefront error, turbulence on and off, both visibilities and
many database altitudes and ground ranges, runs ``pybsm.metrics.niirs`` and
``niirs5`` (``interp=False`` on database nodes; a few ``interp=True`` cases
off the nodes) and ``photon_detector_SNR`` with the scenario's own target,
and writes:

- ``tests/fixtures/pybsm_cases.json``: the pyBSM keyword arguments of every case;
- ``tests/fixtures/pybsm_outputs.npz``: the outputs, one array per quantity,
  indexed like the cases (MTF slices as (case, sample) arrays).

The OTF-function and metric-function fixtures have recipes of their own
(``pybsm_reference_otf.py``, ``pybsm_reference_metrics.py``,
``pybsm_reference_atmosphere.py``); this script runs them too when called
with ``--all``.
"""

from __future__ import annotations

import copy
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
from _pybsm_env import pybsm_required

with pybsm_required():
    import pybsm
    from pybsm import radiance, utils
    from pybsm.metrics import functional as metrics
    from pybsm.simulation import Scenario, Sensor

HERE = Path(__file__).resolve().parent
FIXTURES = HERE.parent / "tests" / "fixtures"
N_CASES = 200
SEED = 20261121

BANDS = {
    "blue": (0.40e-6, 0.50e-6),
    "visible": (0.40e-6, 0.70e-6),
    "red": (0.50e-6, 0.66e-6),
    "nir": (0.55e-6, 0.85e-6),
    "swir": (1.00e-6, 1.70e-6),
    "wide_vnir": (0.40e-6, 1.00e-6),
    "mwir": (3.00e-6, 5.00e-6),
    "mwir_narrow": (3.60e-6, 4.20e-6),
    "lwir": (8.00e-6, 12.00e-6),
    "wide_ir": (3.00e-6, 12.00e-6),
}

SHARPENING = [
    [[0, -0.25, 0], [-0.25, 2.0, -0.25], [0, -0.25, 0]],
    [[-0.1, -0.1, -0.1], [-0.1, 1.8, -0.1], [-0.1, -0.1, -0.1]],
    [[1 / 9] * 3] * 3,
]


def decoder():
    table = np.genfromtxt(
        Path(utils.__file__).parent / "atms" / "fileDecoder.csv", delimiter=",", skip_header=1
    )
    return table


def node_geometry(rng, table, ihaze):
    rows = table[table[:, 3] == ihaze]
    alts = np.unique(rows[:, 1])
    alts = alts[(alts >= 0.002) & (alts <= 24.5)]
    alt = rng.choice(alts)
    ranges = rows[rows[:, 1] == alt, 2]
    gr = rng.choice(ranges)
    return float(alt * 1000.0), float(gr * 1000.0)


def random_case(rng, table, index):
    band_name = list(BANDS)[index % len(BANDS)]
    lo, hi = BANDS[band_name]
    infrared = lo >= 2.9e-6
    n_curve = int(rng.integers(2, 6))
    opt_wl = np.linspace(lo, hi, n_curve)
    D = float(rng.uniform(0.03, 0.5))
    fnum = float(rng.uniform(1.5, 12.0))
    p = float(rng.uniform(2e-6, 30e-6)) if not infrared else float(rng.uniform(10e-6, 30e-6))
    sensor = {
        "name": f"case{index}_{band_name}",
        "D": D,
        "f": D * fnum,
        "p_x": p,
        "opt_trans_wavelengths": opt_wl.tolist(),
        "eta": float(rng.choice([0.0, rng.uniform(0.05, 0.5)])),
        "int_time": float(10 ** rng.uniform(-4, -1)),
        "dark_current": float(rng.choice([0.0, 10 ** rng.uniform(1, 5)])),
        "read_noise": float(rng.uniform(0, 100)),
        "max_n": float(rng.choice([1e4, 5e4, 96000.0, 1e6, 1e8])),
        "max_well_fill": float(rng.choice([1.0, 0.6, rng.uniform(0.2, 1.0)])),
        "bit_depth": float(rng.choice([8.0, 11.9, 12.0, 14.0, 100.0])),
        "n_tdi": float(rng.choice([1.0, 1.0, 4.0, 32.0])),
        "s_x": float(rng.choice([0.0, rng.uniform(0, 0.5) * p / (D * fnum)])),
        "s_y": float(rng.choice([0.0, rng.uniform(0, 0.5) * p / (D * fnum)])),
        "da_x": float(rng.choice([0.0, rng.uniform(0, 2e-3)])),
        "da_y": float(rng.choice([0.0, rng.uniform(0, 2e-3)])),
        "pv": float(rng.choice([0.0, (2 * np.pi * rng.uniform(0, 0.15)) ** 2])),
        "frame_stacks": int(rng.choice([1, 1, 4, 16])),
    }
    if rng.uniform() < 0.5:
        sensor["p_y"] = float(p * rng.uniform(0.7, 1.3))
    if rng.uniform() < 0.3:
        sensor["w_x"] = float(p * rng.uniform(0.6, 1.0))
    if rng.uniform() < 0.7:
        sensor["qe_wavelengths"] = opt_wl.tolist()
        sensor["qe"] = rng.uniform(0.3, 0.95, opt_wl.size).tolist()
    if infrared or rng.uniform() < 0.2:
        sensor.update(
            cold_shield_temperature=float(rng.uniform(60, 120)),
            optics_temperature=float(rng.uniform(220, 300)),
            optics_emissivity=float(rng.uniform(0.0, 0.2)),
            cold_filter_transmission=float(rng.uniform(0.7, 1.0)),
            cold_filter_temperature=float(rng.uniform(60, 120)),
            cold_filter_emissivity=float(rng.uniform(0.0, 0.2)),
        )
    post = {}
    if rng.uniform() < 0.6:
        post["optics_transmission"] = rng.uniform(0.4, 0.95, opt_wl.size).tolist()
    if rng.uniform() < 0.3:
        post["filter_kernel"] = SHARPENING[int(rng.integers(0, len(SHARPENING)))]
    if rng.uniform() < 0.2:
        post["other_noise"] = rng.uniform(0, 30, 2).tolist()
    if rng.uniform() < 0.2:
        post["L_x"] = float(D * rng.uniform(0.2, 1.0))
        post["L_y"] = float(D * rng.uniform(0.2, 1.0))
    ihaze = int(rng.choice([1, 2]))
    altitude, ground_range = node_geometry(rng, table, ihaze)
    scenario = {
        "name": f"scenario{index}",
        "ihaze": ihaze,
        "altitude": altitude,
        "ground_range": ground_range,
        "aircraft_speed": float(rng.choice([0.0, rng.uniform(0, 250)])),
        "ha_wind_speed": float(rng.uniform(5, 40)),
        "cn2_at_1m": float(rng.choice([0.0, 1.7e-14, 10 ** rng.uniform(-16, -13)])),
        "target_reflectance": float(rng.uniform(0.05, 0.6)),
        "target_temperature": float(rng.uniform(270, 320)),
        "background_reflectance": float(rng.uniform(0.02, 0.4)),
        "background_temperature": float(rng.uniform(270, 320)),
    }
    return {"sensor": sensor, "post": post, "scenario": scenario, "interp": False}


def paper_cases():
    """The paper's Olson camera (Table 2) and pybsm_test_cases.md rows 1, 5, 6."""
    olson = {
        "D": 0.275, "f": 4.0, "p_x": 8.0e-6, "eta": 0.4, "int_time": 0.03,
        "read_noise": 25.0, "max_n": 96000.0, "bit_depth": 11.9, "max_well_fill": 0.6,
        "s_x": 0.25 * 8.0e-6 / 4.0, "s_y": 0.25 * 8.0e-6 / 4.0,
        "da_x": 100e-6, "da_y": 100e-6,
        "dark_current": 1e-5 * 8.0e-6 * 8.0e-6 / 1.60217662e-19,
    }
    cases = []
    for band, qe in (("red", 0.8), ("nir", 0.71)):
        lo, hi = BANDS[band]
        wl = [lo, hi]
        for ihaze in (1, 2):
            for gr in (0.0, 20000.0, 60000.0):
                cases.append({
                    "sensor": {"name": f"olson_{band}", **olson, "opt_trans_wavelengths": wl,
                               "qe_wavelengths": wl, "qe": [qe, qe]},
                    "post": {"optics_transmission": [0.5, 0.5]},
                    "scenario": {"name": f"olson_h{ihaze}_{gr:g}", "ihaze": ihaze,
                                 "altitude": 9000.0, "ground_range": gr,
                                 "aircraft_speed": 100.0},
                    "interp": False,
                })
    vis = {"name": "VIS", "D": 0.275, "f": 4.0, "p_x": 8e-6,
           "opt_trans_wavelengths": [0.50e-6, 0.66e-6]}
    cases.append({"sensor": vis, "post": {},
                  "scenario": {"name": "SCN", "ihaze": 1, "altitude": 9000.0,
                               "ground_range": 0.0}, "interp": False})
    return cases


def interp_cases(rng):
    """Off-node geometry with pyBSM's linear interpolation (altitudes >= 75 m)."""
    cases = []
    for i in range(12):
        ihaze = int(rng.choice([1, 2]))
        altitude = float(rng.uniform(75.0, 20000.0))
        ground_range = float(rng.uniform(0.0, 60000.0 if altitude > 3000 else 8000.0))
        lo, hi = list(BANDS.values())[i % len(BANDS)]
        cases.append({
            "sensor": {"name": f"interp{i}", "D": 0.2, "f": 2.0, "p_x": 10e-6,
                       "opt_trans_wavelengths": [lo, hi], "int_time": 0.01,
                       "max_n": 1e6, "read_noise": 20.0},
            "post": {},
            "scenario": {"name": f"interp{i}", "ihaze": ihaze, "altitude": altitude,
                         "ground_range": ground_range, "interp": True},
            "interp": True,
        })
    return cases


def build(case):
    kw = copy.deepcopy(case["sensor"])
    for key in ("opt_trans_wavelengths", "qe", "qe_wavelengths"):
        if key in kw:
            kw[key] = np.asarray(kw[key], dtype=float)
    sensor = Sensor(**kw)
    for key, value in case["post"].items():
        setattr(sensor, key, np.asarray(value, dtype=float) if isinstance(value, list) else value)
    scenario = Scenario(**case["scenario"])
    return sensor, scenario


SCALARS = {
    "niirs": lambda n, n5: n.niirs,
    "niirs_4": lambda n, n5: n.niirs_4,
    "niirs_5": lambda n, n5: n5.niirs,
    "rer_gm": lambda n, n5: n.rer_gm,
    "eho_gm": lambda n, n5: n.eho_gm,
    "rer_0": lambda n, n5: n5.rer_0,
    "rer_90": lambda n, n5: n5.rer_90,
    "rer_5": lambda n, n5: n5.rer,
    "gsd_gm": lambda n, n5: n.gsd_gm,
    "gsd_w": lambda n, n5: n5.gsd_w,
    "gsd_gp": lambda n, n5: n.gsd_gp,
    "elev_angle": lambda n, n5: n.elev_angle,
    "slant_range": lambda n, n5: n.slant_range,
    "ng": lambda n, n5: n.ng,
    "cutoff_frequency": lambda n, n5: n.cutoff_frequency,
    "df": lambda n, n5: n.df,
    "r0_band": lambda n, n5: np.ravel(n.otf.r0_band)[0],
    "snr": lambda n, n5: n.snr.snr,
    "int_time": lambda n, n5: n.snr.int_time,
    "tgt_n": lambda n, n5: n.snr.tgt_n,
    "bkg_n": lambda n, n5: n.snr.bkg_n,
    "contrast_signal": lambda n, n5: n.snr.contrast_signal,
    "well_fraction": lambda n, n5: n.snr.well_fraction,
    "signal_noise": lambda n, n5: n.snr.signal_noise,
    "path_noise": lambda n, n5: n.snr.path_noise,
    "scene_noise": lambda n, n5: n.snr.scene_noise,
    "self_emission_noise": lambda n, n5: n.snr.self_emission_noise,
    "dark_current_noise": lambda n, n5: n.snr.dark_current_noise,
    "quantization_noise": lambda n, n5: n.snr.quantization_noise,
    "total_noise": lambda n, n5: n.snr.total_noise,
    "n_wavelengths": lambda n, n5: n.radiance_wavelengths.size,
    "first_wavelength": lambda n, n5: n.radiance_wavelengths[0],
}


REFLECTANCE_CASES = 30
"""reflectance_to_photoelectrons is recorded for the first cases only (it is slow in pyBSM)."""


def run_case(case, with_reflectance=False):
    sensor, scenario = build(case)
    n = metrics.niirs(sensor=sensor, scenario=scenario, interp=case["interp"])
    sensor5, scenario5 = build(case)
    n5 = metrics.niirs5(sensor=sensor5, scenario=scenario5, interp=case["interp"])
    out = {key: float(f(n, n5)) for key, f in SCALARS.items()}
    system = np.abs(n.otf.system_OTF)
    from pybsm.otf.functional import slice_otf

    out["mtf_u"] = slice_otf(otf=system, ang=0.0)
    out["mtf_v"] = slice_otf(otf=system, ang=np.pi / 2)
    # photon_detector_SNR with the scenario's own target and background.
    sensor_s, scenario_s = build(case)
    if case["interp"]:
        atm = utils.load_database_atmosphere(
            altitude=scenario_s.altitude, ground_range=scenario_s.ground_range,
            ihaze=scenario_s.ihaze)
    else:
        atm = utils.load_database_atmosphere_no_interp(
            altitude=scenario_s.altitude, ground_range=scenario_s.ground_range,
            ihaze=scenario_s.ihaze)
    atm = atm[atm[:, 0] >= sensor_s.opt_trans_wavelengths[0], :]
    atm = atm[atm[:, 0] <= sensor_s.opt_trans_wavelengths[-1], :]
    tgt = radiance.total_radiance(atm=atm, reflectance=scenario_s.target_reflectance,
                                  temperature=scenario_s.target_temperature)
    bkg = radiance.total_radiance(atm=atm, reflectance=scenario_s.background_reflectance,
                                  temperature=scenario_s.background_temperature)
    s = radiance.photon_detector_SNR(sensor=sensor_s, radiance_wavelengths=atm[:, 0],
                                     target_radiance=tgt, background_radiance=bkg)
    for key in ("snr", "int_time", "tgt_n", "bkg_n", "total_noise", "well_fraction"):
        out[f"scenario_{key}"] = float(getattr(s, key))
    if with_reflectance:
        sensor_r, _ = build(case)
        _, pe, weights = radiance.reflectance_to_photoelectrons(
            atm=np.hstack([atm[:, :1], atm[:, 1:]]), sensor=sensor_r,
            int_time=sensor_r.int_time)
        out["reflectance_pe"] = pe
        out["reflectance_weights"] = weights[1]
    else:
        out["reflectance_pe"] = np.full(100, np.nan)
        out["reflectance_weights"] = np.full(1, np.nan)
    return out


def main():
    print(f"pyBSM {pybsm.__version__ if hasattr(pybsm, '__version__') else '0.16.1'}")
    rng = np.random.default_rng(SEED)
    table = decoder()
    cases = paper_cases() + interp_cases(rng)
    cases += [random_case(rng, table, i) for i in range(N_CASES - len(cases))]
    outputs = []
    kept = []
    for case in cases:
        try:
            outputs.append(run_case(case, with_reflectance=len(kept) < REFLECTANCE_CASES))
            kept.append(case)
        except Exception as exc:  # record what pyBSM cannot run, and skip it
            print(f"skipped {case['sensor']['name']}: {type(exc).__name__}: {exc}")
    keys = outputs[0].keys()
    arrays = {}
    for key in keys:
        values = [o[key] for o in outputs]
        if np.ndim(values[0]):
            width = max(len(v) for v in values)
            table_ = np.full((len(values), width), np.nan)
            for i, v in enumerate(values):
                table_[i, : len(v)] = v
            arrays[key] = table_
        else:
            arrays[key] = np.asarray(values, dtype=float)
    FIXTURES.mkdir(parents=True, exist_ok=True)
    (FIXTURES / "pybsm_cases.json").write_text(json.dumps(kept, indent=1))
    np.savez_compressed(FIXTURES / "pybsm_outputs.npz", **arrays)
    print(f"wrote {len(kept)} cases to {FIXTURES}")
    if "--all" in sys.argv:
        for other in ("pybsm_reference_otf.py", "pybsm_reference_metrics.py",
                      "pybsm_reference_atmosphere.py"):
            if (HERE / other).exists():
                subprocess.run([sys.executable, str(HERE / other)], check=True)


if __name__ == "__main__":
    main()
