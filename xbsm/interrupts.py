"""Ctrl-C and SIGTERM during a study run: honoured at every moment, never mid-write.

Python turns SIGINT into a KeyboardInterrupt raised wherever the main thread is.
Raised inside a library that holds a lock (xarray's NetCDF lock, a weakref
callback), it can deadlock the process or be swallowed. So a run handles the
signals itself (:func:`handling_signals`): the handler records the signal in
:data:`INTERRUPTED` and raises only where that is safe; inside a
:func:`deferred` section (writing a file) it only records, and the writer
stops at its next check (:func:`stop_if_interrupted`), between two writes.
The threads computing chunks never see signals; they check the same flag after
each saved chunk.

A run whose result is in place has succeeded (:func:`completing`): a signal that
arrives after that (while the lock is released, the command returns or the
interpreter exits) is recorded, never turned into an "interrupted" run, which
would send the user to resume a run that is complete.
"""

from __future__ import annotations

import contextlib
import signal
import threading


class _Flag:
    """:class:`threading.Event`'s ``is_set``, ``set`` and ``clear``, without its lock.

    The signal handler sets the flag, and Python runs a handler again, in the same
    thread, when another signal arrives while it runs: ``Event.set`` holds the
    Event's lock while it notifies waiters, so a second Ctrl-C (or a SIGTERM) landing
    there made the handler wait for a lock its own thread held, for ever (and every
    later signal's handler with it). Setting one attribute needs no lock: the threads
    computing chunks only read it.
    """

    __slots__ = ("_set",)

    def __init__(self):
        self._set = False

    def is_set(self) -> bool:
        return self._set

    def set(self) -> None:
        self._set = True

    def clear(self) -> None:
        self._set = False


INTERRUPTED = _Flag()
"""Set when SIGINT or SIGTERM arrived during a run (checked between writes)."""

_state = {"deferred": 0, "signal": None, "depth": 0, "complete": False}


class Interrupted(KeyboardInterrupt):
    """A run stopped by a signal; ``signum`` says which (SIGINT or SIGTERM)."""

    def __init__(self, signum=signal.SIGINT):
        super().__init__(signal.Signals(signum).name)
        self.signum = signum

    @property
    def exit_code(self) -> int:
        """The shell's code for death by this signal: 130 for SIGINT, 143 for SIGTERM."""
        return 128 + int(self.signum)


def stop_if_interrupted() -> None:
    """Raise :class:`Interrupted` if a signal arrived, even if its exception was lost."""
    if INTERRUPTED.is_set():
        raise Interrupted(_state["signal"] or signal.SIGINT)


def _on_signal(signum, frame):
    """Record the signal; raise at once unless a write is in progress or the run complete."""
    _state["signal"] = signum
    INTERRUPTED.set()
    if not _state["deferred"] and not _state["complete"]:
        raise Interrupted(signum)


@contextlib.contextmanager
def deferred():
    """A section (a file being written) that a signal never interrupts mid-way.

    The writer calls :func:`stop_if_interrupted` between its writes; the section's
    end checks once more, so a signal that arrived during it is never lost.
    """
    _state["deferred"] += 1
    try:
        yield
    finally:
        _state["deferred"] -= 1
    stop_if_interrupted()


@contextlib.contextmanager
def completing():
    """The section that puts a run's result in place (its last rename or marker file).

    A signal during it waits for it, as in :func:`deferred`. When it ends without an
    error the result is whole and the run has succeeded: from then on a signal is
    recorded but not raised where it lands. Only an explicit check
    (:func:`stop_if_interrupted`, the end of a :func:`deferred` section, such as the
    figures ``xbsm run`` draws after its result) still stops the command.
    """
    _state["deferred"] += 1
    try:
        yield
        _state["complete"] = True
    finally:
        _state["deferred"] -= 1


@contextlib.contextmanager
def handling_signals(signals=(signal.SIGINT, signal.SIGTERM), *, until_exit=False):
    """Handle ``signals`` as described above for the duration of a run.

    Only in the main thread (the only one Python delivers signals to), and only
    for signals whose handler is Python's default (a signal the caller ignores
    or handles itself is left alone). The previous handlers come back at the end.
    Nested sections (the command around :func:`xbsm.study.write`) share one flag,
    cleared only when the outermost begins. ``until_exit``: the command itself, whose
    process ends with the section: its signals are ignored from then on. The
    command's outcome is decided and on disk; a signal while the interpreter exits
    would otherwise print a traceback, or kill the process (Python restores the
    default action for its last moments) after a complete run.
    """
    previous = {}
    if threading.current_thread() is threading.main_thread():
        for signum in signals:
            current = signal.getsignal(signum)
            if current in (signal.default_int_handler, signal.SIG_DFL, _on_signal):
                previous[signum] = current
                signal.signal(signum, _on_signal)
    if not _state["depth"]:
        INTERRUPTED.clear()
        _state["signal"] = None
        _state["complete"] = False
    _state["depth"] += 1
    try:
        yield
    finally:
        _state["depth"] -= 1
        for signum, handler in previous.items():
            signal.signal(signum, signal.SIG_IGN if until_exit else handler)
