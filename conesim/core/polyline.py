"""The polyline: stations, interpolation, resampling, projection, curvature, crossings.

One type for every line conesim measures along: a track's centreline and
boundaries, race control's centreline, the global path and the planner's
paths, the lap-time limit's centreline. A polyline is n points [m] in
order; a closed one joins its last point back to its first (and never
repeats the first point), so it has n segments, an open one n - 1.

Race control's per-step walk (``sim.progress``) and the planner's compiled
nearest-segment search (``planner.geometry``) are specialised projectors
built on a ``Polyline``'s segments; they answer with the same
:class:`~conesim.core.projection.Projection`.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
from numpy.typing import ArrayLike, NDArray

from conesim.core.projection import Projection

FloatArray = NDArray[np.float64]

_CHUNK = 1_000_000  # query x segment pairs per chunk of the brute-force projection and crossings


@dataclass(frozen=True, eq=False)
class Polyline:
    """A polyline in the plane, open or closed.

    Args:
        points: (n, 2) vertices in order [m], n >= 1; copied, read-only.
        closed: whether the last vertex joins the first.

    Attributes:
        points: (n, 2) the vertices [m].
        closed: whether the last vertex joins the first.
    """

    points: FloatArray
    closed: bool = False

    def __post_init__(self) -> None:
        points = np.array(self.points, dtype=float)
        if points.ndim != 2 or points.shape[1] != 2 or len(points) == 0:
            raise ValueError(f"Polyline: points must be (n, 2) with n >= 1, got {points.shape}")
        points.setflags(write=False)
        object.__setattr__(self, "points", points)
        object.__setattr__(self, "closed", bool(self.closed))

    def __len__(self) -> int:
        """The number of vertices n."""
        return len(self.points)

    @cached_property
    def ring(self) -> FloatArray:
        """(k + 1, 2) the segments' end points in order [m]: the vertices, the
        first repeated at the end if closed."""
        return np.vstack([self.points, self.points[:1]]) if self.closed else self.points

    @cached_property
    def deltas(self) -> FloatArray:
        """(k, 2) each segment's vector from its start ``ring[i]`` to its end [m]."""
        return np.diff(self.ring, axis=0)

    @cached_property
    def segment_lengths(self) -> FloatArray:
        """(k,) each segment's length [m] (``np.hypot``)."""
        return np.hypot(self.deltas[:, 0], self.deltas[:, 1])

    @cached_property
    def stations(self) -> FloatArray:
        """(k + 1,) arc length at each point of :attr:`ring` [m]: 0, then the
        running sum of the segment lengths (``np.cumsum``)."""
        return np.concatenate([[0.0], np.cumsum(self.segment_lengths)])

    @property
    def end_station(self) -> float:
        """The last of :attr:`stations` [m]: where the station axis ends, and
        where a closed polyline's stations wrap (:meth:`at`)."""
        return float(self.stations[-1])

    @cached_property
    def length(self) -> float:
        """The total length [m], the segment lengths summed (``np.sum``, pairwise).

        :attr:`end_station` to within rounding (the running sum rounds
        more): a lap's length, by which race control and the planner wrap a
        loop's station differences.
        """
        return float(self.segment_lengths.sum())

    def at(self, stations: ArrayLike) -> FloatArray:
        """Points (q, 2) [m] at arc lengths ``stations`` (q,) [m], linear in between.

        A closed polyline wraps the stations modulo :attr:`end_station`; an
        open one clamps them to its ends.
        """
        query, cum, (x, y) = self._wrap(stations), self.stations, self._ring_columns
        return np.column_stack([np.interp(query, cum, x), np.interp(query, cum, y)])

    @cached_property
    def _ring_columns(self) -> tuple[FloatArray, FloatArray]:
        """:attr:`ring`'s x and y, each contiguous (``np.interp`` copies a strided column
        at every call)."""
        ring = self.ring
        return np.ascontiguousarray(ring[:, 0]), np.ascontiguousarray(ring[:, 1])

    def interpolate(self, values: FloatArray, stations: ArrayLike) -> FloatArray:
        """Values given at the points of :attr:`ring`, (k + 1,), at arc lengths
        ``stations`` [m] (any shape), linear in station; wrapped or clamped as in :meth:`at`."""
        out: FloatArray = np.asarray(np.interp(self._wrap(stations), self.stations, values))
        return out

    def _wrap(self, stations: ArrayLike) -> FloatArray:
        """``stations`` [m] modulo :attr:`end_station` (closed) or clamped to [0, it] (open)."""
        s = np.asarray(stations, dtype=float)
        end = self.stations[-1]
        wrapped: FloatArray = np.mod(s, end) if self.closed else np.minimum(np.maximum(s, 0.0), end)
        return wrapped

    def resample(self, spacing: float, start: float = 0.0) -> Polyline:
        """The polyline through points evenly spaced about ``spacing`` [m] apart.

        A closed polyline gets round(L / spacing) points (at least 3) from arc
        length ``start`` [m] on, so the gap from the last back to the first
        equals the others; an open one keeps both end points (at least 2) and
        ignores ``start``.
        """
        total = self.end_station
        if self.closed:
            count = max(3, round(total / spacing))
            s = start + np.arange(count, dtype=np.float64) * (total / count)
        else:
            count = max(2, round(total / spacing) + 1)
            s = np.linspace(0.0, total, count).astype(np.float64)
        return Polyline(self.at(s), self.closed)

    def sample_every(self, spacing: float) -> Polyline:
        """The open polyline through points exactly ``spacing`` [m] of arc length
        apart from the start, and the end (so the last step may be shorter).

        A closed polyline is walked once round, back to its first point. A
        polyline of length 0 gives its first point alone.
        """
        total = self.end_station
        if total <= 0.0:
            return Polyline(self.points[:1], False)
        s = np.arange(0.0, total, spacing)
        if total - s[-1] > 1e-9:
            s = np.append(s, total)
        pts = self.ring
        x = np.interp(s, self.stations, pts[:, 0])
        return Polyline(np.column_stack([x, np.interp(s, self.stations, pts[:, 1])]), False)

    def project(self, query: ArrayLike, extend_ends: bool = False) -> Projection:
        """Each query point's nearest point on the polyline (exact, every segment tried).

        Ties go to the lower segment index.

        Args:
            query: (q, 2) points [m] (or one (2,) point).
            extend_ends: for an open polyline, extend the first and last
                segments to infinity (for points beyond its ends): their
                stations may then be negative or beyond the length.

        Returns:
            The (q,) projections.
        """
        a, d = self.ring[:-1], self.deltas
        seg_len2 = np.maximum(np.einsum("ij,ij->i", d, d), 1e-18)
        cum = self.stations
        q = np.asarray(query, dtype=float).reshape(-1, 2)
        n = len(q)
        station, offset, distance = np.empty(n), np.empty(n), np.empty(n)
        foot_out, tangent = np.empty((n, 2)), np.empty((n, 2))
        segment = np.empty(n, dtype=np.intp)
        lo = np.zeros(len(a))
        hi = np.ones(len(a))
        if extend_ends and not self.closed:
            lo[0], hi[-1] = -np.inf, np.inf
        chunk = max(1, _CHUNK // max(1, len(a)))
        for start in range(0, n, chunk):
            rows = slice(start, start + chunk)
            qc = q[rows]
            rel = qc[:, None, :] - a[None, :, :]
            t = np.clip(np.einsum("qij,ij->qi", rel, d) / seg_len2, lo, hi)
            foot = a[None] + t[..., None] * d[None]
            dist2 = np.sum((qc[:, None, :] - foot) ** 2, axis=2)
            best = np.argmin(dist2, axis=1)
            pick = np.arange(len(qc))
            f = foot[pick, best]
            seg = d[best]
            length = np.sqrt(seg_len2[best])
            cross = seg[:, 0] * (qc[:, 1] - f[:, 1]) - seg[:, 1] * (qc[:, 0] - f[:, 0])
            cross = self._vertex_sides(qc, f, best, t[pick, best], cross)
            station[rows] = cum[best] + t[pick, best] * length
            offset[rows] = cross / length
            distance[rows] = np.sqrt(dist2[pick, best])
            foot_out[rows] = f
            tangent[rows] = seg / length[:, None]
            segment[rows] = best
        return Projection(foot_out, segment, station, offset, tangent, distance)

    def _vertex_sides(
        self,
        q: FloatArray,
        foot: FloatArray,
        best: NDArray[np.intp],
        t: FloatArray,
        cross: FloatArray,
    ) -> FloatArray:
        """``cross`` with its sign taken, where the foot is a vertex between two
        segments, from the vertex's bisecting normal (the sum of the two segments'
        unit left normals): at an acute vertex the chosen segment's own side is
        wrong for the points ahead of it (a lane cone between a gate's wider
        cones: a point 2 m inside the lane read as 2 m outside)."""  # fmt: skip
        m = len(self.deltas)
        at_start = (t <= 0.0) & ((best > 0) | self.closed)
        at_end = (t >= 1.0) & ((best < m - 1) | self.closed)
        vertex = at_start | at_end
        if not vertex.any() or m < 2:
            return cross
        other = np.where(at_start, best - 1, best + 1) % m
        lengths = np.maximum(self.segment_lengths, 1e-18)[:, None]
        bisector = (  # the unit normals' sum, turned back by 90 deg
            self.deltas[best] / lengths[best] + self.deltas[other] / lengths[other]
        )
        side = bisector[:, 0] * (q[:, 1] - foot[:, 1]) - bisector[:, 1] * (q[:, 0] - foot[:, 0])
        flipped = vertex & (side * cross < 0.0)
        return np.where(flipped, -cross, cross)

    def tangents(self) -> FloatArray:
        """(n, 2) unit tangents at the vertices by central differences
        (one-sided at an open polyline's ends)."""
        p = self.points
        if self.closed:
            d = np.roll(p, -1, axis=0) - np.roll(p, 1, axis=0)
        else:
            d = np.gradient(p, axis=0)
        norm = np.maximum(np.hypot(d[:, 0], d[:, 1]), 1e-12)
        return d / norm[:, None]

    def curvature(self) -> FloatArray:
        """(n,) signed curvature at the vertices [1/m], + turning left (Menger).

        The curvature of the circle through each vertex and its two
        neighbours::

            kappa_i = 2 cross(p_i - p_{i-1}, p_{i+1} - p_i)
                      / (|p_i - p_{i-1}| |p_{i+1} - p_i| |p_{i+1} - p_{i-1}|)

        exactly 1/R for vertices on a circle of radius R, 0 where two of the
        three coincide. A closed polyline's neighbours wrap round; an open
        one's end vertices take their neighbour's value (all 0 below 3
        vertices). The planner's speed profile computes the same numbers in
        its compiled kernel (``planner.kernels.profile_limits``).
        """
        p = self.points
        n = len(p)
        if self.closed:
            if n < 3:
                return np.zeros(n)
            return _menger(np.vstack([p[-1:], p, p[:1]]))
        if n < 3:
            return np.zeros(n)
        inner = _menger(p)
        return np.concatenate([inner[:1], inner, inner[-1:]])

    def crossings(self, other: Polyline | None = None) -> list[tuple[int, int]]:
        """Pairs (i, j) of segments whose interiors properly cross.

        Args:
            other: a second polyline (i indexes this one's segments, j the
                other's); None checks this polyline against itself, skipping
                segments that share a vertex (so i < j - 1).
        """
        p, r = self.ring[:-1], self.deltas
        q, s = (p, r) if other is None else (other.ring[:-1], other.deltas)
        found: list[tuple[int, int]] = []
        rows = max(1, _CHUNK // max(1, len(q)))
        for start in range(0, len(p), rows):
            i, j = _crossing_pairs(p[start : start + rows], r[start : start + rows], q, s)
            i = i + start
            if other is None:
                keep = j > i + 1
                if self.closed:
                    keep &= ~((i == 0) & (j == len(p) - 1))
                i, j = i[keep], j[keep]
            found += [(int(a_), int(b_)) for a_, b_ in zip(i, j, strict=True)]
        return found

    def signed_area(self) -> float:
        """The signed area of the polygon the vertices bound [m^2], + counter-clockwise
        (as if closed: the shoelace formula)."""
        x, y = self.points[:, 0], self.points[:, 1]
        return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y))


def _menger(p: FloatArray) -> FloatArray:
    """(m - 2,) Menger curvature [1/m] at the inner points of (m, 2) points [m],
    with the planner kernel's operations in its order."""
    d = np.diff(p, axis=0)
    step = np.hypot(d[:, 0], d[:, 1])
    chord = p[2:] - p[:-2]
    cross = d[:-1, 0] * d[1:, 1] - d[:-1, 1] * d[1:, 0]
    denom = step[:-1] * step[1:] * np.hypot(chord[:, 0], chord[:, 1])
    with np.errstate(divide="ignore", invalid="ignore"):
        kappa: FloatArray = np.where(denom > 0.0, 2.0 * cross / denom, 0.0)
    return kappa


def _crossing_pairs(
    p: FloatArray, r: FloatArray, q: FloatArray, s: FloatArray
) -> tuple[NDArray[np.intp], NDArray[np.intp]]:
    """Index pairs (i, j) where segment p_i + t r_i properly crosses q_j + u s_j."""
    rxs = r[:, None, 0] * s[None, :, 1] - r[:, None, 1] * s[None, :, 0]
    qp = q[None, :, :] - p[:, None, :]
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        t = (qp[..., 0] * s[None, :, 1] - qp[..., 1] * s[None, :, 0]) / rxs
        u = (qp[..., 0] * r[:, None, 1] - qp[..., 1] * r[:, None, 0]) / rxs
    eps = 1e-9
    hit = (np.abs(rxs) > 1e-12) & (t > eps) & (t < 1 - eps) & (u > eps) & (u < 1 - eps)
    i, j = np.nonzero(hit)
    return i.astype(np.intp), j.astype(np.intp)
