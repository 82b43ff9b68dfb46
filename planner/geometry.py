"""Plane geometry of the planner: projection onto the global path, stations, crossings.

Projection onto the nearest segment (the ROS pipeline's ``classify_cones_by_side``):
for a point ``p`` and a segment from ``a`` with direction ``d``::

    t    = clip(((p - a) . d) / |d|^2, 0, 1)      foot = a + t d
    side = cross(d, p - a) = d_x (p - a)_y - d_y (p - a)_x   (> 0: left)

The signed offset is ``side / |d|`` (distance from the segment's line, + left)
and the station is the arc length from the path's first point to the foot.

Finding the nearest segment exactly without testing all of them: the
segments are grouped 16 at a time (consecutive along the path) into
bounding circles; no segment of a circle (x, y, r) is nearer to ``p`` than
``|p - (x, y)| - r``. A circle whose bound exceeds the best score found so
far (plus 1e-9 m for rounding) is skipped. Ties of the score go to the
nearer segment midpoint, then to the lower index.

A path that passes the same place more than once (the skidpad's centre, a
crossing) makes "the nearest segment" ambiguous. ``project`` therefore takes
an optional station window [lo, hi] (wrapped on a closed path) and a penalty:
segments outside the window count as ``penalty`` metres farther. Near-ties go
to the window's stretch; a point clearly nearest another stretch still
projects there. The same bound holds with distances plus penalties: the
circles holding a window segment are searched first (nearest bound first),
the others only when the best score reaches ``penalty``, which for a cone
near the current stretch it does not.

The search, the projection's numbers, the arc length and the crossing test
(``crosses_boundary``) are compiled (``planner.kernels``): they run per
detection.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from conesim.core.polyline import Polyline
from conesim.core.projection import Projection
from conesim.planner import kernel_chains, kernels

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.intp]


_BLOCK = 16  # segments per bounding circle of the search (``kernels.nearest_segments``)


# Columns of the segment table: start x, y, direction x, y, 1 / length^2,
# mid-station, half length, length, start station.
_SX, _SY, _DX, _DY, _INV_LEN2, _MID_STATION, _HALF_LENGTH, _LENGTH, _STATION0 = range(9)


class PathProjector:
    """Nearest-segment projection onto a polyline (compiled search over bounding circles).

    Args:
        line: the global path in ``reference`` (``GlobalPath.polyline``); a
            closed one includes the segment from its last point back to its
            first. Segments of length 0 are left out.

    Attributes:
        line: the polyline.
        length: its length [m] (``Polyline.length``).
        closed: whether stations wrap around at ``length``.
    """

    def __init__(self, line: Polyline) -> None:
        keep = line.segment_lengths > 0.0
        self._start = line.ring[:-1][keep]
        self._delta = line.deltas[keep]
        self._length = line.segment_lengths[keep]
        self._half_length = 0.5 * self._length
        self._station0 = line.stations[:-1][keep]
        self._mid_station = self._station0 + self._half_length
        self._half_max = 0.5 * float(self._length.max())
        self._blocks = _bounding_circles(self._start, self._delta)
        # One row per segment (columns ``_SX`` ...), gathered with a single
        # ``take`` per query.
        self._table = np.column_stack(
            [
                self._start,
                self._delta,
                1.0 / self._length**2,
                self._mid_station,
                self._half_length,
                self._length,
                self._station0,
            ]
        )
        self.length = line.length
        self.closed = line.closed
        self.line = line
        self._axis = StationAxis(self.length, self.closed)

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
        p = np.ascontiguousarray(np.asarray(points, dtype=float).reshape(-1, 2))
        lo, hi = (0.0, 0.0) if window is None else (float(window[0]), float(window[1]))
        # One compiled call: the window's test and the search.
        seg, foot, station, offset, tangent, distance = kernel_chains.project_window(
            p,
            self._table,
            self._blocks,
            _BLOCK,
            window is not None,
            lo,
            hi,
            float(penalty),
            self.length,
            self.closed,
            self._half_max,
        )
        return Projection(foot, seg, station, offset, tangent, distance)

    def project_around(
        self,
        points: FloatArray,
        back: float,
        ahead: float,
        penalty: float,
        centre: float | None = None,
    ) -> Projection:
        """Project (n, 2) points preferring the stretch around the last point (the sensor).

        The same as ``project(points, (centre - back, centre + ahead), penalty)``
        where ``centre`` is None is the last point's station on the whole path
        (``project(points[-1:]).station[0]``); ``penalty <= 0`` projects with no
        window.

        Args:
            points: (n, 2) [m], n >= 1; the last row is the window's origin.
            back: the window starts this far behind ``centre`` [m] ...
            ahead: ... and ends this far ahead of it [m].
            penalty: see :meth:`project`.
            centre: the window's origin station [m], if known.
        """
        p = np.ascontiguousarray(np.asarray(points, dtype=float).reshape(-1, 2))
        # One compiled call: the origin, the window and the search.
        seg, foot, station, offset, tangent, distance = kernel_chains.project_around(
            p,
            self._table,
            self._blocks,
            _BLOCK,
            float(back),
            float(ahead),
            float(penalty),
            centre is not None,
            0.0 if centre is None else float(centre),
            self.length,
            self.closed,
            self._half_max,
        )
        return Projection(foot, seg, station, offset, tangent, distance)

    @property
    def axis(self) -> StationAxis:
        """The path's station axis."""
        return self._axis


def _bounding_circles(start: FloatArray, delta: FloatArray) -> FloatArray:
    """(b, 3) circles (x, y, r) holding each ``_BLOCK`` consecutive segments, r padded by 1e-9."""
    ends = np.concatenate([start, start + delta], axis=1).reshape(-1, 4)
    circles = []
    for first in range(0, len(start), _BLOCK):
        xy = ends[first : first + _BLOCK].reshape(-1, 2)
        centre = 0.5 * (xy.min(axis=0) + xy.max(axis=0))
        radius = float(np.hypot(*(xy - centre).T).max())
        circles.append([centre[0], centre[1], radius * (1.0 + 1e-12) + 1e-9])
    return np.array(circles, dtype=float).reshape(-1, 3)


@dataclass(frozen=True, slots=True)
class StationAxis:
    """Arc length along a global path, which wraps around on a closed path.

    Attributes:
        length: path length [m].
        closed: whether stations wrap at ``length``.
    """

    length: float
    closed: bool


def crosses_boundary(points: FloatArray, boundary: FloatArray) -> bool:
    """Whether the polyline (p, 2) [m] properly crosses any of the (e, 2, 2) segments [m].

    Proper crossing: each segment's end points lie strictly on opposite sides
    of the other's line (touching and collinear overlap do not count). Compiled
    (``kernels.crosses_boundary``): for each segment's line, the side of each
    polyline point; only a polyline step that straddles the line is tested
    against the line through the segment, and the first crossing ends the search.
    """
    return bool(
        kernels.crosses_boundary(
            np.ascontiguousarray(points, dtype=float).reshape(-1, 2),
            np.ascontiguousarray(boundary, dtype=float).reshape(-1, 2, 2),
        )
    )


def arc_length(points: FloatArray) -> FloatArray:
    """``Polyline(points).stations`` of an open (n, 2) polyline [m]; shape (max(n, 1),).

    The same numbers, compiled (``kernels.arc_length``): the local paths'
    stations are taken several times per control step, where building a
    ``Polyline`` costs more than the sum.
    """
    s: FloatArray = kernels.arc_length(np.ascontiguousarray(points, dtype=float).reshape(-1, 2))
    return s
