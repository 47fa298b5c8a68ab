"""Benchmark: one scenario per call, xbsm against pyBSM 0.16.1, side by side in one run.

What a notebook user, an optimizer or a Monte Carlo loop pays per call. Three
single (scalar) scenarios:

- ``olson_red``: the paper's Olson camera (Table 2), red band, 9 km altitude,
  20 km ground range, 5 km visibility (xbsm: ``xbsm.examples.olson_sensor("red")``
  and ``olson_scenario(ground_range=20000.0, visibility=5.0)``; pyBSM: the same
  camera as ``recipes/bench/bench_niirs.py`` builds it);
- ``mwir_narrow``: fixture case ``case117_mwir_narrow`` of
  ``tests/fixtures/pybsm_cases.json`` (3.6-4.2 um, cold filter, 9 km altitude,
  24 km ground range, turbulence, sharpening kernel, 4 stacked frames);
- ``vis_nadir``: fixture case ``VIS`` (pyBSM's default sensor in 0.50-0.66 um,
  9 km altitude, nadir, 23 km visibility).

pyBSM (its own environment, ``NUMBA_NUM_THREADS=1``, a child process as in
``recipes/_pybsm_runner.py``) times ``metrics.niirs`` (GIQE 3, 4),
``metrics.niirs5`` (GIQE 5) and its SNR path (``load_database_atmosphere_no_interp``
+ ``giqe_radiance`` + ``photon_detector_SNR``, as ``_pybsm_runner.py`` and
``bench_snr.py`` time it). xbsm times ``xbsm.niirs(s, sc)`` (GIQE 3, 4, 5 at
once) and ``xbsm.snr(s, sc)`` for ``method="pybsm"``, ``"accurate"`` and
``"fast"``. Each is timed two ways: (a) the call alone on prebuilt inputs
(xbsm ``sensor``/``scenario`` datasets; pyBSM ``Sensor``/``Scenario``
objects), (b) building the inputs and calling. Every timing is ``--calls``
single calls after 2 warm-up calls; the median, quartiles, min and max are
recorded. The ratio printed is pyBSM's median over xbsm's median, call alone.
The two alternate scenario by scenario (pyBSM's child process, then xbsm), so
that both see about the same machine load; the load average is recorded at
each step.

Then one xbsm ``niirs`` call per method on ``olson_red`` runs under cProfile
(the grouping lives in ``recipes/bench/_profile.py``, shared with ``bench_niirs.py``);
its time is attributed to the innermost xbsm module on the call stack
(``atmosphere``, ``radiometry``, ``noise``, ``otf.*``, ``quadrature``,
``metrics``, ``model``, ``params``, ...), split into that module's own code
with the numpy/scipy it calls directly, and "xarray overhead": time spent in
xarray (and whatever xarray calls) below that module and above any xbsm
kernel. cProfile records only caller-callee pairs, so time two or more levels
below an xbsm function is shared among callers in proportion to each pair's
cumulative time (gprof's rule); a second, exact pass (``sys.setprofile``,
walking the stack at every event) gives the same shares as a check. Both
profilers slow the call down; the shares, not the profiled times, are the
result.

Writes ``docs/benchmarks/bench_single.json``, or ``--out PATH`` (machine, load
average at start and end, versions, commit, every timing and the profile); ``docs/benchmarks.md``
quotes it. Run from the repository root with the project environment;
pyBSM's own environment is made on first use (see ``recipes/README.md``)::

    .venv/bin/python recipes/bench/bench_single.py [--calls 20] [--out PATH]
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # recipes/: the shared helpers

import numpy as np
import xarray as xr
from _profile import print_by_module, profile_call, stack_shares
from _provenance import commit, machine
from _pybsm_runner import CHILD_PRELUDE, run_child

import xbsm
from xbsm.examples import olson_scenario, olson_sensor

ROOT = Path(__file__).resolve().parents[2]
DOCS = ROOT / "docs"
sys.path.insert(0, str(ROOT / "tests"))
import pybsm_cases  # noqa: E402  (tests/pybsm_cases.py: fixture case -> xbsm datasets)

METHODS = ("pybsm", "accurate", "fast")
WARMUP = 2
PROFILE_SCENARIO = "olson_red"

CHILD = CHILD_PRELUDE + r'''
from importlib.metadata import version

def snr(s, sc, interp):
    load = utils.load_database_atmosphere if interp else utils.load_database_atmosphere_no_interp
    atm = load(altitude=sc.altitude, ground_range=sc.ground_range, ihaze=sc.ihaze)
    atm = atm[atm[:, 0] >= s.opt_trans_wavelengths[0], :]
    atm = atm[atm[:, 0] <= s.opt_trans_wavelengths[-1], :]
    emissive = int(s.opt_trans_wavelengths[0] >= 2.9e-6)
    tgt, bkg = radiance.giqe_radiance(atm=atm, is_emissive=emissive)
    return [float(radiance.photon_detector_SNR(
        sensor=s, radiance_wavelengths=atm[:, 0], target_radiance=tgt,
        background_radiance=bkg).snr)]

def niirs(s, sc, interp):
    n = metrics.niirs(sensor=s, scenario=sc, interp=interp)
    return [float(n.niirs), float(n.niirs_4)]

def niirs5(s, sc, interp):
    return [float(metrics.niirs5(sensor=s, scenario=sc, interp=interp).niirs)]

def timed(fn, calls, warmup):
    for _ in range(warmup):
        fn()
    times = []
    for _ in range(calls):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return times

out = {"versions": {p: version(p) for p in ("pybsm", "numpy", "scipy", "numba")},
       "python": sys.version.split()[0], "scenarios": {}}
for case in job["scenarios"]:
    kw = (case["sensor"], case["scenario"])
    interp = case["interp"]
    rows = {}
    for name, fn in (("niirs", niirs), ("niirs5", niirs5), ("snr", snr)):
        # pyBSM's niirs writes the GIQE target into the Scenario; every call writes the same
        s, sc = build(*kw)
        call = timed(lambda: fn(s, sc, interp), job["calls"], job["warmup"])
        build_call = timed(lambda: fn(*build(*kw), interp), job["calls"], job["warmup"])
        rows[name] = {"call": call, "build_call": build_call, "values": fn(*build(*kw), interp)}
    out["scenarios"][case["name"]] = rows
json.dump(out, sys.stdout)
'''


# ---------------------------------------------------------------- scenarios

def fixture_case(name):
    cases = json.loads((ROOT / "tests" / "fixtures" / "pybsm_cases.json").read_text())
    (case,) = [c for c in cases if c["sensor"]["name"] == name]
    return case


def olson_pybsm():
    """The Olson red camera at 20 km, 5 km visibility, as bench_niirs.py gives it to pyBSM."""
    from bench_niirs import pybsm_cases as olson_cases

    (case,) = [c for c in olson_cases() if c["band"] == "red" and c["scenario"]["ihaze"] == 2
               and c["scenario"]["ground_range"] == 20000.0]
    return {"sensor": case["sensor"], "scenario": case["scenario"], "interp": False}


def scenarios():
    """name -> (description, xbsm builder, pyBSM keywords in the runner's format)."""
    out = {"olson_red": (
        "Olson camera (paper Table 2), red band, 9 km altitude, 20 km ground range, "
        "5 km visibility",
        lambda: (olson_sensor("red"), olson_scenario(ground_range=20000.0, visibility=5.0)),
        olson_pybsm())}
    for name, fixture, text in (
            ("mwir_narrow", "case117_mwir_narrow",
             "fixture case117_mwir_narrow: 3.6-4.2 um, 9 km altitude, 24 km ground range, "
             "23 km visibility, turbulence, sharpening kernel, 4 frames"),
            ("vis_nadir", "VIS", "fixture VIS: pyBSM's default sensor in 0.50-0.66 um, "
                                 "9 km altitude, nadir, 23 km visibility")):
        case = fixture_case(fixture)
        out[name] = (text, lambda case=case: pybsm_cases.datasets(case), {
            "sensor": dict(case["sensor"], post=case["post"]),
            "scenario": case["scenario"], "interp": bool(case.get("interp", False))})
    return out


# ---------------------------------------------------------------- timing

def summary(times):
    q1, q2, q3 = statistics.quantiles(times, n=4) if len(times) > 1 else (times[0],) * 3
    return {"median_ms": 1e3 * statistics.median(times), "q1_ms": 1e3 * q1, "q3_ms": 1e3 * q3,
            "min_ms": 1e3 * min(times), "max_ms": 1e3 * max(times), "calls": len(times)}


def timed(fn, calls):
    for _ in range(WARMUP):
        fn()
    times = []
    for _ in range(calls):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return times


def run_pybsm_single(cases, calls):
    """Time pyBSM on each case in its own process (as _pybsm_runner.run_pybsm does)."""
    return run_child(CHILD, {"calls": calls, "warmup": WARMUP,
                             "scenarios": [dict(kw, name=name) for name, kw in cases.items()]})


def time_xbsm(build, calls):
    s, sc = build()
    out = {}
    for func in ("niirs", "snr"):
        fn = getattr(xbsm, func)
        for method in METHODS:
            call = timed(lambda fn=fn, method=method: fn(s, sc, method=method), calls)
            build_call = timed(lambda fn=fn, method=method: fn(*build(), method=method), calls)
            out[f"{func}/{method}"] = {"call": summary(call), "build_call": summary(build_call)}
    return out


def agreement(build, pybsm_values):
    """|NIIRS difference| (GIQE 3, 4, 5) and relative SNR difference from pyBSM, per method."""
    s, sc = build()
    theirs = pybsm_values["niirs"]["values"] + pybsm_values["niirs5"]["values"]
    snr_theirs = pybsm_values["snr"]["values"][0]
    out = {}
    for method in METHODS:
        ours = xbsm.niirs(s, sc, method=method)["niirs"].values
        snr_ours = float(xbsm.snr(s, sc, method=method)["snr_frame"])
        out[method] = {
            "niirs_xbsm": ours.tolist(), "niirs_pybsm": theirs,
            "abs_niirs_difference": [abs(float(a) - b) for a, b in zip(ours, theirs,
                                                                         strict=True)],
            "snr_xbsm": snr_ours, "snr_pybsm": snr_theirs,
            "relative_snr_difference": abs(snr_ours - snr_theirs) / max(abs(snr_theirs), 1.0),
        }
    return out


# ---------------------------------------------------------------- profile

def profile_niirs(build, method):
    """One xbsm.niirs call under cProfile, grouped by module (``recipes/bench/_profile.py``)."""
    s, sc = build()
    xbsm.niirs(s, sc, method=method)  # warm
    t0 = time.perf_counter()
    xbsm.niirs(s, sc, method=method)
    unprofiled = time.perf_counter() - t0
    result = profile_call(lambda: xbsm.niirs(s, sc, method=method))
    return {
        "method": method, "scenario": PROFILE_SCENARIO,
        "unprofiled_call_ms": 1e3 * unprofiled, **result,
        "stack_check": stack_shares(lambda: xbsm.niirs(s, sc, method=method)),
    }


# ---------------------------------------------------------------- report

def fmt(row):
    return f"{row['median_ms']:7.1f} ({row['q1_ms']:.1f}-{row['q3_ms']:.1f})"


def print_tables(record):
    print(f"\nmedian of {record['calls']} single calls after {WARMUP} warm-up calls, in ms "
          "(interquartile range); ratio = pyBSM median / xbsm median, call alone")
    head = (f"{'scenario':12s} {'function':8s} {'method':9s} {'xbsm call':>22s} "
            f"{'xbsm build+call':>22s} {'pyBSM':>7s} {'':>22s} {'ratio':>6s}")
    print(head)
    print("-" * len(head))
    for name, sc in record["scenarios"].items():
        pb = sc["pybsm"]
        for key, row in sc["xbsm"].items():
            func, method = key.split("/")
            theirs = pb["snr" if func == "snr" else "niirs"]["call"]
            label = "snr" if func == "snr" else "niirs"
            print(f"{name:12s} {func:8s} {method:9s} {fmt(row['call']):>22s} "
                  f"{fmt(row['build_call']):>22s} {label:>7s} {fmt(theirs):>22s} "
                  f"{theirs['median_ms'] / row['call']['median_ms']:6.2f}")
        for func in ("niirs5",):
            print(f"{name:12s} {'':8s} {'':9s} {'':>22s} {'':>22s} {func:>7s} "
                  f"{fmt(pb[func]['call']):>22s}")
    print("\npyBSM 0.16.1 (NUMBA_NUM_THREADS=1), ms: call alone | build + call")
    for name, sc in record["scenarios"].items():
        for func, row in sc["pybsm"].items():
            print(f"  {name:12s} {func:7s} {fmt(row['call'])} | {fmt(row['build_call'])}")
    print("\nagreement with pyBSM, method='pybsm': |NIIRS difference| GIQE 3, 4, 5; "
          "SNR difference relative to max(SNR, 1)")
    for name, sc in record["scenarios"].items():
        a = sc["agreement"]["pybsm"]
        print(f"  {name:12s} " + ", ".join(f"{d:.1e}" for d in a["abs_niirs_difference"])
              + f"; SNR {a['relative_snr_difference']:.1e}")
    print("\nload average (1, 5, 15 min) after pyBSM | after xbsm, per scenario")
    for name, sc in record["scenarios"].items():
        print(f"  {name:12s} " + " | ".join(
            ", ".join(f"{v:.2f}" for v in sc[key])
            for key in ("load_average_after_pybsm", "load_average_after_xbsm")))


def print_profile(profiles):
    methods, modules = print_by_module(
        profiles, f"\nprofile of one xbsm.niirs call on {PROFILE_SCENARIO} (cProfile), ms: "
        "own code + numpy it calls directly / xarray below it",
        lambda _, row: f"{row['own_ms']:8.1f} / {row['xarray_ms']:6.1f} ({row['share']:4.0%})")
    for label, key, unit in (("xarray overhead", "xarray_overhead_ms", "ms"),
                             ("profiled total", "profiled_total_ms", "ms"),
                             ("unprofiled call", "unprofiled_call_ms", "ms"),
                             ("function calls", "function_calls", "")):
        cells = []
        for m in methods:
            value = profiles[m][key]
            share = (f" ({profiles[m]['xarray_overhead_share']:.0%})"
                     if key == "xarray_overhead_ms" else "")
            cells.append(f"{value:.1f} {unit}{share}" if unit else f"{value}")
        print(f"{label:22s}" + "".join(f"{c:>24s}" for c in cells))
    print("\ncheck: the same shares from the exact call stack (sys.setprofile)")
    print(f"{'module':22s}" + "".join(f"{m:>12s}" for m in methods))
    for module in modules:
        print(f"{module:22s}" + "".join(
            f"{profiles[m]['stack_check']['by_module_share'].get(module, 0.0):12.0%}"
            for m in methods))
    print(f"{'xarray overhead':22s}" + "".join(
        f"{profiles[m]['stack_check']['xarray_overhead_share']:12.0%}" for m in methods))
    for m in methods:
        print(f"\ntop cumulative, method={m!r} (ms cumulative, ms self, calls):")
        for row in profiles[m]["top_cumulative"][:12]:
            print(f"  {row['cumtime_ms']:8.1f} {row['tottime_ms']:8.1f} {row['ncalls']:7d}  "
                  f"{row['function']}")
        print(f"top self time, method={m!r}:")
        for row in profiles[m]["top_self"][:8]:
            print(f"  {row['cumtime_ms']:8.1f} {row['tottime_ms']:8.1f} {row['ncalls']:7d}  "
                  f"{row['function']}")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--calls", type=int, default=20, help="timed calls per function "
                        f"(after {WARMUP} warm-up calls); median, quartiles, min, max")
    parser.add_argument("--out", type=Path, default=DOCS / "benchmarks" / "bench_single.json",
                        help="JSON file to write (default docs/benchmarks/bench_single.json)")
    args = parser.parse_args()
    if args.calls < 2:
        parser.error("--calls must be at least 2")

    t_start = time.perf_counter()
    record = {"description": __doc__.split("\n\n")[0],
              "command": "python recipes/bench/bench_single.py" + (
                  f" --calls {args.calls}" if args.calls != 20 else "") + (
                  f" --out {args.out}" if args.out != parser.get_default("out") else ""),
              "load_average_at_start": os.getloadavg(), "date": time.strftime("%Y-%m-%d"),
              **commit(), "machine": machine(), "calls": args.calls, "warmup_calls": WARMUP}
    cases = scenarios()

    record["scenarios"] = {}
    for name, (text, build, kw) in cases.items():
        # pyBSM then xbsm, scenario by scenario, so that both see the same machine load
        print(f"timing {name} ...", file=sys.stderr)
        pybsm = run_pybsm_single({name: kw}, args.calls)
        load_between = os.getloadavg()
        theirs = pybsm["scenarios"][name]
        record["scenarios"][name] = {
            "description": text,
            "pybsm": {func: {"call": summary(row["call"]),
                             "build_call": summary(row["build_call"]),
                             "values": row["values"]} for func, row in theirs.items()},
            "xbsm": time_xbsm(build, args.calls),
            "agreement": agreement(build, theirs),
            "load_average_after_pybsm": load_between,
            "load_average_after_xbsm": os.getloadavg(),
        }
    record["versions"] = {
        "xbsm": {"xbsm": xbsm.__version__, "xarray": xr.__version__, "numpy": np.__version__,
                 "python": platform.python_version()},
        "pybsm": {**pybsm["versions"], "python": pybsm["python"]},
    }
    record["profile"] = {m: profile_niirs(cases[PROFILE_SCENARIO][1], m) for m in METHODS}
    record["runtime_s"] = time.perf_counter() - t_start
    record["load_average_at_end"] = os.getloadavg()

    print_tables(record)
    print_profile(record["profile"])
    print(f"\nload average at start {record['load_average_at_start']}, at end "
          f"{record['load_average_at_end']}; {record['runtime_s']:.0f} s")
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(record, indent=1, default=float) + "\n")
    print(f"wrote {args.out}", file=sys.stderr)


if __name__ == "__main__":
    main()
