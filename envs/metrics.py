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
- the plans that fell back to carrying the previous path forward.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy.spatial import cKDTree

from conesim.core.polyline import Polyline
from conesim.envs.loop import StepRecord
from conesim.planner.midline import PlanStatus
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


class RunMetrics:
    """Accumulates an episode's records (``add`` each, in order, the reset's first).

    Args:
        track: the track driven (its true centreline is the midline's reference).
    """

    def __init__(self, track: Track) -> None:
        self.trace = RunTrace()
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
