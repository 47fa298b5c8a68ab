"""xbsm from several threads at once: NetCDF files read and written under one lock.

netCDF-C and HDF5 are not thread-safe and netCDF4-python releases the GIL around them.
Before ``xbsm._netcdf``, four threads making their first call at once (each reading the
atmosphere database) crashed the interpreter: a segmentation fault or a bus error in 9
of 9 runs, in ``load_database``, ``database_conditions`` and ``xbsm.scenario`` alike.
``open_atmosphere`` and ``use_database`` open the file through xarray, whose netCDF4
backend reads a file's metadata outside its lock (pydata/xarray#4100, #9779): four
threads opening at once crashed the interpreter too, until xbsm held the lock around
those opens as well. Four threads each opening their own copy ten times and closing
none crashed 10 of 10 runs with a small file cache: not a race but HDF5 (a file with string
variables open three times, the oldest two closed, opened again), until xbsm opened each
file through one handle (``xbsm._netcdf.open_dataset``).
The first use of a file has to happen inside a fresh process (every read is cached per
process and file), so each check runs a child interpreter and looks at how it ended.
"""

from __future__ import annotations

import os
import subprocess
import sys
import threading

import pytest

#: A child's script: every thread starts at one barrier, then makes its first call.
_CHILD = r"""
import shutil, sys, tempfile, threading
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np
import xarray as xr

import xbsm
from xbsm import atmosphere as atm
from xbsm.examples import olson_scenario, olson_sensor

what, threads = sys.argv[1], int(sys.argv[2])
folder = Path(tempfile.mkdtemp())
# copies of the shipped file: each is a file no thread has read yet (the caches are per file)
copies = [shutil.copy(atm.database_path(), folder / f"copy{i}.nc")
          for i in range(threads if what == "own" else 3)]
barrier = threading.Barrier(threads, timeout=120)  # a thread that died: no wait for ever
# opened before the threads start: xarray reads a file's metadata outside its lock
# (pydata/xarray#4100; with xarray 2023.12 a thread opening the file while xbsm read it
# crashed 4 of 10 runs), which no lock of xbsm's can cover; its data reads take the lock
opened = xr.open_dataset(copies[0], engine="netcdf4", chunks=None) if what == "xarray" else None
if what == "own":  # a small file cache stands for a process with more than 128 files open
    xr.set_options(file_cache_maxsize=4)

def first_call(k):
    barrier.wait()
    path = copies[k % len(copies)] if what != "model" else None
    if what == "read":
        return float(np.nansum(atm.load_database(path).cube[0, 0, 0]))
    if what == "conditions":
        return atm.database_conditions(path)["visibility"]
    if what == "xarray":  # one thread reads through xarray's backend, the others through xbsm
        if k == 0:  # a lazy read, which xarray makes under its lock (the one xbsm takes)
            return float(opened["atmosphere"][0, 0, 0, 0, :5].sum())
        return float(np.nansum(atm.load_database(copies[0]).cube[0, 0, 0, 0, :5]))
    if what == "open":  # xarray's open reads the file's metadata outside its own lock
        for _ in range(20):  # every open reads it again: twenty rounds, all at once
            barrier.wait()
            ds = atm.open_atmosphere(path)
        return float(ds["atmosphere"][0, 0, 0, 0, :5].sum())
    if what == "own":  # its own copy, opened again and again and never closed: xarray kept
        total = 0.0  # a handle per open until its cache evicted the oldest, and HDF5 crashed
        for _ in range(10):  # on a file open three times whose oldest two were closed
            barrier.wait()
            ds = atm.open_atmosphere(copies[k])
            total += float(ds["atmosphere"][0, 0, 0, 0, :5].sum())
        return total
    if what == "use":  # use_database checks the file through xarray on entry
        for _ in range(5):  # each entry loads and validates the whole cube: 5 rounds, 18 s
            barrier.wait()
            with atm.use_database(path):
                visibility = atm.database_conditions()["visibility"]
        return visibility
    sc = olson_scenario(ground_range=20000.0, visibility=5.0)  # what: "model"
    return float(xbsm.snr(olson_sensor("red"), sc)["snr"])

try:
    with ThreadPoolExecutor(threads) as pool:
        answers = list(pool.map(first_call, range(threads)))
finally:
    if opened is not None:
        opened.close()
    shutil.rmtree(folder)
same = answers[1:] if what == "xarray" else answers  # xarray's raw units differ
assert all(a == same[0] for a in same), answers
print("ok", answers)
"""


@pytest.mark.parametrize("what", ["read", "conditions", "xarray", "model", "open", "use", "own"])
def test_first_calls_from_four_threads_at_once_do_not_crash(what):
    done = subprocess.run([sys.executable, "-c", _CHILD, what, "4"], capture_output=True,
                          text=True, timeout=300)
    # a crash ends the child on a signal: a negative return code, no "ok"
    assert done.returncode == 0, (done.returncode, done.stderr[-2000:])
    assert done.stdout.startswith("ok"), done.stdout


@pytest.mark.skipif(not hasattr(os, "fork"), reason="no fork")
@pytest.mark.filterwarnings("ignore:This process:DeprecationWarning")  # fork with threads
def test_a_fork_waits_for_the_netcdf_lock_and_the_child_finds_it_free():
    # A LocalCluster's workers are forked (xbsm.study.store._FORK) from distributed's event
    # loop thread. Had another thread held the lock at that moment, the worker would find it
    # taken by a thread it does not have and wait for ever at its first NetCDF call.
    from xbsm._netcdf import LOCK, forks_wait_for_the_lock

    read, write = os.pipe()
    children = []

    def fork():
        pid = os.fork()
        if pid == 0:  # the child: is the lock free here?
            os.write(write, b"free" if LOCK.acquire(blocking=False) else b"held")
            os._exit(0)
        children.append(pid)

    with forks_wait_for_the_lock():
        with LOCK:  # another thread inside the library
            forker = threading.Thread(target=fork)
            forker.start()
            forker.join(0.5)
            assert forker.is_alive()  # the fork waits for the lock
        forker.join(60)
    assert not forker.is_alive() and children
    os.close(write)  # a child that died without writing: end of file, not a hang
    assert os.read(read, 4) == b"free"
    os.waitpid(children[0], 0)
    os.close(read)
