"""What the fusion EKF accepted and rejected, and why: counters and log lines.

Every message the filter does not use for a reason other than "not my type"
is counted under ``(sensor, reason)`` and logged through ``logging`` (logger
``localization.ekf``): at WARNING the first time a (sensor, reason) pair
occurs and every ``LOG_EVERY``-th time after, at DEBUG otherwise, so a GPS
dropout at 10 Hz does not flood the log.

A late measurement can be replayed, and its gate decision can change with the
prior it meets the second time; the counters then move the message from one
count to the other, so they always hold each message's latest decision.
"""

from __future__ import annotations

import logging
from collections import Counter
from dataclasses import dataclass, field
from enum import StrEnum
from typing import Final

LOG_EVERY: Final = 100

_log = logging.getLogger("conesim.localization.ekf")


class Sensor(StrEnum):
    """The message streams the filter uses."""

    IMU = "imu"
    WHEEL_SPEED = "wheel_speed"
    HEADING = "heading"
    GPS = "gps"


class RejectReason(StrEnum):
    """Why a message was not used."""

    NON_FINITE = "non_finite"  # NaN or inf in a value or a stamp
    OUT_OF_RANGE = "out_of_range"  # a fix's latitude beyond +-90 or longitude beyond +-180 deg
    NO_FIX = "no_fix"  # NavSatFix with status NO_FIX
    BAD_COVARIANCE = "bad_covariance"  # negative, not symmetric, or not PSD
    WRONG_FRAME = "wrong_frame"  # header.frame_id is not the expected frame
    TOO_OLD = "too_old"  # stamped before the oldest state the history holds
    TOO_NEW = "too_new"  # stamped more than max_stamp_jump after the newest message
    NIS_GATE = "nis_gate"  # Mahalanobis distance beyond the chi-square gate


@dataclass(frozen=True, slots=True)
class UpdateResult:
    """The outcome of handing one message to the filter.

    Attributes:
        sensor: which stream it belonged to.
        stamp: its capture stamp [s].
        accepted: whether it changed the estimate (or was kept for initialisation).
        reason: why not, when rejected.
        nis: normalised innovation squared y' S^-1 y, for updates that got that far.
        dof: the measurement's dimension (the NIS's degrees of freedom).
    """

    sensor: Sensor
    stamp: float
    accepted: bool
    reason: RejectReason | None = None
    nis: float | None = None
    dof: int = 0


@dataclass
class Health:
    """Counters of accepted and rejected messages.

    Attributes:
        accepted: messages used, per sensor.
        rejected: messages not used, per (sensor, reason).
        resets: times the filter threw its state away and initialised again.
        replays: late messages that made the filter replay its history.
        discarded_before_init: good messages older than the initial state.
    """

    accepted: Counter[Sensor] = field(default_factory=Counter)
    rejected: Counter[tuple[Sensor, RejectReason]] = field(default_factory=Counter)
    resets: int = 0
    replays: int = 0
    discarded_before_init: int = 0

    def accept(self, sensor: Sensor) -> None:
        """Count one used message."""
        self.accepted[sensor] += 1

    def reject(self, sensor: Sensor, reason: RejectReason, stamp: float, detail: str) -> None:
        """Count and log one rejected message."""
        key = (sensor, reason)
        self.rejected[key] += 1
        count = self.rejected[key]
        level = logging.WARNING if count == 1 or count % LOG_EVERY == 0 else logging.DEBUG
        _log.log(
            level, "rejected %s message at %.6f s: %s (%s; %d so far)", sensor, stamp,
            reason, detail, count,
        )  # fmt: skip

    def revise(self, sensor: Sensor, was_accepted: bool, stamp: float) -> None:
        """Move a replayed message whose gate decision flipped to its new count."""
        if was_accepted:
            self.accepted[sensor] -= 1
            self.reject(sensor, RejectReason.NIS_GATE, stamp, "gated on replay")
        else:
            self.rejected[(sensor, RejectReason.NIS_GATE)] -= 1
            self.accept(sensor)
            _log.debug("%s message at %.6f s accepted on replay", sensor, stamp)

    def count(self, reason: RejectReason | None = None, sensor: Sensor | None = None) -> int:
        """Rejected messages, optionally of one reason and/or one sensor."""
        return sum(
            n
            for (s, r), n in self.rejected.items()
            if (reason is None or r == reason) and (sensor is None or s == sensor)
        )
