"""Archived (issue 23): the preset-tuning study that chose ``fast``'s ``otf_wavelengths=24``.

Superseded for error bounds by ``recipes/evidence/preset_error.py``, whose reference is
independent of the package's quadrature; kept because ``xbsm/methods.py`` cites its result
(``docs/benchmarks/preset_tuning.json``, formerly ``preset_error.json``).

Error of the method presets on random valid sensors and scenarios, and a tuned ``fast``.

The error bounds of ``docs/speed_accuracy.md`` were measured on four systems;
this recipe checks them on N (default 240) random valid cases drawn with a
fixed seed (numpy Generator) over the ranges of the hypothesis strategy in
``tests/test_model_niirs.py``, widened to every mechanism that a numerical
knob touches:

- band: one of 0.4-0.7, 0.55-0.85, 1.0-1.7, 3-5 and 8-12 um;
- aperture 2 cm - 1 m; Q = lambda_min F# / p log-uniform in 0.02-3 (from 150
  to 1 oscillations of the edge integrand at 3 px) with F# in 1-20 and the
  pitch in 2-40 um (so LWIR has Q >= 0.2, MWIR Q >= 0.075); obscuration
  0.05-0.5 in half the cases;
- integration time 1e-5 - 0.1 s (log-uniform), read noise 10 e-, well 1e5 e-;
- jitter 0-20 urad, drift 0-2 mrad/s per axis, wavefront error 0-0.15 waves
  rms: each present in half the cases;
- altitude 2 m - 20 km, ground range 0-300 km, visibility 23 or 5 km,
  Cn2(1 m) 0 (no turbulence), 1.7e-14 (HV 5/7) or 1e-16 - 1e-13, wind
  5-40 m/s, platform speed 0 or 0-250 m/s.

A drawn case is kept if ``accurate`` gives a finite NIIRS for GIQE 3, 4 and 5
(geometry inside the database and above the horizon, SNR > 0); rejected
draws are counted.

The *reference* is ``accurate`` with every resolution knob 4x finer
(``nodes_per_panel``, ``panels_per_oscillation``, ``min_panels`` and
``turbulence_path_samples`` x 4, ``otf_wavelengths=0``): 16x the frequency
nodes at every Q, every database wavelength, 4x the r0 path nodes. Its own
error is estimated against the same rule at 2x per knob. The ``pybsm``
method is compared for context with a pybsm-modelling reference (pyBSM's
modelling, Gauss-Legendre rules at 2x per knob: its numerical error alone)
and with the reference above (numerics plus pyBSM's modelling).

Errors (|NIIRS - reference| per case: median, 95th percentile, max; per
GIQE version and the largest of the three) are reported on every case and on
two subsets: the reference's RER >= 0.2 (the floor of the GIQE 3/4
calibration; below it the NIIRS is very sensitive to the RER, above all
GIQE 5's (log10 RER)^4 term) and every GIQE calibration range.

Which knob dominates ``fast``'s error: on its 20 worst cases (overall and
where RER >= 0.2), ``fast`` rerun with each of its knobs set back to
``accurate``'s value, one at a time; and on every case ``accurate`` with one
knob at ``fast``'s value.

Time per scenario: one ``xbsm.niirs`` call per case (median over
``--timing-cases`` cases, methods interleaved per case), and one call on the
case's sensor over ``--sweep`` ground ranges (a sweep, as in
``docs/speed_accuracy.md``), divided by the number of scenarios. Errors come
from batched calls (cases with the same band along a ``case`` dimension;
every case keeps its own quadrature, so the values equal single calls to
rounding, which the recipe checks on the timing cases).

Then a grid of ``fast`` knob sets (``nodes_per_panel`` 6-8, ``min_panels``
4-8, ``otf_wavelengths`` 8/12/16/24/32/all, ``turbulence_path_samples``
16/32) is measured on ``--grid-cases`` cases (plus ``fast``'s worst); the
cheapest sets within 1e-3 NIIRS there are re-measured on every case and
timed as sweeps against ``accurate`` and ``fast``. The recommendation is the
cheapest set within 1e-3 NIIRS on every case if it is at least 1.3x faster
than ``accurate`` (summed sweep times); otherwise the recipe states the bound
``fast`` really has, and the cheapest set within 1e-3 where RER >= 0.2.

Writes ``docs/benchmarks/preset_tuning.json`` (a run with fewer than 200 cases
writes to ``xbsm_preset_tuning/`` in the system's temporary folder unless
``--out`` is given). Run from the repository root with the project
environment (about 7-10 min on a shared 2-core machine)::

    .venv/bin/python recipes/evidence/archive/preset_tuning.py [--cases 240]
"""

from __future__ import annotations

import argparse
import itertools
import json
import math
import os
import statistics
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))  # recipes/: the shared helpers

import numpy as np
import xarray as xr
from _provenance import commit, machine

import xbsm

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[2]
DEFAULT_OUT = ROOT / "docs" / "benchmarks" / "preset_tuning.json"
GIQE = (3, 4, 5)
SEED = 20260422

BANDS = ((0.4e-6, 0.7e-6), (0.55e-6, 0.85e-6), (1.0e-6, 1.7e-6), (3.0e-6, 5.0e-6),
         (8.0e-6, 12.0e-6))
"""The bands of the hypothesis strategy in tests/test_model_niirs.py."""
Q_RANGE = (0.02, 3.0)
FNUMBER_RANGE = (1.0, 20.0)
PITCH_RANGE = (2e-6, 40e-6)
DIAMETER_RANGE = (0.02, 1.0)

BOUND = 1e-3
"""The error a recommended ``fast`` must stay within (max over cases and GIQE versions)."""
USEFUL_SPEEDUP = 1.3
"""The least speed-up over ``accurate`` that makes a ``fast`` preset worth having."""
GRID = dict(nodes_per_panel=(6, 7, 8), min_panels=(4, 6, 8),
            otf_wavelengths=(8, 12, 16, 24, 32, 0), turbulence_path_samples=(16, 32))
RESOLUTION_KNOBS = ("nodes_per_panel", "panels_per_oscillation", "min_panels",
                    "turbulence_path_samples")
"""Knobs that refine the numerics when increased (``otf_wavelengths``: 0 = every wavelength)."""
CHUNK_BUDGET = 1.5e7
"""Largest (frequency nodes x wavelengths x cases) of one batched call of the reference."""


# --- the random cases -------------------------------------------------------------------


def loguniform(rng, lo, hi):
    return float(math.exp(rng.uniform(math.log(lo), math.log(hi))))


def draw_case(rng) -> dict:
    """One random sensor + scenario as plain keyword dictionaries."""
    band = BANDS[int(rng.integers(len(BANDS)))]
    lam = band[0]
    diameter = float(rng.uniform(*DIAMETER_RANGE))
    while True:  # Q, then a pitch that keeps F# = Q p / lambda_min inside its range
        q = loguniform(rng, *Q_RANGE)
        lo = max(PITCH_RANGE[0], lam * FNUMBER_RANGE[0] / q)
        hi = min(PITCH_RANGE[1], lam * FNUMBER_RANGE[1] / q)
        if lo < hi:
            break
    pitch = loguniform(rng, lo, hi)
    fnumber = q * pitch / lam
    jitter = float(rng.uniform(0.0, 20e-6)) if rng.uniform() < 0.5 else 0.0
    if rng.uniform() < 0.5:
        drift = (float(rng.uniform(0.0, 2e-3)), float(rng.uniform(0.0, 2e-3)))
    else:
        drift = (0.0, 0.0)
    wavefront = float((2 * np.pi * rng.uniform(0.0, 0.15)) ** 2) if rng.uniform() < 0.5 else 0.0
    obscuration = float(rng.uniform(0.05, 0.5)) if rng.uniform() < 0.5 else 0.0
    turbulence = int(rng.integers(3))
    cn2 = (0.0, 1.7e-14, 10 ** float(rng.uniform(-16, -13)))[turbulence]
    sensor = dict(aperture_diameter=diameter, focal_length=diameter * fnumber,
                  pixel_pitch_x=pitch, wavelength_min=band[0], wavelength_max=band[1],
                  obscuration_ratio=obscuration,
                  integration_time=loguniform(rng, 1e-5, 0.1), read_noise=10.0, max_well=1e5,
                  jitter_x=jitter, jitter_y=jitter, drift_rate_x=drift[0],
                  drift_rate_y=drift[1], wavefront_variance=wavefront)
    scenario = dict(altitude=float(rng.uniform(2.0, 20000.0)),
                    ground_range=float(rng.uniform(0.0, 300e3)),
                    visibility=float(rng.choice([5.0, 23.0])),
                    cn2_at_1m=cn2, high_altitude_wind_speed=float(rng.uniform(5.0, 40.0)),
                    platform_speed=float(rng.uniform(0.0, 250.0)) if rng.uniform() < 0.5
                    else 0.0)
    return {"band_um": [band[0] * 1e6, band[1] * 1e6], "Q": q, "fnumber": fnumber,
            "sensor": sensor, "scenario": scenario}


def band_wavelength_count(case) -> int:
    lo, hi = case["sensor"]["wavelength_min"], case["sensor"]["wavelength_max"]
    return int(round((hi - lo) / 10e-9)) + 2


def node_estimate(case, m) -> int:
    """Frequency nodes of a Gauss-Legendre edge rule for one case (n_osc = 3 / Q)."""
    n_osc = 3.0 / case["Q"]
    return m.nodes_per_panel * max(m.min_panels, math.ceil(m.panels_per_oscillation * n_osc))


class Run:
    """Results of one method on every case of a Batches (NaN outside its cases)."""

    def __init__(self, n):
        self.niirs = np.full((3, n), np.nan)
        self.flags = np.zeros((3, n), dtype=np.int64)
        self.rer = np.full(n, np.nan)
        self.snr = np.full(n, np.nan)
        self.seconds = 0.0


class Batches:
    """Cases with the same band, batched along ``case`` in chunks that fit in memory.

    Every case keeps its own edge quadrature (``xbsm.niirs`` pads the others with
    zero weights), so the values equal single-case calls to rounding.
    """

    def __init__(self, cases, indices, sizing_method):
        self.n = len(cases)
        self.sizing = sizing_method
        self.indices = list(indices)
        by_band = {}
        for i in self.indices:
            by_band.setdefault(tuple(cases[i]["band_um"]), []).append(i)
        self.chunks = []
        for members in by_band.values():
            members.sort(key=lambda i: -node_estimate(cases[i], sizing_method))
            chunk, largest = [], 0
            for i in members:
                nodes = node_estimate(cases[i], sizing_method)
                width = max(largest, nodes) * band_wavelength_count(cases[i])
                if chunk and width * (len(chunk) + 1) > CHUNK_BUDGET:
                    self.chunks.append((chunk, *self._datasets(cases, chunk)))
                    chunk, largest = [], 0
                chunk.append(i)
                largest = max(largest, nodes)
            if chunk:
                self.chunks.append((chunk, *self._datasets(cases, chunk)))

    @staticmethod
    def _datasets(cases, chunk):
        def stacked(kind, name):
            values = [cases[i][kind][name] for i in chunk]
            if name in ("wavelength_min", "wavelength_max"):
                return values[0]
            return xr.DataArray(values, dims="case")

        first = cases[chunk[0]]
        sensor = xbsm.sensor(**{k: stacked("sensor", k) for k in first["sensor"]})
        scenario = xbsm.scenario(**{k: stacked("scenario", k) for k in first["scenario"]})
        return sensor, scenario

    def run_chunk(self, k, m, into: Run):
        """One batched call on chunk ``k``; stores its results in ``into``; returns seconds."""
        chunk, sensor, scenario = self.chunks[k]
        t0 = time.perf_counter()
        out = xbsm.niirs(sensor, scenario, method=m)
        values = out["niirs"].transpose("giqe", "case").values
        seconds = time.perf_counter() - t0
        into.niirs[:, chunk] = values
        into.flags[:, chunk] = out["flags"].transpose("giqe", "case").values
        into.rer[chunk] = np.minimum(out["rer"].values, out["rer_giqe5"].values)
        into.snr[chunk] = out["snr"].values
        into.seconds += seconds
        return seconds

    def run(self, m) -> Run:
        into = Run(self.n)
        for k in range(len(self.chunks)):
            self.run_chunk(k, m, into)
        return into


def single_datasets(case):
    return xbsm.sensor(**case["sensor"]), xbsm.scenario(**case["scenario"])


def single_call(datasets, m):
    """Wall time of one xbsm.niirs call, its NIIRS (giqe first) and min(rer, rer_giqe5)."""
    t0 = time.perf_counter()
    out = xbsm.niirs(*datasets, method=m)
    values = out["niirs"].values
    seconds = time.perf_counter() - t0
    return seconds, (values, np.minimum(out["rer"], out["rer_giqe5"]).values)


# --- statistics -------------------------------------------------------------------------


def error_stats(values, reference, mask=None):
    """Median, 95th percentile and max of |values - reference| per GIQE and over all three.

    ``mask`` (cases, or GIQE x cases) selects the cells; "any" is the largest finite
    error per case over its selected GIQE versions. NaN errors (a NaN where the
    reference is finite) are counted in ``nan_cases``, not ranked.
    """
    err = np.abs(values - reference)
    mask = np.ones(err.shape, bool) if mask is None else np.broadcast_to(mask, err.shape)
    out = {}
    for k, g in enumerate(GIQE):
        e = err[k][mask[k]]
        finite = np.isfinite(e)
        out[str(g)] = _summary(e[finite], int((~finite).sum()))
    bad = (mask & ~np.isfinite(err)).any(axis=0)
    good = mask & np.isfinite(err)
    worst = np.max(np.where(good, err, -np.inf), axis=0)
    out["any"] = _summary(worst[good.any(axis=0)], int(bad.sum()))
    return out


def _summary(e, nan_count):
    if e.size == 0:
        return {"cases": 0, "nan_cases": nan_count}
    return {"cases": int(e.size), "median": float(np.median(e)),
            "p95": float(np.percentile(e, 95)), "max": float(np.max(e)),
            "nan_cases": nan_count}


def within(stats, bound):
    return stats["any"].get("max", np.inf) <= bound and stats["any"]["nan_cases"] == 0


def worst_per_case(values, reference):
    err = np.abs(values - reference)
    return np.max(np.where(np.isnan(err), np.inf, err), axis=0)


def knob_values(m, names=None):
    names = names or [k for k in m.knobs() if k != "constants"]
    return {k: getattr(m, k) for k in names}


def jsonable(x):
    """NaN and infinities as null (strict JSON), numpy scalars as Python numbers."""
    if isinstance(x, dict):
        return {k: jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [jsonable(v) for v in x]
    if isinstance(x, (np.floating, float)):
        return float(x) if math.isfinite(x) else None
    if isinstance(x, np.integer):
        return int(x)
    return x


# --- the study --------------------------------------------------------------------------


def draw_valid_cases(n, rng):
    """Draw until ``n`` cases give a finite ``accurate`` NIIRS; return them and the rejects."""
    cases, rejected = [], 0
    while len(cases) < n:
        batch = [draw_case(rng) for _ in range(max(16, 2 * (n - len(cases))))]
        run = Batches(batch, range(len(batch)), xbsm.method("accurate")).run("accurate")
        for i, case in enumerate(batch):
            if len(cases) == n:
                break
            if np.all(np.isfinite(run.niirs[:, i])):
                cases.append(case)
            else:
                rejected += 1
    return cases, rejected


def time_calls(datasets, indices, methods, rng, label):
    """Wall time of one xbsm.niirs call per case and method, methods in random order per case.

    ``datasets[i]`` is the (sensor, scenario) of case ``i``. Returns the times and the
    NIIRS values (giqe first) per method.
    """
    times = {name: [] for name in methods}
    values = {name: {} for name in methods}
    for m in methods.values():  # warm-up
        single_call(datasets[indices[0]], m)
    names = list(methods)
    t_start = time.perf_counter()
    for count, i in enumerate(indices):
        for j in rng.permutation(len(names)):
            seconds, v = single_call(datasets[i], methods[names[j]])
            times[names[j]].append(seconds)
            values[names[j]][i] = v
        if (count + 1) % 80 == 0:
            print(f"  {label}: {count + 1}/{len(indices)} cases timed "
                  f"({time.perf_counter() - t_start:.0f} s)", flush=True)
    return times, values


def sweep_datasets(case, scenarios):
    """The case's sensor on ``scenarios`` ground ranges from 0 to the case's (one sweep)."""
    ground = xr.DataArray(np.linspace(0.0, case["scenario"]["ground_range"], scenarios),
                          dims="sweep")
    return (xbsm.sensor(**case["sensor"]),
            xbsm.scenario(**dict(case["scenario"], ground_range=ground)))


def timing_summary(times, baseline=None, per=1):
    out = {"cases": len(times), "median_ms": 1e3 * statistics.median(times) / per,
           "mean_ms": 1e3 * statistics.fmean(times) / per, "total_s": float(sum(times))}
    if baseline is not None:
        out["speedup_vs_accurate_total"] = float(sum(baseline) / sum(times))
        out["speedup_vs_accurate_median_of_ratios"] = float(
            statistics.median(b / t for b, t in zip(baseline, times, strict=True)))
    return out


def times(x):
    return "n/a" if x is None else f"x{x:.2f}"


def label_of(knobs):
    return ", ".join(f"{k}={v}" for k, v in knobs.items())


def ablation(cases, indices, worst_error, ref, batches, subsets, fast_knobs):
    """fast with one knob back at accurate's value on the 20 worst cases of ``indices``;
    accurate with one knob at fast's value on every case."""
    accurate, fast = xbsm.method("accurate"), xbsm.method("fast")
    worst = [int(i) for i in sorted(indices, key=lambda i: -worst_error[i])[:20]]
    worst_batches = Batches(cases, worst, batches.sizing)
    restored, isolated, fixed = {}, {}, {}
    for k in fast_knobs:
        v = worst_batches.run(xbsm.method("fast", **{k: getattr(accurate, k)})).niirs
        fixed[k] = worst_per_case(v, ref)[worst]
        restored[k] = {"value": getattr(accurate, k), "median": float(np.median(fixed[k])),
                       "max": float(np.max(fixed[k]))}
        if batches is not None and subsets is not None:
            v = batches.run(xbsm.method("accurate", **{k: getattr(fast, k)})).niirs
            isolated[k] = {"value": getattr(fast, k),
                           "error": {s: error_stats(v, ref, m) for s, m in subsets.items()}}
    best_fix = {k: 0 for k in fast_knobs}
    for j in range(len(worst)):
        best_fix[min(fast_knobs, key=lambda k: fixed[k][j])] += 1
    out = {"worst_cases": worst,
           "fast_error_on_worst": {"median": float(np.median(worst_error[worst])),
                                   "max": float(np.max(worst_error[worst]))},
           "fast_with_one_knob_restored_to_accurate": restored,
           "cases_where_restoring_this_knob_helps_most": best_fix,
           "dominant_knob_by_max": min(fast_knobs, key=lambda k: restored[k]["max"]),
           "dominant_knob_by_cases": max(fast_knobs, key=lambda k: best_fix[k])}
    if isolated:
        out["accurate_with_one_knob_at_fast_value"] = isolated
    return out


def print_ablation(name, a, fast_knobs):
    print(f"\nfast's 20 worst cases ({name}): max {a['fast_error_on_worst']['max']:.1e}, "
          f"median {a['fast_error_on_worst']['median']:.1e}; one knob back at accurate's:")
    for k in fast_knobs:
        r = a["fast_with_one_knob_restored_to_accurate"][k]
        line = (f"  {k} = {r['value']}: max {r['max']:.1e}, median {r['median']:.1e}, best "
                f"fix for {a['cases_where_restoring_this_knob_helps_most'][k]} of 20")
        iso = a.get("accurate_with_one_knob_at_fast_value", {}).get(k)
        if iso:
            e = iso["error"]
            line += (f" | accurate with {k} = {iso['value']}: max {e['all']['any']['max']:.1e}"
                     f" (RER >= 0.2: {e['rer_at_least_0.2']['any']['max']:.1e})")
        print(line)
    print(f"  dominant knob: {a['dominant_knob_by_max']} (by max), "
          f"{a['dominant_knob_by_cases']} (by cases)", flush=True)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", type=int, default=240, help="random cases (default 240)")
    parser.add_argument("--grid-cases", type=int, default=96,
                        help="cases for the knob-grid search (default 96, spread over the "
                             "cases, plus fast's 20 worst overall and where RER >= 0.2; "
                             "0 = all); the cheapest sets within the bound are re-measured "
                             "on every case")
    parser.add_argument("--timing-cases", type=int, default=80,
                        help="cases timed per call and as sweeps of one sensor (default 80)")
    parser.add_argument("--sweep", type=int, default=172,
                        help="scenarios (ground ranges) per timed sweep (default 172, the "
                             "sweep size of docs/speed_accuracy.md)")
    parser.add_argument("--candidates", type=int, default=3,
                        help="cheapest grid sets per criterion timed as sweeps (default 3)")
    parser.add_argument("--seed", type=int, default=SEED)
    parser.add_argument("--out", default=None, help="JSON path (default "
                        "docs/benchmarks/preset_tuning.json; a temporary folder below 200 cases)")
    args = parser.parse_args()
    if args.out:
        out_path = Path(args.out)
    elif args.cases >= 200:
        out_path = DEFAULT_OUT
    else:
        out_path = Path(tempfile.gettempdir()) / "xbsm_preset_tuning" / "preset_tuning.json"
    t_start = time.perf_counter()
    load_start = os.getloadavg()
    git = commit()  # at the start: the code this run imports
    rng = np.random.default_rng(args.seed)

    def elapsed():
        return f"{time.perf_counter() - t_start:.0f} s"

    accurate, fast, pybsm = (xbsm.method(n) for n in ("accurate", "fast", "pybsm"))
    finer = {k: getattr(accurate, k) * 4 for k in RESOLUTION_KNOBS}
    half = {k: getattr(accurate, k) * 2 for k in RESOLUTION_KNOBS}
    reference = xbsm.method("accurate", otf_wavelengths=0, **finer)
    reference_half = xbsm.method("accurate", otf_wavelengths=0, **half)
    reference_pybsm = xbsm.method("pybsm", edge_rule="gauss_legendre",
                                  turbulence_path_rule="gauss-legendre", otf_wavelengths=0,
                                  **half)
    fast_knobs = [k for k in accurate.knobs()
                  if k != "name" and getattr(fast, k) != getattr(accurate, k)]

    # 1. cases; every batched run uses the same chunks (sized for the reference), so the
    # radiometry of a case is bit-identical between methods
    cases, rejected = draw_valid_cases(args.cases, rng)
    n = len(cases)
    everything = list(range(n))
    batches = Batches(cases, everything, reference)
    q = np.array([c["Q"] for c in cases])
    print(f"{n} valid cases ({rejected} draws rejected), Q {q.min():.3f}-{q.max():.2f}, "
          f"{len(batches.chunks)} batches; {elapsed()}", flush=True)

    # 2. references and presets (batched)
    ref_run = batches.run(reference)
    ref = ref_run.niirs
    print(f"reference: {ref_run.seconds:.0f} s", flush=True)
    ref_half = batches.run(reference_half).niirs
    ref_pybsm = batches.run(reference_pybsm).niirs
    presets = {"fast": fast, "accurate": accurate, "pybsm": pybsm}
    runs, batched_time = {}, {name: [] for name in presets}
    for _ in range(2):  # two rounds, interleaved; the first one warms up
        for name, m in presets.items():
            runs[name] = batches.run(m)
            batched_time[name].append(runs[name].seconds)
    values = {name: r.niirs for name, r in runs.items()}
    self_check = error_stats(ref_half, ref)
    print(f"presets batched: { {k: round(min(v), 1) for k, v in batched_time.items()} } s; "
          f"reference self-check |ref - ref(2x per knob)| max {self_check['any']['max']:.1e}; "
          f"{elapsed()}", flush=True)

    # subsets: the reference's RER (min of the GIQE 3/4 and GIQE 5 RER) >= 0.2, the floor
    # of the GIQE 3/4 calibration; and every GIQE calibration range (per version)
    rer = ref_run.rer
    calibration_mask = getattr(xbsm.flags, "CALIBRATION_MASK", 0)
    subsets = {"all": None, "rer_at_least_0.2": rer >= 0.2,
               "snr_at_least_2": ref_run.snr >= 2.0,
               "inside_giqe_calibration": (ref_run.flags & calibration_mask) == 0}

    # 3. one call per case and preset on the timing cases: the time per scenario, and a
    # check that batching changes nothing (relative: where the SNR is ~ 0 the NIIRS is far
    # below 0 and its rounding follows the SNR's)
    step = max(1, n // args.timing_cases)
    timing_indices = everything[::step][:args.timing_cases]
    singles = {i: single_datasets(cases[i]) for i in timing_indices}
    single_times, single_values = time_calls(singles, timing_indices, presets, rng, "calls")
    batch_vs_single = {}
    snr_ok = ref_run.snr[timing_indices] >= 1.0
    for name in presets:
        got = np.array([single_values[name][i][0] for i in timing_indices]).T
        got_rer = np.array([single_values[name][i][1] for i in timing_indices])
        rer_b = runs[name].rer[timing_indices]
        batch_vs_single[name] = {
            "rer_relative": float(np.nanmax(np.abs(got_rer - rer_b) / np.abs(rer_b))),
            "niirs_where_snr_at_least_1": float(np.nanmax(np.abs(
                got - values[name][:, timing_indices])[:, snr_ok]))}
    print(f"max |batched - single call|: {batch_vs_single}; {elapsed()}", flush=True)

    results = {}
    for name in presets:
        against = ref_pybsm if name == "pybsm" else ref
        results[name] = {
            "knobs": knob_values(presets[name]),
            "error": error_stats(values[name], against),
            "error_subsets": {k: error_stats(values[name], against, v)
                              for k, v in subsets.items() if v is not None},
            "time_single_call": timing_summary(single_times[name], single_times["accurate"]),
            "time_batched_cases": {"per_case_ms": 1e3 * min(batched_time[name]) / n,
                                   "rounds_s": batched_time[name]},
        }
    results["pybsm"]["error_is_against"] = (
        "pybsm-modelling reference (numerical error of method='pybsm' alone)")
    results["pybsm"]["error_vs_accurate_reference"] = {
        k: error_stats(values["pybsm"], ref, v) for k, v in subsets.items()}
    results["fast"]["error_is_against"] = results["accurate"]["error_is_against"] = (
        "reference (accurate, every resolution knob x4)")

    print(f"\n{'':14s}{'every case':^34s}  {'reference RER >= 0.2':^26s}")
    print(f"{'preset':9s} {'GIQE':>4s}  {'median':8s} {'p95':8s} {'max':8s} {'NaN':>3s}    "
          f"{'median':8s} {'p95':8s} {'max':8s}  ms/call")
    for name in presets:
        for g in (*map(str, GIQE), "any"):
            e = results[name]["error"][g]
            e2 = results[name]["error_subsets"]["rer_at_least_0.2"][g]
            ms = results[name]["time_single_call"]["median_ms"]
            print(f"{name:9s} {g:>4s}  {e['median']:.1e}  {e['p95']:.1e}  {e['max']:.1e}  "
                  f"{e['nan_cases']:3d}    {e2['median']:.1e}  {e2['p95']:.1e}  "
                  f"{e2['max']:.1e}  {ms:6.1f}")
    e = results["pybsm"]["error_vs_accurate_reference"]["snr_at_least_2"]["any"]
    print(f"pybsm vs the accurate reference (modelling + numerics), SNR >= 2: median "
          f"{e['median']:.1e}, p95 {e['p95']:.1e}, max {e['max']:.1e}", flush=True)

    # where fast's error is: by band, Q and RER
    fast_worst = worst_per_case(values["fast"], ref)
    acc_worst = worst_per_case(values["accurate"], ref)
    breakdown = {"by_band": {}, "by_Q": {}, "by_reference_rer": {}}

    def add(group, key, sel):
        sel = np.asarray(sel, dtype=int)
        if sel.size:
            f, a = fast_worst[sel], acc_worst[sel]
            breakdown[group][key] = {"cases": int(sel.size),
                                     "fast_max": float(f[np.isfinite(f)].max()),
                                     "fast_median": float(np.median(f)),
                                     "fast_nan_cases": int(np.sum(~np.isfinite(f))),
                                     "accurate_max": float(a[np.isfinite(a)].max()),
                                     "accurate_nan_cases": int(np.sum(~np.isfinite(a)))}

    for band in BANDS:
        add("by_band", f"{band[0] * 1e6:g}-{band[1] * 1e6:g} um",
            [i for i in everything if abs(cases[i]["band_um"][0] - band[0] * 1e6) < 1e-9])
    for lo, hi in ((0.02, 0.1), (0.1, 0.3), (0.3, 1.0), (1.0, 3.0)):
        add("by_Q", f"{lo:g}-{hi:g}", np.flatnonzero((q >= lo) & (q < hi)))
    for lo, hi in ((0.0, 0.05), (0.05, 0.1), (0.1, 0.2), (0.2, 0.5), (0.5, 2.0)):
        add("by_reference_rer", f"{lo:g}-{hi:g}", np.flatnonzero((rer >= lo) & (rer < hi)))
    print("max error by reference RER (fast / accurate; cases, fast NaN): " + ", ".join(
        f"{k}: {v['fast_max']:.1e} / {v['accurate_max']:.1e} ({v['cases']}, "
        f"{v['fast_nan_cases']})"
        for k, v in breakdown["by_reference_rer"].items()), flush=True)

    # 4. which knob dominates fast's error
    knob_ablation = {
        "all": ablation(cases, everything, fast_worst, ref, batches, subsets, fast_knobs),
        "rer_at_least_0.2": ablation(cases, np.flatnonzero(rer >= 0.2).tolist(), fast_worst,
                                     ref, batches, None, fast_knobs),
        "dominant_knob_is": "by_max: the knob whose restoration to accurate's value lowers "
                            "the max error over fast's 20 worst cases the most; by_cases: the "
                            "knob whose restoration helps most in the most of those cases",
    }
    for name in ("all", "rer_at_least_0.2"):
        print_ablation(name, knob_ablation[name], fast_knobs)
    worst = knob_ablation["all"]["worst_cases"]
    print(elapsed(), flush=True)

    # 5. the knob grid on a subset (batched; knob sets interleaved per chunk so that load
    # from other processes spreads evenly), then the cheapest sets within the bound on the
    # subset re-measured on every case
    rer_worst = knob_ablation["rer_at_least_0.2"]["worst_cases"]
    if args.grid_cases and args.grid_cases < n:
        picked = np.linspace(0, n - 1, args.grid_cases).round().astype(int)
        grid_indices = sorted(set(picked.tolist()) | set(worst) | set(rer_worst))
        grid_batches = Batches(cases, grid_indices, reference)
    else:
        grid_indices, grid_batches = everything, batches
    in_grid = np.zeros(n, bool)
    in_grid[grid_indices] = True
    names = list(GRID)
    configs = [dict(zip(names, combo, strict=True))
               for combo in itertools.product(*(GRID[k] for k in names))]
    methods = [xbsm.method("fast", **c) for c in configs]
    grid_runs = [Run(n) for _ in configs]
    accurate_grid = Run(n)
    t_grid = time.perf_counter()
    for k in range(len(grid_batches.chunks)):
        for j in rng.permutation(len(configs) + 1):
            if j == len(configs):
                grid_batches.run_chunk(k, accurate, accurate_grid)
            else:
                grid_batches.run_chunk(k, methods[j], grid_runs[j])
    print(f"\ngrid: {len(configs)} knob sets on {len(grid_indices)} cases in "
          f"{time.perf_counter() - t_grid:.0f} s; {elapsed()}", flush=True)
    rer_ok = subsets["rer_at_least_0.2"]
    grid = []
    for c, r in zip(configs, grid_runs, strict=True):
        grid.append({"knobs": c, "batched_s": r.seconds,
                     "speedup_batched": accurate_grid.seconds / r.seconds,
                     "error_grid_cases": error_stats(r.niirs, ref, in_grid),
                     "error_grid_cases_rer_at_least_0.2": error_stats(r.niirs, ref,
                                                                      in_grid & rer_ok)})
    criteria = {"all": None, "rer_at_least_0.2": rer_ok}
    grid_key = {"all": "error_grid_cases",
                "rer_at_least_0.2": "error_grid_cases_rer_at_least_0.2"}
    verified = {}
    for c, key in grid_key.items():
        ok = sorted((g for g in grid if within(g[key], BOUND)), key=lambda g: g["batched_s"])
        print(f"{len(ok)} of {len(grid)} knob sets within {BOUND:g} NIIRS on every grid case "
              f"({c}); smallest max errors:")
        for g in sorted(grid, key=lambda g: g[key]["any"]["max"])[:3]:
            print(f"  {label_of(g['knobs'])}: max {g[key]['any']['max']:.1e}, "
                  f"x{g['speedup_batched']:.2f} batched")
        verified[c] = []
        for g in ok[:2 * args.candidates]:  # the cheapest, on every case
            if "error" not in g:
                r = batches.run(xbsm.method("fast", **g["knobs"]))
                g["error"] = error_stats(r.niirs, ref)
                g["error_rer_at_least_0.2"] = error_stats(r.niirs, ref, rer_ok)
            g_key = "error" if c == "all" else "error_rer_at_least_0.2"
            if within(g[g_key], BOUND) and len(verified[c]) < args.candidates:
                verified[c].append(g)
        print(f"  within {BOUND:g} on all {n} cases ({c}), cheapest first: "
              + ("; ".join(label_of(g["knobs"]) for g in verified[c]) or "none"), flush=True)

    # 6. time the presets and the cheapest sets within the bound as sweeps of one sensor
    candidates = dict(presets)
    for c in criteria:
        for g in verified[c]:
            candidates.setdefault(label_of(g["knobs"]), xbsm.method("fast", **g["knobs"]))
    # the smallest change: fast with only otf_wavelengths changed, on every case
    for w in GRID["otf_wavelengths"]:
        knobs = knob_values(xbsm.method("fast", otf_wavelengths=w), names)
        if w == fast.otf_wavelengths:
            continue
        g = next((g for g in grid if g["knobs"] == knobs), None)
        if g is None:  # fast's other knobs are off the grid
            g = {"knobs": knobs, "off_grid": True}
            grid.append(g)
        if "error" not in g:
            r = batches.run(xbsm.method("fast", **knobs))
            g["error"] = error_stats(r.niirs, ref)
            g["error_rer_at_least_0.2"] = error_stats(r.niirs, ref, rer_ok)
        candidates.setdefault(label_of(knobs), xbsm.method("fast", **knobs))
    sweeps = {i: sweep_datasets(cases[i], args.sweep) for i in timing_indices}
    sweep_times, _ = time_calls(sweeps, timing_indices, candidates, rng, "sweeps")
    timed = []
    for label, m in candidates.items():
        knobs = knob_values(m, names)
        g = next((g for g in grid if g["knobs"] == knobs), None) if label not in presets else None
        entry = {"label": label, "knobs": knobs,
                 "time_sweep_per_scenario": timing_summary(
                     sweep_times[label], sweep_times["accurate"], per=args.sweep)}
        if label in presets:
            entry["error"] = results[label]["error"]
            results[label]["time_sweep_per_scenario"] = entry["time_sweep_per_scenario"]
        if g is not None:
            entry.update(error=g["error"], error_rer_at_least_0_2=g["error_rer_at_least_0.2"],
                         speedup_batched=g.get("speedup_batched"),
                         within_bound={"all": within(g["error"], BOUND),
                                       "rer_at_least_0.2": within(g["error_rer_at_least_0.2"],
                                                                  BOUND)})
        timed.append(entry)
        t = entry["time_sweep_per_scenario"]
        print(f"  {label:80s} {t['median_ms']:6.2f} ms/scenario, "
              f"x{t['speedup_vs_accurate_total']:.2f} vs accurate", flush=True)

    def speedup(t):
        return t["time_sweep_per_scenario"]["speedup_vs_accurate_total"]

    fast_err = results["fast"]["error"]["any"]
    fast_err_rer = results["fast"]["error_subsets"]["rer_at_least_0.2"]["any"]
    fast_timed = next(t for t in timed if t["label"] == "fast")
    best = {}
    for c in criteria:
        ok = [t for t in timed if t.get("within_bound", {}).get(c)]
        best[c] = max(ok, key=speedup) if ok else None
    if best["all"] is not None and speedup(best["all"]) >= USEFUL_SPEEDUP:
        b = best["all"]
        recommendation = {
            "verdict": "tune fast", "knobs": b["knobs"], "error": b["error"],
            "speedup_vs_accurate_sweep": speedup(b),
            "speedup_vs_accurate_batched": b.get("speedup_batched"),
            "note": f"the cheapest measured knob set within {BOUND:g} NIIRS on every case",
        }
    else:
        recommendation = {
            "verdict": "state the bound",
            "fast_bound": {"max": fast_err["max"], "p95": fast_err["p95"],
                           "median": fast_err["median"]},
            "fast_bound_rer_at_least_0.2": {"max": fast_err_rer["max"],
                                            "p95": fast_err_rer["p95"]},
            "fast_speedup_vs_accurate_sweep": speedup(fast_timed),
            "fast_speedup_vs_accurate_single_call": results["fast"]["time_single_call"][
                "speedup_vs_accurate_total"],
            "cheapest_within_bound_on_every_case": best["all"],
            "cheapest_within_bound_where_rer_at_least_0.2": best["rer_at_least_0.2"],
            "note": (f"no measured knob set within {BOUND:g} NIIRS on every case is "
                     f"{USEFUL_SPEEDUP}x faster than accurate; fast's bound is its measured "
                     "max error"),
        }
    print(f"\nrecommendation: {recommendation['verdict']}")
    if recommendation["verdict"] == "tune fast":
        b = best["all"]
        print(f"  fast = {label_of(b['knobs'])}: max {b['error']['any']['max']:.1e}, p95 "
              f"{b['error']['any']['p95']:.1e}, x{speedup(b):.2f} vs accurate (sweeps), "
              f"{times(b.get('speedup_batched'))} (batched cases)")
    else:
        print(f"  fast's bound: max {fast_err['max']:.1e}, p95 {fast_err['p95']:.1e} NIIRS "
              f"(RER >= 0.2: max {fast_err_rer['max']:.1e}, p95 {fast_err_rer['p95']:.1e}); "
              f"x{speedup(fast_timed):.2f} vs accurate (sweeps)")
        for c, b in best.items():
            if b is not None:
                e = b["error"] if c == "all" else b["error_rer_at_least_0_2"]
                print(f"  cheapest within {BOUND:g} ({c}): {label_of(b['knobs'])}: max "
                      f"{e['any']['max']:.1e}, p95 {e['any']['p95']:.1e}, x{speedup(b):.2f} "
                      f"(sweeps), {times(b.get('speedup_batched'))} (batched cases)")

    print("\nsummary: max |NIIRS - reference| (GIQE 3 / 4 / 5), every case and RER >= 0.2; "
          "median time per single call and per scenario of a sweep")
    for name in presets:
        e, e2 = results[name]["error"], results[name]["error_subsets"]["rer_at_least_0.2"]
        print(f"  {name:9s} " + " / ".join(f"{e[str(g)]['max']:.1e}" for g in GIQE) + "   "
              + " / ".join(f"{e2[str(g)]['max']:.1e}" for g in GIQE)
              + f"   {results[name]['time_single_call']['median_ms']:.0f} ms/call, "
              f"{results[name]['time_sweep_per_scenario']['median_ms']:.2f} ms/scenario")

    worst_cases = []
    for i in worst[:10]:
        s = cases[i]["sensor"]
        ifov = s["pixel_pitch_x"] / s["focal_length"]
        worst_cases.append({"index": i, "fast_error": float(fast_worst[i]),
                            "accurate_error": float(acc_worst[i]),
                            "reference_rer": float(rer[i]), "snr": float(ref_run.snr[i]),
                            "jitter_px": s["jitter_x"] / ifov, **cases[i]})
    result = {
        "description": __doc__.split("\n\n")[0],
        "command": f"python recipes/evidence/archive/preset_tuning.py --cases {args.cases} "
                   f"--grid-cases {args.grid_cases} --timing-cases {args.timing_cases} "
                   f"--sweep {args.sweep}",
        "git": git, "machine": machine(),
        "load_average_at_start": load_start,
        "seed": args.seed, "cases": n, "rejected_draws": rejected,
        "draw": {"bands_um": [[b[0] * 1e6, b[1] * 1e6] for b in BANDS], "Q": Q_RANGE,
                 "fnumber": FNUMBER_RANGE, "pixel_pitch_m": PITCH_RANGE,
                 "aperture_diameter_m": DIAMETER_RANGE,
                 "note": "see the recipe's docstring and draw_case"},
        "subsets": {"rer_at_least_0.2": int(np.sum(subsets["rer_at_least_0.2"])),
                    "inside_giqe_calibration": {str(g): int(subsets[
                        "inside_giqe_calibration"][k].sum()) for k, g in enumerate(GIQE)},
                    "note": "rer: the reference's min(rer, rer_giqe5); calibration: no "
                            "calibration bit in the reference's flags for that GIQE version"},
        "error": "|NIIRS - reference| per case; median, 95th percentile (linear "
                 "interpolation) and max over the cases, per GIQE version and 'any' (the "
                 "largest of the three per case)",
        "timing": "time_single_call: wall time of one xbsm.niirs call on one case (datasets "
                  f"built beforehand), on {len(timing_indices)} of the cases, methods in "
                  "random order per case, after a warm-up. "
                  "time_sweep_per_scenario: one call on the case's sensor and "
                  f"{args.sweep} ground ranges from 0 to the case's, divided by {args.sweep}, "
                  f"on {len(timing_indices)} of the cases. speedup_vs_accurate_total = summed "
                  "accurate time / summed time. time_batched_cases / speedup_batched: the "
                  "cases with the same band batched along a 'case' dimension (every case "
                  "keeps its own quadrature)",
        "reference": knob_values(reference), "reference_pybsm": knob_values(reference_pybsm),
        "reference_self_check": {"half_knobs": half, "error": self_check},
        "max_batched_minus_single_call_relative": batch_vs_single,
        "presets": results, "fast_breakdown": breakdown, "knob_ablation": knob_ablation,
        "grid": {"cases": len(grid_indices), "bound": BOUND,
                 "accurate_batched_s": accurate_grid.seconds, "points": grid},
        "candidates_timed": {"cases": len(timing_indices), "sweep": args.sweep,
                             "points": timed},
        "recommendation": recommendation,
        "worst_cases_for_fast": worst_cases,
        "per_case": {
            "Q": q.tolist(), "band_min_um": [c["band_um"][0] for c in cases],
            "reference_rer": rer.tolist(), "snr": ref_run.snr.tolist(),
            "reference_niirs": ref.T.tolist(),
            "error": {name: np.abs(values[name] - (ref_pybsm if name == "pybsm" else ref))
                      .T.tolist() for name in presets},
        },
    }
    result["runtime_s"] = time.perf_counter() - t_start
    result["load_average_at_end"] = os.getloadavg()
    out_path.parent.mkdir(parents=True, exist_ok=True)
    out_path.write_text(json.dumps(jsonable(result), indent=1) + "\n")
    print(f"\nwrote {out_path} in {result['runtime_s']:.0f} s")


if __name__ == "__main__":
    main()
