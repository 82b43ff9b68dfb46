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
from dataclasses import dataclass, field, fields
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
    CONES = "cones"  # a cone-detection scan against the map (``localization.cones``)


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
    NO_ASSOCIATION = "no_association"  # a cone scan with no detection matched to the map


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
        cones: a cone scan's association counts, else None.
    """

    sensor: Sensor
    stamp: float
    accepted: bool
    reason: RejectReason | None = None
    nis: float | None = None
    dof: int = 0
    cones: ConeCounts | None = None


@dataclass(slots=True)
class ConeCounts:
    """What became of the detections of cone scans against the map (``localization.cones``).

    Attributes:
        scans: scans associated.
        matched: detections matched to a map cone and used.
        false_positives: detections with no map cone inside the gate.
        colour_mismatches: detections whose only cones inside the gate have another colour.
        ambiguous: detections left out because no unique, jointly compatible match exists.
        misses: map cones in the detector's range and field of view that no
            detection matched (occluded cones included).
        scans_gated: scans whose associations failed the joint NIS gate (none used).
        nis_sum: the joint NIS of the scans used, summed [-].
        dof_sum: their degrees of freedom (2 per matched detection), summed [-].
        nis_in_band: scans used whose NIS lies in its two-sided 95 % chi-square band.
    """

    scans: int = 0
    matched: int = 0
    false_positives: int = 0
    colour_mismatches: int = 0
    ambiguous: int = 0
    misses: int = 0
    scans_gated: int = 0
    nis_sum: float = 0.0
    dof_sum: int = 0
    nis_in_band: int = 0

    def add(self, other: ConeCounts, sign: int = 1) -> None:
        """Add (``sign`` = -1: take away) another scan's counts."""
        for f in fields(self):
            name = f.name
            setattr(self, name, getattr(self, name) + sign * getattr(other, name))

    def as_dict(self) -> dict[str, float]:
        """The counts by name."""
        return {f.name: getattr(self, f.name) for f in fields(self)}


@dataclass(frozen=True, slots=True)
class LandmarkCounts:
    """The map being built (``slam`` mode, ``localization.slam``).

    Attributes:
        confirmed: landmarks in the map now.
        tentative: candidates waiting for more sightings.
        pruned: landmarks removed after too many misses.
        ever_confirmed: landmarks that ever entered the map.
        loop_closed: whether the loop has closed (the map's membership is final).
    """

    confirmed: int = 0
    tentative: int = 0
    pruned: int = 0
    ever_confirmed: int = 0
    loop_closed: bool = False

    def as_dict(self) -> dict[str, int | bool]:
        """The counts by name."""
        return {f.name: getattr(self, f.name) for f in fields(self)}


@dataclass
class Health:
    """Counters of accepted and rejected messages.

    Attributes:
        accepted: messages used, per sensor.
        rejected: messages not used, per (sensor, reason).
        resets: times the filter threw its state away and initialised again.
        replays: late messages that made the filter replay its history.
        discarded_before_init: good messages older than the initial state.
        cones: the cone scans' association counts (``cones`` and ``slam`` modes).
        landmarks: the map being built (``slam`` mode), else None.
    """

    accepted: Counter[Sensor] = field(default_factory=Counter)
    rejected: Counter[tuple[Sensor, RejectReason]] = field(default_factory=Counter)
    resets: int = 0
    replays: int = 0
    discarded_before_init: int = 0
    cones: ConeCounts = field(default_factory=ConeCounts)
    landmarks: LandmarkCounts | None = None

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

    def revise(
        self,
        sensor: Sensor,
        was: RejectReason | None,
        now: RejectReason | None,
        stamp: float,
    ) -> None:
        """Move a replayed message whose decision changed to its new count.

        Args:
            sensor: its stream.
            was: the reason it was rejected the time before (None: it was accepted).
            now: the reason it is rejected on replay (None: it is accepted).
            stamp: its stamp [s].
        """
        if was is None:
            self.accepted[sensor] -= 1
        else:
            self.rejected[(sensor, was)] -= 1
        if now is None:
            self.accept(sensor)
            _log.debug("%s message at %.6f s accepted on replay", sensor, stamp)
        else:
            detail = "gated on replay" if now is RejectReason.NIS_GATE else f"{now} on replay"
            self.reject(sensor, now, stamp, detail)

    def count(self, reason: RejectReason | None = None, sensor: Sensor | None = None) -> int:
        """Rejected messages, optionally of one reason and/or one sensor."""
        return sum(
            n
            for (s, r), n in self.rejected.items()
            if (reason is None or r == reason) and (sensor is None or s == sensor)
        )
