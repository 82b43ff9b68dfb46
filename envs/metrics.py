"""What a run is judged by, accumulated from the closed loop's records.

:class:`RunMetrics` takes every :class:`~envs.loop.StepRecord` of an episode
in order and keeps what the run's result reports beside the race's own
standing (laps, cones, excursions, which the records carry):

- the trajectory per control step (the car's CG, its speed and the
  driver's target speed), for the run picture;
- the localization error at every ``reference -> gps_antenna`` broadcast
  (the published pose against the antenna's true pose then), for the
  position and heading RMSE;
- the planner's midline error: every point of every new plan's path,
  placed in ``reference`` by the pose it was planned with, against the
  true centreline (sampled every ``MIDLINE_SAMPLE_M``);
- the plans that fell back to carrying the previous path forward;
- the events, as ``result.json`` lists them (``RunEvents``): every cone hit
  and every cone down or out (time, which cone, its kind, where it stood),
  every excursion off the track (start, where, end, duration), every lap,
  and where the run ended and why.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy.spatial import cKDTree

from conesim.core.polyline import Polyline
from conesim.envs.loop import StepRecord
from conesim.planner.midline import PlanStatus
from conesim.sim.events import BackOnTrack, ConeDown, ConeHit, LapCompleted, OffTrack
from conesim.tracks import Track

MIDLINE_SAMPLE_M = 0.05  # [m] spacing of the densified true centreline


@dataclass
class RunTrace:
    """Per control step samples for the run picture."""

    t: list[float] = field(default_factory=list)
    x: list[float] = field(default_factory=list)
    y: list[float] = field(default_factory=list)
    speed: list[float] = field(default_factory=list)
    target_speed: list[float] = field(default_factory=list)
    loc_t: list[float] = field(default_factory=list)
    loc_pos_err: list[float] = field(default_factory=list)
    loc_yaw_err: list[float] = field(default_factory=list)


@dataclass(frozen=True)
class ConeEventRecord:
    """A cone hit, or down or out: when [s], which cone (its index in the track),
    its kind, and where it stood [m]."""

    t: float
    cone: int
    kind: str
    x: float
    y: float


@dataclass
class Excursion:
    """One excursion off the track: when it began [s], where the CG left [m], when
    it ended [s] (None if it lasted to the end of the run) and how long [s]."""

    t_start: float
    x: float
    y: float
    t_end: float | None = None
    duration_s: float = 0.0


@dataclass(frozen=True)
class LapRecord:
    """Lap ``lap`` (1, 2, ...): when it ended [s] and its time [s]."""

    lap: int
    t: float
    time_s: float


@dataclass(frozen=True)
class EndRecord:
    """When [s] and where (the CG) [m] the run ended, and why."""

    t: float
    x: float
    y: float
    reason: str


@dataclass
class RunEvents:
    """What happened in a run, in order (``result.json``'s ``events``)."""

    cones_hit: list[ConeEventRecord] = field(default_factory=list)
    cones_down_or_out: list[ConeEventRecord] = field(default_factory=list)
    off_track: list[Excursion] = field(default_factory=list)
    laps: list[LapRecord] = field(default_factory=list)
    end: EndRecord | None = None


class RunMetrics:
    """Accumulates an episode's records (``add`` each, in order, the reset's first).

    Args:
        track: the track driven (its true centreline is the midline's reference).
    """

    def __init__(self, track: Track) -> None:
        self.trace = RunTrace()
        self.events = RunEvents()
        self._kinds = tuple(str(k) for k in track.kinds)
        self.fallbacks = 0
        self._centre = _dense_centreline_tree(track)
        self._midline_sq: list[float] = []
        self._records = 0

    def add(self, record: StepRecord) -> None:
        """Take one record: its broadcasts, plans, and (after the reset's) its trajectory."""
        trace = self.trace
        if self._records:  # the trajectory starts with the first step, as the picture's
            state = record.truth.state
            trace.t.append(record.t)
            trace.x.append(state.x)
            trace.y.append(state.y)
            trace.speed.append(state.speed)
            trace.target_speed.append(record.driver.target_speed if record.driver else 0.0)
        self._records += 1
        self._take_events(record)
        for broadcast in record.broadcasts:
            trace.loc_t.append(broadcast.t)
            trace.loc_pos_err.append(broadcast.position_error)
            trace.loc_yaw_err.append(broadcast.yaw_error)
        if record.driver is None:
            return
        for planned in record.driver.plans:
            self.fallbacks += planned.plan.status is PlanStatus.FALLBACK
            if len(planned.path_reference):
                dist, _ = self._centre.query(planned.path_reference)
                self._midline_sq.extend((dist**2).tolist())

    def _take_events(self, record: StepRecord) -> None:
        """The record's events into ``events``; its end, when it has one."""
        events = self.events
        for event in record.events:
            if isinstance(event, ConeHit | ConeDown):
                row = ConeEventRecord(
                    event.t, event.cone, self._kinds[event.cone], event.x, event.y
                )
                if isinstance(event, ConeHit):
                    events.cones_hit.append(row)
                else:
                    events.cones_down_or_out.append(row)
            elif isinstance(event, OffTrack):
                events.off_track.append(Excursion(event.t, event.x, event.y))
            elif isinstance(event, BackOnTrack) and events.off_track:
                last = events.off_track[-1]
                last.t_end, last.duration_s = event.t, event.t - last.t_start
            elif isinstance(event, LapCompleted):
                events.laps.append(LapRecord(event.lap, event.t, event.lap_time))
        if record.end is not None:
            state = record.truth.state
            events.end = EndRecord(record.t, state.x, state.y, str(record.end))
            for excursion in events.off_track:
                if excursion.t_end is None:
                    excursion.duration_s = record.t - excursion.t_start

    @property
    def localization_pos_rmse_m(self) -> float | None:
        """RMS of the published position's error over the broadcasts [m]."""
        return _rms(self.trace.loc_pos_err)

    @property
    def localization_yaw_rmse_deg(self) -> float | None:
        """RMS of the published heading's error over the broadcasts [deg]."""
        rms = _rms(self.trace.loc_yaw_err)
        return None if rms is None else math.degrees(rms)

    @property
    def midline_rmse_m(self) -> float | None:
        """RMS distance of the planned paths' points from the true centreline [m]."""
        sq = self._midline_sq
        return float(math.sqrt(np.mean(sq))) if sq else None


def _rms(values: list[float]) -> float | None:
    return float(math.sqrt(np.mean(np.square(values)))) if values else None


def _dense_centreline_tree(track: Track) -> cKDTree:
    """The true centreline every ``MIDLINE_SAMPLE_M``, as a k-d tree."""
    centre = Polyline(track.centreline, track.layout == "closed")
    return cKDTree(centre.at(np.arange(0.0, centre.end_station, MIDLINE_SAMPLE_M)))
