"""Interrupting ``xbsm run``: Ctrl-C at 20 different moments, then resuming.

For each try the recipe starts ``xbsm run recipes/studies/interrupt.toml`` from
scratch in a child process, sends it SIGINT (what Ctrl-C sends) after a delay
spread over the whole run (computing, the last chunks, writing the NetCDF),
and checks:

- it exits within 30 s of the signal (else: a hang; the child is killed);
- no file is left under the output's name unless the run had finished, and a
  file that is there opens and equals an uninterrupted run's output;
- no temporary ``.partial`` file is left;
- running the same command again finishes, says how many chunks it found
  done, and that count equals the chunk files the interrupted run left, so
  no finished chunk is computed twice; its output equals the reference.

Prints one line per try and a summary; writes ``docs/benchmarks/interrupt_study.json``.

Run from the repository root with the project environment::

    .venv/bin/python recipes/interrupt_study.py [--tries 20] [--study STUDY.toml]
"""

from __future__ import annotations

import argparse
import json
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import xarray as xr
from _provenance import commit, machine

ROOT = Path(__file__).resolve().parent.parent
STUDY = ROOT / "recipes" / "studies" / "interrupt.toml"
HANG_SECONDS = 30.0


def command(out: Path, study: Path = STUDY) -> list[str]:
    """The command a user types, run with this interpreter."""
    return [sys.executable, "-m", "xbsm.cli", "run", str(study), "-o", str(out), "--no-figures"]


def reference_run(out: Path, study: Path) -> tuple[float, xr.Dataset]:
    """One uninterrupted run: its duration and its output."""
    start = time.perf_counter()
    subprocess.run(command(out, study), check=True, capture_output=True)
    duration = time.perf_counter() - start
    with xr.open_dataset(out) as ds:
        return duration, ds.load()


def same_as(path: Path, reference: xr.Dataset) -> bool:
    """Whether a result file opens and holds the reference's numbers."""
    try:
        with xr.open_dataset(path) as ds:
            return set(ds.data_vars) == set(reference.data_vars) and all(
                np.array_equal(ds[name].values, reference[name].values, equal_nan=True)
                for name in reference.data_vars)
    except (OSError, ValueError):
        return False


def _as_in_a_terminal() -> None:
    """Default Ctrl-C handling in the child, as a command typed in a terminal has.

    A process started in the background by a non-interactive shell inherits SIGINT
    ignored (POSIX), and Python then installs no KeyboardInterrupt handler: without
    this, running the recipe with ``&`` would measure nothing but ignored signals.
    """
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def interrupt_once(out: Path, delay: float, study: Path) -> dict:
    """Start from scratch, SIGINT after ``delay`` seconds, observe the aftermath."""
    shutil.rmtree(out.with_name(out.name + ".parts"), ignore_errors=True)
    out.unlink(missing_ok=True)
    proc = subprocess.Popen(command(out, study), stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, preexec_fn=_as_in_a_terminal)
    time.sleep(delay)
    sent = time.perf_counter()
    proc.send_signal(signal.SIGINT)
    try:
        _, err = proc.communicate(timeout=HANG_SECONDS)
        hang = False
    except subprocess.TimeoutExpired:
        proc.kill()
        _, err = proc.communicate()
        hang = True
    parts = out.with_name(out.name + ".parts")
    return {"delay_s": delay, "hang": hang, "exit_code": proc.returncode,
            "exit_latency_s": time.perf_counter() - sent, "output_exists": out.exists(),
            "partial_left": out.with_name(out.name + ".partial").exists(),
            "chunks_left": len(list(parts.glob("block-*.npz"))) if parts.exists() else 0,
            "message": err.strip().splitlines()[-1] if err.strip() else ""}


def resume(out: Path, study: Path) -> dict:
    """Run the same command again; how many chunks it found done."""
    proc = subprocess.run(command(out, study), capture_output=True, text=True, timeout=600)
    found = re.search(r"(\d+) of (\d+) chunks already done", proc.stderr)
    return {"resume_exit_code": proc.returncode,
            "resume_found_done": int(found.group(1)) if found else None,
            "resume_total_chunks": int(found.group(2)) if found else None}


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--tries", type=int, default=20)
    parser.add_argument("--study", type=Path, default=STUDY, help="study file to interrupt")
    parser.add_argument("--out", type=Path, default=ROOT / "docs/benchmarks/interrupt_study.json")
    args = parser.parse_args()
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "study.nc"
        duration, reference = reference_run(out, args.study)
        print(f"uninterrupted run: {duration:.1f} s", flush=True)
        for i in range(args.tries):
            delay = (i + 0.5) / args.tries * duration * 1.05
            row = interrupt_once(out, delay, args.study)
            finished_before = row["output_exists"]
            row["output_complete"] = same_as(out, reference) if finished_before else None
            if not finished_before:
                row.update(resume(out, args.study))
                row["resumed_output_correct"] = same_as(out, reference)
            rows.append(row)
            print(json.dumps(row), flush=True)
    bad = [r for r in rows if r["hang"] or r["partial_left"]
           or (r["output_exists"] and not r["output_complete"])
           or (not r["output_exists"] and (r["resume_found_done"] != r["chunks_left"]
                                            or not r["resumed_output_correct"]))]
    summary = {"tries": len(rows), "hangs": sum(r["hang"] for r in rows),
               "incomplete_files_left": sum(bool(r["output_exists"] and not r["output_complete"])
                                            for r in rows),
               "finished_before_signal": sum(r["output_exists"] for r in rows),
               "median_exit_latency_s": float(np.median([r["exit_latency_s"] for r in rows])),
               "max_exit_latency_s": max(r["exit_latency_s"] for r in rows),
               "chunks_reused": sum(r.get("resume_found_done") or 0 for r in rows),
               "failures": len(bad), "uninterrupted_s": duration}
    print(json.dumps(summary))
    study = args.study.resolve()
    study = study.relative_to(ROOT) if study.is_relative_to(ROOT) else study
    args.out.write_text(json.dumps({"machine": machine(), "commit": commit(), "study": str(study),
                                    "summary": summary, "tries": rows}, indent=1))
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
