"""Arc-length progress and lateral offset of a point along a polyline.

The projection follows the point from segment to segment: from the previous
answer it walks to the neighbouring segment while that one is closer (a few
scalar steps per physics step, since the car moves centimetres). A
figure-of-eight (skidpad) or a hairpin whose legs lie close together therefore
never makes the car jump to the other leg. The first query (or one after a
reset) searches globally with a ``cKDTree`` and then a window of segments.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.spatial import cKDTree


@dataclass(frozen=True, slots=True)
class Projection:
    """Where a point lies relative to the polyline.

    Attributes:
        s: arc length of the foot point from the polyline's start [m].
        lateral: signed distance to the foot point, left of the driving
            direction positive [m]: the perpendicular offset, or, where the
            foot is a segment's end (beyond either end of an open polyline,
            outside a corner), the distance to that end.
        index: segment index of the foot point.
        tangent: (2,) unit tangent of that segment.
    """

    s: float
    lateral: float
    index: int
    tangent: tuple[float, float]


class PolylineProgress:
    """Project points onto a polyline, tracking the segment between calls.

    Args:
        points: (m, 2) polyline vertices in driving order [m].
        closed: whether the last vertex joins the first.
        window_m: half-width of the search window around the last segment [m].
    """

    def __init__(self, points: NDArray[np.float64], closed: bool, window_m: float = 15.0) -> None:
        pts = np.asarray(points, dtype=float).reshape(-1, 2)
        if len(pts) < 2:
            raise ValueError("PolylineProgress needs at least 2 points")
        self.closed = closed
        ring = np.vstack([pts, pts[:1]]) if closed else pts
        self._starts = ring[:-1]
        self._deltas = np.diff(ring, axis=0)
        self._lengths = np.hypot(self._deltas[:, 0], self._deltas[:, 1])
        if np.any(self._lengths <= 0.0):
            raise ValueError("PolylineProgress: repeated consecutive points")
        self._tangents = self._deltas / self._lengths[:, None]
        self._s0 = np.concatenate([[0.0], np.cumsum(self._lengths)[:-1]])
        self.length = float(self._lengths.sum())
        step = float(np.median(self._lengths))
        self._window = max(2, math.ceil(window_m / step))
        self._tree = cKDTree(pts)
        # Plain-float copies for the scalar walk (faster than numpy per element).
        self._starts_list = [(float(a), float(b)) for a, b in self._starts]
        self._tangents_list = [(float(a), float(b)) for a, b in self._tangents]
        self._lengths_list = [float(v) for v in self._lengths]
        self._s0_list = [float(v) for v in self._s0]
        self._segments = [
            (sx, sy, tx, ty, length)
            for (sx, sy), (tx, ty), length in zip(
                self._starts_list, self._tangents_list, self._lengths_list, strict=True
            )
        ]
        self._last: int | None = None

    def reset(self) -> None:
        """Forget the last segment: the next query searches globally."""
        self._last = None

    def project(self, xy: NDArray[np.float64] | tuple[float, float]) -> Projection:
        """Project one point [m]."""
        if self._last is not None:
            return self._walk(float(xy[0]), float(xy[1]), self._last)
        p = np.asarray(xy, dtype=float)
        n = len(self._starts)
        if self._last is None:
            _, nearest = self._tree.query(p)
            center = int(nearest)
        else:
            center = self._last
        idx = np.arange(center - self._window, center + self._window + 1)
        idx = np.mod(idx, n) if self.closed else idx[(idx >= 0) & (idx < n)]
        rel = p - self._starts[idx]
        u = np.clip(np.einsum("ij,ij->i", rel, self._tangents[idx]), 0.0, self._lengths[idx])
        foot = self._starts[idx] + self._tangents[idx] * u[:, None]
        d2 = np.sum((p - foot) ** 2, axis=1)
        k = int(np.argmin(d2))
        seg = int(idx[k])
        self._last = seg
        t = self._tangents[seg]
        r = p - foot[k]
        lateral = _offset(
            float(t[0] * r[1] - t[1] * r[0]), float(d2[k]), float(u[k]), self._lengths_list[seg]
        )
        return Projection(float(self._s0[seg] + u[k]), lateral, seg, (float(t[0]), float(t[1])))

    def restart_at(self, index: int) -> None:
        """Go on walking from segment ``index`` (as if the last answer had been there)."""
        if not 0 <= index < len(self._segments):
            raise ValueError(f"segment {index} is not in 0..{len(self._segments) - 1}")
        self._last = index

    def project_xy_anew(self, x: float, y: float) -> tuple[float, float, int, float, float]:
        """:meth:`project_xy` searching the whole path, as after :meth:`reset`,
        and leaving the segment the next walk starts from as it was."""
        last = self._last
        self._last = None
        try:
            return self.project_xy(x, y)
        finally:
            self._last = last

    def project_xy(self, px: float, py: float) -> tuple[float, float, int, float, float]:
        """:meth:`project` of one point on plain floats: (s, lateral, index, tx, ty).

        The same answer bit for bit, without building a ``Projection`` (the
        race control's per-step path).
        """
        i = self._last
        if i is None:
            proj = self.project((px, py))
            return proj.s, proj.lateral, proj.index, proj.tangent[0], proj.tangent[1]
        # The walk of ``_walk`` with ``_foot`` and ``_step`` inlined.
        segments = self._segments
        n = len(segments)
        closed = self.closed
        sx, sy, tx, ty, length = segments[i]
        rx, ry = px - sx, py - sy
        u = min(max(rx * tx + ry * ty, 0.0), length)
        fx, fy = rx - tx * u, ry - ty * u
        best_d2, best_u, best_lat = fx * fx + fy * fy, u, tx * fy - ty * fx
        for di in (1, -1):
            while True:
                j = i + di
                if closed:
                    j %= n
                elif not 0 <= j < n:
                    break
                sx, sy, tx, ty, length = segments[j]
                rx, ry = px - sx, py - sy
                u = min(max(rx * tx + ry * ty, 0.0), length)
                fx, fy = rx - tx * u, ry - ty * u
                d2 = fx * fx + fy * fy
                if d2 >= best_d2:
                    break
                i, best_d2, best_u, best_lat = j, d2, u, tx * fy - ty * fx
        self._last = i
        tx, ty = self._tangents_list[i]
        lateral = _offset(best_lat, best_d2, best_u, self._lengths_list[i])
        return self._s0_list[i] + best_u, lateral, i, tx, ty

    def _foot(self, i: int, px: float, py: float) -> tuple[float, float, float]:
        """Distance^2 to segment i, the foot's arc position u, and lateral offset."""
        sx, sy = self._starts_list[i]
        tx, ty = self._tangents_list[i]
        rx, ry = px - sx, py - sy
        u = min(max(rx * tx + ry * ty, 0.0), self._lengths_list[i])
        fx, fy = rx - tx * u, ry - ty * u
        return fx * fx + fy * fy, u, tx * fy - ty * fx

    def _step(self, i: int, di: int) -> int | None:
        j = i + di
        n = len(self._starts_list)
        if self.closed:
            return j % n
        return j if 0 <= j < n else None

    def _walk(self, px: float, py: float, i: int) -> Projection:
        best = self._foot(i, px, py)
        for di in (1, -1):
            while True:
                j = self._step(i, di)
                if j is None:
                    break
                cand = self._foot(j, px, py)
                if cand[0] >= best[0]:
                    break
                i, best = j, cand
        self._last = i
        d2, u, lateral = best
        t = self._tangents_list[i]
        return Projection(
            self._s0_list[i] + u, _offset(lateral, d2, u, self._lengths_list[i]), i, t
        )


def _offset(lateral: float, d2: float, u: float, length: float) -> float:
    """The signed offset of a point from its foot at ``u`` on a segment of
    ``length`` [m]: ``lateral`` (perpendicular) with the foot inside the
    segment, else the distance sqrt(``d2``) to the end it lies at, with
    ``lateral``'s sign (a car past an open polyline's end is that far off it)."""
    if 0.0 < u < length:
        return lateral
    return math.copysign(math.sqrt(d2), lateral)


def segment_crossing(
    p0: NDArray[np.float64], p1: NDArray[np.float64], a: NDArray[np.float64], b: NDArray[np.float64]
) -> float | None:
    """Where the step p0 -> p1 crosses the line segment a-b.

    Returns:
        The fraction u in [0, 1] along p0 -> p1 at the crossing, or None.
    """
    return segment_crossing_xy(
        (float(p0[0]), float(p0[1])),
        (float(p1[0]), float(p1[1])),
        (float(a[0]), float(a[1]), float(b[0]), float(b[1])),
    )


def segment_crossing_xy(
    p0: tuple[float, float], p1: tuple[float, float], line: tuple[float, float, float, float]
) -> float | None:
    """:func:`segment_crossing` on plain floats, the line as (ax, ay, bx, by).

    The same operations in the same order (every physics step).
    """
    p0x, p0y = p0
    p1x, p1y = p1
    ax, ay, bx, by = line
    dx, dy = p1x - p0x, p1y - p0y
    ex, ey = bx - ax, by - ay
    denom = dx * ey - dy * ex
    if denom == 0.0:
        return None
    wx, wy = ax - p0x, ay - p0y
    u = (wx * ey - wy * ex) / denom
    v = (wx * dy - wy * dx) / denom
    if 0.0 <= u <= 1.0 and 0.0 <= v <= 1.0:
        return u
    return None
