"""Race control: lap timing, track limits and the stuck detector.

* Laps: the start/finish line is the segment between the big orange cones. A
  lap counts when the car's reference point (its CG) crosses the finish line
  in the driving direction after net progress along the centreline of at
  least ``min_lap_fraction`` of a lap since the last counted crossing (a
  progress guard: rocking back and forth over the line adds no net progress,
  so it never counts). The crossing time is interpolated linearly within the
  physics step. The first forward crossing of the start line starts the clock
  (a standing start behind the line, as in FS trackdrive); a car placed on or
  just past the line starts the clock at t = 0. On a loop and the skidpad the
  start and finish lines are the same line; on the acceleration lane the
  finish line is the one at 75 m. ``timed_lap_length`` works out the lap
  length for each layout from the centreline.
* Off-track: the car is off track when its whole body (all four footprint
  corners) lies outside the boundaries on one side (FS: "off course" when all
  four wheels leave the track). Each excursion is an event with start and end
  time.
* Where the car is along the track: the centreline projection follows the car
  from segment to segment (``PolylineProgress``), so that the legs of a
  hairpin or a figure of eight never swap. Off the track that walk can hold
  on to the stretch the car left while the car crosses the infield to another
  one; so while the car's centre is outside the track, a search of the whole
  centreline (on leaving, then after each ``rejoin_margin_m`` the car moves)
  moves the walk to a stretch ``rejoin_margin_m`` nearer than the one it
  holds. A cut never pays: the stretch it skips forwards is not progress
  (nor toward a lap's ``min_lap_fraction``, so a lap cut short by more than
  a quarter does not count), one it skips backwards is taken off (driving
  it again earns it back), and the excursion is an off-track event (FS
  charges 10 s per off-course).
* The offset that decides off-track is the projection's lateral one
  (``PolylineProgress.project_xy``, ``Projection.lateral``'s meaning):
  the perpendicular one, or beyond either end of an open centreline the
  distance to that end, so the car is not on a track that has ended.
* Stuck: less than ``stuck_progress_m`` of net progress in ``stuck_time_s``.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from conesim.core.compiled import cached_njit
from conesim.core.polyline import Polyline
from conesim.core.pose import Pose2D
from conesim.sim.progress import PolylineProgress, segment_crossing, segment_crossing_xy


def _probe() -> None:
    """Nothing: what ``cached_njit`` asks numba to cache, from this file's directory."""


_compiled = cached_njit(_probe, "conesim.sim.race_control")

# [m] far above any round-off of the per-step tests, far below any footprint
# or step: the quick answers of ``_off`` and ``_crossed`` keep this much
# away from the cases they leave to the full test.
_QUICK_MARGIN = 0.01


@dataclass(frozen=True)
class RaceRules:
    """Race-control settings.

    Attributes:
        min_lap_fraction: net progress needed between two counted crossings,
            as a fraction of the lap length [-].
        stuck_time_s: window of the stuck detector [s].
        stuck_progress_m: net progress below which the car is stuck [m].
        rejoin_margin_m: with the car's centre off the track, its projection
            moves to another stretch of the track that is this much nearer
            than the one it holds; the whole centreline is searched again
            each time the car has moved this far [m].
    """

    min_lap_fraction: float = 0.75
    stuck_time_s: float = 5.0
    stuck_progress_m: float = 0.5
    rejoin_margin_m: float = 1.0

    def __post_init__(self) -> None:
        if not 0.0 < self.min_lap_fraction <= 1.0:
            raise ValueError(
                f"RaceRules.min_lap_fraction must be in (0, 1], got {self.min_lap_fraction!r}"
            )
        if not self.stuck_time_s > 0.0:
            raise ValueError(f"RaceRules.stuck_time_s must be > 0, got {self.stuck_time_s!r}")
        if not self.stuck_progress_m >= 0.0:
            raise ValueError(
                f"RaceRules.stuck_progress_m must be >= 0, got {self.stuck_progress_m!r}"
            )
        if not (self.rejoin_margin_m >= 0.0 and math.isfinite(self.rejoin_margin_m)):
            raise ValueError(
                f"RaceRules.rejoin_margin_m must be finite and >= 0, got {self.rejoin_margin_m!r}"
            )


@dataclass
class OffTrackEvent:
    """One excursion off the track [s]; ``end`` is None while it lasts."""

    start: float
    end: float | None = None


@dataclass
class RaceState:
    """What race control has recorded so far."""

    clock_start: float | None = None
    lap_times: list[float] = field(default_factory=list)
    crossing_times: list[float] = field(default_factory=list)
    off_track: list[OffTrackEvent] = field(default_factory=list)
    progress_m: float = 0.0
    stuck: bool = False

    @property
    def laps_completed(self) -> int:
        """Number of counted laps."""
        return len(self.lap_times)

    @property
    def is_off_track(self) -> bool:
        """Whether an excursion is under way."""
        return bool(self.off_track) and self.off_track[-1].end is None


class RaceControl:
    """Lap timing, off-track and stuck detection against a track's geometry.

    Args:
        centreline: (m, 2) true centreline in driving order [m].
        closed: whether the centreline is a loop.
        half_widths: (m,) half track width at each centreline point [m].
        start_finish: (2, 2) end points of the start line [m].
        lap_length: distance of one lap along the centreline [m].
        finish_line: (2, 2) end points of the finish line [m]; default the
            start line.
        car_length: footprint length [m].
        car_width: footprint width [m].
        rules: settings.
    """

    def __init__(
        self,
        centreline: NDArray[np.float64],
        closed: bool,
        *,
        half_widths: NDArray[np.float64],
        start_finish: NDArray[np.float64],
        lap_length: float,
        car_length: float,
        car_width: float,
        rules: RaceRules | None = None,
        finish_line: NDArray[np.float64] | None = None,
    ) -> None:
        self.rules = rules or RaceRules()
        self.progress = PolylineProgress(Polyline(centreline, closed))
        self.half_widths = np.asarray(half_widths, dtype=float)
        self.line = np.asarray(start_finish, dtype=float).reshape(2, 2)
        self.finish = (
            self.line if finish_line is None else np.asarray(finish_line, float).reshape(2, 2)
        )
        self.lap_length = float(lap_length)
        hl, hw = 0.5 * car_length, 0.5 * car_width
        self._half_footprint = (hl, hw)  # [m] the corners are (+-hl, +-hw)
        _corners_off(0.0, 1.0, 0.0, 0.0, 1.0, hl, hw)  # compiled (or loaded) now, not in a step
        self._half_widths_list = [float(h) for h in self.half_widths]
        # Plain-float end points for the per-step crossing test.
        lx = [float(v) for v in self.line.ravel()]
        fx = [float(v) for v in self.finish.ravel()]
        self._line_xy = (lx[0], lx[1], lx[2], lx[3])
        self._finish_xy = (fx[0], fx[1], fx[2], fx[3])
        # A CG at least this far inside both boundaries has all four corners
        # inside (no corner is farther from the CG): ``_off`` is False at once;
        # one this far beyond a boundary has all four beyond it: True at once.
        self._corner_reach = math.hypot(hl, hw) + _QUICK_MARGIN
        # The lines' bounding boxes, grown by the margin: a step outside a
        # box does not cross its line (``_crossed`` skips the full test).
        self._line_box = _grown_box(self._line_xy)
        self._finish_box = _grown_box(self._finish_xy)
        self.state = RaceState()
        self._s_last: float | None = None
        self._progress_at_crossing = 0.0
        self._history: deque[tuple[float, float]] = deque()
        self._searched_at: tuple[float, float] | None = None  # the last off-track search

    def start(self, t: float, pose: Pose2D) -> None:
        """Initialise at the start pose; starts the clock if already past the line.

        A new race each time: laps, progress, excursions and the stuck
        window start afresh (a world's reset starts its race control again).
        """
        self.state = RaceState()
        self._progress_at_crossing = 0.0
        self.progress.reset()
        proj = self.progress.project(pose.xy)
        self._s_last = float(proj.station[0])
        self._history = deque([(t, 0.0)])
        self._searched_at = None
        line_mid = self.line.mean(axis=0)
        line_dir = self.line[1] - self.line[0]
        normal = np.array([-line_dir[1], line_dir[0]])
        if np.dot(normal, proj.tangent[0]) < 0:
            normal = -normal
        ahead = float(np.dot(pose.xy - line_mid, normal)) / float(np.linalg.norm(normal))
        if 0.0 <= ahead <= 0.5:
            self.state.clock_start = t
            self.state.crossing_times.append(t)

    def update(self, t_prev: float, t: float, pose_prev: Pose2D, pose: Pose2D) -> None:
        """Account for one physics step from ``pose_prev`` at ``t_prev`` to ``pose`` at ``t``."""
        self.update_xy(t_prev, t, (pose_prev.x, pose_prev.y), (pose.x, pose.y, pose.yaw))

    def update_xy(
        self,
        t_prev: float,
        t: float,
        xy_prev: tuple[float, float],
        pose: tuple[float, float, float],
    ) -> None:
        """:meth:`update` with the CG's previous (x, y) and its (x, y, yaw) now, plain floats."""
        # Runs every physics step: plain-float maths, the checks written out.
        p1x, p1y, yaw = pose
        s, lateral, index, tx, ty = self.progress.project_xy(p1x, p1y)
        if abs(lateral) <= self._half_widths_list[min(index, len(self._half_widths_list) - 1)]:
            self._searched_at = None
        elif self._search_due(p1x, p1y):
            walked = (s, lateral, index, tx, ty)
            s, lateral, index, tx, ty = self._nearer_stretch(p1x, p1y, walked)
            if index != walked[2]:  # a cut across the infield
                self._advance_progress(s, cut=True)
        self._advance_progress(s)
        p0x, p0y = xy_prev
        if (p1x - p0x) * tx + (p1y - p0y) * ty > 0.0:
            self._crossed(t_prev, t, (p0x, p0y), (p1x, p1y))
        self._set_off_track(t, self._off(lateral, index, tx, ty, yaw))
        self._check_stuck(t)

    def _search_due(self, px: float, py: float) -> bool:
        """Whether to search the whole centreline for the off-track centre (px, py):
        on leaving the track, then each time the car has moved ``rejoin_margin_m``
        since the last search (a search every physics step doubled the cost of
        an env step with the car off the track)."""
        last = self._searched_at
        if last is not None and math.hypot(px - last[0], py - last[1]) < self.rules.rejoin_margin_m:
            return False
        self._searched_at = (px, py)
        return True

    def _nearer_stretch(
        self, px: float, py: float, walked: tuple[float, float, int, float, float]
    ) -> tuple[float, float, int, float, float]:
        """The projection of an off-track centre (px, py): the walk's, or that of
        a stretch found by a whole-centreline search when it is
        ``rejoin_margin_m`` nearer (the walk then goes on from there)."""
        return self.progress.nearer_stretch(px, py, walked, self.rules.rejoin_margin_m)

    def is_off_track_at(self, pose: Pose2D) -> bool:
        """Whether the car with its CG at ``pose`` is off the track (all four
        footprint corners beyond one boundary), without recording anything:
        the pose is projected from scratch and the tracker's last segment,
        where the next step's projection starts, is kept."""
        _, lateral, index, tx, ty = self.progress.project_xy_anew(pose.x, pose.y)
        return self._off(lateral, index, tx, ty, pose.yaw)

    def _off(self, lateral: float, index: int, tx: float, ty: float, yaw: float) -> bool:
        """Off track, from the CG's lateral offset at centreline ``index``
        with tangent (tx, ty): each footprint corner's offset is the CG's plus
        the corner's (rotated into the world) on the track's left normal
        (-ty, tx)."""
        halves = self._half_widths_list
        half = halves[min(index, len(halves) - 1)]
        if abs(lateral) + self._corner_reach < half:
            return False  # every corner within a corner's reach of the CG, inside
        if abs(lateral) - self._corner_reach > half:
            return True  # every corner within that reach, beyond the CG's boundary
        hl, hw = self._half_footprint
        return bool(_corners_off(lateral, tx, ty, yaw, half, hl, hw))

    def _advance_progress(self, s: float, cut: bool = False) -> None:
        """Add the change of station to ``s`` [m] (the short way round a loop);
        for a ``cut``, only a loss: a cut never pays."""
        assert self._s_last is not None, "RaceControl.start() must be called first"
        ds = s - self._s_last
        if self.progress.closed:
            length = self.progress.length
            half = 0.5 * length
            ds = (ds + half) % length - half
        self.state.progress_m += min(ds, 0.0) if cut else ds
        self._s_last = s

    def _crossed(
        self, t_prev: float, t: float, p0: tuple[float, float], p1: tuple[float, float]
    ) -> None:
        """A forward step from ``p0`` to ``p1``: start the clock or count a lap."""
        st = self.state
        if st.clock_start is None:
            if _outside(p0, p1, self._line_box):
                return
            u = segment_crossing_xy(p0, p1, self._line_xy)
            if u is not None:
                t_cross = t_prev + u * (t - t_prev)
                st.clock_start = t_cross
                st.crossing_times.append(t_cross)
                self._progress_at_crossing = st.progress_m
            return
        if _outside(p0, p1, self._finish_box):
            return
        u = segment_crossing_xy(p0, p1, self._finish_xy)
        if u is None:
            return
        t_cross = t_prev + u * (t - t_prev)
        needed = self.rules.min_lap_fraction * self.lap_length
        if st.progress_m - self._progress_at_crossing >= needed:
            st.lap_times.append(t_cross - st.crossing_times[-1])
            st.crossing_times.append(t_cross)
            self._progress_at_crossing = st.progress_m

    def _set_off_track(self, t: float, off: bool) -> None:
        """Open or close an excursion at ``t``."""
        events = self.state.off_track
        on = bool(events) and events[-1].end is None
        if off and not on:
            events.append(OffTrackEvent(start=t))
        elif not off and on:
            events[-1].end = t

    def _check_stuck(self, t: float) -> None:
        history = self._history
        st = self.state
        progress = st.progress_m
        history.append((t, progress))
        horizon = t - self.rules.stuck_time_s
        while len(history) > 1 and history[1][0] <= horizon:
            history.popleft()
        t0, p0 = history[0]
        st.stuck = t0 <= horizon and abs(progress - p0) < self.rules.stuck_progress_m


@_compiled
def _corners_off(lateral, tx, ty, yaw, half, hl, hw):  # noqa: PLR0917
    """Whether the four corners (+-hl, +-hw) of a footprint whose CG is
    ``lateral`` off the centreline with tangent (tx, ty), heading ``yaw``, all
    lie beyond the same boundary at ``half``: ``RaceControl._off``'s placing,
    compiled (in the corners' order; the same operations as in Python)."""
    c, sn = math.cos(yaw), math.sin(yaw)
    nx, ny = -ty, tx
    above = below = 0
    for cx, cy in ((hl, hw), (hl, -hw), (-hl, hw), (-hl, -hw)):
        lat = lateral + (c * cx - sn * cy) * nx + (sn * cx + c * cy) * ny
        above += lat > half
        below += lat < -half
    return above == 4 or below == 4


def _grown_box(line: tuple[float, float, float, float]) -> tuple[float, float, float, float]:
    """(x_lo, y_lo, x_hi, y_hi) of a line segment (ax, ay, bx, by), grown by ``_QUICK_MARGIN``."""
    ax, ay, bx, by = line
    m = _QUICK_MARGIN
    return min(ax, bx) - m, min(ay, by) - m, max(ax, bx) + m, max(ay, by) + m


def _outside(
    p0: tuple[float, float], p1: tuple[float, float], box: tuple[float, float, float, float]
) -> bool:
    """Whether the step p0 -> p1 lies wholly on one far side of a grown box: it
    cannot cross the segment inside (``segment_crossing_xy`` would say None)."""
    x_lo, y_lo, x_hi, y_hi = box
    (p0x, p0y), (p1x, p1y) = p0, p1
    return (
        (p0x < x_lo and p1x < x_lo)
        or (p0x > x_hi and p1x > x_hi)
        or (p0y < y_lo and p1y < y_lo)
        or (p0y > y_hi and p1y > y_hi)
    )


def line_crossings_along(
    polyline: NDArray[np.float64], closed: bool, line: NDArray[np.float64]
) -> list[float]:
    """Arc lengths [m] at which a polyline crosses a line segment, in order."""
    along = Polyline(polyline, closed)
    pts, seg, s0 = along.ring, along.segment_lengths, along.stations
    out: list[float] = []
    for i in range(len(pts) - 1):
        u = segment_crossing(pts[i], pts[i + 1], line[0], line[1])
        if u is not None and (not out or s0[i] + u * seg[i] - out[-1] > 1e-6):
            out.append(float(s0[i] + u * seg[i]))
    return out


def timed_lap_length(
    centreline: NDArray[np.float64],
    closed: bool,
    start_line: NDArray[np.float64],
    finish_line: NDArray[np.float64],
) -> float:
    """Centreline distance of one timed lap [m].

    A loop: its whole length. An open lane: from the start line to the finish
    line. A figure of eight (start and finish the same line, crossed several
    times by an open centreline): between the first two crossings, one circle.
    """
    pts = np.asarray(centreline, dtype=float)
    if closed:
        return float(np.hypot(*np.diff(np.vstack([pts, pts[:1]]), axis=0).T).sum())
    starts = line_crossings_along(pts, False, np.asarray(start_line, float))
    finishes = line_crossings_along(pts, False, np.asarray(finish_line, float))
    s_start = starts[0] if starts else 0.0
    later = [s for s in finishes if s > s_start + 1e-6]
    if later:
        return later[0] - s_start
    return float(np.hypot(*np.diff(pts, axis=0).T).sum()) - s_start
