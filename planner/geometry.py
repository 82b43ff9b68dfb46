"""Plane geometry of the planner: projection onto a polyline, stations, crossings.

Projection onto the nearest segment (the seed's ``classify_cones_by_side``):
for a point ``p`` and a segment from ``a`` with direction ``d``::

    t    = clip(((p - a) . d) / |d|^2, 0, 1)      foot = a + t d
    side = cross(d, p - a) = d_x (p - a)_y - d_y (p - a)_x   (> 0: left)

The signed offset is ``side / |d|`` (distance from the segment's line, + left)
and the station is the arc length from the path's first point to the foot.

Finding the nearest segment exactly without testing all of them: the foot of
the nearest segment lies on it, so that segment's midpoint is within
``d* + L_max / 2`` of ``p``, where ``d*`` is the nearest-segment distance and
``L_max`` the longest segment; ``d*`` is at most the distance to the nearest
midpoint. A k-d tree over the midpoints returns the k nearest; a point whose
k-th neighbour is not beyond that bound is tested against every segment.

A path that passes the same place more than once (the skidpad's centre, a
crossing) makes "the nearest segment" ambiguous. ``project`` therefore takes
an optional station window [lo, hi] (wrapped on a closed path) and a penalty:
segments outside the window count as ``penalty`` metres farther. Near-ties go
to the window's stretch; a point clearly nearest another stretch still
projects there. The same bound holds with distances plus penalties.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.spatial import cKDTree

from localization.global_path import GlobalPath

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.intp]

_CANDIDATES = (8, 32)  # nearest segment midpoints tested per point, first then second pass


@dataclass(frozen=True, slots=True)
class Projection:
    """Points projected onto a path's nearest segments.

    Attributes:
        foot: (n, 2) nearest point on the path [m].
        segment: (n,) index of the nearest segment.
        station: (n,) arc length from the path's start to the foot [m].
        offset: (n,) signed distance from the segment's line, + left [m].
        tangent: (n, 2) unit direction of the nearest segment.
        distance: (n,) distance to the foot [m].
    """

    foot: FloatArray
    segment: IntArray
    station: FloatArray
    offset: FloatArray
    tangent: FloatArray
    distance: FloatArray

    def select(self, rows: slice | IntArray) -> Projection:
        """The projections of some of the points."""
        return Projection(
            self.foot[rows],
            self.segment[rows],
            self.station[rows],
            self.offset[rows],
            self.tangent[rows],
            self.distance[rows],
        )


class PathProjector:
    """Nearest-segment projection onto a global path, with a k-d tree.

    Args:
        path: the global path in ``reference``; a closed path includes the
            segment from its last point back to its first.

    Attributes:
        length: total arc length [m].
        closed: whether stations wrap around at ``length``.
    """

    def __init__(self, path: GlobalPath) -> None:
        starts, deltas = path.segments
        lengths = np.hypot(deltas[:, 0], deltas[:, 1])
        keep = lengths > 0.0
        self._start = starts[keep]
        self._delta = deltas[keep]
        self._length = lengths[keep]
        self._length2 = self._length**2
        self._station0 = np.concatenate([[0.0], np.cumsum(self._length)[:-1]])
        self._mid_station = self._station0 + 0.5 * self._length
        self._tree = cKDTree(self._start + 0.5 * self._delta)
        self._half_max = 0.5 * float(self._length.max())
        # One row per segment, gathered with a single fancy index per query:
        # start x, y, direction x, y, 1 / length^2, mid-station, half length.
        self._table = np.column_stack(
            [
                self._start,
                self._delta,
                1.0 / self._length2,
                self._mid_station,
                0.5 * self._length,
            ]
        )
        self.length = float(self._length.sum())
        self.closed = bool(path.closed)
        self.path = path

    def window_mask(self, lo: float, hi: float) -> NDArray[np.bool_]:
        """(k,) True for the segments overlapping stations [lo, hi] [m] (wrapped if closed)."""
        centre = 0.5 * (lo + hi)
        reach = 0.5 * (hi - lo) + 0.5 * self._length
        return np.abs(self.axis.difference(self._mid_station, centre)) <= reach

    def project(
        self,
        points: FloatArray,
        window: tuple[float, float] | None = None,
        penalty: float = math.inf,
    ) -> Projection:
        """Project (n, 2) points [m] in ``reference`` onto their nearest segments.

        Args:
            points: (n, 2) [m].
            window: (lo, hi) stations [m] of the stretch to prefer; None
                searches the whole path alike.
            penalty: distance added to segments outside the window when
                comparing [m]: inf searches the window only (the whole path
                if no segment is in it), 0 ignores the window.
        """
        p = np.asarray(points, dtype=float).reshape(-1, 2)
        prefer = None
        if window is not None and penalty > 0.0 and np.any(self.window_mask(*window)):
            prefer = (0.5 * (window[0] + window[1]), 0.5 * (window[1] - window[0]), penalty)
        seg, t, d2 = self._nearest(p, prefer)
        a, d, length = self._start[seg], self._delta[seg], self._length[seg]
        rel = p - a
        cross = d[:, 0] * rel[:, 1] - d[:, 1] * rel[:, 0]
        return Projection(
            foot=a + t[:, None] * d,
            segment=seg,
            station=self._station0[seg] + t * length,
            offset=cross / length,
            tangent=d / length[:, None],
            distance=np.sqrt(d2),
        )

    def _nearest(
        self, p: FloatArray, prefer: tuple[float, float, float] | None
    ) -> tuple[IntArray, FloatArray, FloatArray]:
        """Each point's segment of least distance + penalty: (segment, t, squared distance).

        ``prefer`` is the window's (centre, half width, penalty) [m]; None for no window.

        The k nearest midpoints are candidates. A point is sure when its k-th
        midpoint is farther than ``first + L_max / 2``, where ``first`` is the
        least candidate midpoint distance + extra: the best segment's distance
        is at most ``first``, so its midpoint is within that bound (module
        docstring). Unsure points are tried again with a larger k, then
        against every segment.
        """
        n_seg = len(self._length)
        seg = np.zeros(len(p), dtype=np.intp)
        t = np.zeros(len(p))
        d2 = np.zeros(len(p))
        todo = np.arange(len(p))
        for wanted in _CANDIDATES:
            k = min(wanted, n_seg)
            dist, cand = self._tree.query(p[todo], k=k)
            cand = np.asarray(cand, dtype=np.intp).reshape(len(todo), k)
            dist = np.asarray(dist, dtype=float).reshape(len(todo), k)
            rows = self._table[cand]
            cost = self._penalty(rows, prefer)
            seg[todo], t[todo], d2[todo] = self._nearest_of(p[todo], cand, rows, cost)
            if k == n_seg:
                return seg, t, d2
            first = dist[:, 0] if cost is None else np.min(dist + cost, axis=1)
            todo = todo[dist[:, -1] <= first + self._half_max]
            if len(todo) == 0:
                return seg, t, d2
        every = np.broadcast_to(np.arange(n_seg), (len(todo), n_seg))
        rows = np.broadcast_to(self._table, (len(todo), *self._table.shape))
        cost = self._penalty(rows, prefer)
        seg[todo], t[todo], d2[todo] = self._nearest_of(p[todo], every, rows, cost)
        return seg, t, d2

    def _penalty(
        self, rows: FloatArray, prefer: tuple[float, float, float] | None
    ) -> FloatArray | None:
        """(n, k) penalty of candidate segments outside the preferred window [m]."""
        if prefer is None:
            return None
        centre, half, penalty = prefer
        away = np.abs(self.axis.difference(rows[..., 5], centre))
        return np.where(away <= half + rows[..., 6], 0.0, penalty)

    @staticmethod
    def _nearest_of(
        p: FloatArray, cand: IntArray, rows: FloatArray, cost: FloatArray | None
    ) -> tuple[IntArray, FloatArray, FloatArray]:
        """Of candidate segments (n, k) with table rows (n, k, 7), the least distance + cost.

        Returns:
            (segment, t, squared distance), each (n,).
        """
        rx = p[:, 0, None] - rows[..., 0]
        ry = p[:, 1, None] - rows[..., 1]
        dx, dy = rows[..., 2], rows[..., 3]
        t = np.clip((rx * dx + ry * dy) * rows[..., 4], 0.0, 1.0)
        gx, gy = rx - t * dx, ry - t * dy
        d2 = gx * gx + gy * gy
        best = np.argmin(d2 if cost is None else np.sqrt(d2) + cost, axis=1)
        index = np.arange(len(p))
        return cand[index, best], t[index, best], d2[index, best]

    @property
    def axis(self) -> StationAxis:
        """The path's station axis."""
        return StationAxis(self.length, self.closed)


@dataclass(frozen=True, slots=True)
class StationAxis:
    """Arc length along a global path, which wraps around on a closed path.

    Attributes:
        length: path length [m].
        closed: whether stations wrap at ``length``.
    """

    length: float
    closed: bool

    def difference(self, s_to: FloatArray | float, s_from: FloatArray | float) -> FloatArray:
        """``s_to - s_from`` [m], wrapped into [-length/2, length/2) on a closed path."""
        return station_difference(s_to, s_from, self.length, self.closed)


def station_difference(
    s_to: FloatArray | float, s_from: FloatArray | float, length: float, closed: bool
) -> FloatArray:
    """Station difference ``s_to - s_from`` [m], wrapped on a closed path of ``length``.

    >>> float(station_difference(1.0, 99.0, 100.0, True))
    2.0
    >>> float(station_difference(1.0, 99.0, 100.0, False))
    -98.0
    """
    diff = np.asarray(s_to, dtype=float) - np.asarray(s_from, dtype=float)
    if closed and length > 0.0:
        diff = (diff + 0.5 * length) % length - 0.5 * length
    return diff


def _orientation(d: FloatArray, c: FloatArray, r: FloatArray) -> FloatArray:
    """(m, k) cross(d_i, r_j - p_i) = cross(d_i, r_j) - c_i, given c_i = cross(d_i, p_i)."""
    return np.outer(d[:, 0], r[:, 1]) - np.outer(d[:, 1], r[:, 0]) - c[:, None]


def segments_cross(
    a0: FloatArray, a1: FloatArray, b0: FloatArray, b1: FloatArray
) -> NDArray[np.bool_]:
    """Whether segments ``a0 a1`` (m, 2) properly cross segments ``b0 b1`` (k, 2).

    Proper crossing: each segment's end points lie strictly on opposite sides
    of the other's line (touching and collinear overlap do not count).

    Returns:
        (m, k) boolean matrix.
    """
    da, db = a1 - a0, b1 - b0
    ca = da[:, 0] * a0[:, 1] - da[:, 1] * a0[:, 0]
    cb = db[:, 0] * b0[:, 1] - db[:, 1] * b0[:, 0]
    b_straddles = _orientation(da, ca, b0) * _orientation(da, ca, b1) < 0.0
    a_straddles = _orientation(db, cb, a0) * _orientation(db, cb, a1) < 0.0
    return b_straddles & a_straddles.T


def arc_length(points: FloatArray) -> FloatArray:
    """Cumulative arc length of an (n, 2) polyline, starting at 0 [m]; shape (n,)."""
    steps = np.hypot(*np.diff(points, axis=0).T) if len(points) > 1 else np.zeros(0)
    return np.concatenate([[0.0], np.cumsum(steps)])


def resample_polyline(points: FloatArray, spacing: float) -> FloatArray:
    """Points every ``spacing`` [m] of arc length along an (n, 2) polyline, ends included.

    The last point is the polyline's end, so the last step may be shorter.
    """
    s = arc_length(points)
    total = float(s[-1])
    if total <= 0.0:
        return points[:1].copy()
    stations = np.arange(0.0, total, spacing)
    if total - stations[-1] > 1e-9:
        stations = np.append(stations, total)
    x = np.interp(stations, s, points[:, 0])
    return np.column_stack([x, np.interp(stations, s, points[:, 1])])
