"""Run pyBSM 0.16.1 side by side with xbsm, from the benchmarks in recipes/.

pyBSM is never a dependency of xbsm: it lives in a virtual environment of its
own (``recipes/_cache/pybsm-venv``, made on first use with
``pip install pybsm==0.16.1``, or the interpreter named by ``$PYBSM_PYTHON``;
see ``recipes/README.md`` and ``recipes/_pybsm_env.py``).
The benchmark sends a job as JSON to a child process running in that
environment with ``NUMBA_NUM_THREADS=1`` (pyBSM's parallel numba kernels
oversubscribe a shared machine: 762 ms vs 53 ms median per ``niirs`` call,
reference notes Sec. 5) and reads back per-scenario timings and results.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import venv

from _pybsm_env import MAKE_VENV, VENV, missing_pybsm_message

#: Start of every child script: imports, the job from stdin, and pyBSM objects from the
#: keyword dictionaries of tests/fixtures/pybsm_cases.json.
CHILD_PRELUDE = r'''
import json, sys, time
import numpy as np
from pybsm.simulation import Sensor, Scenario
from pybsm.metrics import functional as metrics
from pybsm import radiance, utils

job = json.load(sys.stdin)

def build(sensor_kw, scenario_kw):
    kw = dict(sensor_kw)
    post = kw.pop("post", {})
    for key in ("opt_trans_wavelengths", "qe", "qe_wavelengths"):
        if key in kw:
            kw[key] = np.asarray(kw[key], dtype=float)
    s = Sensor(**kw)
    for key, value in post.items():
        setattr(s, key, np.asarray(value, dtype=float) if isinstance(value, list) else value)
    return s, Scenario(**scenario_kw)
'''

CHILD = CHILD_PRELUDE + r'''

def snr_only(s, sc):
    atm = utils.load_database_atmosphere_no_interp(
        altitude=sc.altitude, ground_range=sc.ground_range, ihaze=sc.ihaze)
    atm = atm[atm[:, 0] >= s.opt_trans_wavelengths[0], :]
    atm = atm[atm[:, 0] <= s.opt_trans_wavelengths[-1], :]
    emissive = int(s.opt_trans_wavelengths[0] >= 2.9e-6)
    tgt, bkg = radiance.giqe_radiance(atm=atm, is_emissive=emissive)
    return radiance.photon_detector_SNR(sensor=s, radiance_wavelengths=atm[:, 0],
                                        target_radiance=tgt, background_radiance=bkg).snr

def niirs_both(s, sc):
    n = metrics.niirs(sensor=s, scenario=sc, interp=False)
    s5, sc5 = build(*current)
    n5 = metrics.niirs5(sensor=s5, scenario=sc5, interp=False)
    return [float(n.niirs), float(n.niirs_4), float(n5.niirs)]

kind = job["kind"]
times, values = [], []
# warm up numba and the file cache on the first case
current = (job["cases"][0]["sensor"], job["cases"][0]["scenario"])
s, sc = build(*current)
(snr_only if kind == "snr" else niirs_both)(s, sc)
for case in job["cases"]:
    current = (case["sensor"], case["scenario"])
    t0 = time.perf_counter()
    s, sc = build(*current)
    value = snr_only(s, sc) if kind == "snr" else niirs_both(s, sc)
    times.append(time.perf_counter() - t0)
    values.append(value if isinstance(value, list) else float(value))
json.dump({"times": times, "values": values}, sys.stdout)
'''


def pybsm_python() -> str:
    """Interpreter of an environment with pyBSM 0.16.1 (created on first use)."""
    explicit = os.environ.get("PYBSM_PYTHON")
    if explicit:
        return explicit
    python = VENV / "bin" / "python"
    if not python.exists():
        print(f"creating {VENV} with pybsm==0.16.1 ...", file=sys.stderr)
        venv.create(VENV, with_pip=True)
        install = [str(python), "-m", "pip", "install", "-q", "pybsm==0.16.1"]
        if subprocess.run(install).returncode:
            raise SystemExit(f"could not install pybsm==0.16.1 into {VENV}; make it by hand "
                             f"from the repository root:\n    {MAKE_VENV}")
    return str(python)


def run_pybsm(kind: str, cases: list[dict]) -> dict:
    """Time pyBSM on each case; ``kind`` is "snr" or "niirs".

    Returns ``{"times": [s per case], "values": [...]}``.
    """
    return run_child(CHILD, {"kind": kind, "cases": cases})


def run_child(script: str, job: dict) -> dict:
    """Run ``script`` in pyBSM's environment (one numba thread) on ``job``; its JSON answer."""
    env = dict(os.environ, NUMBA_NUM_THREADS="1", PYTHONWARNINGS="ignore")
    python = pybsm_python()
    proc = subprocess.run([python, "-c", script], input=json.dumps(job), capture_output=True,
                          text=True, env=env)
    if proc.returncode:
        if "No module named 'pybsm" in proc.stderr:
            raise SystemExit(missing_pybsm_message(python))
        sys.stderr.write(proc.stderr)
        proc.check_returncode()
    return json.loads(proc.stdout)
