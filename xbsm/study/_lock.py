"""One writer per output: an operating-system lock on ``OUT.nc.lock`` held for a run.

The lock is the kernel's (``flock`` on POSIX, ``msvcrt.locking`` on Windows), so
it dies with its process: a lock file left by a killed run is simply taken over.
The file holds the owner's pid, host, study title and start time, which the
refusal quotes. After locking, the file is checked to still be the one at the
path (a finishing run unlinks it), so two runs can never both believe they own it.
"""

from __future__ import annotations

import json
import os
import socket
import threading
import time
from pathlib import Path

from .spec import StudyError

try:
    import fcntl
except ImportError:  # Windows
    fcntl = None
    import msvcrt


def lock_path(output: Path) -> Path:
    """The lock file of an output."""
    return output.with_name(output.name + ".lock")


def _try_lock(fd: int) -> bool:
    try:
        if fcntl is not None:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        else:
            msvcrt.locking(fd, msvcrt.LK_NBLCK, 1)
    except OSError:
        return False
    return True


def _owner_text(fd: int) -> str:
    """What a lock file says about its owner, for the refusal message."""
    try:
        os.lseek(fd, 0, os.SEEK_SET)
        owner = json.loads(os.read(fd, 65536).decode() or "{}")
        return (f"process {owner['pid']} on {owner['host']} (study {owner['study']!r}, "
                f"started {owner['started']})")
    except (OSError, ValueError, KeyError, TypeError):
        return "another process"


#: Lock files this process holds: the file descriptor, how many nested holders, which thread.
_HELD: dict = {}
#: Guards :data:`_HELD`: two threads entering at once would both find an output not held,
#: and the one the kernel refuses would blame "another process" (130 of 300 such races).
_HELD_LOCK = threading.Lock()


def _forget_in_child() -> None:
    """In a forked child (a LocalCluster worker, see ``store._FORK``): close the lock files.

    ``flock`` belongs to the open file, which a fork shares: a worker left running after
    its run died would keep the output locked. Closing the child's copy leaves the
    parent's lock held.
    """
    global _HELD_LOCK
    _HELD_LOCK = threading.Lock()  # the fork may have copied it held by another thread
    for fd, *_ in _HELD.values():
        try:
            os.close(fd)
        except OSError:
            pass
    _HELD.clear()


if hasattr(os, "register_at_fork"):
    os.register_at_fork(after_in_child=_forget_in_child)


class OutputLock:
    """Exclusive right to write one output (and its parts) for the life of a run.

    Re-entrant within a thread: the command takes it before it builds the study
    (so a second run is refused at once) and :func:`xbsm.study.write` again. Another
    thread of the same process is refused as another process is (the kernel's lock is
    the process's, so it cannot tell threads apart).
    """

    def __init__(self, output: Path, study: str):
        self.path = lock_path(output)
        self.output = output
        self.study = study
        self.fd = None

    def __enter__(self) -> OutputLock:
        with _HELD_LOCK:
            return self._enter(os.path.abspath(self.path))

    def _enter(self, key: str) -> OutputLock:
        held = _HELD.get(key)
        if held is not None:
            if held[2] != threading.get_ident():
                raise StudyError(f"{self.output} is being written by another thread of this "
                                 f"process ({_owner_text(held[0])}); wait for it to finish "
                                 f"(its lock: {self.path})")
            held[1] += 1
            self.fd = held[0]
            return self
        while True:
            try:
                fd = os.open(self.path, os.O_RDWR | os.O_CREAT, 0o644)
            except OSError as err:
                raise StudyError(f"cannot write to {self.path.parent}: "
                                 f"{err.strerror or err}") from None
            if not _try_lock(fd):
                owner = _owner_text(fd)
                os.close(fd)
                raise StudyError(f"{self.output} is being written by {owner}; wait for it to "
                                 f"finish or stop it (its lock: {self.path})")
            try:
                same = os.path.samestat(os.fstat(fd), os.stat(self.path))
            except FileNotFoundError:
                same = False
            if same:
                break
            os.close(fd)  # the owner unlinked the file as we locked it: lock the new one
        self.fd = fd
        owner = {"pid": os.getpid(), "host": socket.gethostname(), "study": self.study,
                 "started": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())}
        os.ftruncate(fd, 0)
        os.lseek(fd, 0, os.SEEK_SET)
        os.write(fd, json.dumps(owner).encode())
        _HELD[key] = [fd, 1, threading.get_ident()]
        return self

    def __exit__(self, *exc) -> None:
        with _HELD_LOCK:
            key = os.path.abspath(self.path)
            _HELD[key][1] -= 1
            if _HELD[key][1]:
                return
            del _HELD[key]
            try:
                self.path.unlink(missing_ok=True)  # while still holding it (see the module)
            finally:
                os.close(self.fd)
                self.fd = None
