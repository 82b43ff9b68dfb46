"""reference_path_planning: the local path between the cones, in ``os_sensor``.

The ROS pipeline's node, step by step (each step named as a function):

1. ``cones_to_sensor``: left and right cones from ``reference`` into
   ``os_sensor`` with the latest transform (spec 000: ``Time(0)``);
   ``merge_doubled``: of two cones of a side standing closer than a cone
   spacing (a gate's big orange cones beside the edge's), the inner kept.
2. ``in_view``: cones within ``max_range``, ahead of ``min_x``, and between
   ``min_boundary_offset`` and ``max_boundary_offset`` from the global path
   (others are false positives, not boundary cones); then, once the track's
   width and middle in view are estimated, not more than ``boundary_tolerance``
   inside their boundary line (``bridges.estimate_track``).
3. ``virtual_partners``, ``delaunay_edges``, ``find_bridges`` (``bridges``):
   Delaunay on all cones, the checked left-right bridges and their midpoints.
4. ``ordered_midpoints`` (``kernels.ordering``): the used bridges' midpoints
   from the nearest one in front, chaining nearest neighbours.
5. ``fit_path`` (``spline``): B-spline through them, resampled every 0.5 m;
   ``keep_in_lane`` (``lane``): moved into the lane less the car's body.
6. ``check_path``: at least two midpoints, at least ``min_path_length`` long,
   starting within ``max_start_distance``, and crossing no boundary edge;
   6b. with a ``map_check`` (the autopilot's: ``Autopilot.off_lane_reason``),
   not leaving the lane as the global path places it, where a missed cone
   left no edge to cross.
7. ``speed_profile``: the waypoint speeds.

When step 6 fails, ``carry_path_forward`` moves the previous plan's path into
the current frame through the frame tree (old ``os_sensor`` at the old stamp
-> ``reference`` -> ``os_sensor`` now), drops what lies behind the car, and the
plan reports ``PlanStatus.FALLBACK`` with the reason; with nothing to carry
forward it is ``PlanStatus.FAILED`` with an empty path.

It runs per detection, so the steps are compiled (``planner.kernels``;
step 3's triangulation and step 5's fit are scipy's), and
``reference_path_planning`` runs the compiled steps between two scipy calls
in one call each (``planner.kernel_chains``): steps 2 and 3a in
``cones_with_partners``, steps 3 and 4 after the triangulation in
``bridges_and_midpoints``, step 6's numbers with step 7's limits after the
spline in ``kernel_chains.check_and_limit``, each
given its settings groups (``MidlineConfig.view_settings`` ...,
``SpeedProfileConfig.limit_settings``, built once per config).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from enum import StrEnum

import numpy as np
from numpy.typing import NDArray

from conesim.core.messages import FRAME_OS_SENSOR, Header
from conesim.localization.frames import LATEST, Buffer, TransformError
from conesim.planner import kernel_chains, kernels
from conesim.planner.bridges import (
    Bridges,
    ConeSet,
    PairTable,
    TrackEstimate,
    delaunay_simplices,
)
from conesim.planner.classify import LEFT, RIGHT, ClassifiedCones
from conesim.planner.config import MidlineConfig, SpeedProfileConfig
from conesim.planner.geometry import FloatArray, arc_length, crosses_boundary
from conesim.planner.lane import keep_in_lane
from conesim.planner.messages import BridgeLines, LocalPath, Midpoints, Waypoints
from conesim.planner.speed_profile import profile_speeds, speed_profile
from conesim.planner.spline import fit_path

SpeedFn = Callable[[FloatArray, "FloatArray | None"], FloatArray]
"""``speeds(path, s)``: the waypoints' speeds for a path and its arc length (or None)."""

MapCheck = Callable[[FloatArray, float, TrackEstimate], str]
"""``map_check(path, stamp, track)``: why a sound path still leaves the lane the global
path and the cones in view agree on, or "" (step 6b)."""

_DEFAULT_CONFIG = MidlineConfig()  # frozen: built once
_DEFAULT_SPEED = SpeedProfileConfig()


class PlanStatus(StrEnum):
    """Outcome of one planning step."""

    OK = "ok"
    FALLBACK = "fallback"  # the previous path, carried into the current frame
    FAILED = "failed"  # no path at all


@dataclass(frozen=True, slots=True)
class LocalPlan:
    """Everything one planning step produced, in ``os_sensor`` at ``header.stamp``.

    Attributes:
        header: the transform's stamp and the sensor frame.
        cones: real cones in view followed by their virtual partners.
        bridges: the left-right Delaunay edges with their checks.
        midpoints: (k, 2) ordered midpoints the path goes through [m].
        path: (p, 2) the path, every ``spacing`` of arc length [m].
        speeds: (p,) target speed at each path point [m/s].
        status: ok, fallback or failed.
        reason: why the fresh path was not sound ("" when ok).
        track: the width and middle of the track in view.
        dropped: cones left out of view or as false positives.
    """

    header: Header
    cones: ConeSet
    bridges: Bridges
    midpoints: FloatArray
    path: FloatArray
    speeds: FloatArray
    status: PlanStatus
    reason: str
    track: TrackEstimate
    dropped: int

    @property
    def fallback(self) -> bool:
        """True when the path is the previous one carried forward."""
        return self.status is PlanStatus.FALLBACK

    @property
    def left(self) -> FloatArray:
        """(a, 2) real left cones in view [m]."""
        return self.cones.points[(self.cones.side == LEFT) & ~self.cones.virtual]

    @property
    def right(self) -> FloatArray:
        """(b, 2) real right cones in view [m]."""
        return self.cones.points[(self.cones.side == RIGHT) & ~self.cones.virtual]

    @property
    def virtual(self) -> FloatArray:
        """(v, 2) virtual partners [m]."""
        return self.cones.points[self.cones.virtual]

    @property
    def bridge_lines(self) -> FloatArray:
        """(m, 2, 2) every left-right Delaunay edge, [left end, right end] [m]."""
        pts = self.cones.points
        return np.stack([pts[self.bridges.left], pts[self.bridges.right]], axis=1)

    def local_path(self) -> LocalPath:
        """``/local_planned_path``."""
        d = np.diff(self.path, axis=0)
        yaw = np.arctan2(d[:, 1], d[:, 0]) if len(d) else np.zeros(0)
        yaw = np.concatenate([yaw, yaw[-1:]]) if len(yaw) else np.zeros(len(self.path))
        return LocalPath(self.header, self.path, yaw)

    def waypoints(self) -> Waypoints:
        """``/final_waypoints`` and ``/waypoint_speed_bars``."""
        return Waypoints(self.header, self.path, self.speeds)

    def bridge_message(self) -> BridgeLines:
        """``/delaunay_internal_lines``."""
        return BridgeLines(self.header, self.bridge_lines, self.bridges.used)

    def midpoint_message(self) -> Midpoints:
        """``/delaunay_internal_midpoints``."""
        return Midpoints(self.header, self.midpoints)


def cones_to_sensor(
    cones: ClassifiedCones, buffer: Buffer, time: float, sensor_frame: str
) -> tuple[ConeSet, float]:
    """Step 1: the classified cones in ``sensor_frame``; also the stamp used [s]."""
    transform = buffer.lookup_transform(sensor_frame, cones.header.frame_id, time)
    n = len(cones.points)
    # The cones and their tangents' tips in one call (row by row, the same
    # numbers), stacked by one compiled loop.
    mapped = transform.transform_points(kernels.with_tips(cones.points, cones.tangent))
    points = mapped[:n]
    tangent = mapped[n:] - points
    cone_set = ConeSet(
        points=points,
        side=cones.side,
        offset=cones.offset,
        station=cones.station,
        tangent=tangent,
        virtual=np.zeros(len(points), dtype=bool),
        axis=cones.axis,
    )
    return cone_set, transform.stamp


def merge_doubled(cones: ConeSet, config: MidlineConfig) -> ConeSet:
    """Step 1b: of two cones of one side closer than ``doubled_cone_distance``, the outer goes.

    A start/finish gate's big orange cones stand 0.3 m before and after the
    line and often outside the lane's edge, beside the edge's own cone: the
    bridges to the three then zigzag, and the midline with them. The lane
    is bounded by the inner one; "outer" is the larger offset from the
    global path towards the cone's side (a shift of the whole path, a
    survey's bias, leaves the order as it is).
    """
    d = config.doubled_cone_distance
    n = len(cones.points)
    if d <= 0.0 or n < 2:
        return cones
    pts = cones.points
    gap = np.hypot(pts[:, None, 0] - pts[None, :, 0], pts[:, None, 1] - pts[None, :, 1])
    outward = cones.side * cones.offset  # how far out towards its side
    same = cones.side[:, None] == cones.side[None, :]
    inner = (outward[None, :] < outward[:, None]) | (
        (outward[None, :] == outward[:, None]) & (np.arange(n)[None, :] < np.arange(n)[:, None])
    )  # j is inner to i (ties: the first kept)
    drop = (same & inner & (gap < d)).any(axis=1)
    return cones.select(~drop) if drop.any() else cones


def in_view(cones: ConeSet, config: MidlineConfig) -> NDArray[np.bool_]:
    """Step 2a: (n,) mask of the cones in range and at a boundary's distance from the path."""
    keep: NDArray[np.bool_] = kernels.in_view(cones.points, cones.offset, config.view_settings)
    return keep


def boundary_cones(
    cones: ConeSet, config: MidlineConfig
) -> tuple[ConeSet, PairTable, TrackEstimate, int]:
    """Step 2: the cones that may bound the track, their pair table and the track estimate.

    ``in_view``, ``pair_table`` and ``estimate_track``; when the track is
    measured, the cones more than ``boundary_tolerance`` inside their boundary
    line are dropped and the pair table rebuilt (the estimate stays). One
    compiled call (``kernels.boundary_cones``).

    Returns:
        The kept cones, their pair table, the width and middle in view, and
        how many cones were dropped.
    """
    axis = cones.axis
    keep, left, right, dist, same, span, middle, width, centre, measured = kernels.boundary_cones(
        *cones.located(),
        axis.length,
        axis.closed,
        config.view_settings,
    )
    real = cones if len(keep) == len(cones) else cones.select(keep)
    pairs = PairTable(left, right, dist, same, span, middle)
    track = TrackEstimate(float(width), float(centre), bool(measured))
    return real, pairs, track, len(cones) - len(real)


def cones_with_partners(
    cones: ConeSet, config: MidlineConfig
) -> tuple[ConeSet, TrackEstimate, int]:
    """Steps 2 and 3a in one compiled call (``kernel_chains.plan_cones``).

    ``boundary_cones``, then ``virtual_partners`` joined after the kept
    cones: the same cones, estimate and count, without the pair table.

    Returns:
        The kept cones followed by their virtual partners, the width and
        middle in view, and how many cones were dropped.
    """
    axis = cones.axis
    points, side, offset, station, tangent, virtual, width, centre, measured, dropped = (
        kernel_chains.plan_cones(
            *cones.located(),
            cones.tangent,
            axis.length,
            axis.closed,
            config.view_settings,
            config.partner_settings,
        )
    )
    cone_set = ConeSet(points, side, offset, station, tangent, virtual, axis)
    return cone_set, TrackEstimate(float(width), float(centre), bool(measured)), int(dropped)


def bridges_and_midpoints(
    cones: ConeSet,
    simplices: NDArray[np.intc],
    config: MidlineConfig,
    track: TrackEstimate,
    sensor_station: float,
) -> tuple[Bridges, FloatArray, FloatArray, float]:
    """Steps 3 and 4 after the triangulation, one compiled call (``kernel_chains.plan_midpoints``).

    ``find_bridges`` on the triangulation's edges, ``ordered_midpoints``, and
    the boundary edges as segments.

    Args:
        cones: real and virtual cones.
        simplices: (t, 3) their Delaunay triangles (``bridges.delaunay_simplices``).
        config: the settings.
        track: the width in view (checked when measured).
        sensor_station: the sensor's station [m].

    Returns:
        The bridges, the (e, 2, 2) boundary segments [m], the (m, 2) ordered
        midpoints [m] and their polyline's length [m].
    """
    axis = cones.axis
    left, right, length, valid, used, mid, station, boundary, ordered, ordered_length = (
        kernel_chains.plan_midpoints(
            simplices,
            *cones.located(),
            cones.virtual,
            axis.length,
            axis.closed,
            track.measured,
            track.width,
            sensor_station,
            config.bridge_settings,
            config.ordering_settings,
        )
    )
    bridges = Bridges(left, right, length, valid, used, mid, station)
    return bridges, boundary, ordered, float(ordered_length)


def check_path(
    path: FloatArray,
    n_midpoints: int,
    boundary: FloatArray,
    config: MidlineConfig,
    length: float | None = None,
    *,
    crosses: bool | None = None,
    start: float | None = None,
) -> str:
    """Step 6: why the path is not sound, or "" when it is.

    Args:
        path: (p, 2) the fitted path [m].
        n_midpoints: ordered midpoints it was fitted through.
        boundary: (e, 2, 2) boundary edges it may not cross [m].
        config: the thresholds.
        length: the path's length [m] if known (``arc_length(path)[-1]``).
        crosses: whether it crosses a boundary edge, if known
            (``crosses_boundary(path, boundary)``).
        start: the first point's distance from the sensor [m], if known
            (``np.hypot(*path[0])``).
    """
    if n_midpoints < 2:
        return f"{n_midpoints} ordered midpoints (need 2)"
    if length is None:
        length = float(arc_length(path)[-1])
    if length < config.min_path_length:
        return f"path {length:.2f} m long (need {config.min_path_length} m)"
    if start is None:
        start = float(np.hypot(path[0, 0], path[0, 1]))
    if start > config.max_start_distance:
        return f"path starts {start:.2f} m away (max {config.max_start_distance} m)"
    if crosses is None:
        crosses = crosses_boundary(path, boundary)
    if crosses:
        return "path crosses a track boundary"
    return ""


def carry_path_forward(
    previous: LocalPlan | None,
    buffer: Buffer,
    time: float,
    reference_frame: str,
    sensor_frame: str,
) -> FloatArray | None:
    """The previous plan's path in ``sensor_frame`` at ``time``, from its nearest point on.

    Through the frame tree's time-travel lookup, with ``reference_frame`` as the
    fixed frame: ``previous.header.frame_id`` at the previous stamp ->
    ``reference_frame`` -> ``sensor_frame`` at ``time``. None when there is
    no previous path, the frame tree cannot transform it (e.g. the old stamp
    left the cache), or fewer than two points remain.
    """
    if previous is None or len(previous.path) < 2:
        return None
    try:
        moved = buffer.transform_points_full(
            sensor_frame,
            time,
            previous.header.frame_id,
            previous.path,
            previous.header.stamp,
            reference_frame,
        )
    except TransformError:
        return None
    nearest = int(np.argmin(np.hypot(moved[:, 0], moved[:, 1])))
    moved = moved[nearest:]
    return moved if len(moved) >= 2 else None


def reference_path_planning(
    cones: ClassifiedCones,
    buffer: Buffer,
    config: MidlineConfig | None = None,
    speed_config: SpeedProfileConfig | None = None,
    *,
    v_start: float | None = None,
    previous: LocalPlan | None = None,
    time: float = LATEST,
    sensor_frame: str = FRAME_OS_SENSOR,
    speeds: SpeedFn | None = None,
    map_check: MapCheck | None = None,
) -> LocalPlan:
    """Plan the local path between the classified cones, in ``sensor_frame``.

    Args:
        cones: left and right cones in ``reference`` (``classify_cones_by_side``).
        buffer: the frame tree.
        config: midline settings.
        speed_config: speed profile limits.
        v_start: current speed, the profile's start [m/s]; None leaves it free.
        previous: the last plan, carried forward when this one is not sound.
        time: lookup time [s]; :data:`LATEST` as in the ROS pipeline.
        sensor_frame: the frame the path is planned in.
        speeds: how the waypoints get their speeds, ``speeds(path, s)`` with
            ``s`` the path's arc length (None for a path carried forward);
            by default the speed profile of ``speed_config`` from ``v_start``.
            The autopilot passes its global-path speeds here, so that no
            profile is computed only to be replaced.
        map_check: step 6b, called on a path step 6 passed with the stamp
            used and the track in view; a reason it returns fails the path.

    Returns:
        The plan with every intermediate.

    Raises:
        The frame tree's errors when ``cones`` cannot be mapped at ``time``.
    """
    config = config or _DEFAULT_CONFIG
    all_cones, stamp = cones_to_sensor(cones, buffer, time, sensor_frame)
    all_cones = merge_doubled(all_cones, config)
    cone_set, track, dropped = cones_with_partners(all_cones, config)
    bridges, boundary, midpoints, midpoints_length = bridges_and_midpoints(
        cone_set, delaunay_simplices(cone_set.points), config, track, cones.sensor_station
    )
    path = np.ascontiguousarray(fit_path(midpoints, config, midpoints_length), dtype=float)
    path = keep_in_lane(path, boundary, track, config)
    # The check's numbers, the arc length for the speed profile and the
    # profile's limits: one compiled call.
    s, length, start, crosses, limits = kernel_chains.check_and_limit(
        path, boundary, speeds is None, (speed_config or _DEFAULT_SPEED).limit_settings
    )
    reason = check_path(
        path, len(midpoints), boundary, config, length, crosses=crosses, start=start
    )
    if not reason and map_check is not None:
        reason = map_check(path, stamp, track)
    status = PlanStatus.OK
    if reason:
        carried = carry_path_forward(previous, buffer, stamp, cones.header.frame_id, sensor_frame)
        status = PlanStatus.FAILED if carried is None else PlanStatus.FALLBACK
        path = np.zeros((0, 2)) if carried is None else carried
        if speeds is None:
            path_speeds = speed_profile(path, speed_config, v_start)
        else:
            path_speeds = speeds(path, None)
    elif speeds is None:
        path_speeds = profile_speeds(limits, speed_config, v_start)
    else:
        path_speeds = speeds(path, s)
    return LocalPlan(
        header=Header(stamp, sensor_frame),
        cones=cone_set,
        bridges=bridges,
        midpoints=midpoints,
        path=path,
        speeds=path_speeds,
        status=status,
        reason=reason,
        track=track,
        dropped=dropped,
    )
