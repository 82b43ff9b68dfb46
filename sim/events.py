"""What happened in one physics step: the world's events, and the race's standing.

Race control and the cone field keep their own bookkeeping (``RaceState``,
``ConeField.hit_ids`` ...); :meth:`World.step` turns what changed in a step
into events, so that a consumer (the closed loop's records, metrics, a bag,
a reward) reads what happened instead of diffing another object's state.

Each event has the simulation time it happened [s] and where, in
``reference`` [m]:

- :class:`ConeHit`: the car touched a cone (once per cone, FS "hit");
- :class:`ConeDown`: a cone is down or out (once per cone; FS charges 2 s);
- :class:`OffTrack` / :class:`BackOnTrack`: the car's whole body left the
  track / came back (FS "off course", 10 s each);
- :class:`LapCompleted`: the finish line crossed after a lap (its time
  interpolated within the step).
"""

from __future__ import annotations

from dataclasses import dataclass

from conesim.core.messages import Message


@dataclass(frozen=True, slots=True)
class ConeHit:
    """The car touched cone ``cone`` (its index in the track) at ``t`` [s], at (x, y) [m]."""

    t: float
    cone: int
    x: float
    y: float


@dataclass(frozen=True, slots=True)
class ConeDown:
    """Cone ``cone`` is down or out at ``t`` [s]; (x, y) is where it stood [m]."""

    t: float
    cone: int
    x: float
    y: float


@dataclass(frozen=True, slots=True)
class OffTrack:
    """The car's whole footprint left the track at ``t`` [s]; (x, y) is its CG [m]."""

    t: float
    x: float
    y: float


@dataclass(frozen=True, slots=True)
class BackOnTrack:
    """The car came back onto the track at ``t`` [s]; (x, y) is its CG [m]."""

    t: float
    x: float
    y: float


@dataclass(frozen=True, slots=True)
class LapCompleted:
    """Lap ``lap`` (1, 2, ...) ended at ``t`` [s], the crossing's time, in ``lap_time`` [s]."""

    t: float
    lap: int
    lap_time: float


Event = ConeHit | ConeDown | OffTrack | BackOnTrack | LapCompleted
"""Anything :meth:`World.step` reports happened."""


@dataclass(frozen=True, slots=True)
class RaceStanding:
    """The race so far, after a step (cumulative; the truth that scoring reads).

    Attributes:
        progress_m: net progress along the true centreline [m].
        laps_completed: counted laps.
        lap_times: each counted lap's time [s].
        cones_hit: cones touched.
        cones_down_or_out: cones down or out.
        off_track_events: excursions off the track (one under way included).
        off_track: whether the car is off the track now.
        stuck: whether race control finds the car stuck now.
    """

    progress_m: float
    laps_completed: int
    lap_times: tuple[float, ...]
    cones_hit: int
    cones_down_or_out: int
    off_track_events: int
    off_track: bool
    stuck: bool


@dataclass(frozen=True, slots=True)
class WorldStep:
    """One physics step of the world.

    Attributes:
        t: simulation time after the step [s].
        messages: the measurements delivered at this step, in stamp order.
        events: what happened during the step, in the order it was found.
    """

    t: float
    messages: list[Message]
    events: list[Event]
