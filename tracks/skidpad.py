"""Geometry of the Formula Student skidpad (figure of eight).

FS layout (REFERENCES.md, "Formula Student tracks"): two pairs of concentric
circles, inner diameter 15.25 m and outer 21.25 m, centres 18.25 m apart, so
the 3 m wide tracks of the two circles touch where the entry lane crosses.
The FS procedure: enter the lane, drive two laps clockwise on the right
circle (the second timed), then two laps counter-clockwise on the left circle
(the second timed), and leave along the exit lane in the entry direction.

What we derive:

1. ``find_circles``: split the blue and yellow cones into two groups
   (``scipy.cluster.vq.kmeans2``) and fit a circle to each colour of each
   group (algebraic fit refined by ``scipy.optimize.least_squares``). Each
   group must give two concentric rings: the inner and outer cones.
2. the right circle is the one on the right of the start pose's heading
   (without a start pose: the one whose inner ring is yellow, the right
   side of a car driving it clockwise).
3. the centreline: the entry lane up to the crossing (midway between the
   centres), ONE clockwise lap of the right circle, ONE counter-clockwise lap
   of the left circle, each on radius (r_inner + r_outer) / 2, then the exit
   lane; resampled every 0.5 m. One lap each, not two: the second lap retraces
   the first, so a centreline for progress and error measures needs only one.
4. boundaries: the centreline offset by half the width to each side (the
   rings cross each other, so cone polylines would not make boundaries).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.cluster.vq import kmeans2
from scipy.optimize import least_squares

from conesim.core.polyline import Polyline
from conesim.core.pose import Pose2D
from conesim.tracks.derived import SkidpadCircle, TrackGeometry
from conesim.tracks.errors import TrackGeometryError
from conesim.tracks.kinds import ConeKind

FloatArray = NDArray[np.float64]

MIN_RING_CONES = 4  # fewest cones that define a ring
MAX_RING_RMS = 0.25  # [m] cones further off a fitted circle: not a ring
CONCENTRIC_TOL = 1.0  # [m] inner and outer ring centres must agree within this
STEP = 0.05  # [m] sampling of the circles and lanes before resampling
CENTRELINE_SPACING = 0.5  # [m]


def fit_circle(points: FloatArray) -> tuple[FloatArray, float, float]:
    """Least-squares circle through ``points`` (n, 2) [m].

    Returns:
        centre (2,) [m], radius [m], RMS of the radial residuals [m].
    """
    x, y = points[:, 0], points[:, 1]
    design = np.column_stack([2 * x, 2 * y, np.ones(len(x))])
    sol, *_ = np.linalg.lstsq(design, x**2 + y**2, rcond=None)
    centre0 = sol[:2]
    r0 = float(np.sqrt(max(sol[2] + centre0 @ centre0, 1e-12)))

    def residual(p: FloatArray) -> FloatArray:
        return np.hypot(x - p[0], y - p[1]) - p[2]

    fit = least_squares(residual, np.array([*centre0, r0]))
    centre, radius = fit.x[:2], float(abs(fit.x[2]))
    return centre, radius, float(np.sqrt(np.mean(residual(fit.x) ** 2)))


def find_circles(
    blue: FloatArray, yellow: FloatArray
) -> tuple[SkidpadCircle, SkidpadCircle] | None:
    """The two skidpad circles, or None if the cones do not form them.

    Returns:
        Two circles, in no particular order.
    """
    if len(blue) < 2 * MIN_RING_CONES or len(yellow) < 2 * MIN_RING_CONES:
        return None
    points = np.vstack([blue, yellow])
    is_blue = np.arange(len(points)) < len(blue)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # "one of the clusters is empty"
        _, label = kmeans2(points, 2, minit="++", rng=np.random.default_rng(0))
    circles = []
    for group in (0, 1):
        rings = []
        for colour, kind in ((True, ConeKind.BLUE), (False, ConeKind.YELLOW)):
            members = points[(label == group) & (is_blue == colour)]
            if len(members) < MIN_RING_CONES:
                return None
            centre, radius, rms = fit_circle(members)
            if rms > MAX_RING_RMS or not 1.0 < radius < 50.0:
                return None
            rings.append((radius, centre, kind))
        (r_a, c_a, k_a), (r_b, c_b, _) = sorted(rings, key=lambda ring: ring[0])
        if np.hypot(*(c_a - c_b)) > CONCENTRIC_TOL or not 1.0 < r_b - r_a < 0.8 * r_b:
            return None
        circles.append(SkidpadCircle(0.5 * (c_a + c_b), r_a, r_b, k_a))
    gap = float(np.hypot(*(circles[0].centre - circles[1].centre)))
    if (
        not 0.5 * (circles[0].radius + circles[1].radius)
        < gap
        < 4.0 * max(c.r_outer for c in circles)
    ):
        return None
    return circles[0], circles[1]


def right_and_left(
    circles: tuple[SkidpadCircle, SkidpadCircle], start_pose: Pose2D | None
) -> tuple[SkidpadCircle, SkidpadCircle]:
    """The circles ordered (right, left) relative to the driving direction."""
    a, b = circles
    if start_pose is not None:
        heading = np.array([np.cos(start_pose.yaw), np.sin(start_pose.yaw)])
        rel = a.centre - start_pose.xy
        a_is_right = heading[0] * rel[1] - heading[1] * rel[0] < 0
    else:
        a_is_right = a.inner_kind == ConeKind.YELLOW
    return (a, b) if a_is_right else (b, a)


@dataclass(frozen=True)
class _Frame:
    """The crossing of the figure of eight and the directions there.

    Attributes:
        crossing: (2,) midway between the circle centres [m].
        ahead: (2,) unit vector of driving through the crossing.
        left: (2,) unit vector to the left of ``ahead``.
        right_circle: the circle driven clockwise first.
        left_circle: the circle driven counter-clockwise next.
    """

    crossing: FloatArray
    ahead: FloatArray
    left: FloatArray
    right_circle: SkidpadCircle
    left_circle: SkidpadCircle

    @classmethod
    def of(cls, right: SkidpadCircle, left: SkidpadCircle) -> _Frame:
        across = right.centre - left.centre
        ahead = np.array([-across[1], across[0]]) / np.hypot(*across)
        return cls(
            0.5 * (right.centre + left.centre), ahead, np.array([-ahead[1], ahead[0]]), right, left
        )

    def along(self, points: FloatArray) -> FloatArray:
        """(n,) distance of points ahead of the crossing [m]."""
        return (points - self.crossing) @ self.ahead

    def lateral(self, points: FloatArray) -> FloatArray:
        """(n,) distance of points left of the lanes' axis [m]."""
        return (points - self.crossing) @ self.left


def skidpad_geometry(
    cones: FloatArray, kinds: tuple[ConeKind, ...], start_pose: Pose2D | None
) -> TrackGeometry:
    """Derive the skidpad centreline, widths, boundaries and timing line.

    Raises:
        TrackGeometryError: the blue and yellow cones do not form two pairs of
            concentric rings.
    """
    kind = np.array([str(k) for k in kinds])
    found = find_circles(cones[kind == ConeKind.BLUE], cones[kind == ConeKind.YELLOW])
    if found is None:
        raise TrackGeometryError(
            "skidpad: the blue and yellow cones do not form two pairs of concentric circles"
        )
    frame = _Frame.of(*right_and_left(found, start_pose))
    right, left = frame.right_circle, frame.left_circle
    orange = cones[kind == ConeKind.ORANGE]
    lane_width = _lane_width(orange, frame)
    s_in, s_out = _lane_extent(orange, start_pose, frame)

    entry = frame.crossing + np.outer(np.arange(s_in, 0.0, STEP), frame.ahead)
    loop_r = _circle(right, frame.crossing, clockwise=True)
    loop_l = _circle(left, frame.crossing, clockwise=False)
    leave = frame.crossing + np.outer(np.arange(0.0, s_out + STEP / 2, STEP), frame.ahead)
    dense = np.vstack([entry, loop_r, loop_l, leave])
    section = np.concatenate(
        [np.zeros(len(entry)), np.ones(len(loop_r)), np.full(len(loop_l), 2), np.zeros(len(leave))]
    )
    dense_line = Polyline(dense)
    centre = dense_line.resample(CENTRELINE_SPACING)
    centreline = centre.points
    cum = dense_line.stations
    nearest = np.clip(np.searchsorted(cum, centre.stations), 0, len(dense) - 1)
    widths = np.choose(section[nearest].astype(int), [lane_width, right.width, left.width])
    side = np.array([[-t[1], t[0]] for t in centre.tangents()])
    half = 0.5 * widths[:, None]
    line = _timing_line(cones[kind == ConeKind.BIG_ORANGE], frame, lane_width)
    return TrackGeometry(
        centreline=centreline,
        widths=np.asarray(widths, dtype=float),
        left_boundary=centreline + side * half,
        right_boundary=centreline - side * half,
        timing_lines=(line,),
        direction=frame.ahead,
        length_m=float(cum[-1]),
        closed=False,
        curvature=centre.curvature(),
        circles=(right, left),
    )


def _circle(circle: SkidpadCircle, crossing: FloatArray, clockwise: bool) -> FloatArray:
    start = np.arctan2(*(crossing - circle.centre)[::-1])
    count = max(16, int(np.ceil(2 * np.pi * circle.radius / STEP)))
    sweep = np.linspace(0.0, 2 * np.pi, count, endpoint=False) * (-1 if clockwise else 1)
    angle = start + sweep
    return circle.centre + circle.radius * np.column_stack([np.cos(angle), np.sin(angle)])


def _lane_width(orange: FloatArray, frame: _Frame) -> float:
    """Lane width: twice the median lateral offset of the orange lane cones, or
    the gap between the inner rings."""
    right, left = frame.right_circle, frame.left_circle
    if len(orange) >= 2:
        lateral, along = np.abs(frame.lateral(orange)), np.abs(frame.along(orange))
        lane = lateral[(lateral > 0.25) & (along > 0.5 * max(right.r_inner, left.r_inner))]
        if len(lane):
            return float(2.0 * np.median(lane))
    gap = float(np.hypot(*(right.centre - left.centre))) - right.r_inner - left.r_inner
    if gap <= 0:
        raise TrackGeometryError(
            "skidpad: the inner circles overlap, there is no lane between them"
        )
    return gap


def _lane_extent(
    orange: FloatArray, start_pose: Pose2D | None, frame: _Frame
) -> tuple[float, float]:
    """Start (negative) and end of the lanes along ``frame.ahead`` from the crossing [m]:
    the orange lane cones and the start pose, at least past the outer circles."""
    reach = max(frame.right_circle.r_outer, frame.left_circle.r_outer)
    marks = [frame.along(orange)]
    if start_pose is not None:
        marks.append(frame.along(start_pose.xy[None]))
    along = np.concatenate(marks)
    if not len(along):
        return -reach, reach
    return min(-reach, float(along.min())), max(reach, float(along.max()))


def _timing_line(big: FloatArray, frame: _Frame, lane_width: float) -> FloatArray:
    lateral = frame.lateral(big) if len(big) else np.zeros(0)
    if np.any(lateral > 0) and np.any(lateral <= 0):
        return np.vstack([big[lateral > 0].mean(axis=0), big[lateral <= 0].mean(axis=0)])
    half = frame.left * lane_width / 2
    return np.vstack([frame.crossing + half, frame.crossing - half])
