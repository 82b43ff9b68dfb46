"""Sensor timing: the settings every sensor shares, and the capture clock.

Capture quantisation. Sensor ``i`` nominally captures at ``phase + k / rate``
(k = 0, 1, ...). The simulator only exists at its physics steps, so a capture
happens at the *first physics step at or after* the nominal time and is stamped
with that step's time ``t``; its message is delivered at the first step with
``t >= stamp + latency``. Both comparisons allow ``TIME_EPS`` (1 ns) for float
round-off in ``k * dt``. When the rates divide the physics rate and the
latencies are whole steps, this is exact: with physics at 200 Hz, GPS 10 Hz,
heading 20 Hz, IMU 100 Hz, wheel speed 50 Hz, cones 10 Hz and latencies of
0.05 / 0.12 / 0.2 s, every stamp is a nominal time and every delivery is at
stamp + latency. Otherwise a stamp is late by less than one physics step
(jitter, as a real driver's timestamps have), and a latency rounds up to the
next step. A sensor faster than the physics captures at most once per step; the
nominal times it skips are counted in ``CaptureClock.skipped``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from conesim.sim.sensors.validation import check_non_negative, check_positive

TIME_EPS = 1e-9  # [s] tolerance of the capture and delivery comparisons


@dataclass(frozen=True)
class SensorTiming:
    """Settings shared by every sensor config (the base of ``GpsConfig`` etc.).

    Attributes:
        rate: capture rate [Hz], > 0.
        latency: delay from capture (the stamp) to delivery [s], >= 0.
        phase: offset of the first nominal capture time [s], >= 0.
        enabled: whether the sensor captures at all.
    """

    rate: float = 10.0  # [Hz]
    latency: float = 0.0  # [s]
    phase: float = 0.0  # [s]
    enabled: bool = True

    def __post_init__(self) -> None:
        owner = type(self).__name__
        check_positive(owner, "rate", self.rate, "[Hz]")
        check_non_negative(owner, "latency", self.latency, "[s]")
        check_non_negative(owner, "phase", self.phase, "[s]")
        self._validate()

    def _validate(self) -> None:
        """Range checks of a subclass's own fields (raise ``ValueError``)."""

    @property
    def period(self) -> float:
        """Nominal sample period 1 / rate [s]."""
        return 1.0 / self.rate


class CaptureClock:
    """Decides at which physics steps one sensor captures.

    Args:
        rate: capture rate [Hz].
        phase: first nominal capture time [s].
    """

    def __init__(self, rate: float, phase: float = 0.0) -> None:
        self.rate = rate
        self.phase = phase
        self.k = 0  # index of the next nominal capture
        self.skipped = 0  # nominal captures that fell between two physics steps

    @property
    def k(self) -> int:
        """Index of the next nominal capture."""
        return self._k

    @k.setter
    def k(self, value: int) -> None:
        self._k = value
        # ``due`` runs every physics step: its threshold is kept, not recomputed.
        # The earliest step time that captures, next_nominal - TIME_EPS [s].
        self.threshold = self.phase + value / self.rate - TIME_EPS

    @property
    def next_nominal(self) -> float:
        """Nominal time of the next capture, phase + k / rate [s]."""
        return self.phase + self.k / self.rate

    def due(self, t: float) -> bool:
        """Whether the step at time ``t`` [s] captures; if so, move to the next capture.

        >>> clock = CaptureClock(rate=10.0)
        >>> [round(t, 3) for t in (0.0, 0.075, 0.15, 0.225) if clock.due(t)]
        [0.0, 0.15, 0.225]
        """
        if t < self.threshold:  # next_nominal - TIME_EPS
            return False
        k_next = max(self.k + 1, math.floor((t + TIME_EPS - self.phase) * self.rate) + 1)
        self.skipped += k_next - self.k - 1
        self.k = k_next
        return True

    def reset(self) -> None:
        """Start again from the first nominal capture."""
        self.k = 0
        self.skipped = 0
