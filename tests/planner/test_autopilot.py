"""The autopilot driven by synthetic messages: closed loop, rates, counters, determinism.

The closed loop uses a kinematic bicycle about the rear axle written here (the
planner's tests do not depend on ``sim``): 100 Hz steps, the frame tree at
20 Hz, detections of the synthetic track's cones at 10 Hz delivered 0.1 s
after capture, wheel speed at 50 Hz, and the autopilot stepped at 50 Hz
with the messages delivered since its last step.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from types import ModuleType

import numpy as np
import pytest
from numpy.testing import assert_allclose

from conesim.core.messages import ConeDetections, Header, Message, WheelSpeed
from conesim.core.pose import Pose2D
from conesim.localization.frames import Buffer
from conesim.planner import Autopilot, AutopilotConfig, ControlCommand, PlanStatus
from conesim.planner.bridges import TrackEstimate
from conesim.planner.config import ConeMemoryConfig

AXLE_TO_ANTENNA = 0.465  # [m] PurePursuitConfig.rear_axle_x = -0.465 in os_sensor
WHEELBASE = 1.53  # [m]


@dataclass
class Bicycle:
    """Kinematic bicycle: rear axle (x, y) [m], yaw [rad], speed v [m/s]."""

    x: float
    y: float
    yaw: float
    v: float = 0.0

    def step(self, steering: float, accel: float, dt: float) -> None:
        """Advance by ``dt`` [s] (explicit Euler)."""
        self.x += self.v * math.cos(self.yaw) * dt
        self.y += self.v * math.sin(self.yaw) * dt
        self.yaw += self.v * math.tan(steering) / WHEELBASE * dt
        self.v = max(self.v + accel * dt, 0.0)

    @property
    def antenna(self) -> Pose2D:
        """The ``gps_antenna`` pose."""
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        return Pose2D(self.x + AXLE_TO_ANTENNA * c, self.y + AXLE_TO_ANTENNA * s, self.yaw)


def drive(
    synth: ModuleType,
    track,
    seconds: float,
    config: AutopilotConfig | None = None,
    pose_error: tuple[float, float, float] | None = None,
) -> tuple[Autopilot, list[ControlCommand], list]:
    """Run the closed loop on ``track`` from its first centreline point at rest;
    from ``pose_error``'s time t [s] on, the pose broadcast is ``pose_error``'s
    (dx, dy) [m] off the car's."""
    start = synth.pose_on(track, 0)
    car = Bicycle(
        start.x - AXLE_TO_ANTENNA * math.cos(start.yaw),
        start.y - AXLE_TO_ANTENNA * math.sin(start.yaw),
        start.yaw,
    )
    buffer = Buffer()
    autopilot = Autopilot(buffer, track.global_path, config, control_rate=50.0)
    cones = np.vstack([track.left, track.right])
    pending: list[tuple[float, ConeDetections]] = []
    command = ControlCommand(0.0, 0.0, 0.0)
    commands, trace = [], []
    messages: list[Message] = []
    for k in range(round(seconds * 100)):
        t = k * 0.01
        if k % 5 == 0:
            pose = car.antenna
            if pose_error is not None and t >= pose_error[0]:
                pose = Pose2D(pose.x + pose_error[1], pose.y + pose_error[2], pose.yaw)
            synth.set_pose(buffer, pose, t)
        if k % 10 == 0:
            pending.append((t + 0.1, synth.detect(cones, car.antenna, t, max_range=20.0)))
        if k % 2 == 0:
            messages.append(WheelSpeed(Header(t, "gps_antenna"), car.v, 0.01))
        while pending and pending[0][0] <= t + 1e-9:
            messages.append(pending.pop(0)[1])
        if k % 2 == 0:  # the 50 Hz control clock
            command = autopilot.step(t, messages).command
            commands.append(command)
            messages = []
        car.step(command.steering, command.acceleration, 0.01)
        trace.append((t, car.antenna, car.v))
    return autopilot, commands, trace


def test_after_lap_one_the_car_races_the_inner_circle(synth: ModuleType) -> None:
    """On a R = 15 m circle, 3 m wide, cones 3.5 m apart, the lap-1 map's racing
    line is the inner circle (the fastest on a ring): once the car has gone
    round, it drives it: R 13.5 + 0.7 m half width + 0.4 m margin. (The
    fixture's 5 m along the centre puts the outer cones 5.5 m apart, more
    than FS allows and than ``racing_line.SMOOTHING_M`` smooths.)"""
    racing = AutopilotConfig.from_dict(
        {"pure_pursuit": {"slip_stiffness": math.inf}, "racing_line": True, "racing_margin": 0.4}
    )
    autopilot, _, trace = drive(synth, synth.circle_track(spacing=3.5), 16.0, racing)
    assert autopilot.racing is not None
    lap_one = next(i for i, (t, _, _) in enumerate(trace) if t >= 9.0)
    radius = np.array([math.hypot(p.x, p.y) for _, p, _ in trace])
    assert np.max(np.abs(radius[: lap_one // 2] - 15.0)) < 0.3  # lap 1: the midline
    late = radius[-300:]  # the last 3 s
    assert late.min() > 14.5 and late.max() < 14.8  # the antenna, ahead of the axle


def stadium(synth: ModuleType, straight: float = 30.0, radius: float = 10.0):
    """A counter-clockwise stadium: straights of ``straight`` at y = -+radius,
    half circles about (+-straight / 2, 0), 3 m wide, cones every 3 m."""
    half = 0.5 * straight
    x = np.arange(-half, half, 0.25)
    a = np.arange(-math.pi / 2, math.pi / 2, 0.25 / radius)
    centre = np.vstack(
        [
            np.column_stack([x, np.full_like(x, -radius)]),
            np.column_stack([half + radius * np.cos(a), radius * np.sin(a)]),
            np.column_stack([-x, np.full_like(x, radius)]),
            np.column_stack([-half - radius * np.cos(a), -radius * np.sin(a)]),
        ]
    )
    return synth.build_track(centre, True, 3.0, 3.0)


def test_the_racing_speed_preview_reads_the_racing_line_only(synth: ModuleType) -> None:
    """On a stadium (straights into R = 10 m turns), lap 1 is the midline's: the
    commands are the same, bit for bit, whatever ``racing_speed_preview``. On the
    racing line a target read 1 s ahead rather than 0.15 s brakes for the turns
    earlier: the car reaches each turn slower and laps slower."""
    track = stadium(synth)
    ring = np.vstack([track.centre, track.centre[:1]])
    length = float(np.sum(np.hypot(*np.diff(ring, axis=0).T)))
    runs = []
    for preview in (0.15, 1.0):
        config = AutopilotConfig.from_dict(
            {"pure_pursuit": {"slip_stiffness": math.inf}, "racing_speed_preview": preview}
        )
        autopilot, commands, trace = drive(synth, track, 22.0, config)
        assert autopilot.on_racing_line
        runs.append((commands, trace))
    (short, trace), (long, _) = runs
    # The antenna's distance travelled: lap 1 (the sensor's) ends past one length.
    xy = np.array([(p.x, p.y) for _, p, _ in trace])
    travelled = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(xy, axis=0).T))])
    lap_one = float(trace[int(np.searchsorted(travelled, length))][0])
    first_change = next(i for i, (a, b) in enumerate(zip(short, long, strict=True)) if a != b)
    # The map is done once the sensor, 0.8 m ahead of the antenna, is round
    # (12.2 s); the racing line's first scan is the first at which they differ.
    assert lap_one < short[first_change].stamp < lap_one + 1.5
    speed_short = np.array([v for _, _, v in trace])
    speed_long = np.array([v for _, _, v in runs[1][1]])
    late = slice(int(np.searchsorted(travelled, length + 2.0 * length / 3.0)), None)
    assert speed_long[late].mean() < speed_short[late].mean() - 0.5  # 11.9 against 13.1 m/s
    far_long = np.sum(np.hypot(*np.diff([(p.x, p.y) for _, p, _ in runs[1][1]], axis=0).T))
    assert far_long < travelled[-1] - 5.0  # 244 m against 255 m in 22 s


def test_a_pose_off_the_lap_map_hands_the_steering_back_to_the_cones(
    synth: ModuleType,
) -> None:
    """As above, but from 12 s (racing since about 9 s) the pose is 0.6 m off, as a
    drifting receiver's would be: the scan's cones no longer stand on the lap map's,
    and the cones' midline steers (planned in the sensor's frame, it needs no
    pose): the car is back on R 15 m. Followed by the pose, the inner circle
    would have put it 0.6 m inward of R 14.6 m, 0.4 m from the inner cones' side."""
    racing = AutopilotConfig.from_dict(
        {"pure_pursuit": {"slip_stiffness": math.inf}, "racing_line": True, "racing_margin": 0.4}
    )
    track = synth.circle_track(spacing=3.5)
    autopilot, _, trace = drive(synth, track, 18.0, racing, pose_error=(12.0, 0.6, 0.0))
    assert autopilot.racing is not None and autopilot.racing_off_map_count > 0
    assert not autopilot.on_racing_line  # nor is the feed-forward given the midline's path
    late = np.array([math.hypot(p.x, p.y) for _, p, _ in trace[-300:]])  # the last 3 s
    assert np.max(np.abs(late - 15.0)) < 0.3


def test_closed_loop_on_a_circle(synth: ModuleType, circle) -> None:
    """12 s on the R = 15 m circle: within 0.3 m of the centreline, up to speed, no fallback.

    The kinematic plant's wheels do not slip, so pure pursuit's rear-slip
    compensation is off here (with it the car runs 0.31 m inside).
    """
    no_slip = AutopilotConfig.from_dict({"pure_pursuit": {"slip_stiffness": math.inf}})
    autopilot, commands, trace = drive(synth, circle, 12.0, no_slip)
    radius = np.array([math.hypot(p.x, p.y) for _, p, _ in trace])
    speeds = np.array([v for _, _, v in trace])
    assert np.max(np.abs(radius - 15.0)) < 0.3
    # a_lat = 12 + 0.0122 v^2 [m/s^2] on R = 15 m: v^2 = 12 / (1/15 - 0.0122),
    # 14.84 m/s at most, reached from rest at 3 m/s^2 in about 5 s.
    profile = AutopilotConfig().speed_profile
    assert (profile.a_lat_max, profile.a_lat_aero) == (12.0, 0.0122)
    v_circle = math.sqrt(12.0 / (1.0 / 15.0 - 0.0122))
    assert v_circle == pytest.approx(14.84, abs=0.01)
    # Lap 1 (94 m) is driven by 9 s; from there the racing line's own limit,
    # 13 + 0.0132 v^2 (``racing_speed_profile``): 15.59 m/s on R = 15 m (the
    # line keeps to R 14.9 m there, cones 5 m apart: 15.36-15.60 m/s planned).
    t = np.array([stamp for stamp, _, _ in trace])
    assert v_circle - 1.0 < speeds[np.searchsorted(t, 8.0)] < v_circle + 0.3
    assert autopilot.on_racing_line
    v_racing = math.sqrt(13.0 / (1.0 / 15.0 - 0.0132))
    assert v_racing == pytest.approx(15.59, abs=0.01)
    assert v_racing - 1.0 < speeds[-1] < v_racing + 0.3
    assert len(commands) == 600  # 50 Hz for 12 s
    assert autopilot.plan_count == 119  # 10 Hz, the first delivered at 0.1 s
    assert autopilot.fallback_count == autopilot.failed_count == autopilot.skipped_count == 0
    assert autopilot.tf_latest_count == 0  # every stamp had its transform
    # Every intermediate is exposed.
    plan = autopilot.plan
    assert plan is not None and plan.status is PlanStatus.OK
    assert len(autopilot.left_cones) > 0 and len(autopilot.right_cones) > 0
    assert plan.bridge_lines.shape[1:] == (2, 2) and len(plan.midpoints) >= 2
    assert plan.waypoints().speeds.shape == (len(plan.path),)
    assert autopilot.lookahead_point is not None and autopilot.path_now.shape[1] == 2
    assert autopilot.target_speed > 0.0
    # speed_source "global": the waypoints' speeds are the global plan's,
    # v_circle all round the circle, once the car is at it.
    assert autopilot.global_speed is not None
    assert_allclose(plan.speeds[5:], v_circle, rtol=2e-3)


def test_closed_loop_is_deterministic(synth: ModuleType, hairpin) -> None:
    """Two runs give the same commands, bit for bit."""
    _, a, _ = drive(synth, hairpin, 4.0)
    _, b, _ = drive(synth, hairpin, 4.0)
    assert a == b


def test_closed_loop_through_a_hairpin(synth: ModuleType, hairpin) -> None:
    """Around the R = 3.5 m hairpin: within 0.85 m of the middle, where the path's room
    lets it (measured 0.81 m): 1.5 m half lane less 0.7 m half car less 0.25 m
    clearance leaves the rear axle 0.55 m; the antenna, 0.47 m ahead of it,
    runs up to 0.47^2 / (2 R) = 0.03 m farther out, plus pure pursuit's cut.

    At sqrt(14 / (1/3.5 - 0.0143)) = 7.2 m/s the lookahead law gives
    2 + 0.4 * 7.2 = 4.9 m, whose chord in R = 3.5 m lies
    R - sqrt(R^2 - (L_d / 2)^2) = 0.96 m inside: more than the 0.8 m a 1.4 m
    car has in a 3 m lane. Capped at the radius (lookahead_radius_ratio 1),
    the chord lies 0.47 m inside.
    """
    # the limits these figures were worked for (the defaults: 12 m/s^2, 1)
    fast = {"speed_profile": {"a_lat_max": 14.0, "steering_weight_min": 0.0}}
    autopilot, _, trace = drive(synth, hairpin, 7.5, AutopilotConfig.from_dict(fast))
    antenna = np.array([[p.x, p.y] for _, p, _ in trace])
    chord = 3.5 - math.sqrt(3.5**2 - (3.5 / 2) ** 2)
    assert chord == pytest.approx(0.47, abs=0.01)
    assert np.max(hairpin.distance_to_centre(antenna)) < 0.85
    assert antenna[-1, 1] > 6.5 and antenna[-1, 0] < -4.0  # on the exit leg (y = 7 m)
    assert autopilot.fallback_count == 0
    uncapped = AutopilotConfig.from_dict(
        {**fast, "pure_pursuit": {"lookahead_radius_ratio": math.inf}}
    )
    _, _, trace = drive(synth, hairpin, 7.5, uncapped)
    wide = np.array([[p.x, p.y] for _, p, _ in trace])
    assert np.max(hairpin.distance_to_centre(wide)) > 0.8


def test_every_step_controls_on_the_callers_clock(synth: ModuleType, straight) -> None:
    """One command per step, stamped with the step's time; a step's plans are
    the ones its detections made; the rate must be positive."""
    scene = synth.make_scene(straight, Pose2D(0.0, 0.0, 0.0))
    autopilot = Autopilot(scene.buffer, straight.global_path, control_rate=25.0)
    out = [autopilot.step(k * 0.04) for k in range(5)]
    assert [o.command.stamp for o in out] == pytest.approx([0.0, 0.04, 0.08, 0.12, 0.16])
    assert all(o.plans == () and o.lookahead is None for o in out)  # no detection yet
    planned = autopilot.step(0.2, [scene.detections])
    ((only,),) = (planned.plans,)
    assert only.plan is autopilot.plan and only.plan.status is PlanStatus.OK
    assert planned.path_reference is autopilot.path_reference and len(planned.path_reference)
    assert planned.lookahead is not None
    with pytest.raises(ValueError, match="control_rate must be > 0"):
        Autopilot(scene.buffer, straight.global_path, control_rate=0.0)


def test_without_a_path_it_stops_with_straight_wheels(synth: ModuleType, straight) -> None:
    """Before any detection: steering 0; at 5 m/s it brakes (PI on v_ref = 0: -1.5*5 - ...)."""
    scene = synth.make_scene(straight, Pose2D(0.0, 0.0, 0.0))
    autopilot = Autopilot(scene.buffer, straight.global_path)
    assert autopilot.control(0.0) == ControlCommand(0.0, 0.0, 0.0)
    autopilot.on_wheel_speed(WheelSpeed(Header(0.02, "gps_antenna"), 5.0, 0.01))
    command = autopilot.control(0.02)
    assert command.steering == 0.0 and command.acceleration < -7.0


def test_fallback_is_counted_and_the_path_kept(synth: ModuleType, straight) -> None:
    """A good plan, then an empty detection: a fallback, counted, the path carried on."""
    scene = synth.make_scene(straight, Pose2D(0.0, 0.0, 0.0))
    autopilot = Autopilot(scene.buffer, straight.global_path)
    empty = ConeDetections(Header(scene.stamp, "os_sensor"), np.zeros((0, 3)))
    assert autopilot.on_detections(empty).status is PlanStatus.FAILED
    assert autopilot.failed_count == 1
    autopilot.on_detections(scene.detections)
    assert autopilot.plan.status is PlanStatus.OK
    good = autopilot.plan.path
    plan = autopilot.on_detections(empty)
    assert plan.status is PlanStatus.FALLBACK and autopilot.fallback
    assert autopilot.fallback_count == 1 and autopilot.plan_count == 3
    assert np.array_equal(plan.path, good)  # same pose: the same path
    assert autopilot.control(1.0).steering == 0.0


def test_speed_from_the_frame_tree_without_wheel_speed(synth: ModuleType, straight) -> None:
    """No wheel speed: 1 m in 0.1 s of the sensor in the frame tree is 10 m/s."""
    scene = synth.make_scene(straight, Pose2D(0.0, 0.0, 0.0), stamp=0.9)
    synth.set_pose(scene.buffer, Pose2D(1.0, 0.0, 0.0), 1.0)
    autopilot = Autopilot(scene.buffer, straight.global_path)
    assert autopilot.speed() == pytest.approx(10.0)


def test_detection_newer_than_the_frame_tree(synth: ModuleType, straight) -> None:
    """A detection stamped after the newest transform is classified at the latest one."""
    scene = synth.make_scene(straight, Pose2D(0.0, 0.0, 0.0), stamp=1.0)
    late = ConeDetections(Header(1.05, "os_sensor"), scene.detections.points)
    autopilot = Autopilot(scene.buffer, straight.global_path)
    plan = autopilot.on_detections(late)
    assert plan is not None and plan.status is PlanStatus.OK
    assert autopilot.tf_latest_count == 1
    assert autopilot.classified.header.stamp == 1.0


def test_no_frame_tree_skips_the_detection(straight) -> None:
    """Without any transform the detection is skipped and counted."""
    autopilot = Autopilot(Buffer(), straight.global_path, AutopilotConfig())
    det = ConeDetections(Header(1.0, "os_sensor"), np.zeros((1, 3)))
    assert autopilot.on_detections(det) is None
    assert autopilot.skipped_count == 1


def test_pursuit_continues_along_the_global_path_beyond_a_short_path(
    synth: ModuleType, circle
) -> None:
    """On the R 15 m circle at 15 m/s (lookahead 2 + 0.4 * 15 = 8 m, under the
    radius cap of 15 m), cones seen to 9 m give a path that ends inside the
    lookahead circle (6.4 m from the rear axle, the cones placed 5 m apart
    as they fall at 15 deg round the circle): the target is then on the
    global path (the centreline), 8 m from the rear axle, and the steering
    the circle's geometric angle; without the continuation it is the path's
    last point, nearer."""
    pose = synth.pose_on(circle, 30)
    scene = synth.make_scene(circle, pose, max_range=9.0)
    speed = WheelSpeed(Header(scene.stamp, "gps_antenna"), 15.0, 0.01)
    steered = {}
    for beyond in (True, False):
        autopilot = Autopilot(
            scene.buffer, circle.global_path, AutopilotConfig(pursue_global_beyond_path=beyond)
        )
        autopilot.on_wheel_speed(speed)
        assert autopilot.on_detections(scene.detections).status is PlanStatus.OK
        command = autopilot.control(scene.stamp)
        path = autopilot.path_now
        axle_x = autopilot.config.pure_pursuit.rear_axle_x
        end_distance = math.hypot(path[-1, 0] - axle_x, path[-1, 1])
        assert end_distance < 7.0  # the cone path ends well inside the circle
        target = autopilot.lookahead_point
        distance = math.hypot(target[0] - axle_x, target[1])
        if beyond:
            assert_extension_continues(autopilot, path, radius=15.0, pose=pose)
            assert distance == pytest.approx(8.0, abs=1e-6)
            on_map = pose.transform_points(target[None])[0]
            assert math.hypot(*on_map) == pytest.approx(15.0, abs=0.02)  # on the centreline
        else:
            assert np.array_equal(autopilot.pursuit_path, path)
            assert_allclose(target, path[-1])
            assert distance == pytest.approx(end_distance)
        steered[beyond] = command.steering
    # The rear axle is on the circle too: the geometric angle for a chord of
    # 8 m in R 15 m is atan(L / R) (slip-corrected a little more).
    assert steered[True] == pytest.approx(math.atan(WHEELBASE / 15.0), rel=0.15)


def test_a_path_reaching_past_the_lookahead_is_pursued_as_it_is(synth: ModuleType, circle) -> None:
    """Cones seen to 20 m: the path reaches beyond 8 m, nothing is added."""
    scene = synth.make_scene(circle, synth.pose_on(circle, 0), max_range=20.0)
    autopilot = Autopilot(scene.buffer, circle.global_path)
    autopilot.on_wheel_speed(WheelSpeed(Header(scene.stamp, "gps_antenna"), 15.0, 0.01))
    autopilot.on_detections(scene.detections)
    autopilot.control(scene.stamp)
    assert np.array_equal(autopilot.pursuit_path, autopilot.path_now)


def assert_extension_continues(
    autopilot: Autopilot, path: np.ndarray, radius: float, pose: Pose2D
) -> np.ndarray:
    """The global points added to ``path`` start 0.5 m past its end along the
    circle of ``radius`` about the origin and follow it every 0.5 m (chords
    of 0.5 m); returns them in ``reference``."""
    added = autopilot.pursuit_path[len(path) :]
    assert len(added) > 0 and np.array_equal(autopilot.pursuit_path[: len(path)], path)
    gap = math.hypot(*(added[0] - path[-1]))
    assert gap == pytest.approx(0.5, abs=0.05)  # the cone path's end is on the centreline
    steps = np.hypot(*np.diff(added, axis=0).T)
    assert_allclose(steps, 0.5, atol=1e-3)
    on_map = pose.transform_points(added)
    assert_allclose(np.hypot(on_map[:, 0], on_map[:, 1]), radius, atol=0.01)
    return on_map


def test_pursuit_continuation_wraps_round_a_loop(synth: ModuleType, circle) -> None:
    """Near the end of the loop's stations (the car at 315 deg, the cone path
    to about 343 deg) the global points run on past station 0 (360 deg)
    without a jump."""
    pose = synth.pose_on(circle, 630)
    scene = synth.make_scene(circle, pose, max_range=9.0)
    autopilot = Autopilot(scene.buffer, circle.global_path)
    autopilot.on_wheel_speed(WheelSpeed(Header(scene.stamp, "gps_antenna"), 15.0, 0.01))
    assert autopilot.on_detections(scene.detections).status is PlanStatus.OK
    autopilot.control(scene.stamp)
    on_map = assert_extension_continues(autopilot, autopilot.path_now, 15.0, pose)
    angles = np.unwrap(np.arctan2(on_map[:, 1], on_map[:, 0]))
    assert angles[0] < 0.0 < angles[-1]  # atan2: from -17 deg to +17 deg


def test_pursuit_continuation_stops_at_an_open_path_s_end(synth: ModuleType, straight) -> None:
    """An open lane ending at x = 70 m, the car at 64 m at 15 m/s: the cone
    path reaches the end, 6.5 m from the rear axle, inside the 8 m
    lookahead, and the global path has nothing beyond it to add."""
    pose = Pose2D(64.0, 0.0, 0.0)
    scene = synth.make_scene(straight, pose, max_range=20.0)
    autopilot = Autopilot(scene.buffer, straight.global_path)
    autopilot.on_wheel_speed(WheelSpeed(Header(scene.stamp, "gps_antenna"), 15.0, 0.01))
    autopilot.on_detections(scene.detections)
    autopilot.control(scene.stamp)
    on_map = pose.transform_points(autopilot.pursuit_path)
    assert on_map[:, 0].max() == pytest.approx(70.0, abs=1e-6)
    assert np.array_equal(autopilot.pursuit_path, autopilot.path_now)
    assert autopilot.steering.distance < autopilot.steering.lookahead == pytest.approx(8.0)


def test_lookahead_cap_reads_the_corner_beyond_the_cones(synth: ModuleType, hairpin) -> None:
    """The cone path stops 2 m before the R 3.5 m hairpin's turn, the car 6 m
    before it at 12 m/s (lookahead 2 + 0.4 * 12 = 6.8 m, into the turn):
    with the global points beyond the cones the cap sees the turn and holds
    the lookahead to its radius, so the target is on the entry leg, not
    across the turn's inside; without them no cap applies."""
    centre = hairpin.centre
    pose = synth.pose_on(hairpin, int(np.argmin(np.hypot(centre[:, 0] + 6.0, centre[:, 1]))))
    scene = synth.make_scene(hairpin, pose, max_range=20.0)
    for beyond in (True, False):
        config = AutopilotConfig(pursue_global_beyond_path=beyond)
        autopilot = Autopilot(scene.buffer, hairpin.global_path, config)
        autopilot.on_wheel_speed(WheelSpeed(Header(scene.stamp, "gps_antenna"), 12.0, 0.01))
        plan = autopilot.on_detections(scene.detections)
        keep = int(np.argmin(pose.transform_points(plan.path)[:, 0] < -2.0))
        assert keep >= 2
        autopilot.plan = dataclasses.replace(plan, path=plan.path[:keep], speeds=plan.speeds[:keep])
        autopilot.path_reference = autopilot.path_reference[:keep]
        autopilot.path_speeds = autopilot.path_speeds[:keep]
        autopilot.path_curvature = autopilot.path_curvature[:keep]
        autopilot.control(scene.stamp)
        target = pose.transform_points(autopilot.lookahead_point[None])[0]
        if beyond:
            assert autopilot.steering.lookahead == pytest.approx(3.5, rel=0.02)
            assert -3.5 < target[0] < -2.0 and abs(target[1]) < 0.1  # on the entry leg
        else:
            assert autopilot.steering.lookahead == pytest.approx(6.8)


def test_pursuit_continuation_takes_the_right_circle_at_a_figure_of_eight(
    synth: ModuleType,
) -> None:
    """A skidpad-like eight: circle A (centre (0, R)) counter-clockwise, then
    circle B (centre (0, -R)) clockwise, both leaving the origin along +x.
    A cone path ending at the origin is equally near both stations there;
    the station window about the sensor's station picks the one ahead: at
    the end of A the global points go on round B (y < 0), at the end of B
    round A (y > 0)."""
    from conesim.tracks.global_path import global_path_from_centreline

    radius = 9.125  # [m] the skidpad's centre line
    a = np.arange(0.0, 2.0 * math.pi, 0.01)
    circle_a = np.column_stack([radius * np.sin(a), radius - radius * np.cos(a)])
    circle_b = np.column_stack([radius * np.sin(a), -radius + radius * np.cos(a)])
    eight = np.vstack([circle_a, circle_b])
    stations = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(eight, axis=0).T))])
    lap = stations[-1] + float(np.hypot(*(eight[0] - eight[-1])))
    half = stations[len(circle_a)]

    def at(s: np.ndarray) -> np.ndarray:
        s = np.mod(s, lap)
        ring = np.vstack([eight, eight[:1]])
        ring_s = np.append(stations, lap)
        return np.column_stack([np.interp(s, ring_s, ring[:, 0]), np.interp(s, ring_s, ring[:, 1])])

    path = global_path_from_centreline(eight, closed=True)
    for end_station, side in ((half, -1.0), (lap, 1.0)):
        sensor = at(np.array([end_station - 5.0, end_station - 4.9]))
        yaw = math.atan2(*(sensor[1] - sensor[0])[::-1])
        pose = Pose2D(float(sensor[0, 0]), float(sensor[0, 1]), yaw)
        buffer = Buffer()
        synth.set_pose(buffer, pose, 1.0)
        autopilot = Autopilot(buffer, path)
        cone_path = at(end_station - np.arange(4.0, -0.01, -0.5))  # to the origin
        autopilot.station_hint = end_station - 5.0
        autopilot.path_reference = cone_path
        autopilot.path_curvature = np.zeros(len(cone_path))
        local = pose.inverse_transform_points(cone_path)
        pursued, _ = autopilot._pursuit_path(local, 15.0)
        added = pose.transform_points(pursued[len(local) :])
        assert len(added) > 10
        assert np.all(side * added[2:, 1] > 0.0), (side, added[:4])


def test_no_pursuit_continuation_where_the_map_and_the_cones_disagree(
    synth: ModuleType, circle
) -> None:
    """The scene of the continuation test with the pose in the frame tree
    0.5 m to the side of where the cones were seen: the cone path's end lies
    0.5 m from the global path, within the default 1 m gap (continued), not
    within a gap of 0.3 m (the car keeps to the cones). (A pose more than
    about 1 m off already fails the planner's own checks of the cones
    against the global path.)"""
    scene = synth.make_scene(circle, synth.pose_on(circle, 30), max_range=9.0)
    buffer = Buffer()
    synth.set_pose(buffer, synth.pose_on(circle, 30, lateral=0.5), scene.stamp)
    for gap, continued in ((1.0, True), (0.3, False)):
        autopilot = Autopilot(
            buffer, circle.global_path, AutopilotConfig(pursue_global_max_gap=gap)
        )
        autopilot.on_wheel_speed(WheelSpeed(Header(scene.stamp, "gps_antenna"), 15.0, 0.01))
        assert autopilot.on_detections(scene.detections).status is PlanStatus.OK
        autopilot.control(scene.stamp)
        added = len(autopilot.pursuit_path) - len(autopilot.path_now)
        assert (added > 0) is continued, (gap, added)


def test_speeds_brake_to_a_stop_within_a_path_that_leaves_the_map(
    synth: ModuleType, straight
) -> None:
    """A 20 m path in view whose end lies 2 m off the global path (more than the 1 m
    ``pursue_global_max_gap``): the plan brakes to a stop at its end,
    v^2 = 2 a_brake d (a_brake 8 m/s^2: 17.9 m/s 20 m before it, 12.6 m/s 10 m
    before). The same path ending on the map ends at the global plan's speed."""
    scene = synth.make_scene(straight, Pose2D(0.0, 0.0, 0.0))
    autopilot = Autopilot(scene.buffer, straight.global_path)
    autopilot.on_wheel_speed(WheelSpeed(Header(scene.stamp, "gps_antenna"), 25.0, 0.01))
    x = np.arange(0.0, 20.01, 0.5)
    off_map = np.column_stack([x, np.where(x > 17.0, (x - 17.0) * 2.0 / 3.0, 0.0)])
    s = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(off_map, axis=0).T))])
    v = autopilot._global_speeds(off_map, s, sensor_station=10.0)
    assert v[-1] == 0.0
    assert np.all(v <= np.sqrt(2.0 * 8.0 * (s[-1] - s)) + 1e-9)
    assert v[0] == pytest.approx(math.sqrt(2.0 * 8.0 * s[-1]), rel=1e-9)
    on_map = np.column_stack([x, np.zeros_like(x)])
    v_on = autopilot._global_speeds(on_map, x - x[0], sensor_station=10.0)
    v_end = autopilot.global_speed.speed_at(10.0 + 20.0)
    assert v_on[-1] == pytest.approx(v_end, rel=1e-9) and v_end > 20.0


def test_a_path_off_the_lane_on_the_map_is_refused(synth: ModuleType, straight) -> None:
    """``off_lane_reason`` on a straight global path along x (sensor at the origin,
    heading +x), a 3 m lane measured 0.2 m left of it: a path 1.65 m left of
    the global path lies 1.45 m from the lane's middle, inside half the width
    (1.5 m); at 1.75 m, 1.55 m: refused, unless the margin allows 0.1 m more."""
    scene = synth.make_scene(straight, Pose2D(0.0, 0.0, 0.0))
    track = TrackEstimate(width=3.0, centre=0.2, measured=True)
    x = np.arange(0.0, 10.01, 0.5)
    for margin, y, refused in ((0.0, 1.65, False), (0.0, 1.75, True), (0.1, 1.75, False)):
        autopilot = Autopilot(
            scene.buffer, straight.global_path, AutopilotConfig(lane_check_margin=margin)
        )
        path = np.column_stack([x, np.where(x > 6.0, y, 0.0)])
        reason = autopilot.off_lane_reason(path, scene.stamp, track, sensor_station=10.0)
        assert bool(reason) is refused, (margin, y, reason)
        if refused:
            assert "1.55 m from its middle, allowed 1.50 m" in reason


def test_an_off_lane_plan_falls_back_to_the_previous_path(synth: ModuleType, straight) -> None:
    """A sound plan, then the same scene with a lane check that refuses every
    path (a margin of -10 m): the second plan carries the first one forward,
    with the check's reason."""
    scene = synth.make_scene(straight, Pose2D(0.0, 0.0, 0.0))
    autopilot = Autopilot(scene.buffer, straight.global_path, AutopilotConfig())
    assert autopilot.on_detections(scene.detections).status is PlanStatus.OK
    strict = Autopilot(scene.buffer, straight.global_path, AutopilotConfig(lane_check_margin=-10.0))
    strict.plan = autopilot.plan
    plan = strict.on_detections(scene.detections)
    assert plan.status is PlanStatus.FALLBACK
    assert "leaves the lane on the map" in plan.reason


def test_cones_missed_in_a_scan_are_planned_from_memory(synth: ModuleType, straight) -> None:
    """The same scene twice, then with every other cone missed: with the memory
    the third plan has all the cones of the first; without, half."""
    scene = synth.make_scene(straight, Pose2D(0.0, 0.0, 0.0))
    full = scene.detections
    half = ConeDetections(full.header, full.points[::2], full.colours)
    for keep, expected in ((5, len(full)), (0, len(half))):
        config = AutopilotConfig(cone_memory=ConeMemoryConfig(keep_scans=keep))
        autopilot = Autopilot(scene.buffer, straight.global_path, config)
        autopilot.on_detections(full)
        autopilot.on_detections(full)
        autopilot.on_detections(half)
        assert autopilot.classified is not None
        assert len(autopilot.classified.points) == expected
