"""Geometry of closed loops (trackdrive, autocross) and open lanes (acceleration).

Steps (``lane_geometry``):

1. ``unique_cones``: a cone listed twice (a layout that repeats its first
   cone to close the loop) is one cone; ``order_side``: order the blue and
   the yellow cones (ordering.py) and orient them the same way round.
2. a provisional centreline between them (midline.py).
3. ``driving_reversed``: the driving direction is the start pose's heading;
   without a start pose, the direction that puts the blue cones on the left.
4. ``assign_sides``: orange and big orange cones lying on a boundary (within
   half the local half-width of it) join that side's cones: the start line's
   big orange cones close the gap they leave in a loop's boundaries, and the
   orange braking zone extends the acceleration lane. Orange cones elsewhere
   (e.g. the fssim acceleration's end-of-lane cone on the centreline) do not.
   In a loop they are markers on the lane's edge, not its shape
   (``onto_edge``): one standing off the edge drawn through the blue (or
   yellow) cones, as a start gate wider than the lane does, joins it at its
   nearest point of that edge, so the edge does not kink out to it.
5. the final centreline, resampled every 0.5 m from the start/finish line
   (a loop) or from the lane's start (open), and the widths: distance to the
   left plus distance to the right boundary spline.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray
from scipy.spatial import cKDTree

from conesim.core.polyline import Polyline
from conesim.core.pose import Pose2D
from conesim.tracks.derived import TrackGeometry
from conesim.tracks.errors import TrackGeometryError
from conesim.tracks.kinds import ConeKind
from conesim.tracks.midline import Midline, centreline_between
from conesim.tracks.ordering import order_loop, order_path
from conesim.tracks.timing import TimingLine, big_orange_lines, perpendicular_line

FloatArray = NDArray[np.float64]

CENTRELINE_SPACING = 0.5  # [m] spacing of Track.centreline
MIN_SIDE_CONES = 3  # a boundary needs at least this many cones
SIDE_TOLERANCE = 0.5  # an orange cone joins a side within this fraction of the half-width
ON_EDGE_M = 0.05  # [m] an orange cone this close to a loop's edge is on it, as it stands
DUPLICATE_M = 0.1  # [m] cones of one side closer than this are one cone listed twice
LANE_END_FINISH_M = 1.0  # [m] an open lane without a finish line finishes this far before its end


def lane_geometry(
    cones: FloatArray, kinds: tuple[ConeKind, ...], closed: bool, start_pose: Pose2D | None
) -> TrackGeometry:
    """Derive the geometry of a loop or a lane from its cones.

    Args:
        cones: (n, 2) cone positions [m].
        kinds: (n,) their kinds.
        closed: a loop (True) or an open lane (False).
        start_pose: where the car starts; None derives the direction from the
            cone colours.

    Raises:
        TrackGeometryError: fewer than 3 blue or 3 yellow cones, or cones from
            which no centreline can be derived.
    """
    kind = np.array([str(k) for k in kinds])
    blue = unique_cones(cones[kind == ConeKind.BLUE])
    yellow = unique_cones(cones[kind == ConeKind.YELLOW])
    if len(blue) < MIN_SIDE_CONES or len(yellow) < MIN_SIDE_CONES:
        raise TrackGeometryError(
            f"a track needs at least {MIN_SIDE_CONES} blue (left) and {MIN_SIDE_CONES} "
            f"yellow (right) cones, found {len(blue)} blue and {len(yellow)} yellow"
        )
    left = order_side(blue, closed)
    right = align_to(order_side(yellow, closed), left, closed)
    mid = centreline_between(left, right, closed)
    if driving_reversed(mid, start_pose, blue):
        left, right = left[::-1], right[::-1]
        mid = centreline_between(left, right, closed)
    orange = cones[(kind == ConeKind.ORANGE) | (kind == ConeKind.BIG_ORANGE)]
    if len(orange):
        on_left, on_right = assign_sides(orange, mid)
        if closed:
            on_left, on_right = onto_edge(on_left, mid.left), onto_edge(on_right, mid.right)
        left = orient_like(order_side(np.vstack([blue, on_left]), closed), mid)
        right = align_to(order_side(np.vstack([yellow, on_right]), closed), left, closed)
        mid = centreline_between(left, right, closed)
    lines = _timing_lines(cones[kind == ConeKind.BIG_ORANGE], mid, start_pose)
    return _finish(mid, left, right, lines)


def unique_cones(points: FloatArray) -> FloatArray:
    """The cones (n, 2) [m] without repeats: of cones closer than ``DUPLICATE_M``
    to an earlier one, only the earlier is kept."""
    pairs = cKDTree(points).query_pairs(DUPLICATE_M, output_type="ndarray")
    if len(pairs) == 0:
        return points
    keep = np.ones(len(points), dtype=bool)
    keep[np.max(pairs, axis=1)] = False
    return points[keep]


def onto_edge(markers: FloatArray, edge: FloatArray) -> FloatArray:
    """Marker cones (k, 2) [m] moved to their nearest point of the dense ``edge`` (p, 2)
    [m], those farther than ``ON_EDGE_M`` from it; those on it stay as they stand."""
    if len(markers) == 0:
        return markers
    distance, nearest = cKDTree(edge).query(markers)
    return np.where((distance > ON_EDGE_M)[:, None], edge[nearest], markers)


def order_side(points: FloatArray, closed: bool) -> FloatArray:
    """The cones of one boundary in tour order (direction arbitrary)."""
    return points[order_loop(points) if closed else order_path(points)]


def align_to(other: FloatArray, reference: FloatArray, closed: bool) -> FloatArray:
    """``other`` ordered the same way round as ``reference`` and, for a loop,
    starting at its cone nearest to ``reference[0]``."""
    if closed:
        if np.sign(Polyline(other).signed_area()) != np.sign(Polyline(reference).signed_area()):
            other = other[::-1]
        first = int(np.argmin(np.hypot(*(other - reference[0]).T)))
        return np.roll(other, -first, axis=0)
    same = np.hypot(*(other[0] - reference[0])) + np.hypot(*(other[-1] - reference[-1]))
    crossed = np.hypot(*(other[-1] - reference[0])) + np.hypot(*(other[0] - reference[-1]))
    return other[::-1] if crossed < same else other


def orient_like(points: FloatArray, mid: Midline) -> FloatArray:
    """Ordered boundary cones turned to run in the direction of ``mid``."""
    if mid.closed:
        same = np.sign(Polyline(points).signed_area()) == np.sign(mid.line.signed_area())
        return points if same else points[::-1]
    s = mid.line.project(points[[0, -1]]).station
    return points if s[0] <= s[1] else points[::-1]


def driving_reversed(mid: Midline, start_pose: Pose2D | None, blue: FloatArray) -> bool:
    """Whether the driving direction is against the direction of ``mid``.

    With a start pose: its heading against the centreline's tangent where it
    stands. Without: most blue cones on the right of ``mid``.
    """
    if start_pose is None:
        lateral = mid.line.project(blue).lateral
        return bool(np.sum(np.sign(lateral)) < 0)
    s = mid.line.project(start_pose.xy).station
    ahead = _point_at(mid, s[0] + 0.25) - _point_at(mid, s[0] - 0.25)
    heading = np.array([np.cos(start_pose.yaw), np.sin(start_pose.yaw)])
    return bool(np.dot(ahead, heading) < 0)


def assign_sides(orange: FloatArray, mid: Midline) -> tuple[FloatArray, FloatArray]:
    """Orange cones lying on the left and on the right boundary.

    A cone is on a side when its distance from the centreline (extended
    beyond the ends of a lane) is within ``SIDE_TOLERANCE`` of the local
    half-width, measured where the centreline ends for cones beyond it.
    """
    lateral = mid.line.project(orange, extend_ends=not mid.closed).lateral
    dl, dr = mid.half_widths(mid.line.project(orange).foot)
    half = np.where(lateral > 0, dl, dr)
    near = np.abs(np.abs(lateral) - half) <= np.maximum(SIDE_TOLERANCE * half, 0.5)
    return orange[near & (lateral > 0)], orange[near & (lateral <= 0)]


def _timing_lines(big: FloatArray, mid: Midline, start_pose: Pose2D | None) -> list[TimingLine]:
    lines = big_orange_lines(big, mid)
    if mid.closed:
        if start_pose is None:
            return lines[:1] or [perpendicular_line(mid, 0.0)]
        s_start = float(mid.line.project(start_pose.xy).station[0])
        if not lines:
            return [perpendicular_line(mid, s_start)]
        total = mid.line.end_station
        ahead = [((line.s - s_start) % total, line) for line in lines]
        return [min(ahead, key=lambda pair: min(pair[0], total - pair[0]))[1]]
    if not lines:
        s0 = 0.0
        if start_pose is not None:
            s0 = float(mid.line.project(start_pose.xy).station[0])
        lines = [perpendicular_line(mid, s0)]
    if len(lines) == 1:
        # No finish line of big orange cones: the run ends at the lane's end
        # (the validator warns), not never.
        end = perpendicular_line(mid, mid.line.end_station - LANE_END_FINISH_M)
        if end.s > lines[0].s:
            lines.append(end)
    return lines


def _finish(
    mid: Midline, left: FloatArray, right: FloatArray, lines: list[TimingLine]
) -> TrackGeometry:
    closed = mid.closed
    start_s = lines[0].s if closed else 0.0
    line = mid.line.resample(CENTRELINE_SPACING, start=start_s)
    centreline = line.points
    if len(centreline) < 3:
        raise TrackGeometryError("the centreline is shorter than 1 m")
    dl, dr = mid.half_widths(centreline)
    if closed:
        start_point = lines[0].ends.mean(axis=0)
        left = _roll_to(left, start_point)
        right = _roll_to(right, start_point)
        direction = line.tangents()[0]
    else:
        direction = _unit(_point_at(mid, lines[0].s + 0.25) - _point_at(mid, lines[0].s - 0.25))
    return TrackGeometry(
        centreline=centreline,
        widths=dl + dr,
        left_boundary=np.array(left, dtype=float),
        right_boundary=np.array(right, dtype=float),
        timing_lines=tuple(np.array(line.ends, dtype=float) for line in lines),
        direction=direction,
        length_m=mid.line.end_station,
        closed=closed,
        curvature=line.curvature(),
    )


def _point_at(mid: Midline, s: float) -> FloatArray:
    return mid.line.at([s])[0]


def _roll_to(points: FloatArray, target: FloatArray) -> FloatArray:
    return np.roll(points, -int(np.argmin(np.hypot(*(points - target).T))), axis=0)


def _unit(v: FloatArray) -> FloatArray:
    return v / max(float(np.hypot(*v)), 1e-12)
