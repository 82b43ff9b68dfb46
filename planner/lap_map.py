"""The first lap's cones, kept as a map: from it, lap 2's racing line.

A Formula Student car explores lap 1 on the cones' midline and races the
laps after on a line through the map it built (the usual FS pipeline: lap 1
maps, later laps optimise). ``LapMap`` keeps every classified cone of lap 1
in ``reference``: a detection within ``radius`` of a map cone is another
sighting of it (its position the mean of its sightings, its side a vote);
a cone seen fewer than ``min_sightings`` times (a false positive, drawn anew
each scan) is left out, and so is one whose vote and whose side of the
global path disagree, and one standing more than ``OUTLIER_M`` wider of the
path than its side's neighbours (a start gate's big orange cones: kept, they
kinked the line to a radius of 0.9 m at the gate of a generated track).

``racing_path`` orders each side's cones along the global path into a
closed boundary and solves ``planner.racing_line``'s QPs (minimum curvature,
shortest path) in that corridor, keeping the car's centre half its width
plus ``margin`` from the boundaries; of the blends of the two lines it keeps
the one the planner's own speed plan (``GlobalSpeedPlan``) laps fastest.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from conesim.core.polyline import Polyline
from conesim.planner.classify import LEFT
from conesim.planner.config import SpeedProfileConfig
from conesim.planner.geometry import FloatArray, PathProjector
from conesim.planner.global_speed import GlobalSpeedPlan
from conesim.planner.racing_line import Corridor, racing_lines
from conesim.tracks.global_path import GlobalPath, global_path_from_centreline

BLENDS = (0.0, 0.25, 0.5, 0.75, 1.0)  # shares of the shortest path tried
OUTLIER_M = 0.5  # [m] a cone this much wider than its neighbours bounds nothing
OUTLIER_WINDOW_M = 8.0  # [m] its neighbours: within this along the path


class LapMap:
    """Cones seen on lap 1, merged by position (module docstring).

    Args:
        radius: a detection this close to a map cone is that cone [m].
        min_sightings: a cone seen fewer times is not in the map.
    """

    def __init__(self, radius: float = 0.5, min_sightings: int = 3) -> None:
        self.radius = radius
        self.min_sightings = min_sightings
        self._sum: list[list[float]] = []  # [x sum, y sum, sightings, side votes]
        self._grid: dict[tuple[int, int], list[int]] = {}

    def __len__(self) -> int:
        return sum(1 for c in self._sum if c[2] >= self.min_sightings)

    def add(self, points: FloatArray, sides: NDArray[np.int8]) -> None:
        """Fold one scan's classified cones into the map: (n, 2) positions in
        ``reference`` [m] and their sides (n,) (``ClassifiedCones.points``, ``side``)."""
        r = self.radius
        xy, labels = np.asarray(points).tolist(), np.asarray(sides).tolist()
        for (x, y), side in zip(xy, labels, strict=True):
            i, j = math.floor(x / r), math.floor(y / r)
            best, best_d = -1, r
            for key in ((i + a, j + b) for a in (-1, 0, 1) for b in (-1, 0, 1)):
                for k in self._grid.get(key, ()):
                    c = self._sum[k]
                    d = math.hypot(c[0] / c[2] - x, c[1] / c[2] - y)
                    if d < best_d:
                        best, best_d = k, d
            if best < 0:
                self._grid.setdefault((i, j), []).append(len(self._sum))
                self._sum.append([x, y, 1.0, float(side)])
            else:
                c = self._sum[best]
                c[0] += x
                c[1] += y
                c[2] += 1.0
                c[3] += float(side)

    def cones(self) -> tuple[FloatArray, FloatArray]:
        """The mapped cones (n, 2) [m] and their sides (n,) (``LEFT`` / ``RIGHT``)."""
        kept = [c for c in self._sum if c[2] >= self.min_sightings and c[3] != 0.0]
        if not kept:
            return np.zeros((0, 2)), np.zeros(0)
        a = np.asarray(kept)
        return a[:, :2] / a[:, 2:3], np.sign(a[:, 3])

    def racing_path(
        self,
        global_path: GlobalPath,
        clearance: float,
        config: SpeedProfileConfig,
        *,
        body: tuple[float, float] = (0.0, 0.0),
    ) -> GlobalPath:
        """The fastest blend's line through the mapped lane (module docstring);
        ``body``: half the car's width and its front ahead of the rear axle [m]
        (``Corridor.body_front``: the front corner's sweep outside a turn).

        Raises:
            ValueError: too few cones on a side, or no line fits (``RacingLineError``).
        """
        points, sides = self.cones()
        projector = PathProjector(global_path.polyline)
        proj = projector.project(points) if len(points) else None
        boundaries = []
        for side in (LEFT, -LEFT):
            if proj is None:
                raise ValueError("no cones mapped")
            keep = (sides == side) & (np.sign(proj.lateral) == side)
            keep[keep] = _inner(proj.station[keep], np.abs(proj.lateral[keep]), global_path)
            if keep.sum() < 8:
                raise ValueError(f"{int(keep.sum())} cones mapped on one side")
            order = np.argsort(proj.station[keep])
            boundaries.append(Polyline(points[keep][order], True))
        centre = np.asarray(global_path.xy, dtype=float)
        lines = racing_lines(Corridor(centre, boundaries[0], boundaries[1], clearance, *body))
        paths = [
            global_path_from_centreline(lines.line(b), True, global_path.origin) for b in BLENDS
        ]
        return min(paths, key=lambda p: lap_time(GlobalSpeedPlan(p, config)))


def lap_time(plan: GlobalSpeedPlan) -> float:
    """The flying lap of a closed path's speed plan [s] (ds over each step's mean speed)."""
    v = 0.5 * (plan.speeds[1:] + plan.speeds[:-1])
    return float(np.sum(np.diff(plan.stations) / v))


def _inner(station: FloatArray, lateral: FloatArray, path: GlobalPath) -> NDArray[np.bool_]:
    """Which of one side's cones bound the lane: not more than ``OUTLIER_M`` farther
    from the path than the median of that side's cones within ``OUTLIER_WINDOW_M``
    along it (a start gate's big orange cones stand wider than the lane)."""
    length = path.polyline.end_station
    gap = np.abs(station[:, None] - station[None, :])
    gap = np.minimum(gap, length - gap)
    near = np.where(gap <= OUTLIER_WINDOW_M, lateral[None, :], np.nan)
    return lateral <= np.nanmedian(near, axis=1) + OUTLIER_M
