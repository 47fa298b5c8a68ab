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
"""

from __future__ import annotations

import contextlib
import signal
import threading

INTERRUPTED = threading.Event()
"""Set when SIGINT or SIGTERM arrived during a run (checked between writes)."""

_state = {"deferred": 0, "signal": None, "depth": 0}


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
    """Record the signal; raise at once unless a write is in progress."""
    _state["signal"] = signum
    INTERRUPTED.set()
    if not _state["deferred"]:
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
def handling_signals(signals=(signal.SIGINT, signal.SIGTERM)):
    """Handle ``signals`` as described above for the duration of a run.

    Only in the main thread (the only one Python delivers signals to), and only
    for signals whose handler is Python's default (a signal the caller ignores
    or handles itself is left alone). The previous handlers come back at the end.
    Nested sections (the command around :func:`xbsm.study.write`) share one flag,
    cleared only when the outermost begins.
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
    _state["depth"] += 1
    try:
        yield
    finally:
        _state["depth"] -= 1
        for signum, handler in previous.items():
            signal.signal(signum, handler)
