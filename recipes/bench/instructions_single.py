"""Benchmark: instructions a single xbsm call executes, counted by callgrind (valgrind).

Wall-clock time on a shared machine can move by 2x within minutes (issue 22, eleventh
session: one and the same `snr` took 1.6-3.5 ms in interleaved rounds), which hides a change
of a few percent. The number of instructions a call executes does not depend on the load:
this recipe runs each checkout's ``xbsm.snr`` and ``xbsm.niirs`` (method ``accurate``) on the
Olson red camera at 20 km in 5 km visibility (the scenario of ``bench_single.py``) under
callgrind, whose counts are zeroed on entry to ``os.getppid`` (called after 5 warm-up
calls) and dumped on entry to ``os.getpgrp`` (called after the counted calls). Each
(checkout, function) runs twice, with ``--calls`` and twice as many calls; the difference
of the two dumps over ``--calls`` is the instructions of one call, free of what the markers
and the end of the run add (about 49 M, the same in both). Repeats of one checkout have
agreed within 0.5 % (9.26 and 9.30 M for one ``snr``).

What it does not say: instructions are not time (a memory-bound kernel costs more per
instruction than interpreter code, which is most of a single call); it measures one
scenario of tiny arrays, not a sweep. Use it for single-call changes of a few percent,
``bench_single.py`` (pyBSM side by side) for the time itself on a quiet machine.

Requires valgrind (``apt-get install valgrind``). Run from the repository root::

    .venv/bin/python recipes/bench/instructions_single.py [--checkout PATH ...]
        [--calls 20] [--functions snr niirs] [--out PATH]

Writes ``docs/benchmarks/instructions_single.json`` (or ``--out``): the machine, valgrind's
version, each checkout's commit, both dumps and the instructions per call.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # recipes/: the shared helpers

from _provenance import commit, machine  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]

#: The child: warm-up calls, zero the counts, the counted calls, dump the counts.
CHILD = """
import os, sys
import xbsm
from xbsm.examples import olson_scenario, olson_sensor
sensor, scenario = olson_sensor("red"), olson_scenario(ground_range=20000.0, visibility=5.0)
function, calls = getattr(xbsm, sys.argv[1]), int(sys.argv[2])
for _ in range(5):
    function(sensor, scenario, method="accurate")
os.getppid()  # callgrind --zero-before
for _ in range(calls):
    function(sensor, scenario, method="accurate")
os.getpgrp()  # callgrind --dump-before
"""


def counted(checkout: Path, function: str, calls: int) -> int:
    """Instructions between the two markers of one child run under callgrind."""
    with tempfile.TemporaryDirectory() as folder:
        out = Path(folder) / "callgrind.out"
        env = {**os.environ, "PYTHONPATH": str(checkout)}
        subprocess.run(
            ["valgrind", "--tool=callgrind", "--zero-before=os_getppid*",
             "--dump-before=os_getpgrp*", f"--callgrind-out-file={out}",
             sys.executable, "-c", CHILD, function, str(calls)],
            env=env, cwd=folder, check=True, capture_output=True)
        dumps = sorted(Path(folder).glob("callgrind.out.*"))
        if not dumps:
            raise RuntimeError("callgrind wrote no dump at os.getpgrp: the markers were not "
                               "found (a Python built without symbols?)")
        totals = re.search(r"^totals:\s+(\d+)", dumps[0].read_text(), re.MULTILINE)
        return int(totals.group(1))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--checkout", action="append", type=Path,
                        help="a checkout to count (repeatable; default: this one)")
    parser.add_argument("--calls", type=int, default=20)
    parser.add_argument("--functions", nargs="+", default=["snr", "niirs"],
                        choices=["snr", "niirs"])
    parser.add_argument("--out", type=Path,
                        default=ROOT / "docs" / "benchmarks" / "instructions_single.json")
    args = parser.parse_args()
    if shutil.which("valgrind") is None:
        sys.exit("valgrind is not installed (apt-get install valgrind)")
    checkouts = [c.resolve() for c in (args.checkout or [ROOT])]
    version = subprocess.run(["valgrind", "--version"], capture_output=True,
                             text=True).stdout.strip()
    rows = []
    for checkout in checkouts:
        label = commit(checkout)["commit"] or str(checkout)
        for function in args.functions:
            once = counted(checkout, function, args.calls)
            twice = counted(checkout, function, 2 * args.calls)
            per_call = (twice - once) / args.calls
            rows.append({"checkout": str(checkout), "commit": label, "function": function,
                         "calls": [args.calls, 2 * args.calls], "totals": [once, twice],
                         "instructions_per_call": per_call})
            print(f"{label:>12} {function:6s} {per_call / 1e6:8.3f} M instructions a call "
                  f"(dumps {once:,} and {twice:,})", flush=True)
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps({"machine": machine(), "valgrind": version,
                                    "scenario": "olson_sensor('red'), 20 km, 5 km visibility, "
                                                "method 'accurate'",
                                    "checkouts": [commit(c) for c in checkouts],
                                    "rows": rows}, indent=1))
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
