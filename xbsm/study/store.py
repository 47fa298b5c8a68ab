"""Writing a lazy study result to NetCDF safely: chunk by chunk, resumable, atomic.

:func:`write` computes the result one chunk at a time (in parallel, on the
local threads or a ``dask.distributed`` cluster) and saves each finished
chunk at once, as a small file in ``OUT.nc.parts/`` (written under a
temporary name and renamed, so a chunk file is either whole or absent). When
every chunk is there it streams them into ``OUT.nc.partial`` and renames that
to ``OUT.nc``: a file with the output's name is always complete. An
interrupted run keeps its finished chunks; running it again computes only the
missing ones (the parts directory records which study it belongs to and is
discarded if the study changed).
"""

from __future__ import annotations

import contextlib
import functools
import hashlib
import itertools
import json
import os
import shutil
import sys
import threading
from pathlib import Path

import dask
import dask.array as dsa
import dask.diagnostics
import numpy as np
import xarray as xr

from ..atmosphere import database_path
from .spec import StudyError


def netcdf_ready(ds: xr.Dataset) -> xr.Dataset:
    """A copy whose attributes NetCDF can hold (no None; booleans as integers)."""
    ds = ds.copy()
    for var in [*ds.variables.values(), ds]:
        for key, value in list(var.attrs.items()):
            if value is None:
                del var.attrs[key]
            elif isinstance(value, bool):
                var.attrs[key] = int(value)
    return ds


@functools.lru_cache(maxsize=4)
def atmosphere_checksum(path=None) -> str:
    """SHA-256 of the atmosphere database file, for the provenance of a result."""
    digest = hashlib.sha256()
    with open(database_path(path), "rb") as handle:
        for block in iter(lambda: handle.read(1 << 22), b""):
            digest.update(block)
    return digest.hexdigest()


def dependency_versions() -> str:
    """The versions of xbsm's runtime dependencies, for provenance and ``xbsm info``."""
    import importlib.metadata as md

    names = ("numpy", "scipy", "xarray", "dask", "netCDF4", "matplotlib")
    return ", ".join(f"{name} {md.version(name)}" for name in names)


def _block_indices(chunks: dict[str, tuple]):
    """The index of every chunk of the grid (one entry per dimension)."""
    return itertools.product(*(range(len(sizes)) for sizes in chunks.values()))


def _fingerprint(result: xr.Dataset) -> str:
    """What a parts directory must match to be reused: variables, shapes, chunks, attrs."""
    layout = {name: [var.dims, var.shape, var.chunks] for name, var in result.data_vars.items()}
    text = json.dumps([layout, {k: str(v) for k, v in result.attrs.items()}], default=str)
    return hashlib.sha256(text.encode()).hexdigest()


INTERRUPTED = threading.Event()
"""Set by the ``xbsm`` command's Ctrl-C handler (see :func:`stop_if_interrupted`)."""


def stop_if_interrupted() -> None:
    """Raise KeyboardInterrupt if Ctrl-C was pressed, even if the first one was lost.

    Python delivers Ctrl-C as an exception in the main thread, which a library
    may swallow (a bare ``except:``), and never in the threads computing chunks.
    The command's handler also sets :data:`INTERRUPTED`; checking it between
    stages and after every saved chunk makes Ctrl-C stop the run regardless.
    """
    if INTERRUPTED.is_set():
        raise KeyboardInterrupt


def _save_block(arrays: dict, file: Path) -> None:
    """Save one computed chunk (every variable's block) atomically, then stop if interrupted."""
    partial = file.with_name(file.name + ".tmp")
    with open(partial, "wb") as handle:
        np.savez(handle, **arrays)
    os.replace(partial, file)
    stop_if_interrupted()


def _block_file(parts: Path, index) -> Path:
    return parts / ("block-" + "-".join(map(str, index)) + ".npz")


def _prepare_parts(result: xr.Dataset, parts: Path) -> None:
    """Create the parts directory, or reuse it only if it belongs to this study."""
    manifest = parts / "study.json"
    fingerprint = _fingerprint(result)
    if parts.exists():
        try:
            same = json.loads(manifest.read_text())["fingerprint"] == fingerprint
        except (OSError, ValueError, KeyError):
            same = False
        if same:
            return
        shutil.rmtree(parts)
    parts.mkdir()
    manifest.write_text(json.dumps({"fingerprint": fingerprint}))


def _load_block(parts: Path, name: str, var_dims: tuple, grid: tuple, block_id=None):
    """One variable's values in one chunk, read back from its chunk file."""
    index = [0] * len(grid)
    for dim, i in zip(var_dims, block_id, strict=True):
        index[grid.index(dim)] = i
    with np.load(_block_file(parts, index)) as saved:
        return saved[name]


def _assembled(result: xr.Dataset, parts: Path) -> xr.Dataset:
    """The result with every variable read lazily from the chunk files."""
    grid = tuple(result.chunks)
    variables = {}
    for name, var in result.data_vars.items():
        data = dsa.map_blocks(_load_block, parts, name, var.dims, grid, dtype=var.dtype,
                              chunks=var.chunks, meta=np.array((), dtype=var.dtype))
        variables[name] = xr.Variable(var.dims, data, var.attrs, var.encoding)
    coords = {name: coord.variable.compute() for name, coord in result.coords.items()}
    return xr.Dataset(variables, coords=coords, attrs=result.attrs)


def _compute_missing(result: xr.Dataset, parts: Path, scheduler: str, workers: int,
                     progress: bool) -> None:
    """Compute and save every chunk that has no file yet."""
    chunks = dict(result.chunks)
    grid = tuple(chunks)
    # every variable's blocks as delayed objects, in one pass over the graph (selecting
    # the result chunk by chunk instead rebuilds and culls the whole graph for each)
    blocks = {name: var.data.to_delayed() for name, var in result.data_vars.items()}
    tasks = []
    for index in _block_indices(chunks):
        if _block_file(parts, index).exists():
            continue
        arrays = {name: blocks[name][tuple(index[grid.index(dim)] for dim in var.dims)]
                  for name, var in result.data_vars.items()}
        tasks.append(dask.delayed(_save_block)(arrays, _block_file(parts, index)))
    total = int(np.prod([len(sizes) for sizes in chunks.values()]))
    if progress:
        print(f"{total - len(tasks)} of {total} chunks already done; computing {len(tasks)} "
              f"with {workers} worker(s) ({scheduler})", file=sys.stderr)
    if not tasks:
        return
    if scheduler in ("threads", "synchronous"):
        bar = dask.diagnostics.ProgressBar(out=sys.stderr) if progress else contextlib.nullcontext()
        with bar:
            dask.compute(*tasks, scheduler=scheduler, num_workers=workers)
        return
    _compute_distributed(tasks, scheduler, workers, progress)


def _compute_distributed(tasks, scheduler: str, workers: int, progress: bool) -> None:
    """Run the chunk tasks on a dask.distributed cluster (a LocalCluster or an address)."""
    try:
        from dask.distributed import Client, LocalCluster
        from dask.distributed import progress as show_progress
    except ImportError:
        raise StudyError("scheduler " + repr(scheduler) + " needs dask.distributed: "
                         "pip install \"xbsm[distributed]\"") from None
    with contextlib.ExitStack() as stack:
        if scheduler == "local-cluster":
            # dashboard on a free port: a busy 8787 makes distributed retry and leak a socket
            cluster = stack.enter_context(LocalCluster(n_workers=workers, threads_per_worker=1,
                                                       dashboard_address=":0"))
            client = stack.enter_context(Client(cluster))
        else:
            client = stack.enter_context(Client(scheduler))
        futures = client.compute(tasks)
        if progress:
            show_progress(futures)
        client.gather(futures)


def _finalize(result: xr.Dataset, parts: Path, path: Path) -> None:
    """Stream the chunk files into ``path`` through a temporary file, then rename."""
    partial = path.with_name(path.name + ".partial")
    final = _assembled(result, parts).assign_attrs(
        xbsm_atmosphere_sha256=atmosphere_checksum(), xbsm_dependencies=dependency_versions(),
        date_created=np.datetime_as_string(np.datetime64("now", "s")) + "Z")
    try:
        with dask.config.set(scheduler="synchronous"):  # one thread: nothing waits on a lock
            netcdf_ready(final).to_netcdf(partial)
        os.replace(partial, path)
    except BaseException:
        partial.unlink(missing_ok=True)
        raise
    shutil.rmtree(parts, ignore_errors=True)


def check_output(path, overwrite: bool = False) -> Path:
    """``path`` as a Path if a result may be written there, else a StudyError saying why."""
    path = Path(path)
    if path.is_dir():
        raise StudyError(f"{path} is a directory; give a file name such as {path / 'out.nc'}")
    if path.exists() and not overwrite:
        raise StudyError(f"{path} exists; pass overwrite=True (--overwrite) to replace it")
    if not path.parent.is_dir():
        raise StudyError(f"cannot write {path}: the directory {path.parent} does not exist")
    return path


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
        Print progress to standard error.

    Returns
    -------
    Path
        ``path``, complete.

    Raises
    ------
    StudyError
        ``path`` exists (without ``overwrite``) or its directory is not writable.
    """
    path = check_output(path, overwrite)
    if not result.chunks:  # an eager Dataset: one chunk
        result = result.chunk()
    parts = path.with_name(path.name + ".parts")
    try:
        _prepare_parts(result, parts)
    except OSError as err:
        raise StudyError(f"cannot write to {path.parent}: {err.strerror or err}") from None
    _compute_missing(result, parts, scheduler, workers, progress)
    stop_if_interrupted()
    _finalize(result, parts, path)
    return path
