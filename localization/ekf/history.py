"""The filter's short memory: recent inputs and measurements, each with the state after it.

Measurements arrive late (GPS 0.05-0.2 s after capture) while the IMU keeps
driving the state forward. The filter therefore keeps, for the last
``window`` seconds, every input and measurement in stamp order together with
a snapshot of the state right after it. A message stamped in the past is
inserted at its place; the filter restores the snapshot just before it and
replays everything after it, which gives exactly the estimate it would have
had if the message had arrived on time.

Order at equal stamps is fixed by the sensor (IMU first, then wheel speed,
heading, GPS), then by arrival, so that the order never depends on latency.
Older entries are dropped; the snapshot after the last dropped one becomes the
``base``, and a message stamped before it is too old to apply.
"""

from __future__ import annotations

import bisect
from dataclasses import dataclass
from typing import Any, Final, NamedTuple

import numpy as np
from numpy.typing import NDArray

from conesim.localization.ekf.augmented import MapState
from conesim.localization.ekf.health import ConeCounts, RejectReason, Sensor
from conesim.localization.ekf.measurements import Measurement

FloatArray = NDArray[np.float64]

RANK: Final = {
    Sensor.IMU: 0,
    Sensor.WHEEL_SPEED: 1,
    Sensor.HEADING: 2,
    Sensor.GPS: 3,
    Sensor.CONES: 4,
}
"""Processing order of messages with equal stamps."""


class Snapshot(NamedTuple):
    """The filter's state at one time (arrays are shared with the filter and read-only).

    A named tuple: immutable like a frozen dataclass, and cheaper to build
    (one per message and per replayed message).

    Attributes:
        t: time of the state [s].
        x: state, (n, 1).
        P: covariance, (n, n).
        u: IMU input held from ``t`` on, (3,).
        u_cov: its per-sample covariance, (3, 3).
        book: the map's bookkeeping when the filter builds a map
            (``localization.slam.book.MapBook``, immutable), else None.
        map: the landmarks' part of the state then (``x`` and ``P`` are the
            vehicle's; :class:`~.augmented.MapState`, immutable), else None.
    """

    t: float
    x: FloatArray
    P: FloatArray
    u: FloatArray
    u_cov: FloatArray
    book: Any = None
    map: MapState | None = None


@dataclass(slots=True)
class Entry:
    """One processed message and what came of it.

    Attributes:
        measurement: the message, checked.
        after: the state right after it.
        accepted: whether it was applied (False: gated).
        nis: its normalised innovation squared, if an update.
        reason: why it was not applied, if it was not.
        cones: a cone scan's association counts, else None.
    """

    measurement: Measurement
    after: Snapshot
    accepted: bool
    nis: float | None
    reason: RejectReason | None = None
    cones: ConeCounts | None = None


def order_key(m: Measurement) -> tuple[float, int]:
    """Sort key of a message: (stamp, sensor rank)."""
    return (m.stamp, RANK[m.sensor])


class History:
    """Entries in stamp order over the last ``window`` seconds, above a base state.

    Args:
        base: the state before the first entry (e.g. the initial state).
        window: how long entries are kept, back from the newest stamp [s].
    """

    def __init__(self, base: Snapshot, window: float) -> None:
        self.base = base
        self.window = window
        self.entries: list[Entry] = []
        self._keys: list[tuple[float, int]] = []

    @property
    def latest(self) -> Snapshot:
        """The state after the newest entry."""
        return self.entries[-1].after if self.entries else self.base

    def too_old(self, m: Measurement) -> bool:
        """Whether ``m`` is stamped before the base state."""
        return m.stamp < self.base.t

    def position(self, m: Measurement) -> int:
        """Index at which ``m`` belongs (after entries with an equal key)."""
        return bisect.bisect_right(self._keys, order_key(m))

    def cut(self, index: int) -> list[Entry]:
        """Remove and return the entries from ``index`` on."""
        if index >= len(self.entries):
            return []
        later = self.entries[index:]
        del self.entries[index:]
        del self._keys[index:]
        return later

    def append(self, entry: Entry) -> None:
        """Add an entry after the last one (its key must not sort before it)."""
        self.entries.append(entry)
        self._keys.append(order_key(entry.measurement))

    def prune(self, newest: float | None = None) -> None:
        """Drop entries older than the newest stamp minus the window.

        Args:
            newest: the newest stamp [s], if not the last entry's (entries held
                back for a replay elsewhere are newer than every entry here).
        """
        if not self.entries:
            return
        if newest is None:
            newest = self.entries[-1].measurement.stamp
        horizon = newest - self.window
        if self.entries[0].measurement.stamp >= horizon:
            return
        drop = bisect.bisect_left(self._keys, (horizon, -1))
        if drop:
            self.base = self.entries[drop - 1].after
            del self.entries[:drop]
            del self._keys[:drop]

    def snapshot_at(self, t: float) -> Snapshot:
        """The newest state at or before ``t`` [s].

        Raises:
            ValueError: ``t`` is before the base state.
        """
        if t < self.base.t:
            raise ValueError(
                f"time {t!r} s is before the oldest state held ({self.base.t!r} s); "
                f"the history keeps {self.window!r} s"
            )
        i = bisect.bisect_right(self._keys, (t, len(RANK)))
        return self.entries[i - 1].after if i else self.base
