"""Progress on stderr: a one-line bar for a run, and a sweep's runs done and time left.

``ProgressBar`` redraws one terminal line in place (``\\r``). ``SweepProgress``
is what ``conesim sweep`` shows: runs done of the total, clean so far,
errors, and the time left (the mean wall time per run finished so far
times the runs left, over the workers). On a terminal it is the bar; when
stderr is not a terminal (a log file, CI) it writes a plain line at every
tenth of the runs and a last one, so that a log shows progress without a
line per run.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from typing import TextIO

STEPS = 10
"""Not on a terminal: a line at every 1/STEPS of the runs."""


class ProgressBar:
    """A one-line progress bar on a terminal.

    Args:
        stream: the terminal.
        label: what the line starts with.
        width: the bar's width [characters].
    """

    def __init__(self, stream: TextIO, label: str = "conesim run", width: int = 30) -> None:
        self.stream = stream
        self.label = label
        self.width = width
        self._shown = -1

    def draw(self, fraction: float, text: str, *, force: bool = False) -> None:
        """Redraw when the bar moves (or ``force``): ``fraction`` in [0, 1], then ``text``."""
        filled = min(self.width, max(0, int(self.width * fraction)))
        if filled != self._shown or force:
            self._shown = filled
            bar = "#" * filled + "." * (self.width - filled)
            self.stream.write(f"\r{self.label} [{bar}] {text}\x1b[K")
            self.stream.flush()

    def update(self, t: float, limit: float) -> None:
        """A run's simulated time ``t`` [s] against its limit [s]."""
        self.draw(t / limit if limit > 0 else 0.0, f"{t:6.1f} s simulated")

    def close(self) -> None:
        """End the line."""
        self.stream.write("\n")
        self.stream.flush()


def format_duration(seconds: float) -> str:
    """``75.0`` -> ``1:15``, ``3725.0`` -> ``1:02:05``; ``?`` when not known.

    >>> format_duration(75.0), format_duration(3725.0), format_duration(math.nan)
    ('1:15', '1:02:05', '?')
    """
    if not math.isfinite(seconds):
        return "?"
    minutes, secs = divmod(round(max(0.0, seconds)), 60)
    hours, minutes = divmod(minutes, 60)
    return f"{hours}:{minutes:02d}:{secs:02d}" if hours else f"{minutes}:{secs:02d}"


class SweepProgress:
    """A sweep's progress on ``stream`` (see the module docstring).

    Args:
        stream: stderr.
        total: the sweep's runs.
        skipped: those already done (a resumed sweep), counted as done.
        clean: how many of the skipped were clean.
        errors: how many of the skipped ended in an error.
        tty: draw the bar (a terminal) or write sparse lines.
        clock: the wall clock [s].
    """

    def __init__(
        self,
        stream: TextIO,
        total: int,
        *,
        skipped: int = 0,
        clean: int = 0,
        errors: int = 0,
        tty: bool = False,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        self.stream = stream
        self.total = total
        self.done = skipped
        self.clean = clean
        self.errors = errors
        self.skipped = skipped
        self.clock = clock
        self.started = clock()
        self.bar = ProgressBar(stream, "conesim sweep") if tty else None
        self._step = self._steps()
        if self.bar is not None:
            self.bar.draw(self._fraction(), self.text(), force=True)

    def _fraction(self) -> float:
        return self.done / self.total if self.total else 1.0

    def _steps(self) -> int:
        return math.floor(self._fraction() * STEPS)

    def eta(self) -> float:
        """The time left [s] (nan before a run of this session has finished)."""
        ran = self.done - self.skipped
        if ran <= 0:
            return math.nan
        return (self.clock() - self.started) / ran * (self.total - self.done)

    def text(self) -> str:
        """``12/40 runs, 11 clean, 1 error, 0:35 left``."""
        errors = f", {self.errors} error{'s' if self.errors != 1 else ''}" if self.errors else ""
        return (
            f"{self.done}/{self.total} runs, {self.clean} clean{errors}, "
            f"{format_duration(self.eta())} left"
        )

    def finished(self, *, clean: bool, error: bool) -> None:
        """One more run done."""
        self.done += 1
        self.clean += clean
        self.errors += error
        if self.bar is not None:
            self.bar.draw(self._fraction(), self.text(), force=True)
            return
        step = self._steps()
        if step > self._step or self.done == self.total:
            self._step = step
            self.stream.write(f"conesim sweep: {self.text()}\n")
            self.stream.flush()

    def note(self, line: str) -> None:
        """A line of its own (a run that failed), above the bar."""
        if self.bar is not None:
            self.stream.write("\r\x1b[K")
        self.stream.write(f"conesim sweep: {line}\n")
        if self.bar is not None:
            self.bar.draw(self._fraction(), self.text(), force=True)
        self.stream.flush()

    def close(self) -> None:
        """End the bar's line."""
        if self.bar is not None:
            self.bar.close()
