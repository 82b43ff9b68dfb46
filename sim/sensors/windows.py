"""Time windows of capture time, for a sensor's dropouts.

A window is a pair (start [s], duration [s]) of capture time; a capture at
``t`` falls in it when ``start <= t < start + duration``. The GPS receiver
and the heading sensor keep their dropouts this way, so that both check and
test them alike.
"""

from __future__ import annotations

from conesim.sim.sensors.validation import check_non_negative, check_positive

Windows = tuple[tuple[float, float], ...]
"""((start [s], duration [s]), ...)."""


def check_windows(owner: str, field: str, windows: Windows) -> None:
    """Require each window to be a pair with start >= 0 and duration > 0 [s].

    Raises:
        ValueError: naming ``owner.field[i]`` and what is allowed.
    """
    for i, window in enumerate(windows):
        if len(window) != 2:
            raise ValueError(
                f"{owner}.{field}[{i}] = {window!r} is out of range: "
                "allowed a pair (start [s], duration [s])"
            )
        check_non_negative(owner, f"{field}[{i}].start", window[0], "[s]")
        check_positive(owner, f"{field}[{i}].duration", window[1], "[s]")


def in_windows(t: float, windows: Windows) -> bool:
    """Whether capture time ``t`` [s] falls in one of the windows."""
    return any(start <= t < start + duration for start, duration in windows)
