"""Set-up cost of a study against its chunk count: time and memory to the first saved chunk.

The same 10^6-scenario study (ground range x altitude x focal length x visibility x
drift rate, recipes/studies/million.toml) cut into 250, 1,000, 10,000 and 100,000
chunks by ``[run] chunks``, and (``--chunks 937500``) the same study stretched to
the 10^10 scenarios a study file may hold, at the default chunking. For each,
``xbsm run`` starts in a child process from a given checkout (``PYTHONPATH``), and
the recipe records the wall time from the start until the first chunk file appears
in ``OUT.nc.parts/`` and the child's peak resident memory until then (``VmHWM`` of
``/proc/PID/status``, Linux), then stops the child. A child that saves nothing
within ``--timeout`` seconds is recorded as such, with its memory at that moment.
Several checkouts are measured in turns, so
"before" and "after" share one run of the machine.

Run from the repository root, e.g. with the issue's starting point in a worktree::

    git worktree add ../before 391ccfe
    .venv/bin/python recipes/bench/study_setup_scaling.py --checkout . --checkout ../before

Writes ``docs/benchmarks/study_setup_scaling.json``.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # recipes/: the shared helpers

from _provenance import commit, machine

ROOT = Path(__file__).resolve().parents[2]
STUDY = ROOT / "recipes" / "studies" / "million.toml"

#: chunk count -> chunk lengths that give it on the million study's grid
#: (ground_range 100, altitude 10, focal_length 10, visibility 2, drift_rate_x 50)
LAYOUTS = {
    250: {"ground_range": 20, "drift_rate_x": 1},
    1_000: {"ground_range": 10, "visibility": 1, "drift_rate_x": 1},
    10_000: {"ground_range": 1, "visibility": 1, "drift_rate_x": 1},
    100_000: {"ground_range": 1, "altitude": 1, "visibility": 1, "drift_rate_x": 1},
}
#: the largest study a study file may describe (10^10 scenarios: the drift axis 10^4 times
#: longer), at the default chunking (at most 20,000 scenarios a chunk): 937,500 chunks
LARGEST = 937_500


def largest_text() -> str:
    """The million study stretched to the 10^10-scenario limit, default chunking."""
    text = STUDY.read_text().split("[run]")[0]
    return text.replace("num = 50 }", "num = 500000 }")


def study_text(chunks: dict) -> str:
    """The million study with the given chunk lengths (and no other [run] keys)."""
    text = STUDY.read_text().split("[run]")[0]
    lengths = ", ".join(f"{dim} = {size}" for dim, size in chunks.items())
    return text + f"\n[run]\nchunks = {{ {lengths} }}\n"


def peak_rss_mb(pid: int) -> float:
    """The process's peak resident memory so far [MB] (Linux)."""
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("VmHWM:"):
            return int(line.split()[1]) / 1024
    return float("nan")


def first_chunk(checkout: Path, chunk_count: int, timeout: float) -> dict:
    """Start ``xbsm run`` from ``checkout``; time and memory until its first chunk file."""
    with tempfile.TemporaryDirectory() as tmp:
        study = Path(tmp) / "study.toml"
        study.write_text(largest_text() if chunk_count == LARGEST
                         else study_text(LAYOUTS[chunk_count]))
        out = Path(tmp) / "out.nc"
        env = {**os.environ, "PYTHONPATH": str(checkout.resolve())}
        start = time.perf_counter()
        proc = subprocess.Popen([sys.executable, "-m", "xbsm.cli", "run", str(study), "-o",
                                 str(out), "--no-figures"], env=env, cwd=tmp,
                                stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        parts = Path(tmp) / "out.nc.parts"
        seconds, memory = None, float("nan")
        while time.perf_counter() - start < timeout and proc.poll() is None:
            memory = peak_rss_mb(proc.pid)
            if parts.is_dir() and any(parts.glob("block-*.npz")):
                seconds = time.perf_counter() - start
                break
            time.sleep(0.05)
        proc.send_signal(signal.SIGKILL)
        proc.wait()
        shutil.rmtree(parts, ignore_errors=True)
    return {"chunks": chunk_count, "first_chunk_s": seconds, "peak_rss_mb": round(memory, 1),
            "timed_out": seconds is None, "timeout_s": timeout}


def checkout_commit(checkout: Path) -> str:
    """The commit a checkout stands at (with '+changes' when its xbsm/ differs)."""
    head = subprocess.run(["git", "-C", str(checkout), "rev-parse", "--short", "HEAD"],
                          capture_output=True, text=True).stdout.strip()
    dirty = subprocess.run(["git", "-C", str(checkout), "status", "--porcelain", "xbsm"],
                           capture_output=True, text=True).stdout.strip()
    return head + ("+changes" if dirty else "")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--checkout", type=Path, action="append",
                        help="a checkout to measure (repeatable; default: this one)")
    parser.add_argument("--chunks", type=int, nargs="+", default=sorted(LAYOUTS),
                        choices=[*sorted(LAYOUTS), LARGEST])
    parser.add_argument("--timeout", type=float, default=300.0,
                        help="seconds to wait for the first chunk file")
    parser.add_argument("--out", type=Path,
                        default=ROOT / "docs" / "benchmarks" / "study_setup_scaling.json")
    args = parser.parse_args()
    checkouts = args.checkout or [ROOT]
    rows = []
    print(f"load average at start: {os.getloadavg()}", flush=True)
    for count in args.chunks:
        for checkout in checkouts:
            row = {"checkout": checkout_commit(checkout),
                   **first_chunk(checkout, count, args.timeout), "load_1min": os.getloadavg()[0]}
            rows.append(row)
            print(json.dumps(row), flush=True)
    args.out.write_text(json.dumps({"machine": machine(), "commit": commit(), "rows": rows},
                                   indent=1))
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
