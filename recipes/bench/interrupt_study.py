"""Racing, interrupting and damaging ``xbsm run``: a file under the output's name never lies.

Every check runs real ``xbsm run`` child processes (``python -m xbsm.cli run``,
SIGINT restored to its default as in a terminal) and compares every complete
output file, cell by cell (every data variable, NaN equal to NaN), with an
uninterrupted run of its own study. Scenarios (``--scenarios``, all but
``compute`` by default):

``race``
    Two different studies on one output: study A (``--ground-ranges`` ground
    ranges x 2 visibilities x 20 aperture diameters, ``chunk_scenarios = 40``:
    the review's study with 40 ground ranges instead of 97, 40 chunks instead of
    100) and a copy at another altitude (B), started on the same ``-o out.nc``
    ``--race-delay`` seconds apart. The second must be refused at once, with one
    stderr line naming the first's process; A's file must equal A's reference;
    then B, run again with ``--overwrite``, must equal B's reference.
``study``
    Study A interrupted once some chunks are saved, then study B run on the same
    output: A's chunks must be set aside (one line naming the study) and the
    file must equal B's reference (the review's mix, one run after the other).
``database``
    The atmosphere database replaced between an interrupt and the resume: run,
    SIGINT once some chunks are saved, resume from a copy of the package whose
    ``atmosphere.nc`` has the ground-reflected radiance (GRND_RFLT) halved
    (``PYTHONPATH``). The resume must set the old chunks aside (one line) and
    write what an uninterrupted run with the modified database writes. Two
    variants: interrupted from the checkout (the commit differs too), and from
    an unmodified copy of the package (only the database differs).
``version``
    Likewise with a package copy whose ``__version__`` differs; the output
    equals A's reference.
``signals``
    SIGINT at ``--signal-tries`` moments and SIGTERM at ``--sigterm-tries``
    moments of the default study (``xbsm run -o out.nc``, figures drawn): half
    spread over writing the NetCDF file (timed from the child's own line "chunks
    computed: N of N (100 %)"), half over drawing the figures (timed from its
    line "wrote out.nc"), both windows measured on an uninterrupted run, and
    SIGINT at ``--open-tries`` moments 5-100 ms after "wrote out.nc", where the
    figures open the file (the review's swallowed Ctrl-C). Each must exit within
    3 s with 130 / 143 (0 if it had finished), never hang (killed after 30 s),
    print no traceback, not go on working after the signal and exit 0, leave no
    ``.partial`` file nor a half-written figure; a file under the output's name
    must equal the reference; a run stopped before its file exists is run again
    (``--no-figures``) and must reuse every chunk left and equal it.
``damage``
    After an interrupt, one ``block-*.npz`` is truncated, bit-flipped, or
    rewritten as a valid file with one number changed and its old digest
    ("tampered"), or replaced by another chunk's verified file of the same shapes
    ("swapped"); the resume must say it recomputes that file and equal the
    reference. Also a run killed with SIGKILL (stale lock, no handler): the
    next run takes the lock over and resumes.
``refusals``
    A second writer of the same study, an existing output without
    ``--overwrite``, the study file as output (with and without
    ``--overwrite``), a missing directory, a directory as output: each exit
    code 2 with exactly one stderr line, nothing changed. The race's refusals
    are counted with them in the summary.
``compute``
    The former recipe: SIGINT at ``--compute-tries`` moments spread over a whole
    run of ``recipes/studies/interrupt.toml`` (computing, writing), then the
    same command again must reuse exactly the chunks left and equal an
    uninterrupted run.

Prints one line per try and a table; writes ``docs/benchmarks/interrupt_study.json``
(per scenario: machine, commit, settings, summary and every try). Scenarios not
run keep their previous entry in that file.

Run from the repository root with the project environment::

    .venv/bin/python recipes/bench/interrupt_study.py [--scenarios race,signals] [--race-tries 10]
        [--signal-tries 30] [--sigterm-tries 4] [--open-tries 8] [--damage-tries 1]
        [--compute-tries 20]
"""

from __future__ import annotations

import argparse
import collections
import json
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # recipes/: the shared helpers

import netCDF4
import numpy as np
import xarray as xr
from _provenance import commit, machine

from xbsm.atmosphere import database_path

ROOT = Path(__file__).resolve().parents[2]
STUDY = ROOT / "recipes" / "studies" / "interrupt.toml"
HANG_SECONDS = 30.0  # a child still alive this long after its signal is a hang (killed)
EXIT_LIMIT = 3.0  # issue 20: a signal is honoured within 3 s
LONG = 900.0  # an uninterrupted run that takes longer than this is a hang too
SCENARIOS = ("race", "study", "database", "version", "signals", "damage", "refusals",
             "compute")
DEFAULT_SCENARIOS = SCENARIOS[:-1]

#: Study A of the race (the review's): ground range x visibility x 20 aperture diameters.
RACE_STUDY = """title = "{title}"
[sensor]
preset = "olson"
band = "nir"
[scenario]
altitude = {altitude}
platform_speed = 100.0
[sweep]
ground_range = {{ start = 0.0, stop = 300e3, num = {ground_ranges} }}
visibility = [23.0, 5.0]
aperture_diameter = {{ start = 0.05, stop = 0.25, num = 20 }}
[run]
chunk_scenarios = 40
"""

_DONE = re.compile(r"(\d+) of (\d+) chunks already done")
_PERCENT = re.compile(r"chunks computed: \d+ of \d+ \((\d+) %")


def _as_in_a_terminal() -> None:
    """Default Ctrl-C handling in the child, as a command typed in a terminal has.

    A process started in the background by a non-interactive shell inherits SIGINT
    ignored (POSIX), and Python then installs no KeyboardInterrupt handler: without
    this, running the recipe with ``&`` would measure nothing but ignored signals.
    """
    signal.signal(signal.SIGINT, signal.SIG_DFL)


# --- child processes ----------------------------------------------------------------------


class Child:
    """One ``xbsm`` command in a child process, its output lines timestamped as they come."""

    def __init__(self, args, cwd: Path, package: Path):
        env = {**os.environ, "PYTHONUNBUFFERED": "1",
               "PYTHONPATH": os.pathsep.join(filter(None, [str(package),
                                                           os.environ.get("PYTHONPATH")]))}
        self.args = [str(a) for a in args]
        self.lines = []  # (seconds since start, "out" or "err", text)
        self._changed = threading.Condition()
        self._open = 2
        self.started = time.perf_counter()
        # cwd is a scratch directory: `python -m` puts it first on sys.path, before PYTHONPATH
        self.proc = subprocess.Popen([sys.executable, "-m", "xbsm.cli", *self.args], cwd=cwd,
                                     env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                     text=True, preexec_fn=_as_in_a_terminal)
        self._readers = [threading.Thread(target=self._read, args=(stream, name), daemon=True)
                         for stream, name in ((self.proc.stdout, "out"), (self.proc.stderr, "err"))]
        for reader in self._readers:
            reader.start()
        self.sent = self.signum = self.ended = None
        self.hang = False

    def _read(self, stream, name: str) -> None:
        for line in stream:
            with self._changed:
                self.lines.append((time.perf_counter() - self.started, name, line.rstrip("\n")))
                self._changed.notify_all()
        with self._changed:
            self._open -= 1
            self._changed.notify_all()

    def wait_line(self, pattern, timeout: float, predicate=None) -> float | None:
        """Seconds from the start to the first line matching ``pattern``; None if it ended."""
        pattern = re.compile(pattern)

        def found():
            for t, _, text in self.lines:
                match = pattern.search(text)
                if match and (predicate is None or predicate(match)):
                    return t
            return None

        with self._changed:
            self._changed.wait_for(lambda: found() is not None or not self._open, timeout)
            return found()

    def send(self, signum) -> bool:
        """Send a signal now; False (nothing sent) if the process had already ended."""
        if self.proc.poll() is not None:
            return False
        self.sent, self.signum = time.perf_counter(), signum
        self.proc.send_signal(signum)
        return True

    def finish(self, timeout: float = HANG_SECONDS) -> Child:
        """Wait for the end (killing it after ``timeout`` s: a hang) and for its output."""
        try:
            self.proc.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            self.hang = True
            self.proc.kill()
            self.proc.wait()
        self.ended = time.perf_counter()
        for reader in self._readers:
            reader.join(timeout=10)
        return self

    @property
    def code(self) -> int:
        return self.proc.returncode

    @property
    def err(self) -> list[str]:
        return [text for _, name, text in self.lines if name == "err" and text.strip()]

    @property
    def seconds(self) -> float:
        return self.ended - self.started

    @property
    def latency(self) -> float | None:
        """Seconds from the signal to the end of the process."""
        return None if self.sent is None else self.ended - self.sent

    def found_done(self) -> int | None:
        for text in self.err:
            if match := _DONE.search(text):
                return int(match.group(1))
        return None

    def record(self) -> dict:
        """The facts every try reports about this child."""
        return {"exit_code": self.code, "hang": self.hang, "seconds": round(self.seconds, 3),
                "signal": None if self.signum is None else signal.Signals(self.signum).name,
                "exit_latency_s": None if self.latency is None else round(self.latency, 3),
                "stderr_last": self.err[-1] if self.err else ""}


def run_to_end(args, cwd, package) -> Child:
    """An uninterrupted command; it must succeed."""
    child = Child(args, cwd, package).finish(LONG)
    if child.code != 0:
        raise SystemExit(f"{' '.join(child.args)} failed ({child.code}): {child.err[-3:]}")
    return child


# --- comparing files ----------------------------------------------------------------------


def load(path: Path) -> xr.Dataset:
    with xr.open_dataset(path) as ds:
        return ds.load()


def differing_cells(path: Path, reference: xr.Dataset) -> dict:
    """How many cells of ``path`` differ from the reference, every data variable, NaN == NaN.

    ``cells_differing`` counts the cells that differ (a missing variable or another
    shape counts all of its cells); ``equal`` is np.array_equal(equal_nan) of every
    variable and equal coordinates; ``error`` says why a file does not open.
    """
    try:  # any failure to read it is a broken file
        ds = load(path)
    except Exception as err:  # noqa: BLE001
        return {"equal": False, "cells_differing": None, "error": f"{type(err).__name__}: {err}"}
    cells = differ = 0
    equal = set(ds.data_vars) == set(reference.data_vars) and all(
        name in ds.coords and np.array_equal(ds[name].values, coord.values)
        for name, coord in reference.coords.items())
    for name, ref in reference.data_vars.items():
        cells += ref.size
        if name not in ds or ds[name].shape != ref.shape:
            differ += ref.size
            equal = False
            continue
        a, b = ds[name].values, ref.values
        same = a == b
        if a.dtype.kind in "fc":
            same |= np.isnan(a) & np.isnan(b)
        differ += int(np.size(same) - np.count_nonzero(same))
        equal &= np.array_equal(a, b, equal_nan=a.dtype.kind in "fc")
    return {"equal": bool(equal and differ == 0), "cells_differing": differ, "cells": cells,
            "error": None}


def cells_between(a: xr.Dataset, b: xr.Dataset) -> int:
    """Cells that differ between two references (the scenario means something only if > 0)."""
    total = 0
    for name, var in a.data_vars.items():
        x, y = var.values, b[name].values
        same = x == y
        if x.dtype.kind in "fc":
            same |= np.isnan(x) & np.isnan(y)
        total += int(same.size - np.count_nonzero(same))
    return total


# --- the scratch world: outputs, studies, package copies ----------------------------------


class World:
    """The scratch directory: the output, the studies, package copies and the references."""

    def __init__(self, tmp: Path, ground_ranges: int):
        self.tmp = tmp
        self.work = tmp / "work"
        self.work.mkdir()
        self.out = self.work / "out.nc"
        self.study_a = self.work / "a.toml"
        self.study_b = self.work / "b.toml"
        self.study_a.write_text(RACE_STUDY.format(title="race A, 9 km", altitude=9000.0,
                                                  ground_ranges=ground_ranges))
        self.study_b.write_text(RACE_STUDY.format(title="race B, 6 km", altitude=6000.0,
                                                  ground_ranges=ground_ranges))
        self.checkout = ROOT
        self.references = {}

    def clean(self) -> None:
        """Nothing of an earlier try: output, parts (and set-aside parts), lock, figures."""
        for path in self.work.glob(self.out.name + "*"):
            if path.is_dir():
                shutil.rmtree(path)
            else:
                path.unlink()
        shutil.rmtree(self.figures, ignore_errors=True)

    @property
    def parts(self) -> Path:
        return self.out.with_name(self.out.name + ".parts")

    @property
    def figures(self) -> Path:
        return self.out.with_name(self.out.stem + "_figures")

    def blocks(self) -> list[Path]:
        return sorted(self.parts.glob("block-*.npz")) if self.parts.exists() else []

    def set_aside(self) -> list[Path]:
        return sorted(self.work.glob(self.out.name + ".parts.set-aside-*"))

    def leftovers(self) -> dict:
        """Temporary files a stopped run must not leave."""
        temporary = [p.name for p in self.work.glob(self.out.name + ".partial")]
        if self.figures.exists():
            temporary += [p.name for p in self.figures.iterdir() if not p.name.endswith(".png")]
        return {"partial_left": bool(temporary), "temporary_files": temporary}

    def package(self, name: str, *, database=None, version=None) -> Path:
        """A copy of the xbsm package in ``TMP/name/xbsm`` with its database beside it.

        ``xbsm/data/atmosphere.nc`` is the checkout's relative symlink to
        ``../../atmosphere.nc``, so the copy's database is ``TMP/name/atmosphere.nc``.
        """
        top = self.tmp / name
        shutil.copytree(ROOT / "xbsm", top / "xbsm", symlinks=True,
                        ignore=shutil.ignore_patterns("__pycache__"))
        data = top / "xbsm" / "data" / "atmosphere.nc"
        if data.is_symlink() or not data.exists():
            data.unlink(missing_ok=True)
            data.symlink_to(Path("..") / ".." / "atmosphere.nc")
        if database is None:
            (top / "atmosphere.nc").symlink_to(database_path())
        else:
            shutil.copyfile(database_path(), top / "atmosphere.nc")
            database(top / "atmosphere.nc")
        if version is not None:
            init = top / "xbsm" / "__init__.py"
            text, count = re.subn(r'^__version__ = "([^"]*)"', f'__version__ = "\\1{version}"',
                                  init.read_text(), flags=re.M)
            if count != 1:
                raise SystemExit(f"no __version__ line in {init}")
            init.write_text(text)
        return top

    def reference(self, key: str, study, package: Path, extra=()) -> xr.Dataset:
        """An uninterrupted run's output (computed once per key)."""
        if key not in self.references:
            self.clean()
            args = ["run", *([study] if study else []), "-o", self.out, *extra]
            child = run_to_end(args, self.work, package)
            self.references[key] = (load(self.out), child)
            print(f"reference {key}: {child.seconds:.1f} s", flush=True)
            self.clean()
        return self.references[key][0]


def halve_ground_reflected(path: Path) -> None:
    """Halve the GRND_RFLT component of a database file in place (netCDF4)."""
    with netCDF4.Dataset(path, "a") as nc:
        names = [str(n) for n in nc["component"][:]]
        k = names.index("GRND_RFLT")
        var = nc["atmosphere"]
        var.set_auto_maskandscale(False)
        var[:, :, :, k, :] = var[:, :, :, k, :] * np.float32(0.5)


# --- pieces of a try ----------------------------------------------------------------------


def run_args(world: World, study: Path, *extra) -> list:
    return ["run", study, "-o", world.out, "--no-figures", *extra]


def interrupt_at(world: World, study: Path, package: Path, percent: int,
                 signum=signal.SIGINT) -> tuple[Child, dict]:
    """Start from scratch, send ``signum`` once ``percent`` % of the chunks are computed."""
    world.clean()
    child = Child(run_args(world, study), world.work, package)
    child.wait_line(_PERCENT, LONG, lambda m: int(m.group(1)) >= percent)
    child.send(signum)
    child.finish()
    row = {"interrupt": child.record(), "chunks_left": len(world.blocks()),
           "lock_left": world.out.with_name(world.out.name + ".lock").exists(),
           **world.leftovers()}
    return child, row


def one_line(child: Child) -> bool:
    return child.code == 2 and len(child.err) == 1


# --- scenarios ----------------------------------------------------------------------------


def scenario_race(world: World, args) -> list[dict]:
    ref = {world.study_a: world.reference("A", world.study_a, ROOT, ["--no-figures"]),
           world.study_b: world.reference("B", world.study_b, ROOT, ["--no-figures"])}
    print(f"references A and B differ in {cells_between(*ref.values())} cells", flush=True)
    rows = []
    for i in range(args.race_tries):
        world.clean()
        first = Child(run_args(world, world.study_a), world.work, ROOT)
        time.sleep(args.race_delay)
        second = Child(run_args(world, world.study_b), world.work, ROOT)
        second.finish(LONG)
        first_running = first.proc.poll() is None
        first.finish(LONG)
        row = {"try": i, "first": first.record(), "second": second.record(),
               "first_running_when_second_ended": first_running,
               "refusal_lines": second.err if second.code == 2 else first.err}
        problems = []
        refused, writer = (second, first) if second.code == 2 else (first, second)
        if sorted([first.code, second.code]) != [0, 2]:
            problems.append(f"exit codes {first.code} and {second.code}, not one 0 and one 2")
        elif refused is not second:
            problems.append("the first run was refused, not the second")
        if not (one_line(refused) and f"process {writer.proc.pid} " in refused.err[0]):
            problems.append("the refusal is not one line naming the writer's process")
        if not first_running:
            problems.append("the second ended after the first: not refused while it ran")
        study_of = {first: world.study_a, second: world.study_b}
        row["writer_file"] = differing_cells(world.out, ref[study_of[writer]])
        row["set_aside_after_race"] = len(world.set_aside())
        rerun = Child(run_args(world, study_of[refused], "--overwrite"), world.work, ROOT)
        rerun.finish(LONG)
        row["rerun"] = {**rerun.record(), "found_done": rerun.found_done(),
                        "set_aside_lines": sum("set aside" in line for line in rerun.err)}
        row["rerun_file"] = differing_cells(world.out, ref[study_of[refused]])
        for key in ("writer_file", "rerun_file"):
            if not row[key]["equal"]:
                problems.append(f"{key}: {row[key]}")
        if rerun.code != 0:
            problems.append(f"rerun exit {rerun.code}")
        row["problems"] = problems
        rows.append(row)
        print(f"race {i}: second {second.code} after {second.seconds:.1f} s "
              f"({row['refusal_lines'][:1]}); first {first.code} in {first.seconds:.1f} s; "
              f"files {row['writer_file']['cells_differing']} / "
              f"{row['rerun_file']['cells_differing']} cells differ; {problems or 'ok'}",
              flush=True)
    return rows


def _resume_from(world: World, name: str, interrupt_package: Path, resume_package: Path,
                 reference: xr.Dataset, percent: int, aside_says: str,
                 resume_study: Path | None = None) -> dict:
    """Interrupt with one package, resume with another: parts set aside, output = reference."""
    child, row = interrupt_at(world, world.study_a, interrupt_package, percent)
    resume = Child(run_args(world, resume_study or world.study_a), world.work,
                   resume_package).finish(LONG)
    aside_lines = [line for line in resume.err if "set aside" in line]
    aside = world.set_aside()
    row.update(variant=name, resume={**resume.record(), "found_done": resume.found_done()},
               set_aside_lines=aside_lines,
               set_aside_chunks=len(list(aside[0].glob("block-*.npz"))) if aside else 0,
               file=differing_cells(world.out, reference))
    problems = []
    if row["interrupt"]["hang"] or child.code not in (130,):
        problems.append(f"interrupt exit {child.code}")
    if row["chunks_left"] == 0:
        problems.append("no chunk left by the interrupt: nothing to set aside (try a later "
                        "--interrupt-percent)")
    if resume.code != 0:
        problems.append(f"resume exit {resume.code}")
    if len(aside_lines) != 1 or aside_says not in aside_lines[0]:
        problems.append(f"set-aside lines {aside_lines}, expected one naming {aside_says!r}")
    if resume.found_done() != 0:
        problems.append(f"resume found {resume.found_done()} chunks done, expected 0")
    if row["set_aside_chunks"] != row["chunks_left"]:
        problems.append(f"{row['set_aside_chunks']} chunks set aside of {row['chunks_left']}")
    if not row["file"]["equal"]:
        problems.append(f"file: {row['file']}")
    row["problems"] = problems
    print(f"{name}: interrupt {child.code} after {row['chunks_left']} chunks "
          f"({row['interrupt']['exit_latency_s']} s); resume {resume.code}: {aside_lines}; "
          f"{row['file']['cells_differing']} cells differ; {problems or 'ok'}", flush=True)
    return row


def scenario_database(world: World, args) -> list[dict]:
    pristine = world.package("pristine") if not (world.tmp / "pristine").exists() \
        else world.tmp / "pristine"
    halved = world.package("halved", database=halve_ground_reflected)
    reference = world.reference("A, GRND_RFLT halved", world.study_a, halved, ["--no-figures"])
    original = world.reference("A", world.study_a, ROOT, ["--no-figures"])
    print(f"halving GRND_RFLT changes {cells_between(reference, original)} cells", flush=True)
    rows = []
    for i in range(args.damage_tries):
        for name, package in (("from the checkout", ROOT), ("from an unmodified copy", pristine)):
            rows.append({"try": i, **_resume_from(world, f"database {name}", package, halved,
                                                  reference, args.interrupt_percent,
                                                  "atmosphere database")})
    return rows


def scenario_version(world: World, args) -> list[dict]:
    pristine = world.package("pristine") if not (world.tmp / "pristine").exists() \
        else world.tmp / "pristine"
    bumped = world.package("bumped", version="+harness")
    reference = world.reference("A", world.study_a, ROOT, ["--no-figures"])
    rows = []
    for i in range(args.damage_tries):
        for name, package in (("from the checkout", ROOT), ("from an unmodified copy", pristine)):
            rows.append({"try": i, **_resume_from(world, f"version {name}", package, bumped,
                                                  reference, args.interrupt_percent,
                                                  "xbsm version")})
    return rows


def scenario_study(world: World, args) -> list[dict]:
    """Study A interrupted, then study B (another altitude) run on the same output."""
    reference = world.reference("B", world.study_b, ROOT, ["--no-figures"])
    return [{"try": i, **_resume_from(world, "study B after A", ROOT, ROOT, reference,
                                      args.interrupt_percent, "study", world.study_b)}
            for i in range(args.damage_tries)]


def _same_shapes(a: Path, b: Path) -> bool:
    with np.load(a) as x, np.load(b) as y:
        return sorted(x.files) == sorted(y.files) and all(
            x[n].shape == y[n].shape for n in x.files) and any(
            not np.array_equal(x[n], y[n], equal_nan=True) for n in x.files if n != "__digest__")


def _damage(file: Path, how: str, blocks: list[Path]) -> None:
    data = bytearray(file.read_bytes())
    if how == "truncated":
        file.write_bytes(bytes(data[:len(data) // 2]))
    elif how == "bit-flipped":
        data[len(data) // 2] ^= 0x10
        file.write_bytes(bytes(data))
    elif how == "tampered":  # a valid file with one number changed and the old digest
        with np.load(file) as saved:
            arrays = {name: saved[name] for name in saved.files}
        name = next(n for n, a in arrays.items() if a.dtype.kind == "f" and np.isfinite(a).any())
        flat = arrays[name].reshape(-1)
        flat[np.flatnonzero(np.isfinite(flat))[0]] += 1.0
        with open(file, "wb") as handle:
            np.savez(handle, **arrays)
    elif how == "swapped":  # another chunk's whole, verified file under this chunk's name
        donor = next(b for b in blocks if b != file and _same_shapes(b, file))
        shutil.copyfile(donor, file)


def scenario_damage(world: World, args) -> list[dict]:
    reference = world.reference("A", world.study_a, ROOT, ["--no-figures"])
    rows = []
    for i in range(args.damage_tries):
        for how in ("truncated", "bit-flipped", "tampered", "swapped", "killed"):
            signum = signal.SIGKILL if how == "killed" else signal.SIGINT
            child, row = interrupt_at(world, world.study_a, ROOT, args.interrupt_percent, signum)
            blocks = world.blocks()
            victim = blocks[len(blocks) // 2] if blocks and how != "killed" else None
            if victim is not None:
                _damage(victim, how, blocks)
            resume = Child(run_args(world, world.study_a), world.work, ROOT).finish(LONG)
            said = [line for line in resume.err if "did not verify" in line]
            row.update(**{"try": i}, damage=how, victim=victim.name if victim else None,
                       resume={**resume.record(), "found_done": resume.found_done()},
                       recompute_lines=said, file=differing_cells(world.out, reference))
            problems = []
            expected_code = -signal.SIGKILL if how == "killed" else 130
            if child.code != expected_code or child.hang:
                problems.append(f"interrupt exit {child.code}, expected {expected_code}")
            if not blocks:
                problems.append("no chunk left by the interrupt (try a later --interrupt-percent)")
            if resume.code != 0:
                problems.append(f"resume exit {resume.code}: {resume.err[-1:]}")
            if victim is not None:
                if len(said) != 1 or victim.name not in said[0]:
                    problems.append(f"recompute lines {said}, expected one naming {victim.name}")
                if resume.found_done() != len(blocks) - 1:
                    problems.append(f"resume found {resume.found_done()} done of "
                                    f"{len(blocks)} left, one damaged")
            elif resume.found_done() != len(blocks):
                problems.append(f"resume found {resume.found_done()} done of {len(blocks)} left")
            if not row["file"]["equal"]:
                problems.append(f"file: {row['file']}")
            row["problems"] = problems
            rows.append(row)
            print(f"damage {how}: {len(blocks)} chunks left, {row['victim']}; resume "
                  f"{resume.code}: {said}; {row['file']['cells_differing']} cells differ; "
                  f"{problems or 'ok'}", flush=True)
    return rows


def scenario_refusals(world: World, args) -> list[dict]:
    rows = []

    def refused(name, child, unchanged=None):
        row = {"case": name, **child.record(), "stderr": child.err}
        problems = [] if one_line(child) else [f"exit {child.code} with {len(child.err)} lines"]
        if unchanged is not None and not unchanged():
            problems.append("a file changed")
        row["problems"] = problems
        rows.append(row)
        print(f"refusal {name}: {child.code} {child.err}; {problems or 'ok'}", flush=True)

    world.clean()
    writer = Child(run_args(world, world.study_a, "--workers", "1"), world.work, ROOT)
    writer.wait_line(_DONE, LONG)
    refused("second writer, same study",
            Child(run_args(world, world.study_a), world.work, ROOT).finish(LONG))
    rows[-1]["writer_running_when_refused"] = writer.proc.poll() is None
    rows[-1]["names_writer"] = f"process {writer.proc.pid} " in (rows[-1]["stderr"] or [""])[0]
    if not rows[-1]["names_writer"]:
        rows[-1]["problems"].append("does not name the writer's process")
    writer.send(signal.SIGINT)
    writer.finish()
    rows[-1]["writer_after_sigint"] = writer.record()

    world.clean()
    world.out.write_bytes(b"a finished run")
    refused("existing output without --overwrite",
            Child(run_args(world, world.study_a), world.work, ROOT).finish(LONG),
            lambda: world.out.read_bytes() == b"a finished run")
    study = world.study_a.read_bytes()
    for extra in ([], ["--overwrite"]):
        refused("output is the study file" + (" --overwrite" if extra else ""),
                Child(["run", world.study_a, "-o", world.study_a, *extra], world.work,
                      ROOT).finish(LONG), lambda: world.study_a.read_bytes() == study)
    refused("output directory missing",
            Child(["run", world.study_a, "-o", world.work / "missing" / "out.nc"], world.work,
                  ROOT).finish(LONG))
    refused("output is a directory",
            Child(["run", world.study_a, "-o", world.work], world.work, ROOT).finish(LONG))
    world.clean()
    return rows


def _all_computed(match) -> bool:
    return match.group(1) == "100"


def _segments(calibration: Child) -> list[tuple[str, str, float]]:
    """The stretches of a run after its last chunk: (what, line that starts it, seconds).

    The first is writing the NetCDF file (from "chunks computed: N of N (100 %)" to
    "wrote OUT.nc"); then one per figure (from the line of the file before it) and
    the last from the last figure's line to the end of the process.
    """
    computed = calibration.wait_line(_PERCENT, 0, _all_computed)
    marks = [("writing the NetCDF file", _PERCENT.pattern, computed)]
    marks += [(f"after {Path(text.split(' ', 1)[1]).name}", f"^{re.escape(text)}$", t)
              for t, name, text in calibration.lines
              if name == "out" and text.startswith("wrote ") and t >= computed]
    ends = [t for *_, t in marks[1:]] + [calibration.seconds]
    return [(what, line, end - t) for (what, line, t), end in zip(marks, ends, strict=True)]


def _moments(count: int, segments) -> list[tuple[str, str, float]]:
    """``count`` moments: half spread over writing the file, half over the figures' stretches.

    Each is (what, the line it is timed from, seconds after that line), so a run
    slower or faster than the calibration is still hit in the same stretch.
    """
    first = (count + 1) // 2
    (what, line, write), figures = segments[0], segments[1:]
    moments = [(what, line, (i + 0.5) / first * write) for i in range(first)]
    total = sum(length for *_, length in figures)
    for i in range(count - first):
        at = (i + 0.5) / (count - first) * total
        for what, line, length in figures:
            if at < length:
                moments.append((what, line, at))
                break
            at -= length
    return moments


def scenario_signals(world: World, args) -> list[dict]:
    world.reference("default study", None, ROOT)
    reference, calibration = world.references["default study"]
    segments = _segments(calibration)
    wrote_line = rf"^wrote {re.escape(str(world.out))}$"
    print("default study after its last chunk: " + ", ".join(
        f"{what} {length:.2f} s" for what, _, length in segments), flush=True)
    moments = [(signal.SIGINT, *m) for m in _moments(args.signal_tries, segments)]
    moments += [(signal.SIGTERM, *m) for m in _moments(args.sigterm_tries, segments)]
    # densely where the figures open the file just written (the review's swallowed Ctrl-C)
    moments += [(signal.SIGINT, *segments[1][:2], 0.005 + 0.1 * i / max(1, args.open_tries))
                for i in range(args.open_tries)]
    rows = []
    for signum, after, line, offset in moments:
        world.clean()
        child = Child(["run", "-o", world.out], world.work, ROOT)
        start = child.wait_line(line, LONG, _all_computed if line == _PERCENT.pattern else None)
        if start is not None:  # timed from the child's own line
            time.sleep(max(0.0, child.started + start + offset - time.perf_counter()))
        sent = child.send(signum)
        child.finish()
        written = child.wait_line(wrote_line, 0)
        at = None if child.sent is None else child.sent - child.started
        phase = ("ended before the signal" if not sent else
                 "writing the NetCDF file" if written is None or written > at else "figures")
        row = {"signal": signal.Signals(signum).name, "aimed_at": after,
               "offset_s": round(offset, 3), "sent_at_s": None if at is None else round(at, 3),
               "phase": phase, **child.record(), **world.leftovers(),
               "output_exists": world.out.exists(), "chunks_left": len(world.blocks()),
               "stderr": child.err[-2:]}
        problems = []
        # killed by the signal itself (returncode -signum) is what a shell also shows as 128 + n
        expected = (0,) if not sent else (128 + signum, -signum, 0)
        if child.hang:
            problems.append("hang")
        elif child.code not in expected:
            problems.append(f"exit {child.code}, expected {expected}")
        if sent and child.latency > EXIT_LIMIT:
            problems.append(f"exit {child.latency:.2f} s after the signal")
        if row["partial_left"]:
            problems.append(f"left {row['temporary_files']}")
        if any("Traceback" in line for line in child.err):
            problems.append("a traceback")
        if sent and child.code == 0 and any(t > at + 0.05 for t, *_ in child.lines):
            problems.append("the signal was ignored: output after it, then exit 0")
        if world.out.exists():
            row["file"] = differing_cells(world.out, reference)
            if not row["file"]["equal"]:
                problems.append(f"file: {row['file']}")
        else:
            rerun = Child(["run", "-o", world.out, "--no-figures"], world.work, ROOT).finish(LONG)
            row["rerun"] = {**rerun.record(), "found_done": rerun.found_done()}
            row["file"] = differing_cells(world.out, reference)
            if rerun.code != 0 or not row["file"]["equal"]:
                problems.append(f"rerun exit {rerun.code}, file {row['file']}")
            if rerun.found_done() != row["chunks_left"]:
                problems.append(f"rerun found {rerun.found_done()} chunks done of "
                                f"{row['chunks_left']} left")
        row["problems"] = problems
        if problems:
            row["stderr"] = child.err  # all of it, to see where it went wrong
        rows.append(row)
        print(f"{row['signal']} {offset:.2f} s into {after} ({phase}): exit {child.code} "
              f"after {row['exit_latency_s']} s; file {row['file']['cells_differing']} cells "
              f"differ{'' if world.out.exists() else ' (no file)'}; {problems or 'ok'}",
              flush=True)
    return rows


def scenario_compute(world: World, args) -> list[dict]:
    """The former recipe: SIGINT spread over a whole run of a larger study, then resume."""
    reference = world.reference("compute", args.study, ROOT, ["--no-figures"])
    duration = world.references["compute"][1].seconds
    rows = []
    for i in range(args.compute_tries):
        delay = (i + 0.5) / args.compute_tries * duration * 1.05
        world.clean()
        child = Child(run_args(world, args.study), world.work, ROOT)
        time.sleep(delay)
        sent = child.send(signal.SIGINT)
        child.finish()
        row = {"delay_s": round(delay, 3), **child.record(), **world.leftovers(),
               "output_exists": world.out.exists(), "chunks_left": len(world.blocks())}
        problems = []
        if child.hang:
            problems.append("hang")
        elif child.code not in ((130, 0) if sent else (0,)):
            problems.append(f"exit {child.code}")
        if row["partial_left"]:
            problems.append(f"left {row['temporary_files']}")
        if not world.out.exists():
            rerun = Child(run_args(world, args.study), world.work, ROOT).finish(LONG)
            row["rerun"] = {**rerun.record(), "found_done": rerun.found_done()}
            if rerun.found_done() != row["chunks_left"]:
                problems.append(f"rerun found {rerun.found_done()} of {row['chunks_left']} left")
        row["file"] = differing_cells(world.out, reference)
        if not row["file"]["equal"]:
            problems.append(f"file: {row['file']}")
        row["problems"] = problems
        rows.append(row)
        print(f"compute {i}: SIGINT at {delay:.1f} s: exit {child.code} after "
              f"{row['exit_latency_s']} s, {row['chunks_left']} chunks left; {problems or 'ok'}",
              flush=True)
    return rows


# --- summary ------------------------------------------------------------------------------


def _children(row: dict):
    """Every child record of a try (the run itself, interrupts, reruns, race partners)."""
    if "exit_code" in row:
        yield row
    for key in ("first", "second", "interrupt", "resume", "rerun", "writer_after_sigint"):
        if isinstance(row.get(key), dict) and "exit_code" in row[key]:
            yield row[key]


def _files(row: dict):
    for key in ("file", "writer_file", "rerun_file"):
        if isinstance(row.get(key), dict):
            yield row[key]


def summarize(rows: list[dict]) -> dict:
    children = [c for row in rows for c in _children(row)]
    latencies = [c["exit_latency_s"] for c in children
                 if c.get("exit_latency_s") is not None and c.get("signal") != "SIGKILL"]
    files = [f for row in rows for f in _files(row)]
    codes = collections.Counter(str(c["exit_code"]) for c in children)
    return {"tries": len(rows), "hangs": sum(c["hang"] for c in children),
            "files_compared": len(files),
            "mixed_or_stale_cells": sum(f["cells_differing"] or 0 for f in files),
            "unreadable_files": sum(f["error"] is not None for f in files),
            "exit_codes": dict(sorted(codes.items())),
            "signals_sent": len(latencies),
            "exit_latency_median_s": float(np.median(latencies)) if latencies else None,
            "exit_latency_max_s": max(latencies) if latencies else None,
            "exits_over_3_s": sum(t > EXIT_LIMIT for t in latencies),
            "failures": sum(bool(row["problems"]) for row in rows),
            "problems": [p for row in rows for p in row["problems"]]}


def _refusal_summary(results: dict) -> dict:
    """Every refusal of the run (race and refusals): exit 2 with exactly one stderr line."""
    lines = [len(r["stderr"]) for r in results.get("refusals", {}).get("tries", [])]
    lines += [len(r["refusal_lines"]) for r in results.get("race", {}).get("tries", [])]
    return {"refusals": len(lines), "one_line": sum(n == 1 for n in lines)}


def _without(value, tmp: str):
    """``value`` with the scratch directory's path written as $TMP (no machine paths)."""
    if isinstance(value, str):
        return value.replace(tmp, "$TMP")
    if isinstance(value, dict):
        return {key: _without(item, tmp) for key, item in value.items()}
    if isinstance(value, list):
        return [_without(item, tmp) for item in value]
    return value


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenarios", default=",".join(DEFAULT_SCENARIOS),
                        help=f"comma-separated, of {', '.join(SCENARIOS)} (default: all but "
                             "compute)")
    parser.add_argument("--race-tries", type=int, default=10)
    parser.add_argument("--race-delay", type=float, default=1.5,
                        help="seconds between the two runs of the race")
    parser.add_argument("--ground-ranges", type=int, default=40,
                        help="ground ranges of the race study (x 2 visibilities x 20 apertures, "
                             "40 scenarios a chunk); the review used the database's 97")
    parser.add_argument("--signal-tries", type=int, default=30, help="SIGINT moments")
    parser.add_argument("--sigterm-tries", type=int, default=4, help="SIGTERM moments")
    parser.add_argument("--open-tries", type=int, default=8,
                        help="SIGINT moments 5-100 ms after 'wrote OUT.nc' (the figures open it)")
    parser.add_argument("--damage-tries", type=int, default=1,
                        help="tries of each database, version and damage variant")
    parser.add_argument("--interrupt-percent", type=int, default=40,
                        help="interrupt once this share of the chunks is computed")
    parser.add_argument("--compute-tries", type=int, default=20)
    parser.add_argument("--study", type=Path, default=STUDY, help="study of `compute`")
    parser.add_argument("--out", type=Path, default=ROOT / "docs/benchmarks/interrupt_study.json")
    args = parser.parse_args()
    chosen = [s.strip() for s in args.scenarios.split(",") if s.strip()]
    if unknown := set(chosen) - set(SCENARIOS):
        parser.error(f"unknown scenarios {sorted(unknown)}; choose from {', '.join(SCENARIOS)}")
    args.study = args.study.resolve()
    settings = {k: (str(v) if isinstance(v, Path) else v) for k, v in vars(args).items()
                if k not in ("out", "scenarios")}
    study = args.study.relative_to(ROOT) if args.study.is_relative_to(ROOT) else args.study
    settings["study"] = str(study)
    results = {}
    started = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="xbsm-race-") as tmp:
        world = World(Path(tmp), args.ground_ranges)
        for name in chosen:
            begin, load_before = time.perf_counter(), os.getloadavg()[0]
            rows = globals()[f"scenario_{name}"](world, args)
            results[name] = {"machine": machine(), "commit": commit(),
                             "date": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
                             "seconds": round(time.perf_counter() - begin, 1),
                             # other users' load on the machine: the latencies depend on it
                             "load_average_1min": [round(load_before, 2),
                                                   round(os.getloadavg()[0], 2)],
                             "settings": settings, "summary": summarize(rows), "tries": rows}
        results = _without(results, tmp)
    previous = {}
    if args.out.exists():
        old = json.loads(args.out.read_text())
        previous = old.get("scenarios", {})
    scenarios = {**previous, **results}
    table = {name: {k: v for k, v in entry["summary"].items() if k != "problems"}
             for name, entry in scenarios.items()}
    overall = {"hangs": sum(s["hangs"] for s in table.values()),
               "mixed_or_stale_cells": sum(s["mixed_or_stale_cells"] for s in table.values()),
               "failures": sum(s["failures"] for s in table.values()),
               **_refusal_summary(scenarios)}
    args.out.write_text(json.dumps({"recipe": "recipes/bench/interrupt_study.py",
                                    "summary": overall, "per_scenario": table,
                                    "scenarios": scenarios}, indent=1)
                        + "\n")
    print(f"\n{'scenario':<10} {'tries':>5} {'hangs':>5} {'cells':>6} {'fail':>4} "
          f"{'latency median/max s':>21}  exit codes")
    for name, s in table.items():
        lat = (f"{s['exit_latency_median_s']:.2f} / {s['exit_latency_max_s']:.2f}"
               if s["signals_sent"] else "-")
        print(f"{name:<10} {s['tries']:>5} {s['hangs']:>5} {s['mixed_or_stale_cells']:>6} "
              f"{s['failures']:>4} {lat:>21}  {s['exit_codes']}")
    print(json.dumps(overall))
    for name in results:
        for problem in results[name]["summary"]["problems"]:
            print(f"{name}: {problem}")
    print(f"{time.perf_counter() - started:.0f} s; wrote {args.out}")


if __name__ == "__main__":
    main()
