"""Progress of a run on standard error: a bar in a terminal, a few lines in a log.

In a terminal the line is redrawn in place; when standard error is a file or a
pipe (a batch job, CI), a line is printed each time another ``step`` percent is
done, so a log holds tens of lines, not thousands of carriage returns.
"""

from __future__ import annotations

import sys
import threading
import time


class Progress:
    """Counts finished items of one phase (computing chunks, writing the file)."""

    def __init__(self, what: str, total: int, *, enabled: bool = True, step: float = 10.0,
                 stream=None):
        self.what, self.total, self.done = what, max(int(total), 0), 0
        self.stream = stream or sys.stderr
        self.enabled = enabled and self.total > 0
        self.terminal = self.enabled and getattr(self.stream, "isatty", lambda: False)()
        self.step, self.next_report = step, step
        self.started = time.monotonic()
        self._lock = threading.Lock()  # chunks finish on several threads

    def add(self, count: int = 1) -> None:
        """``count`` more items finished."""
        with self._lock:
            self._add(count)

    def _add(self, count: int) -> None:
        self.done += count
        if not self.enabled:
            return
        percent = 100.0 * self.done / self.total
        if self.terminal:
            bar = "#" * int(percent // 2.5)
            self.stream.write(f"\r[{bar:<40}] {percent:5.1f}% {self.what} "
                              f"({self._elapsed()})")
            if self.done >= self.total:
                self.stream.write("\n")
            self.stream.flush()
        elif percent >= self.next_report or self.done >= self.total:
            print(f"xbsm: {self.what}: {self.done} of {self.total} ({percent:.0f} %, "
                  f"{self._elapsed()})", file=self.stream, flush=True)
            while self.next_report <= percent:
                self.next_report += self.step

    def _elapsed(self) -> str:
        seconds = int(time.monotonic() - self.started)
        return f"{seconds // 60} min {seconds % 60:02d} s" if seconds >= 60 else f"{seconds} s"
