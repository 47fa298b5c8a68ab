"""netCDF4 files that threads can share: every open, read and write under one lock.

netCDF-C and HDF5, as the netCDF4 wheels build them, are not thread-safe, and
netCDF4-python releases the GIL around their calls: two threads in the library at once
crash the process. Before this lock, four threads making their first xbsm call at the
same time (each reading the atmosphere database once) ended in a segmentation fault or
a bus error nine times out of nine (``tests/atmosphere/test_threads.py``).

The lock is xarray's own HDF5 lock, the one its netCDF4 backend takes around every
call, so xbsm's direct calls also wait for a thread reading a file through xarray. It is
not re-entrant: inside :func:`netcdf_file` nothing may read a file through xarray (a
lazily loaded array's ``.values``); callers bring their arrays into memory first.
"""

from __future__ import annotations

import contextlib
import threading

import netCDF4

try:
    from xarray.backends.locks import HDF5_LOCK as LOCK
except ImportError:  # a future xarray that moves it: xbsm's calls still exclude each other
    LOCK = threading.Lock()


@contextlib.contextmanager
def netcdf_file(path, mode: str = "r", **kwargs):
    """``netCDF4.Dataset(path, mode, **kwargs)``, open only while the lock is held."""
    with LOCK, netCDF4.Dataset(path, mode, **kwargs) as nc:
        yield nc
