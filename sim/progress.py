"""Arc-length progress and lateral offset of a point along a polyline.

The projection follows the point from segment to segment: from the previous
answer it walks to the neighbouring segment while that one is closer (a few
scalar steps per physics step, since the car moves centimetres). A
figure-of-eight (skidpad) or a hairpin whose legs lie close together therefore
never makes the car jump to the other leg. The first query (or one after a
reset) searches globally: the nearest vertex, then a window of segments around it.

The walk runs at every physics step (race control), and the search each metre
the car moves off the track, so both are numba kernels on floats (no
``fastmath``, Python's ``min``/``max``: the numbers of their plain
formulations bit for bit; ``tests/sim/test_step_fast_paths.py`` compares them
with those, kept in ``tests/sim/progress_reference.py``).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from conesim.core.compiled import cached_njit
from conesim.core.polyline import Polyline
from conesim.core.projection import Projection
from conesim.sim.kernel_math import py_max, py_min


def _probe() -> None:
    """Nothing: what ``cached_njit`` asks numba to cache, from this file's directory."""


_compiled = cached_njit(_probe, "conesim.sim.progress")


class PolylineProgress:
    """Project points onto a polyline, tracking the segment between calls.

    Args:
        line: the polyline in driving order, at least 2 points, no two
            consecutive ones equal.
        window_m: half-width of the search window around the nearest vertex [m].

    Attributes:
        line: the polyline.
        closed: whether its last vertex joins the first.
        length: its length [m] (``Polyline.length``).
    """

    def __init__(self, line: Polyline, window_m: float = 15.0) -> None:
        if len(line) < 2:
            raise ValueError("PolylineProgress needs at least 2 points")
        self.line = line
        self.closed = line.closed
        self._starts = line.ring[:-1]
        self._deltas = line.deltas
        self._lengths = line.segment_lengths
        if np.any(self._lengths <= 0.0):
            raise ValueError("PolylineProgress: repeated consecutive points")
        self._tangents = self._deltas / self._lengths[:, None]
        self._s0 = line.stations[:-1]
        self.length = line.length
        step = float(np.median(self._lengths))
        self._window = max(2, math.ceil(window_m / step))
        self._vertices = np.ascontiguousarray(line.points, dtype=float)  # (m, 2), the search's
        self._vertices.setflags(write=False)
        # Plain-float copies for the scalar walk (faster than numpy per element).
        self._starts_list = [(float(a), float(b)) for a, b in self._starts]
        self._tangents_list = [(float(a), float(b)) for a, b in self._tangents]
        self._lengths_list = [float(v) for v in self._lengths]
        self._s0_list = [float(v) for v in self._s0]
        # (start x, start y, tangent x, tangent y, length) of each segment, for the walk.
        self._segments = np.column_stack([self._starts, self._tangents, self._lengths])
        self._segments.setflags(write=False)
        self._s0_array = np.ascontiguousarray(self._s0, dtype=float)
        # The walk's kernels compile (or load) now, not in the first step (a pure call).
        sx, sy = self._starts_list[0]
        _walked(self._segments, self._s0_array, sx, sy, 0, self.closed)
        _search(self._vertices, self._segments, sx, sy, self._window, self.closed)
        self._last: int | None = None

    def reset(self) -> None:
        """Forget the last segment: the next query searches globally."""
        self._last = None

    def project(self, xy: NDArray[np.float64] | tuple[float, float]) -> Projection:
        """Project one point (2,) [m]: a ``Projection`` of one row.

        Its station and segment are :meth:`project_xy`'s; its ``lateral``
        is the same offset to within rounding (``project_xy`` keeps the
        perpendicular where the foot is inside the segment).
        """
        px, py = float(xy[0]), float(xy[1])
        i = self._last
        i, d2, u, offset = self._search(px, py) if i is None else self._walk(px, py, i)
        self._last = i
        sx, sy = self._starts_list[i]
        tx, ty = self._tangents_list[i]
        return Projection(
            foot=np.array([[sx + tx * u, sy + ty * u]]),
            segment=np.array([i], dtype=np.intp),
            station=np.array([self._s0_list[i] + u]),
            offset=np.array([offset]),
            tangent=np.array([[tx, ty]]),
            distance=np.array([math.sqrt(d2)]),
        )

    def _search(self, px: float, py: float) -> tuple[int, float, float, float]:
        """The nearest of the segments within the window around the nearest
        vertex: (segment, distance^2, the foot's arc position u, perpendicular offset)."""
        seg, d2, u, lateral = _search(
            self._vertices, self._segments, px, py, self._window, self.closed
        )
        return int(seg), d2, u, lateral

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

    def nearer_stretch(
        self, px: float, py: float, walked: tuple[float, float, int, float, float], margin: float
    ) -> tuple[float, float, int, float, float]:
        """The walk's projection ``walked`` of (px, py) (:meth:`project_xy`'s), or that
        of a stretch a whole-path search finds ``margin`` [m] nearer, from which the
        walk then goes on (a point that left the line and rejoined it elsewhere)."""
        s, lateral, index, tx, ty = self.project_xy_anew(px, py)
        if abs(lateral) < abs(walked[1]) - margin:
            self.restart_at(index)
            return s, lateral, index, tx, ty
        return walked

    def project_xy(self, px: float, py: float) -> tuple[float, float, int, float, float]:
        """:meth:`project` of one point on plain floats: (s, lateral, index, tx, ty).

        The same station, segment and tangent, without building a
        ``Projection`` (race control's per-step path). ``lateral`` is the
        signed distance to the foot, + left [m]: the perpendicular offset
        where the foot is inside the segment, else the distance to the
        segment's end with the offset's sign (``Projection.lateral``'s
        meaning, on plain floats).
        """
        i = self._last
        if i is not None:
            s, lateral, i, tx, ty = _walked(self._segments, self._s0_array, px, py, i, self.closed)
            self._last = i
            return s, lateral, i, tx, ty
        i, d2, u, offset = self._search(px, py)
        self._last = i
        tx, ty = self._tangents_list[i]
        return self._s0_list[i] + u, _offset(offset, d2, u, self._lengths_list[i]), i, tx, ty

    def _walk(self, px: float, py: float, i: int) -> tuple[int, float, float, float]:
        """From segment i on to each neighbour while it is nearer: (segment,
        distance^2, the foot's arc position u, perpendicular offset)."""
        j, d2, u, lateral = _walk(self._segments, px, py, i, self.closed)
        return int(j), d2, u, lateral


@_compiled
def _search(vertices, segments, px, py, window, closed):  # noqa: PLR0917
    """:meth:`PolylineProgress._search`, compiled: the segments ``nearest - window``
    to ``nearest + window`` around the vertex nearest to (px, py) (the first of
    equals; wrapped on a loop, clipped on an open line), and of those the nearest
    (the first of equals, in that order). Race control searches the whole line
    each metre the car moves off the track."""
    nearest = 0
    best = math.inf
    for k in range(vertices.shape[0]):
        dx, dy = vertices[k, 0] - px, vertices[k, 1] - py
        d2 = dx * dx + dy * dy
        if d2 < best:
            nearest, best = k, d2
    n = segments.shape[0]
    seg, best_d2, best_u, best_lat = -1, math.inf, 0.0, 0.0
    for k in range(nearest - window, nearest + window + 1):
        j = k % n if closed else k
        if not 0 <= j < n:
            continue
        sx, sy, tx, ty, length = (
            segments[j, 0], segments[j, 1], segments[j, 2], segments[j, 3], segments[j, 4]
        )  # fmt: skip
        rx, ry = px - sx, py - sy
        u = py_min(py_max(rx * tx + ry * ty, 0.0), length)
        # p - (start + t u), not the walk's (p - start) - t u: the numpy search's rounding
        fx, fy = px - (sx + tx * u), py - (sy + ty * u)
        d2 = fx * fx + fy * fy
        if seg < 0 or d2 < best_d2:
            seg, best_d2, best_u, best_lat = j, d2, u, tx * fy - ty * fx
    return seg, best_d2, best_u, best_lat


@_compiled
def _walk(segments, px, py, i, closed):
    """:meth:`PolylineProgress._walk` on the (n, 5) ``segments`` (start, unit
    tangent, length), compiled: it runs every physics step."""
    n = segments.shape[0]
    sx, sy, tx, ty, length = (
        segments[i, 0],
        segments[i, 1],
        segments[i, 2],
        segments[i, 3],
        segments[i, 4],
    )
    rx, ry = px - sx, py - sy
    u = py_min(py_max(rx * tx + ry * ty, 0.0), length)
    fx, fy = rx - tx * u, ry - ty * u
    best_d2, best_u, best_lat = fx * fx + fy * fy, u, tx * fy - ty * fx
    for di in (1, -1):
        while True:
            j = i + di
            if closed:
                j %= n
            elif not 0 <= j < n:
                break
            sx, sy, tx, ty, length = (
                segments[j, 0], segments[j, 1], segments[j, 2], segments[j, 3], segments[j, 4]
            )  # fmt: skip
            rx, ry = px - sx, py - sy
            u = py_min(py_max(rx * tx + ry * ty, 0.0), length)
            fx, fy = rx - tx * u, ry - ty * u
            d2 = fx * fx + fy * fy
            if d2 >= best_d2:
                break
            i, best_d2, best_u, best_lat = j, d2, u, tx * fy - ty * fx
    return i, best_d2, best_u, best_lat


@_compiled
def _walked(segments, s0, px, py, i, closed):  # noqa: PLR0917
    """:meth:`PolylineProgress.project_xy` after the walk from segment ``i``:
    (s, lateral, segment, tangent x, tangent y), compiled."""
    j, d2, u, lateral = _walk(segments, px, py, i, closed)
    return s0[j] + u, _offset(lateral, d2, u, segments[j, 4]), j, segments[j, 2], segments[j, 3]


@_compiled
def _offset(lateral, d2, u, length):
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
