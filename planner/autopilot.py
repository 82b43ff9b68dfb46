"""The autopilot: the planner's stages wired at their rates, from messages and the frame tree.

What a real car's software has, and nothing more: the frame tree (fed by
localization), the global path, and the messages it receives.

- Cone detections (10 Hz, ``/sorted_cones_time``) get the cones of the
  last scans they missed (``planner.cone_memory``), then trigger
  ``classify_cones_by_side`` at the detection's stamp (if the frame tree has
  no transform there yet, at the latest one, counted in ``tf_latest_count``)
  and ``reference_path_planning`` with the latest transform, as in the ROS
  pipeline; a path that leaves the lane as the global path places it is
  not taken (``off_lane_reason``, ``AutopilotConfig.lane_check_margin``).
  With ``speed_source = "global"`` the waypoints' speeds are then the
  global path's speed plan at their stations (``planner.global_speed``),
  limited to what the car reaches accelerating from its speed.
  The plan's path is also kept in ``reference``, and the sensor's station
  along the global path is kept as the next classification's
  ``station_hint``.
- Wheel speeds update the speed estimate; without any, the speed is the
  sensor's displacement in the frame tree over ``speed_window``.
- Control runs at every :meth:`Autopilot.step`, on the closed loop's one
  clock (``control_rate``, 50 Hz by default): the path is brought from
  ``reference`` into the current ``os_sensor`` frame, pure pursuit steers
  toward its lookahead point, and the PI controller tracks the waypoint
  speeds, within the friction ellipse left by the lateral acceleration the
  steering asks for (v^2 tan(delta) / L), and not accelerating while the
  steering is at full lock (``full_lock_share``). Without a path the car
  brakes to a stop with the wheels straight.

Building an autopilot runs one planning step on a made-up track
(``warm_up_planner``), once per process: the planner's compiled kernels load
there (from numba's cache; or compiled, on a cold cache) rather than on the
first detection.

Each :meth:`Autopilot.step` returns an :class:`AutopilotStep`: the command
and what the step produced (the plans made from its detections, with their
left/right cones in ``reference``, bridge lines, midpoints, path and
waypoints with speeds; the path followed, in ``reference``; the path pure
pursuit followed and its lookahead point, in ``os_sensor`` now; the target
speed). The same are attributes of the autopilot (``classified``, ``plan``,
``path_reference``, ``path_now``, ``pursuit_path``, ``lookahead_point``,
``command``), with counters ``plan_count``, ``fallback_count``,
``failed_count``, ``tf_latest_count``, ``skipped_count``.
"""

from __future__ import annotations

import dataclasses
import functools
import logging
import math
from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np
from scipy.spatial import cKDTree

from conesim.core.compiled import parallel_warm_up
from conesim.core.messages import (
    FRAME_OS_SENSOR,
    FRAME_REFERENCE,
    ConeDetections,
    Header,
    Message,
    WheelSpeed,
)
from conesim.core.pose import Pose2D
from conesim.localization.frames import (
    LATEST,
    Buffer,
    ExtrapolationError,
    TransformError,
    TransformStamped,
)
from conesim.planner.bridges import TrackEstimate
from conesim.planner.classify import ClassifiedCones, classify_cones_by_side
from conesim.planner.cone_memory import ConeMemory
from conesim.planner.config import AutopilotConfig
from conesim.planner.geometry import FloatArray, PathProjector, arc_length
from conesim.planner.global_fit import smoothed_global_path
from conesim.planner.global_speed import GlobalSpeedPlan
from conesim.planner.lap_map import LapMap, lap_time
from conesim.planner.messages import ControlCommand
from conesim.planner.midline import LocalPlan, PlanStatus, reference_path_planning
from conesim.planner.pure_pursuit import SteeringResult, lookahead_distance, pure_pursuit
from conesim.planner.speed_control import SpeedController, target_on_path
from conesim.planner.speed_profile import forward_pass, speed_profile
from conesim.tracks.global_path import GlobalPath, global_path_from_centreline

_log = logging.getLogger(__name__)

CONTROL_RATE = 50.0  # [Hz] ARCHITECTURE.md: pure pursuit and speed control


def default_config(localization: str) -> AutopilotConfig:
    """The autopilot's settings for a localization mode: ``AutopilotConfig.cautious()``
    with ``raw`` (the ROS pipeline's broadcaster: a pose up to 150 ms old); the
    midline on every lap with ``cones`` and ``slam`` (a pose to 0.2-0.3 m, for a
    racing line that passes the cones 0.4 m off: autocross went off the track
    with slam); else the defaults."""
    if localization == "raw":
        return AutopilotConfig.cautious()
    if localization in ("cones", "slam"):
        return AutopilotConfig(racing_line=False)
    return AutopilotConfig()


@dataclass(frozen=True, slots=True)
class Planned:
    """One detection's classification and plan.

    Attributes:
        classified: its cones by side, in ``reference``.
        plan: the local plan (``os_sensor`` at the detection).
        path_reference: (n, 2) the plan's path in ``reference`` [m].
    """

    classified: ClassifiedCones
    plan: LocalPlan
    path_reference: FloatArray


@dataclass(frozen=True, slots=True)
class AutopilotStep:
    """What one control step of the autopilot produced.

    Attributes:
        command: steering [rad] and acceleration [m/s^2], stamped now.
        plans: the plans made from this step's detections, oldest first.
        path_reference: (n, 2) the path followed, in ``reference`` [m] (the
            last plan's; empty before the first).
        pursuit_path: (m, 2) the path pure pursuit followed, ``os_sensor`` now [m].
        lookahead: (2,) the lookahead point in ``os_sensor`` now [m], or None
            (no path: braking with the wheels straight).
        target_speed: the speed controller's target [m/s].
    """

    command: ControlCommand
    plans: tuple[Planned, ...]
    path_reference: FloatArray
    pursuit_path: FloatArray
    lookahead: FloatArray | None
    target_speed: float


@functools.cache
@parallel_warm_up
def warm_up_planner() -> None:
    """One planning step on a made-up gentle bend, once per process.

    Each compiled kernel (``planner.kernels``) is loaded from numba's cache,
    or compiled on a cold cache (``conesim.core.compiled``: with helper
    processes on idle cores), on its first call. Calling them here, when the
    autopilot is built, keeps that out of the first detection's latency. The
    step has its own path, frame tree and cones (a 3.5 m wide bend, cones
    every 2.5 m): no autopilot's state is touched, and the kernels keep no
    state.
    """
    x = np.arange(0.0, 40.0, 0.5)
    centre = np.column_stack([x, 0.002 * x**2])
    normal = np.column_stack([-0.004 * x, np.ones_like(x)])
    normal /= np.hypot(normal[:, 0], normal[:, 1])[:, None]
    cones = np.vstack([centre + 1.75 * normal, centre - 1.75 * normal])[::5]
    cones = cones[np.argsort(np.hypot(cones[:, 0], cones[:, 1]))]
    buffer = Buffer()
    buffer.set_transform(
        TransformStamped.from_pose2d(FRAME_REFERENCE, FRAME_OS_SENSOR, 1.0, Pose2D(0.0, 0.0, 0.0))
    )
    detections = ConeDetections(
        Header(1.0, FRAME_OS_SENSOR), np.column_stack([cones, np.zeros(len(cones))])
    )
    projector = PathProjector(global_path_from_centreline(centre, closed=False).polyline)
    plan = reference_path_planning(classify_cones_by_side(detections, buffer, projector), buffer)
    speed_profile(plan.path, v_start=1.0, s=arc_length(plan.path), v_end=1.0)
    projector.project(centre[-1:], window=(30.0, 40.0))  # the pursuit's look beyond the path


class Autopilot:
    """The planner and controller, driven by messages at their rates.

    Args:
        buffer: the frame tree, fed by localization.
        global_path: the global path in ``reference``.
        config: every stage's settings and the frame names.
        control_rate: how often :meth:`step` is called [Hz] (the loop's clock).
    """

    def __init__(
        self,
        buffer: Buffer,
        global_path: GlobalPath,
        config: AutopilotConfig | None = None,
        *,
        control_rate: float = CONTROL_RATE,
    ) -> None:
        if not (math.isfinite(control_rate) and control_rate > 0.0):
            raise ValueError(f"Autopilot: control_rate must be > 0 [Hz], got {control_rate!r}")
        warm_up_planner()
        self.buffer = buffer
        self.config = config or AutopilotConfig()
        self.control_rate = float(control_rate)
        global_path = smoothed_global_path(global_path, self.config.global_path_min_scatter)
        self.global_path = global_path
        self.projector = PathProjector(global_path.polyline)
        self.global_speed = (
            GlobalSpeedPlan(global_path, self.config.speed_profile)
            if self.config.global_speed
            else None
        )
        self.speed_controller = SpeedController(self.config.speed_control)
        self.memory = ConeMemory(self.config.cone_memory)
        self.classified: ClassifiedCones | None = None
        self.plan: LocalPlan | None = None
        self.path_reference: FloatArray = np.zeros((0, 2))
        self.path_now: FloatArray = np.zeros((0, 2))
        self.pursuit_path: FloatArray = np.zeros((0, 2))
        self.steering: SteeringResult | None = None
        self.path_curvature: FloatArray = np.zeros(0)  # [1/m] global, at the waypoints
        self.target_speed = 0.0  # [m/s]
        self.command: ControlCommand | None = None
        self.wheel_speed: float | None = None  # [m/s]
        self.plan_count = 0
        self.fallback_count = 0
        self.failed_count = 0
        self.tf_latest_count = 0
        self.skipped_count = 0
        self.station_hint: float | None = None  # [m] the sensor's last station
        self.path_speeds: FloatArray = np.zeros(0)  # [m/s] at the path's points
        # Lap 1 maps the cones; from lap 2 a racing line through them (``racing_line``).
        self.lap_map = LapMap() if self.config.racing_line and global_path.closed else None
        self.racing: GlobalSpeedPlan | None = None
        self.travelled = 0.0  # [m] along the global path, while lap 1 maps
        self._racing_station: float | None = None
        self._racing_projector: PathProjector | None = None
        self._map_tree: cKDTree | None = None  # the lap map's cones, once racing
        self._racing_on_map = True
        self.racing_off_map_count = 0  # scans steered by the midline: the pose off the map
        self.on_racing_line = False  # whether the current path is the racing line's
        self._racing_speed_control = dataclasses.replace(  # its target speed's preview
            self.config.speed_control, preview_time=self.config.racing_speed_preview
        )
        self._last_control: float | None = None

    # -- intermediates -----------------------------------------------------------------------

    @property
    def left_cones(self) -> FloatArray:
        """(n, 2) left cones of the last detection, ``reference`` [m]."""
        return self.classified.left if self.classified is not None else np.zeros((0, 2))

    @property
    def right_cones(self) -> FloatArray:
        """(n, 2) right cones of the last detection, ``reference`` [m]."""
        return self.classified.right if self.classified is not None else np.zeros((0, 2))

    @property
    def fallback(self) -> bool:
        """Whether the current path is a previous one carried forward."""
        return self.plan is not None and self.plan.status is PlanStatus.FALLBACK

    @property
    def lookahead_point(self) -> FloatArray | None:
        """(2,) the last lookahead point, in ``os_sensor`` at the last control step [m]."""
        return None if self.steering is None else self.steering.target

    # -- inputs ------------------------------------------------------------------------------

    def on_wheel_speed(self, message: WheelSpeed) -> None:
        """Update the speed estimate [m/s] (a non-finite speed is ignored)."""
        if math.isfinite(message.speed):
            self.wheel_speed = float(message.speed)

    def on_detections(self, message: ConeDetections) -> LocalPlan | None:
        """Classify and plan; returns the plan, or None if the frame tree could not serve it."""
        c = self.config
        try:
            try:
                message = self.memory.recall(
                    message, self.buffer, c.reference_frame, message.header.stamp
                )
            except ExtrapolationError:
                message = self.memory.recall(message, self.buffer, c.reference_frame, LATEST)
            try:
                classified = classify_cones_by_side(
                    message, self.buffer, self.projector, c.classifier,
                    station_hint=self.station_hint, reference_frame=c.reference_frame,
                )  # fmt: skip
            except ExtrapolationError:
                classified = classify_cones_by_side(
                    message, self.buffer, self.projector, c.classifier, time=LATEST,
                    station_hint=self.station_hint, reference_frame=c.reference_frame,
                )  # fmt: skip
                self.tf_latest_count += 1
            station = classified.sensor_station
            plan = reference_path_planning(
                classified,
                self.buffer,
                c.midline,
                c.speed_profile,
                v_start=self.speed(),
                previous=self.plan,
                sensor_frame=c.sensor_frame,
                speeds=(
                    None
                    if self.global_speed is None
                    else functools.partial(self._global_speeds, sensor_station=station)
                ),
                map_check=(
                    None
                    if math.isinf(c.lane_check_margin)
                    else functools.partial(self.off_lane_reason, sensor_station=station)
                ),
            )
            curvature = self._global_curvature(plan.path, station)
            path_reference = self.buffer.transform_points(
                c.reference_frame, c.sensor_frame, plan.path, plan.header.stamp
            )
        except TransformError as err:
            self.skipped_count += 1
            # The first skip says why (e.g. detections in a frame the tree does
            # not have); later ones are only counted, at 10 Hz they would flood.
            (_log.warning if self.skipped_count == 1 else _log.debug)(
                "detections at %.6f s skipped (%d so far): %s",
                message.header.stamp,
                self.skipped_count,
                err,
            )
            return None
        self._map_lap(classified)
        speeds = plan.speeds
        racing = None
        if self.racing is not None and self._on_map(classified):
            racing = self._racing_segment()
        if racing is not None:
            path_reference, speeds, curvature = racing
        self.on_racing_line = racing is not None
        self.path_curvature = curvature  # set with the plan it belongs to
        self.classified = classified
        self.station_hint = classified.sensor_station
        self.plan = plan
        self.path_reference = path_reference
        self.path_speeds = speeds
        self.plan_count += 1
        self.fallback_count += plan.status is PlanStatus.FALLBACK
        self.failed_count += plan.status is PlanStatus.FAILED
        return plan

    def _map_lap(self, classified: ClassifiedCones) -> None:
        """Lap 1: fold the scan into the lap map; once the sensor has gone round the
        global path, make the racing line (``AutopilotConfig.racing_line``)."""
        if self.lap_map is None or self.racing is not None:
            return
        if self.station_hint is not None:
            length = self.projector.line.end_station
            step = classified.sensor_station - self.station_hint
            self.travelled += (step + 0.5 * length) % length - 0.5 * length
        own = ~self.memory.recalled[classified.index]  # the scan's own cones, not echoes
        self.lap_map.add(classified.points[own], classified.side[own])
        if self.travelled < self.projector.line.end_station:
            return
        c = self.config
        try:
            m = c.midline
            path = self.lap_map.racing_path(
                self.global_path, m.body_half_width + c.racing_margin, c.racing_speed_profile,
                body=(m.body_half_width, m.body_front),
            )  # fmt: skip
        except (ValueError, ArithmeticError) as exc:
            _log.warning("no racing line through the lap-1 map (%s); the midline stays", exc)
            self.lap_map = None
            return
        racing = GlobalSpeedPlan(path, c.racing_speed_profile)
        plan_s = lap_time(racing)
        midline_s = math.inf if self.global_speed is None else lap_time(self.global_speed)
        if plan_s >= midline_s:
            # A lane too narrow for the margin leaves no faster line than the midline.
            _log.info(
                "the racing line laps in %.2f s, the midline in %.2f s: the midline stays",
                plan_s, midline_s,
            )  # fmt: skip
            self.lap_map = None
            return
        self.racing = racing
        self._racing_projector = PathProjector(path.polyline)
        self._map_tree = cKDTree(self.lap_map.cones()[0])

    def _on_map(self, classified: ClassifiedCones) -> bool:
        """Whether the scan's own cones, placed by the pose, stand where the lap map
        has them: the median distance of those within 1 m of a map cone at most
        ``racing_map_tolerance``. The racing line is followed by the pose alone;
        a pose off by more than the margin (a consumer receiver's drift, a lost
        fix) would follow it into the cones, and the cones' midline steers
        instead (``racing_off_map_count``). With fewer than 3 cones matched the
        last scan's answer stands."""
        assert self._map_tree is not None
        own = ~self.memory.recalled[classified.index]
        points = classified.points[own]
        if len(points) >= 3:
            d = self._map_tree.query(points, distance_upper_bound=1.0)[0]
            d = d[np.isfinite(d)]
            if len(d) >= 3:
                self._racing_on_map = bool(np.median(d) <= self.config.racing_map_tolerance)
        self.racing_off_map_count += not self._racing_on_map
        return self._racing_on_map

    def _racing_segment(self) -> tuple[FloatArray, FloatArray, FloatArray] | None:
        """The racing line from 3 m behind the sensor to the planner's range ahead,
        in ``reference``: points, speeds (accelerating from the car's speed) and
        curvature; None where the frame tree has no pose (the cones' plan stays)."""
        racing, projector = self.racing, self._racing_projector
        assert racing is not None and projector is not None
        c = self.config
        try:
            sensor = self.buffer.lookup_pose2d(c.reference_frame, c.sensor_frame, LATEST)
        except TransformError:
            return None
        here = np.array([[sensor.x, sensor.y]])
        hint = self._racing_station
        window = None if hint is None else (hint - 5.0, hint + c.midline.max_range)
        station = float(projector.project(here, window=window).station[0])
        self._racing_station = station
        stations = station + np.arange(-3.0, c.midline.max_range + 0.25, 0.5)
        points = racing.points_at(stations)
        s = stations - stations[0]
        v = racing.speeds_at(stations)
        v[0] = min(v[0], max(self.speed(), 0.0))
        v = forward_pass(s, v, c.racing_speed_profile.a_drive)
        return points, v, racing.curvature_at(stations)

    def _global_speeds(
        self, path: FloatArray, s: FloatArray | None, *, sensor_station: float
    ) -> FloatArray:
        """The waypoints' speeds from the global path's plan (``speed_source``
        ``"global"``) or the local profile ending at its speed where the path
        ends (``"local"``); a path of one point or none gets the local profile.

        With ``horizon_stop`` the global plan's speeds are held to what
        brakes at ``a_brake`` to v_end at the end of the path in view,
        v_i^2 <= v_end^2 + 2 a_brake (s_end - s_i): v_end is the global
        plan's speed there where the path's end lies on the map (within
        ``pursue_global_max_gap`` of the global path), and 0 where it does
        not: where the map and the cones disagree the car can always stop
        within what it has seen.
        """
        assert self.global_speed is not None
        profile = self.config.speed_profile
        if len(path) <= 1:
            return speed_profile(path, profile, self.speed(), s=s)
        s = arc_length(path) if s is None else s
        v_end = self.global_speed.speed_at(sensor_station + float(path[0, 0]) + float(s[-1]))
        if not self._end_on_map(path, sensor_station):
            v_end = 0.0  # the map and the cones disagree there: stop within what is seen
        if self.config.speed_source == "global":
            v = self.global_speed.speeds_at(self._stations(path, s, sensor_station))
            if profile.horizon_stop:  # brake to v_end at the end of the path in view
                v = np.minimum(v, np.sqrt(v_end * v_end + 2.0 * profile.a_brake * (s[-1] - s)))
            v[0] = min(v[0], max(self.speed(), 0.0))
            return forward_pass(s, v, profile.a_drive)
        return speed_profile(path, profile, self.speed(), s=s, v_end=v_end)

    def off_lane_reason(
        self, path: FloatArray, stamp: float, track: TrackEstimate, *, sensor_station: float
    ) -> str:
        """Why the cone ``path`` (``os_sensor`` at ``stamp``) leaves the lane as the global
        path places it, or "" (``AutopilotConfig.lane_check_margin``).

        Each point's signed offset from the global path (searched from 5 m
        behind the sensor's station to twice the path's length ahead), less the
        middle's offset the cones in view give, may be at most half their
        width plus the margin.
        """
        c = self.config
        try:
            points = self.buffer.transform_points(c.reference_frame, c.sensor_frame, path, stamp)
        except TransformError:
            return ""  # nothing to check against: the cones alone decide
        # The path's points lie at most twice its length ahead along the global
        # path (a path on the inside of a hairpin of R 3 m about a centre of
        # 4 m runs 0.75 m per metre of it); a window that is wide errs on the
        # side of passing the path (a nearer segment), one that ends short
        # would measure the points beyond it to its end.
        ahead = 2.0 * float(arc_length(path)[-1]) + max(float(path[0, 0]), 0.0) + 5.0
        window = (sensor_station - 5.0, sensor_station + ahead)
        lateral = self.projector.project(points, window=window).lateral - track.centre
        worst = float(np.max(np.abs(lateral)))
        allowed = 0.5 * track.width + c.lane_check_margin
        if worst <= allowed:
            return ""
        return (
            f"path leaves the lane on the map ({worst:.2f} m from its middle, "
            f"allowed {allowed:.2f} m)"
        )

    def _end_on_map(self, path: FloatArray, sensor_station: float) -> bool:
        """Whether the path's end, placed in ``reference`` by the latest pose, lies
        within ``pursue_global_max_gap`` of the global path (searched from 5 m
        behind the sensor's station to the planner's range ahead)."""
        c = self.config
        try:
            end = self.buffer.transform_points(c.reference_frame, c.sensor_frame, path[-1:], LATEST)
        except TransformError:
            return False
        window = (sensor_station - 5.0, sensor_station + c.midline.max_range)
        gap = float(self.projector.project(end, window=window).distance[0])
        return gap <= c.pursue_global_max_gap

    def _global_curvature(self, path: FloatArray, sensor_station: float) -> FloatArray:
        """The global path's curvature at the waypoints (``speed_source`` ``"global"``;
        empty otherwise), for the lookahead cap."""
        if self.global_speed is None or self.config.speed_source != "global" or len(path) <= 1:
            return np.zeros(0)
        stations = self._stations(path, arc_length(path), sensor_station)
        return self.global_speed.curvature_at(stations)

    @staticmethod
    def _stations(path: FloatArray, s: FloatArray, sensor_station: float) -> FloatArray:
        """The waypoints' global-path stations: the sensor's, plus the path's first
        point's distance ahead (x in ``os_sensor``), plus arc length."""
        return sensor_station + float(path[0, 0]) + s

    def speed(self) -> float:
        """Speed estimate [m/s]: the last wheel speed, else from the frame tree, else 0."""
        if self.wheel_speed is not None:
            return self.wheel_speed
        c = self.config
        try:
            now = self.buffer.lookup_transform(c.reference_frame, c.sensor_frame, LATEST)
            t0 = now.stamp - c.speed_window
            before = self.buffer.lookup_pose2d(c.reference_frame, c.sensor_frame, t0)
        except TransformError:
            return 0.0
        if t0 < 0.0:
            return 0.0
        pose = now.to_pose2d()
        return math.hypot(pose.x - before.x, pose.y - before.y) / c.speed_window

    # -- control -----------------------------------------------------------------------------

    def control(self, t: float) -> ControlCommand:
        """One control step at time ``t`` [s]: steering and acceleration."""
        c = self.config
        dt = 1.0 / self.control_rate if self._last_control is None else t - self._last_control
        self._last_control = t
        speed = self.speed()
        path = self._path_in_sensor_frame()
        if len(path) == 0 or self.plan is None:
            self.pursuit_path = path
            self.steering = None
            self.target_speed = 0.0
            acceleration = self.speed_controller.step(0.0, speed, dt)
            self.command = ControlCommand(t, 0.0, acceleration)
            return self.command
        self.pursuit_path, curvature = self._pursuit_path(path, speed)
        cap = self._lookahead_cap(self.pursuit_path, curvature, speed)
        # The racing line's curvature is its own; the midline's is the global path's.
        own = curvature if self.on_racing_line else None
        self.steering = pure_pursuit(self.pursuit_path, speed, c.pure_pursuit, cap, own)
        axle = np.array([c.pure_pursuit.rear_axle_x, 0.0])
        preview = self._racing_speed_control if self.on_racing_line else c.speed_control
        v_ref, a_ff = target_on_path(path, self.path_speeds, axle, speed, preview)
        self.target_speed = v_ref
        a_lat = speed * speed * math.tan(self.steering.steering) / c.pure_pursuit.wheelbase
        acceleration = self.speed_controller.step(v_ref, speed, dt, a_ff, a_lat)
        lock = c.speed_control.full_lock_share * c.pure_pursuit.max_steer
        if abs(self.steering.steering) >= lock:
            # At full lock the car turns no tighter; faster, it only runs wider.
            acceleration = min(acceleration, 0.0)
        self.command = ControlCommand(t, self.steering.steering, acceleration)
        return self.command

    def _lookahead_cap(self, path: FloatArray, curvature: FloatArray, speed: float) -> float | None:
        """``lookahead_radius_ratio`` times the tightest radius within the lookahead [m].

        The radius is the global path's at the points of the pursued path
        (``curvature``: ``path_curvature`` at the waypoints, with
        ``speed_source = "global"``, and the global path's own beyond them)
        from the one nearest the rear axle to one lookahead distance on. A
        lookahead longer than the radius aims across the inside of a hairpin:
        the chord of L_d in a circle of R lies R - sqrt(R^2 - L_d^2 / 4)
        inside it, 0.96 m for 4.9 m in 3.5 m but 0.47 m for L_d = R.
        """
        pp = self.config.pure_pursuit
        if len(curvature) != len(path) or len(path) < 2:
            return None
        axle = np.array([pp.rear_axle_x, 0.0])
        s = arc_length(path)
        nearest = int(np.argmin(np.hypot(path[:, 0] - axle[0], path[:, 1] - axle[1])))
        ahead = (s >= s[nearest]) & (s <= s[nearest] + lookahead_distance(speed, pp))
        kappa = float(np.max(np.abs(curvature[ahead])))
        return pp.lookahead_radius_ratio / kappa if kappa > 0.0 else None

    def _pursuit_path(self, path: FloatArray, speed: float) -> tuple[FloatArray, FloatArray]:
        """The path pure pursuit follows, ``os_sensor`` [m], and the global
        path's curvature at its points [1/m] (for the lookahead cap; empty
        without ``speed_source = "global"``).

        The local path, and when it ends inside the lookahead circle
        (``pursue_global_beyond_path``; the lookahead before its cap, which is
        then taken over both), the global path from the station of its end
        to 1.5 m beyond one lookahead distance, every 0.5 m, unless the end
        lies farther than ``pursue_global_max_gap`` from it. The end's
        station is looked for from 5 m behind the sensor's station at the
        plan to the planner's range (``midline.max_range``, 30 m) ahead of
        it: the skidpad's other circle, about 57 m round, lies outside.
        """
        c = self.config
        pp = c.pure_pursuit
        gs = self.global_speed
        hint = self.station_hint
        curvature = self.path_curvature
        if not c.pursue_global_beyond_path or gs is None or hint is None:
            return path, curvature
        look = lookahead_distance(speed, pp)
        end_x, end_y = float(path[-1, 0]), float(path[-1, 1])
        if math.hypot(end_x - pp.rear_axle_x, end_y) >= look:
            return path, curvature
        window = (hint - 5.0, hint + c.midline.max_range)
        end = self.projector.project(self.path_reference[-1:], window=window)
        if not float(end.distance[0]) <= c.pursue_global_max_gap:
            return path, curvature  # the map and the cones disagree here
        stations = float(end.station[0]) + np.arange(0.5, look + 2.0, 0.5)
        if not gs.closed:
            stations = stations[stations <= gs.length]
            if len(stations) == 0:
                return path, curvature
        try:
            beyond = self.buffer.transform_points(
                c.sensor_frame, c.reference_frame, gs.points_at(stations), LATEST
            )
        except TransformError:
            return path, curvature
        if len(curvature) == len(path):
            curvature = np.concatenate([curvature, gs.curvature_at(stations)])
        return np.vstack([path, beyond]), curvature

    def _path_in_sensor_frame(self) -> FloatArray:
        """The plan's path in the latest ``os_sensor`` frame (the planned one if that fails)."""
        if self.plan is None or len(self.path_reference) == 0:
            self.path_now = np.zeros((0, 2))
            return self.path_now
        c = self.config
        try:
            self.path_now = self.buffer.transform_points(
                c.sensor_frame, c.reference_frame, self.path_reference, LATEST
            )
        except TransformError:
            self.path_now = self.plan.path
        return self.path_now

    def step(self, t: float, messages: Iterable[Message] = ()) -> AutopilotStep:
        """One control step at ``t`` [s]: take the messages delivered since the
        last step (detections plan, wheel speeds update the speed), then steer
        and set the acceleration."""
        plans: list[Planned] = []
        for message in messages:
            if isinstance(message, ConeDetections):
                plan = self.on_detections(message)
                if plan is not None:
                    assert self.classified is not None  # set with the plan
                    plans.append(Planned(self.classified, plan, self.path_reference))
            elif isinstance(message, WheelSpeed):
                self.on_wheel_speed(message)
        command = self.control(t)
        return AutopilotStep(
            command=command,
            plans=tuple(plans),
            path_reference=self.path_reference,
            pursuit_path=self.pursuit_path,
            lookahead=self.lookahead_point,
            target_speed=self.target_speed,
        )
