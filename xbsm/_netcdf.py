"""netCDF4 files that threads can share: every open, read and write under one lock.

netCDF-C and HDF5, as the netCDF4 wheels build them, are not thread-safe, and
netCDF4-python releases the GIL around their calls: two threads in the library at once
crash the process. Before this lock, four threads making their first xbsm call at the
same time (each reading the atmosphere database once) ended in a segmentation fault or
a bus error nine times out of nine (``tests/atmosphere/test_threads.py``).

The lock is xarray's own for netCDF4 files (its netCDF-C lock and its HDF5 lock, in
xarray's order), so xbsm's direct calls also wait for a thread reading a file through
xarray.

xarray's ``open_dataset`` reads a file's metadata outside its lock (pydata/xarray#4100,
#9779): four threads opening the database at once crashed the interpreter. So xbsm opens
files through xarray inside :data:`LOCK` and hands xarray the same lock
(``open_dataset(..., lock=LOCK)``, also what the lazy reads take): the thread that holds
:data:`LOCK` may take it again, which xarray's own locks do not allow. Inside
:func:`netcdf_file` a lazily loaded array of a file xarray opened with its default lock
would still wait for ever: callers bring such arrays into memory first.
"""

from __future__ import annotations

import contextlib
import os
import threading

import netCDF4

try:  # netCDF-C's lock and HDF5's, taken in xarray's one global order
    from xarray.backends.netCDF4_ import NETCDF4_PYTHON_LOCK as _LIBRARY_LOCK
except ImportError:  # a future xarray that moves it: xbsm's calls still exclude each other
    _LIBRARY_LOCK = threading.Lock()


class _NestedLock:
    """xarray's netCDF4 lock, which the thread holding it through this object may retake."""

    def __init__(self):
        self._held = threading.local()  # this thread's depth of acquires

    def acquire(self, blocking: bool = True) -> bool:
        depth = getattr(self._held, "depth", 0)
        if not depth and not _LIBRARY_LOCK.acquire(blocking):
            return False
        self._held.depth = depth + 1
        return True

    def release(self) -> None:
        self._held.depth -= 1
        if not self._held.depth:
            _LIBRARY_LOCK.release()

    def locked(self) -> bool:
        return _LIBRARY_LOCK.locked()

    def __enter__(self) -> bool:
        return self.acquire()

    def __exit__(self, *exc) -> None:
        self.release()

    def __reduce__(self):
        return _lock, ()  # in another process (a dask worker), that process's own lock


LOCK = _NestedLock()
"""The lock around every netCDF4 call of xbsm (re-entrant in the thread that holds it)."""


def _lock() -> _NestedLock:
    return LOCK


@contextlib.contextmanager
def netcdf_file(path, mode: str = "r", **kwargs):
    """``netCDF4.Dataset(path, mode, **kwargs)``, open only while the lock is held."""
    with LOCK, netCDF4.Dataset(path, mode, **kwargs) as nc:
        yield nc


def write_variables(nc, ds) -> None:
    """Write an eager Dataset's variables, dimensions and attributes into the open file ``nc``.

    For :func:`netcdf_file` (``mode="w"``), so that the whole write is under :data:`LOCK`:
    xarray's ``to_netcdf`` takes its lock around data writes only, not while it creates
    dimensions and variables (and it is the lock that :data:`LOCK` holds, so it cannot be
    called inside it). Numbers are written as they are (no fill value, no scaling),
    strings as netCDF strings; non-dimension coordinates are named in the global
    ``coordinates`` attribute, where xarray reads them back as coordinates. It is also
    cheaper: ``to_netcdf`` asks which dask scheduler runs, which imports
    ``dask.distributed`` (0.45 s of every study's serial assembly).
    """
    for dim, size in ds.sizes.items():
        nc.createDimension(dim, size)
    for name, var in ds.variables.items():
        values = var.values
        if values.dtype.kind in "UO":
            variable = nc.createVariable(name, str, var.dims)
            variable[...] = values.astype(object)
        else:
            variable = nc.createVariable(name, values.dtype, var.dims, fill_value=False)
            variable.set_auto_maskandscale(False)
            variable[...] = values
        variable.setncatts(var.attrs)
    others = sorted(name for name in ds.coords if name not in ds.dims)
    nc.setncatts({**ds.attrs, **({"coordinates": " ".join(others)} if others else {})})


def open_dataset(path):
    """``xarray.open_dataset`` of a netCDF4 file, through the process's one handle of it.

    Read only, no dask; the handle is opened and closed under :data:`LOCK`.

    HDF5 crashes (a segmentation fault in ``H5F_addr_decode`` under ``H5T__conv_vlen``)
    when a file with string variables, as the atmosphere database has, is open three
    times in one process, the oldest two handles are closed and the file is opened
    again: no thread needed (HDFGroup/hdf5#5359, Unidata/netcdf4-python#1444; HDF5
    1.12.2 and 2.2.0 alike). xarray gives every ``open_dataset`` a handle of its own in
    its file cache; a dataset that is not closed keeps it open until the cache evicts
    it, oldest first, which is that pattern: four threads each opening their own copy
    of the database ten times with ``open_atmosphere`` crashed 10 of 10 runs with
    ``file_cache_maxsize=4`` (standing for a process with more than 128 files open),
    0 of 10 with this. Here every open of a file shares one cache key (path and stamp,
    not a new id), so the process holds one handle of the file however many datasets
    read it (``check_supported`` included), plus at most one :func:`netcdf_file` of the
    thread holding the lock: two at once, which crashed in none of the orders of opens
    and closes tried. The file manager also takes :data:`LOCK`, so closing the
    handle when the last dataset is garbage collected happens under it too: xarray
    2023.12 gave each manager a lock of its own, and 38 of 82 closes in that stress ran
    outside :data:`LOCK` (0 with this).
    """
    import xarray as xr
    from xarray.backends import CachingFileManager, NetCDF4DataStore

    path = os.fspath(path)
    stat = os.stat(path)  # a rewritten file gets a handle of its own
    manager = CachingFileManager(netCDF4.Dataset, path, mode="r", lock=LOCK,
                                 manager_id=("xbsm", stat.st_size, stat.st_mtime_ns))
    with LOCK:  # xarray reads the metadata outside its own lock (see above)
        return xr.open_dataset(NetCDF4DataStore(manager, mode="r", lock=LOCK), chunks=None)


# --- forks that wait for the lock ---------------------------------------------------------
#
# A LocalCluster's workers are forked from the process that built a study
# (``xbsm.study.store._FORK``). A fork copies the lock as it is: had another thread of the
# parent (a notebook's background read, say) held it at that moment, the worker would start
# with the lock taken by a thread it does not have, wait for ever at its first NetCDF call,
# and inherit netCDF-C and HDF5 in the middle of that thread's call. While
# :func:`forks_wait_for_the_lock` is entered anywhere in the process, every fork first
# takes the lock (so no thread is inside the library) and both sides release it after.

_waiting = 0  # how many callers have entered forks_wait_for_the_lock
_waiting_count = threading.Lock()
_taken_for_fork = threading.local()  # per forking thread: did its before-hook take the lock?


def _before_fork() -> None:
    # a thread that holds the lock itself forks with it held: it exists in the child too
    holds = getattr(LOCK._held, "depth", 0)
    _taken_for_fork.lock = bool(_waiting) and not holds and _LIBRARY_LOCK.acquire()


def _after_fork() -> None:  # in the parent and in the child
    if getattr(_taken_for_fork, "lock", False):
        _taken_for_fork.lock = False
        _LIBRARY_LOCK.release()


if hasattr(os, "register_at_fork"):
    os.register_at_fork(before=_before_fork, after_in_parent=_after_fork,
                        after_in_child=_after_fork)


@contextlib.contextmanager
def forks_wait_for_the_lock():
    """While inside, a fork of this process (from any thread) waits for :data:`LOCK`.

    It waits until no thread holds the lock, so the child starts with the lock free and
    the library idle.
    """
    global _waiting
    with _waiting_count:
        _waiting += 1
    try:
        yield
    finally:
        with _waiting_count:
            _waiting -= 1
