"""The finished chunks of a run in ``OUT.nc.parts/``: saved whole, verified, never mixed.

A chunk file ``block-I-J-….npz`` holds, for one chunk of the scenario grid, the
blocks of every variable that chunk owns (a variable without a grid dimension is
saved once, by the chunks at index 0 along it), plus a SHA-256 digest of the
fingerprint of the run, of the file's own name (a chunk copied under another
chunk's name does not verify) and of every array. It is written under a temporary name,
synced and renamed, so it is whole or absent; one that does not verify is
recomputed, never trusted. ``study.json`` holds the fingerprint (every input
that determines the numbers, see :func:`fingerprint`): parts made by a run with
another fingerprint are set aside with one line saying what differs.
"""

from __future__ import annotations

import functools
import hashlib
import json
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import scipy
import xarray as xr

from .._version import __version__
from ..atmosphere import database_path

MANIFEST = "study.json"
_DIGEST = "__digest__"

#: What each fingerprint entry covers, in the words of the set-aside message.
_MEANING = {"layout": "the result's variables, shapes or coordinates",
            "study": "the study or its method", "atmosphere": "the atmosphere database",
            "xbsm": "the xbsm version", "code": "xbsm's code", "numpy": "the numpy version",
            "scipy": "the scipy version"}


def atmosphere_checksum(path=None) -> str:
    """SHA-256 of the atmosphere database file (default: the one in use), for provenance."""
    file = database_path(path)
    stat = file.stat()
    return _file_digest(file, stat.st_size, stat.st_mtime_ns)


@functools.lru_cache(maxsize=4)
def _file_digest(path: Path, size: int, mtime_ns: int) -> str:
    """SHA-256 of ``path`` (cached per size and modification time: a rewrite is re-read)."""
    digest = hashlib.sha256()
    with open(path, "rb") as handle:
        for block in iter(lambda: handle.read(1 << 22), b""):
            digest.update(block)
    return digest.hexdigest()


@functools.cache
def code_checksum() -> str:
    """SHA-256 of xbsm's own source files: any change to the code changes it."""
    package = Path(__file__).resolve().parent.parent
    digest = hashlib.sha256()
    for file in sorted(package.rglob("*.py")):
        digest.update(str(file.relative_to(package)).encode() + b"\0" + file.read_bytes())
    return digest.hexdigest()


@functools.cache
def code_commit() -> str:
    """The git commit xbsm runs from when installed from a checkout, else ''."""
    top = Path(__file__).resolve().parent.parent.parent
    if not (top / ".git").exists():
        return ""
    try:
        done = subprocess.run(["git", "-C", str(top), "rev-parse", "HEAD"], capture_output=True,
                              text=True, timeout=10, check=True)
    except (OSError, subprocess.SubprocessError):
        return ""
    return done.stdout.strip()


def _layout(result: xr.Dataset) -> str:
    """Digest of the variables' dims, shapes, chunks and dtypes and of every coordinate."""
    digest = hashlib.sha256()
    for name, var in sorted(result.data_vars.items()):
        digest.update(json.dumps([name, var.dims, var.shape, var.chunks, str(var.dtype)],
                                 default=str).encode())
    for name, coord in sorted(result.coords.items()):
        values = np.asarray(coord.values)
        digest.update(json.dumps([name, coord.dims, str(values.dtype)]).encode())
        digest.update(values.astype(str).tobytes() if values.dtype == object else
                      np.ascontiguousarray(values).tobytes())
    return digest.hexdigest()


def fingerprint(result: xr.Dataset) -> dict[str, str]:
    """Everything that determines a result's numbers, entry by entry."""
    attrs = {key: str(value) for key, value in result.attrs.items() if key != "date_created"}
    return {"layout": _layout(result),
            "study": hashlib.sha256(json.dumps(attrs, sort_keys=True).encode()).hexdigest(),
            "atmosphere": atmosphere_checksum(), "xbsm": __version__,
            "code": code_checksum(), "numpy": np.__version__, "scipy": scipy.__version__}


def _digest_of(print_: dict) -> str:
    return hashlib.sha256(json.dumps(print_, sort_keys=True).encode()).hexdigest()


def prepare(parts: Path, print_: dict, say=print) -> None:
    """Make ``parts`` ready for this run: reuse it only if its fingerprint is this run's.

    Parts of another run are renamed ``PARTS.set-aside-TIME`` (never deleted: they
    may be a long run's work) with one line through ``say`` naming what differs.
    """
    manifest = parts / MANIFEST
    if parts.exists():
        try:
            theirs = json.loads(manifest.read_text())["fingerprint"]
        except (OSError, ValueError, KeyError, TypeError):
            theirs = None
        if theirs == print_:
            return
        aside = parts.with_name(f"{parts.name}.set-aside-{time.strftime('%Y%m%dT%H%M%S')}"
                                f"-{os.getpid()}")
        os.replace(parts, aside)
        if isinstance(theirs, dict):
            differ = [_MEANING.get(k, k) for k in print_ if theirs.get(k) != print_[k]]
            why = "they were computed with another " + ", ".join(
                d.removeprefix("the ") for d in differ) if differ else "their fingerprint differs"
        else:
            why = f"their {MANIFEST} is missing or damaged"
        say(f"set aside the finished chunks in {parts} ({why}): now {aside.name}; nothing of "
            "them is reused; delete it when it is no longer needed")
    parts.mkdir()
    temporary = manifest.with_name(MANIFEST + ".tmp")
    temporary.write_text(json.dumps({"fingerprint": print_}, indent=1))
    os.replace(temporary, manifest)


def block_file(parts: Path, index) -> Path:
    """The chunk file of one chunk of the grid."""
    return parts / ("block-" + "-".join(map(str, index)) + ".npz")


def _digest_arrays(print_digest: str, arrays: dict) -> str:
    digest = hashlib.sha256(print_digest.encode())
    for name in sorted(arrays):
        value = np.ascontiguousarray(arrays[name])
        digest.update(json.dumps([name, str(value.dtype), value.shape]).encode())
        digest.update(value.tobytes())
    return digest.hexdigest()


def save(file: Path, arrays: dict, print_: dict) -> None:
    """Save one chunk's arrays with their digest: whole (synced, then renamed) or absent."""
    digest = _digest_arrays(_digest_of(print_) + file.name, arrays)
    partial = file.with_name(file.name + ".tmp")
    with open(partial, "wb") as handle:
        np.savez(handle, **arrays, **{_DIGEST: np.array(digest)})
        handle.flush()
        os.fsync(handle.fileno())
    os.replace(partial, file)


def load(file: Path, print_: dict) -> dict | None:
    """One chunk's arrays if its file is whole and belongs to this run, else None."""
    try:
        with open(file, "rb") as handle, np.load(handle, allow_pickle=False) as saved:
            arrays = {name: saved[name] for name in saved.files}
    except Exception:  # noqa: BLE001: any failure to read it (truncated, bit flips) is damage
        return None
    digest = arrays.pop(_DIGEST, None)
    if digest is None or str(digest) != _digest_arrays(_digest_of(print_) + file.name, arrays):
        return None
    return arrays


def verified(parts: Path, print_: dict, say=print) -> set:
    """The chunk indices whose files are whole; damaged ones are deleted, said once.

    Reads the directory once, so a resumed run costs one listing, not one look-up
    per chunk of the grid (a 10^10-scenario study has about 10^6 chunks).
    """
    done, damaged = set(), []
    for entry in sorted(os.scandir(parts), key=lambda e: e.name):
        if not (entry.name.startswith("block-") and entry.name.endswith(".npz")):
            continue
        file = Path(entry.path)
        if load(file, print_) is None:
            file.unlink(missing_ok=True)
            damaged.append(file.name)
        else:
            done.add(tuple(int(i) for i in entry.name[len("block-"):-len(".npz")].split("-")))
    if damaged:
        say(f"{len(damaged)} chunk file(s) in {parts} did not verify and will be computed "
            f"again: {', '.join(damaged[:5])}{' ...' if len(damaged) > 5 else ''}")
    return done


def stderr_line(text: str) -> None:
    """One line to standard error, prefixed as the command's messages are."""
    print(f"xbsm: {text}", file=sys.stderr, flush=True)
