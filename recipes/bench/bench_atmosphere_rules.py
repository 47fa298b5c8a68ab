"""Cost of each atmosphere interpolation rule in the package's kernel.

``xbsm.atmosphere.interpolate_database`` (the numpy interpolation that ``atmosphere_at``
wraps, without its flags) on 20,000
random scenarios: altitude log-uniform in 2 m-20 km, ground range uniform in
0-100 km, both visibilities; two wavelength windows, 0.4-0.9 um (51 samples) and
8-12 um (401). The rules alternate within each of ``--repeats`` rounds, so the load of
the shared machine falls on all of them alike. Prints microseconds per scenario
(median and minimum over the rounds) and writes
``docs/benchmarks/bench_atmosphere_rules.json``. No pyBSM counterpart: its
``load_database_atmosphere`` handles one scenario per call and re-reads the decoder
CSV each time (``recipes/bench/bench_single.py`` times whole calls against pyBSM).

Run from the repository root with the project environment::

    .venv/bin/python recipes/bench/bench_atmosphere_rules.py [--repeats 5]
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

from xbsm.atmosphere import INTERPOLATIONS, interpolate_database, load_database

OUT = Path(__file__).resolve().parents[2] / "docs" / "benchmarks" / "bench_atmosphere_rules.json"
WINDOWS_UM = {"0.4-0.9 um": (0.4, 0.9), "8-12 um": (8.0, 12.0)}
RULES = tuple(r for r in INTERPOLATIONS if r != "exact")


def scenarios(n: int, seed: int = 7):
    rng = np.random.default_rng(seed)
    altitude = np.exp(rng.uniform(np.log(2.0), np.log(20e3), n))
    return altitude, rng.uniform(0.0, 100e3, n), rng.choice([5.0, 23.0], n)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--scenarios", type=int, default=20_000)
    args = parser.parse_args()
    db = load_database()
    altitude, ground_range, visibility = scenarios(args.scenarios)
    report = {"scenarios": args.scenarios, "repeats": args.repeats, "us_per_scenario": {}}
    for label, (lo, hi) in WINDOWS_UM.items():
        index = np.flatnonzero((db.wavelength >= lo * 1e-6 - 1e-12)
                               & (db.wavelength <= hi * 1e-6 + 1e-12))
        window = slice(int(index[0]), int(index[-1]) + 1)
        times = {rule: [] for rule in RULES}
        for rule in RULES:  # warm-up: caches (the database, the extinction profile)
            interpolate_database(db, altitude[:100], ground_range[:100], visibility[:100],
                                 rule, window)
        for _ in range(args.repeats):
            for rule in RULES:
                start = time.perf_counter()
                interpolate_database(db, altitude, ground_range, visibility, rule, window)
                times[rule].append((time.perf_counter() - start) / args.scenarios * 1e6)
        report["us_per_scenario"][label] = {
            "wavelengths": index.size,
            **{rule: {"median": float(np.median(t)), "min": float(np.min(t))}
               for rule, t in times.items()}}
        for rule, t in times.items():
            print(f"{label} ({index.size} wavelengths) {rule:>20}: median {np.median(t):7.1f}"
                  f"  min {np.min(t):7.1f} us per scenario", flush=True)
    OUT.write_text(json.dumps(report, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
