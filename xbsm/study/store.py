"""Writing a lazy study result to NetCDF: one writer, resumable, never a wrong file.

:func:`write` takes the output's lock (one run per output, :mod:`._lock`),
fingerprints everything that determines the numbers (the result's layout, the
study and method, the atmosphere database, xbsm's version and code, numpy and
scipy), and keeps finished chunks in ``OUT.nc.parts/`` only while the
fingerprint matches (:mod:`._parts`). It computes the missing chunks in batches
(the graph of a batch is culled once, so set-up grows linearly with the study)
on the local threads, or one task per chunk on a ``dask.distributed`` cluster,
saving each as soon as it is done. Then it streams the chunk files into
``OUT.nc.partial`` one chunk at a time, with signals deferred to the gaps between
writes (:mod:`xbsm.interrupts`), and renames it to ``OUT.nc``: a file with the output's
name is always complete and holds only this run's numbers.
"""

from __future__ import annotations

import asyncio
import contextlib
import functools
import itertools
import os
import shutil
import sys
import uuid
import warnings
from pathlib import Path

import dask.local
import dask.threaded
import numpy as np
import xarray as xr
from dask.highlevelgraph import HighLevelGraph

from .._netcdf import forks_wait_for_the_lock, netcdf_file, write_variables
from ..interrupts import completing, deferred, handling_signals, stop_if_interrupted
from . import _parts
from ._lock import OutputLock
from ._parts import atmosphere_checksum, code_commit, stderr_line
from ._progress import Progress
from .spec import StudyError

__all__ = ["OutputLock", "atmosphere_checksum", "check_output", "dependency_versions",
           "netcdf_ready", "write"]

#: Chunks computed per batch and worker: each batch's graph is culled once.
_BATCH_PER_WORKER = 16
#: How long a new LocalCluster's workers may take to start.
_WORKER_START_SECONDS = 120
#: A LocalCluster's workers keep glibc's own heap trimming: distributed sets
#: MALLOC_TRIM_THRESHOLD_=65536, which also turns off glibc's adaptive mmap threshold,
#: so every large numpy temporary is mmapped, page-faulted and unmapped again: one
#: chunk of recipes/studies/million.toml took 0.64 s instead of 0.36 s with it set
#: (a peak memory that returns to the OS sooner is not worth it: a chunk's temporaries
#: are bounded by ``chunk_scenarios``). A value in the user's environment still wins.
#: The key is left out of the settings rather than set to None: distributed 2023.6 (the
#: floor) passes None on as the string "None".
_TRIM_SETTING = "MALLOC_TRIM_THRESHOLD_"


#: On Linux a LocalCluster's workers are forked from the process that built the study
#: rather than spawned: they start with xbsm imported and the atmosphere database read.
#: Spawned, each worker imported xbsm (1.2-1.5 s) and made a slow first model call (about
#: 1 s more) before its first chunk began 2.7-2.9 s after the cluster was up, and the
#: cluster itself took 1.6-2.0 s to start instead of 0.6-0.7 s (a 3 x 10^5-scenario cut of
#: recipes/studies/million.toml on 2 cores: 16.8-21.1 s spawned, 12.1-16.1 s forked).
#: The forking thread is distributed's event loop; xbsm's other threads wait (the caller
#: in the cluster's start, distributed's idle executors), and a fork waits until no thread
#: of the process holds the NetCDF lock (``_netcdf.forks_wait_for_the_lock``), which a
#: worker reading a database it was not forked with would otherwise find taken for ever.
#: Not on macOS (fork is unsafe with its system libraries) nor Windows.
_FORK = sys.platform == "linux"


def _start_method() -> dict:
    """How a new LocalCluster starts its worker processes (see _FORK)."""
    return {"distributed.worker.multiprocessing-method": "fork"} if _FORK else {}


#: A LocalCluster's workers run without distributed's statistical profiler (a thread
#: that samples the computing thread's stack every 10 ms, for the dashboard's profile
#: page): with it a worker's process used 19 % more CPU than its computing thread, 6 %
#: without (7 chunks of recipes/studies/million.toml, getrusage per thread and process),
#: CPU its sibling worker lacks when there are as many workers as cores.
_WORKER_SETTINGS = {"distributed.worker.profile.enabled": False}


@contextlib.contextmanager
def _forking():
    """Forks that wait for the NetCDF lock, for :data:`_FORK`.

    Python 3.12+'s warning about a fork in a threaded process is silenced meanwhile.
    """
    with forks_wait_for_the_lock(), warnings.catch_warnings():
        warnings.filterwarnings("ignore", r"This process \(pid=\d+\) is multi-threaded, use "
                                r"of fork\(\) may lead to deadlocks", DeprecationWarning)
        yield


def _worker_environ() -> dict:
    """Distributed's pre-spawn worker environment without its heap-trimming setting."""
    environ = dask.config.get("distributed.nanny.pre-spawn-environ", default={})
    return {"distributed.nanny.pre-spawn-environ":
            {name: value for name, value in environ.items() if name != _TRIM_SETTING}}


def netcdf_ready(ds: xr.Dataset) -> xr.Dataset:
    """A copy whose attributes NetCDF can hold (no None; booleans as integers)."""
    ds = ds.copy()
    for var in [*ds.variables.values(), ds]:
        var.attrs = _netcdf_attrs(var.attrs)
    return ds


def _netcdf_attrs(attrs: dict) -> dict:
    return {key: int(value) if isinstance(value, bool) else value
            for key, value in attrs.items() if value is not None}


def dependency_versions() -> str:
    """The versions of xbsm's runtime dependencies, for provenance and ``xbsm info``."""
    import importlib.metadata as md

    names = ("numpy", "scipy", "xarray", "dask", "netCDF4", "matplotlib")
    return ", ".join(f"{name} {md.version(name)}" for name in names)


def check_output(path, overwrite: bool = False, study_file=None) -> Path:
    """``path`` as a Path if a result may be written there, else a StudyError saying why."""
    path = Path(path)
    if path.is_dir():
        raise StudyError(f"{path} is a directory; give a file name such as {path / 'out.nc'}")
    if study_file is not None and path.exists() and path.samefile(study_file):
        raise StudyError(f"the output {path} is the study file itself; give another name "
                         "with -o")
    if path.exists() and not overwrite:
        raise StudyError(f"{path} exists (a finished run); give --overwrite "
                         "(overwrite=True) to compute it again, or another output with -o")
    if not path.parent.is_dir():
        raise StudyError(f"cannot write {path}: the directory {path.parent} does not exist")
    return path


# --- the chunk grid ---------------------------------------------------------------------


class _Grid:
    """The result's chunk grid: every dimension's block sizes, and which block is whose."""

    def __init__(self, result: xr.Dataset):
        self.chunks = dict(result.chunks)
        self.dims = tuple(self.chunks)
        self.offsets = {dim: np.concatenate([[0], np.cumsum(sizes)])
                        for dim, sizes in self.chunks.items()}

    def indices(self):
        """Every chunk index, in order."""
        return itertools.product(*(range(len(sizes)) for sizes in self.chunks.values()))

    @property
    def count(self) -> int:
        """How many chunks."""
        return int(np.prod([len(sizes) for sizes in self.chunks.values()]))

    def block(self, index, var_dims) -> tuple:
        """A variable's block index inside chunk ``index``."""
        return tuple(index[self.dims.index(dim)] for dim in var_dims)

    def owns(self, index, var_dims) -> bool:
        """Whether chunk ``index`` saves the variable's block (index 0 along its other dims)."""
        return all(i == 0 for dim, i in zip(self.dims, index, strict=True)
                   if dim not in var_dims)

    def region(self, index, var_dims) -> tuple:
        """The variable's slices for the block of chunk ``index``."""
        out = []
        for dim in var_dims:
            i = index[self.dims.index(dim)]
            out.append(slice(int(self.offsets[dim][i]), int(self.offsets[dim][i + 1])))
        return tuple(out)


# --- computing the missing chunks -------------------------------------------------------


def _save_chunk(file: Path, names: tuple, print_: dict, on_saved, blocks: list) -> None:
    """Save one computed chunk; stop the run here if a signal arrived meanwhile."""
    _parts.save(file, dict(zip(names, blocks, strict=True)), print_)
    if on_saved is not None:
        on_saved()
    stop_if_interrupted()


def _batch_graph(variables, grid, graph, batch, parts, print_, on_saved):
    """The tasks that compute and save the chunks of ``batch``: a graph culled once.

    ``variables`` is ``(name, dask key prefix, dims)`` of every data variable.
    """
    owned = {index: [(name, (key, *grid.block(index, dims))) for name, key, dims in variables
                     if grid.owns(index, dims)] for index in batch}
    dsk = dict(graph.cull({key for pairs in owned.values() for _, key in pairs}))
    saves = []
    for index, pairs in owned.items():
        task = functools.partial(_save_chunk, _parts.block_file(parts, index),
                                 tuple(name for name, _ in pairs), print_, on_saved)
        dsk[("xbsm-save-chunk", *index)] = (task, [key for _, key in pairs])
        saves.append(("xbsm-save-chunk", *index))
    return dsk, saves


def _batches(items: list, size: int):
    for start in range(0, len(items), size):
        yield items[start:start + size]


def _compute_missing(result, grid, parts, print_, missing, scheduler, workers, progress):
    """Compute and save the chunks in ``missing``.

    On the local threads batch after batch; on ``dask.distributed`` chunk by chunk as
    workers free up (:func:`_compute_distributed`).
    """
    if not missing:
        return
    graph = HighLevelGraph.merge(*(var.data.__dask_graph__() for var in result.data_vars.values()))
    variables = [(name, var.data.name, var.dims) for name, var in result.data_vars.items()]
    if scheduler in ("threads", "synchronous"):
        run_graph = (functools.partial(dask.threaded.get, num_workers=workers)
                     if scheduler == "threads" else dask.local.get_sync)
        for batch in _batches(missing, max(1, workers) * _BATCH_PER_WORKER):
            dsk, keys = _batch_graph(variables, grid, graph, batch, parts, print_, progress.add)
            run_graph(dsk, keys)
            stop_if_interrupted()
        return
    with _distributed_client(scheduler, workers) as client:
        _compute_distributed(client, _chunk_tasks(variables, grid, graph, missing, parts,
                                                  print_, workers), progress)


def _run_chunk(dsk: dict, key) -> None:
    """Compute one chunk's graph up to its save task, in the worker, with no scheduler."""
    dask.local.get_sync(dsk, key)


def _chunk_tasks(variables, grid, graph, missing, parts, print_, workers):
    """``(chunk index, task)`` per missing chunk: one task computes and saves the chunk.

    The graph is culled once per batch, as on the threads, then cut into each chunk's own
    part (about 40 tasks, 15 kB pickled, in recipes/studies/million.toml).
    """
    from dask.optimization import cull

    for batch in _batches(missing, max(1, workers) * _BATCH_PER_WORKER):
        dsk, saves = _batch_graph(variables, grid, graph, batch, parts, print_, None)
        for key in saves:
            yield key[1:], functools.partial(_run_chunk, cull(dsk, [key])[0], key)


def _compute_distributed(client, tasks, progress) -> None:
    """Run the chunk tasks on the cluster, twice as many in flight as it has threads.

    A worker computes and saves a chunk in one task and goes on to the next at once: no
    barrier between batches, no transfer between workers, one chunk in a worker's memory
    at a time. Each finished chunk is counted as it ends; a signal stops the run at the
    next one and the chunks still running are cancelled (those saved are kept).
    """
    from dask.distributed import as_completed

    run = uuid.uuid4().hex[:12]  # this run's keys, on a cluster others may share
    slots = 2 * max(1, sum(client.nthreads().values()))
    tasks = iter(tasks)

    def submit(count):
        return [client.submit(task, key=(f"xbsm-chunk-{run}", *index), pure=False)
                for index, task in itertools.islice(tasks, count)]

    running = as_completed(submit(slots))
    try:
        for future in running:
            future.result()  # a chunk's error ends the run here
            progress.add()
            stop_if_interrupted()
            running.update(submit(1))
    finally:
        client.cancel(list(running.futures))


@contextlib.contextmanager
def _distributed_client(scheduler: str, workers: int):
    """A dask.distributed client: of a new LocalCluster, or of the cluster at an address.

    A new LocalCluster is stopped with the client, in this thread: stopped from another
    one (to overlap with the file's assembly), distributed 2023.6 (xbsm's floor) left the
    asyncio event loop tornado made for this thread open, with its two sockets.
    """
    try:
        from dask.distributed import Client, LocalCluster
    except ImportError:
        raise StudyError("scheduler " + repr(scheduler) + " needs dask.distributed: "
                         "pip install \"xbsm[distributed]\"") from None
    with contextlib.ExitStack() as stack:
        if scheduler == "local-cluster":
            # dashboard on a free port: a busy 8787 makes distributed retry and leak a socket;
            # glibc's default heap trimming (see _TRIM_SETTING); workers forked (_FORK), no
            # profiler (_WORKER_SETTINGS)
            with dask.config.set({**_worker_environ(), **_start_method(), **_WORKER_SETTINGS}), \
                    _forking():
                cluster = stack.enter_context(LocalCluster(
                    n_workers=workers, threads_per_worker=1, dashboard_address=":0"))
            client = stack.enter_context(Client(cluster))
            try:  # a cluster whose workers never came up would wait for them forever
                client.wait_for_workers(workers, timeout=_WORKER_START_SECONDS)
            except (TimeoutError, asyncio.TimeoutError):  # the same class from Python 3.11
                raise StudyError(f"the LocalCluster's {workers} worker(s) did not start within "
                                 f"{_WORKER_START_SECONDS} s (an overloaded machine?); "
                                 "finished chunks are kept, run the same command again, or "
                                 "use --scheduler threads") from None
            yield client
        else:
            yield stack.enter_context(Client(scheduler))


# --- streaming the chunks into one NetCDF file ------------------------------------------


def _skeleton(result: xr.Dataset, attrs: dict) -> xr.Dataset:
    """The file without its data variables: coordinates (no fill values) and attributes."""
    coords = {name: coord.variable.compute() for name, coord in result.coords.items()}
    return netcdf_ready(xr.Dataset(coords=coords, attrs={**result.attrs, **attrs}))


def _define(nc, result: xr.Dataset) -> None:
    """Create every data variable in the open file, with its attributes and encoding."""
    for dim in {dim for var in result.data_vars.values() for dim in var.dims}:
        if dim not in nc.dimensions:
            nc.createDimension(dim, result.sizes[dim])
    for name, var in result.data_vars.items():
        dtype = np.dtype("i1") if var.dtype == bool else var.dtype
        fill = np.nan if dtype.kind == "f" else False
        encoding = {key: var.encoding[key] for key in ("zlib", "complevel", "shuffle")
                    if key in var.encoding}
        variable = nc.createVariable(name, dtype, var.dims, fill_value=fill,
                                     chunksizes=_storage_chunks(var, dtype), **encoding)
        variable.set_auto_maskandscale(False)
        attrs = _netcdf_attrs(var.attrs)
        if var.dtype == bool:
            attrs["dtype"] = "bool"  # how xarray stores booleans, so they read back as such
        others = [c for c, coord in result.coords.items()
                  if c not in result.dims and set(coord.dims) <= set(var.dims)]
        if others:
            attrs["coordinates"] = " ".join(others)
        variable.setncatts(attrs)


def _storage_chunks(var: xr.DataArray, dtype: np.dtype) -> tuple | None:
    """HDF5 chunks of the study's chunk blocks, so that each block is one contiguous write.

    A block cut along an inner dimension is otherwise many small strided pieces of a
    contiguous variable: 50 blocks of (500, 10, 2, 2, 3) into ten (500, 10, 100, 2, 3)
    variables took 2.37 s, 0.40 s in aligned chunks. None (netCDF's own choice) for
    a scalar or a block beyond HDF5's 4 GB chunk limit.
    """
    if not var.ndim:
        return None
    sizes = tuple(max(lengths) for lengths in var.chunks)
    return sizes if np.prod(sizes, dtype=float) * dtype.itemsize < 2**31 else None


def _stream(result, skeleton, grid, parts, print_, partial: Path, progress) -> None:
    """Create ``partial`` from the skeleton and write every chunk file's blocks into it."""
    dims = {name: var.dims for name, var in result.data_vars.items()}
    with netcdf_file(partial, "w") as nc:
        write_variables(nc, skeleton)
        _define(nc, result)
        for index in grid.indices():
            stop_if_interrupted()
            file = _parts.block_file(parts, index)
            arrays = _parts.load(file, print_)
            if arrays is None:
                file.unlink(missing_ok=True)
                raise StudyError(f"chunk file {file} was damaged after it was saved; it has "
                                 "been removed: run the same command again to compute it")
            for name, block in arrays.items():
                nc[name][grid.region(index, dims[name])] = block
            progress.add()


def _assemble(result, grid, parts, print_, path: Path, progress: bool) -> None:
    """Stream the chunk files into ``path`` through a temporary file, then rename."""
    partial = path.with_name(path.name + ".partial")
    attrs = {"xbsm_atmosphere_sha256": atmosphere_checksum(),
             "xbsm_code_sha256": _parts.code_checksum(), "xbsm_commit": code_commit() or None,
             "xbsm_dependencies": dependency_versions(),
             "date_created": np.datetime_as_string(np.datetime64("now", "s")) + "Z"}
    skeleton = _skeleton(result, attrs)  # may compute coordinates: interruptible, no file yet
    try:
        with deferred():  # a signal stops the writing between two chunks, never inside one
            _stream(result, skeleton, grid, parts, print_, partial, Progress(
                "writing the NetCDF file", grid.count, enabled=progress))
            with open(partial, "rb+") as handle:
                os.fsync(handle.fileno())
        with completing():  # from here a signal no longer makes the run "interrupted"
            os.replace(partial, path)
    except (OSError, RuntimeError) as err:
        partial.unlink(missing_ok=True)
        raise WriteFailed(_write_error(partial, err)) from None
    except BaseException:
        partial.unlink(missing_ok=True)
        raise


class WriteFailed(StudyError):
    """The result file could not be written (a full disk, a file-size limit, an I/O error).

    After the HDF5 library has refused a write it may be unable to shut down: HDF5 1.10.5,
    1.12.2 and 1.14.2 (in netCDF4's wheels 1.6.1 to 1.7.1) crash the interpreter at exit (SIGSEGV)
    while cleaning up the file they could not close. ``xbsm run`` therefore ends the
    process at once after saying so; a Python caller gets this exception.
    """


def _write_error(file: Path, err: Exception) -> str:
    """One line for a failed write: the file, the error and the disk's free space."""
    free = shutil.disk_usage(file.parent).free
    text = getattr(err, "strerror", None) or str(err)
    full = " (the disk is full)" if free < 64 << 20 or "No space" in text else ""
    return (f"cannot write {file}: {text}{full}; {free / 1e6:.0f} MB free on its disk; "
            "finished chunks are kept, run the same command again once there is room")


# --- the public writer ------------------------------------------------------------------


def write(result: xr.Dataset, path, *, overwrite: bool = False, scheduler: str = "threads",
          workers: int = 2, progress: bool = False) -> Path:
    """Compute a lazy study result into a NetCDF file, safely and resumably.

    Parameters
    ----------
    result : xr.Dataset
        From :func:`xbsm.study.run` (any dask-backed Dataset works).
    path : str or Path
        The NetCDF file to write.
    overwrite : bool
        Replace an existing ``path``; without it an existing file is an error.
    scheduler : str
        ``"threads"``, ``"synchronous"``, ``"local-cluster"`` (a
        ``dask.distributed`` LocalCluster) or a scheduler address.
    workers : int
        Threads, or LocalCluster workers.
    progress : bool
        Print progress to standard error (a bar in a terminal, a line per 10 %
        otherwise).

    Returns
    -------
    Path
        ``path``, complete.

    Raises
    ------
    StudyError
        ``path`` exists (without ``overwrite``), another run is writing it, its
        directory is not writable, or the disk is full.
    KeyboardInterrupt
        (:class:`xbsm.interrupts.Interrupted`) on SIGINT or SIGTERM: finished
        chunks are kept, and the same call resumes.
    """
    path = check_output(path, overwrite)
    if not result.chunks:  # an eager Dataset: one chunk
        result = result.chunk()
    parts = path.with_name(path.name + ".parts")
    say = stderr_line
    with handling_signals(), OutputLock(path, result.attrs.get("title", "")):
        check_output(path, overwrite)  # again: another run may have finished it meanwhile
        grid, print_ = _Grid(result), _parts.fingerprint(result)
        try:
            _parts.prepare(parts, print_, say)
        except OSError as err:
            raise StudyError(f"cannot write to {path.parent}: {err.strerror or err}") from None
        done = _parts.verified(parts, print_, say)
        missing = [index for index in grid.indices() if index not in done]
        if progress:
            say(f"{len(done)} of {grid.count} chunks already done; computing {len(missing)} "
                f"with {workers} worker(s) ({scheduler})")
        _compute_missing(result, grid, parts, print_, missing, scheduler, workers,
                         Progress("chunks computed", len(missing), enabled=progress))
        _assemble(result, grid, parts, print_, path, progress)
        shutil.rmtree(parts, ignore_errors=True)
    return path
