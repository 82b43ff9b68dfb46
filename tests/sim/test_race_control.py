"""Tests for sim.race_control and sim.progress on a circular track."""

from __future__ import annotations

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose

from conesim.core.polyline import Polyline
from conesim.core.pose import Pose2D
from conesim.sim import race_control
from conesim.sim.progress import PolylineProgress, segment_crossing, segment_crossing_xy
from conesim.sim.race_control import RaceControl, RaceRules

R = 20.0  # [m] centreline radius
N = 400


def circle_control(**rules: float) -> RaceControl:
    """A counter-clockwise circle, 4 m wide, timing line across it at angle 0."""
    t = np.linspace(0.0, 2 * math.pi, N, endpoint=False)
    centre = np.column_stack([R * np.cos(t), R * np.sin(t)])
    lap = N * 2 * R * math.sin(math.pi / N)
    return RaceControl(
        centre,
        True,
        half_widths=np.full(N, 2.0),
        start_finish=np.array([[R - 2.0, 0.0], [R + 2.0, 0.0]]),
        lap_length=lap,
        car_length=2.9,
        car_width=1.4,
        rules=RaceRules(**rules),
    )


def pose_on_circle(angle: float, radius: float = R) -> Pose2D:
    """Pose on a CCW circle at polar ``angle``, heading along it."""
    return Pose2D(radius * math.cos(angle), radius * math.sin(angle), angle + math.pi / 2)


def drive(rc: RaceControl, angles: np.ndarray, dt: float, radius: float = R) -> None:
    """Feed race control a pose per step."""
    prev = pose_on_circle(angles[0], radius)
    rc.start(0.0, prev)
    for k, a in enumerate(angles[1:], start=1):
        pose = pose_on_circle(a, radius)
        rc.update((k - 1) * dt, k * dt, prev, pose)
        prev = pose


def test_lap_times_at_constant_speed() -> None:
    """At 10 m/s the lap time is 2 pi R / v = 12.566 s, interpolated within the step."""
    rc = circle_control()
    v, dt = 10.0, 1 / 200
    omega = v / R
    start = -0.1  # 2 m behind the line
    angles = start + omega * dt * np.arange(int(3 * 2 * math.pi / omega / dt))
    drive(rc, angles, dt)
    st = rc.state
    assert st.laps_completed == 2
    # The polygon's chords are slightly shorter than the arc; the time is exact.
    assert_allclose(st.lap_times, [2 * math.pi * R / v] * 2, rtol=1e-9)
    assert_allclose(st.clock_start, 0.1 / omega, rtol=1e-6)
    assert not st.off_track and not st.stuck


def test_rocking_over_the_line_never_counts() -> None:
    """Back and forth across the line 50 times: no lap."""
    rc = circle_control()
    angles = 0.05 * np.sin(np.linspace(0, 50 * 2 * math.pi, 5000))
    drive(rc, angles, 1 / 200)
    assert rc.state.laps_completed == 0
    assert abs(rc.state.progress_m) < 1.1


def test_off_track_event_has_start_and_end() -> None:
    """Driving a circle of radius 24 m (body fully outside a 22 m edge) is an excursion."""
    rc = circle_control()
    dt = 1 / 200
    angles = np.linspace(0.5, 1.0, 50)
    prev = pose_on_circle(angles[0])
    rc.start(0.0, prev)
    radii = [R] * 10 + [R + 4.0] * 20 + [R] * 20
    for k, (a, r) in enumerate(zip(angles[1:], radii[1:], strict=True), start=1):
        pose = pose_on_circle(a, r)
        rc.update((k - 1) * dt, k * dt, prev, pose)
        prev = pose
    events = rc.state.off_track
    assert len(events) == 1
    assert_allclose([events[0].start, events[0].end], [10 * dt, 30 * dt])


def test_stuck_after_no_progress() -> None:
    """Standing still for longer than stuck_time_s sets stuck."""
    rc = circle_control(stuck_time_s=2.0)
    pose = pose_on_circle(1.0)
    rc.start(0.0, pose)
    dt = 0.1
    for k in range(1, 30):
        rc.update((k - 1) * dt, k * dt, pose, pose)
        assert rc.state.stuck == (k * dt >= 2.0 - 1e-9)


def test_projection_window_follows_a_figure_eight() -> None:
    """On a figure eight the projection stays on the branch being driven."""
    t = np.linspace(0, 2 * math.pi, 400, endpoint=False)
    eight = np.column_stack([10 * np.sin(t), 10 * np.sin(t) * np.cos(t)])
    prog = PolylineProgress(Polyline(eight, True), window_m=5.0)
    s_values = [prog.project(p).station[0] for p in eight[3::5]]  # start off the crossing
    assert np.all(np.diff(s_values) > 0)


def test_projecting_anew_leaves_the_walk_where_it_was() -> None:
    """Driving the eight through its crossing, a look at a far point
    (``project_xy_anew``, as the start-pose check does) between two steps
    changes none of the walk's answers."""
    t = np.linspace(0, 2 * math.pi, 400, endpoint=False)
    eight = np.column_stack([10 * np.sin(t), 10 * np.sin(t) * np.cos(t)])
    plain = PolylineProgress(Polyline(eight, True), window_m=5.0)
    looked = PolylineProgress(Polyline(eight, True), window_m=5.0)
    far = PolylineProgress(Polyline(eight, True), window_m=5.0).project_xy(-9.0, -2.0)
    for p in eight[3::5]:
        assert looked.project_xy_anew(-9.0, -2.0) == far  # as a fresh search finds it
        assert looked.project_xy(*p) == plain.project_xy(*p)


ARC_SEGMENTS = 94  # chords on each 15 m semicircle of the stadium


def stadium_control(**rules: float) -> RaceControl:
    """A counter-clockwise stadium 4 m wide: y = 0 from x = 0 to 100 (driving
    +x), a semicircle of 15 m about (100, 15), y = 30 back to x = 0, a
    semicircle about (0, 15); the line across it at x = 10."""
    straight = np.arange(0.0, 100.0, 0.5)
    a = np.linspace(-math.pi / 2, math.pi / 2, ARC_SEGMENTS + 1)[:-1]
    centre = np.vstack(
        [
            np.column_stack([straight, np.zeros_like(straight)]),
            np.column_stack([100.0 + 15.0 * np.cos(a), 15.0 + 15.0 * np.sin(a)]),
            np.column_stack([100.0 - straight, np.full_like(straight, 30.0)]),
            np.column_stack([-15.0 * np.cos(a), 15.0 - 15.0 * np.sin(a)]),
        ]
    )
    arc = ARC_SEGMENTS * 30.0 * math.sin(math.pi / (2 * ARC_SEGMENTS))  # chords' length
    return RaceControl(
        centre,
        True,
        half_widths=np.full(len(centre), 2.0),
        start_finish=np.array([[10.0, -2.0], [10.0, 2.0]]),
        lap_length=200.0 + 2.0 * arc,
        car_length=2.9,
        car_width=1.4,
        rules=RaceRules(**rules),
    )


def cut_across_the_infield(rc: RaceControl) -> list[bool]:
    """From (20, 0) along y = 0 to x = 50, straight across the infield to the
    other straight (50, 30), then 10 m along it; off track at each step."""
    legs = [
        [Pose2D(x, 0.0, 0.0) for x in np.arange(20.0, 50.0, 0.05)],
        [Pose2D(50.0, y, math.pi / 2) for y in np.arange(0.0, 30.0, 0.05)],
        [Pose2D(x, 30.0, math.pi) for x in np.arange(50.0, 39.99, -0.05)],
    ]
    poses = [p for leg in legs for p in leg]
    dt = 0.01
    rc.start(0.0, poses[0])
    off = []
    for k in range(1, len(poses)):
        rc.update((k - 1) * dt, k * dt, poses[k - 1], poses[k])
        off.append(rc.state.is_off_track)
    return off


def test_a_cut_across_the_infield_rejoins_the_other_straight() -> None:
    """Off the track, the projection moves to the straight the car crosses to
    once that is 1 m nearer (y > 15.5); the 147.1 m the cut skips (50 m, a
    semicircle's chords, 50 m) are not progress: 30 m before it and 10 m after.
    One excursion: the body leaves at y > 2 + 1.45 and is back at y > 26.55."""
    rc = stadium_control()
    off = cut_across_the_infield(rc)
    assert rc.progress.project_xy(40.0, 30.0)[2] > 200 + ARC_SEGMENTS  # on the top straight
    assert_allclose(rc.state.progress_m, 30.0 + 10.0, atol=1e-9)
    events = rc.state.off_track
    assert len(events) == 1 and events[0].end is not None
    # Steps of 0.05 m from y = 0 at k = 600 (0.01 s each): out at 3.45 m, back at 26.55 m.
    assert_allclose([events[0].start, events[0].end], [6.0 + 0.69, 6.0 + 5.31], atol=0.011)
    assert not any(off[-200:])


def test_a_cut_backwards_takes_off_the_stretch_it_skips() -> None:
    """From the top straight at x = 60 (driving -x) 10 m to x = 50, across the
    infield down to the bottom straight, then 10 m along it: the 147.1 m
    skipped backwards are taken off (10 - 147.1 + 10 m), so that driving them
    again only earns them back."""
    rc = stadium_control()
    legs = [
        [Pose2D(x, 30.0, math.pi) for x in np.arange(60.0, 50.0, -0.05)],
        [Pose2D(50.0, y, -math.pi / 2) for y in np.arange(30.0, 0.0, -0.05)],
        [Pose2D(x, 0.0, 0.0) for x in np.arange(50.0, 60.01, 0.05)],
    ]
    poses = [p for leg in legs for p in leg]
    rc.start(0.0, poses[0])
    for k in range(1, len(poses)):
        rc.update((k - 1) * 0.01, k * 0.01, poses[k - 1], poses[k])
    arc = ARC_SEGMENTS * 30.0 * math.sin(math.pi / (2 * ARC_SEGMENTS))
    assert_allclose(rc.state.progress_m, 10.0 - (50.0 + arc + 50.0) + 10.0, atol=1e-9)
    assert len(rc.state.off_track) == 1


def test_without_rejoining_the_walk_holds_the_straight_it_left() -> None:
    """The same cut with the rejoin margin out of reach: the walk stays on
    y = 0, the car counts as off track to the end, and the 10 m driven along
    the other straight read as 10 m backwards: progress 30 - 10 m."""
    rc = stadium_control(rejoin_margin_m=1e6)
    off = cut_across_the_infield(rc)
    assert off[-1]
    assert_allclose(rc.state.progress_m, 30.0 - 10.0, atol=1e-9)


def test_beyond_the_end_of_an_open_centreline_is_off_the_track() -> None:
    """Along the axis of an open straight (0 to 100 m, 4 m wide) past its end:
    off once every corner is 2 m beyond it, the CG at 100 + 2 + 0.7 m (the
    car's half width across the axis: the corners' offsets along the normal)."""
    x = np.arange(0.0, 100.5, 0.5)
    rc = RaceControl(
        np.column_stack([x, np.zeros_like(x)]),
        False,
        half_widths=np.full(len(x), 2.0),
        start_finish=np.array([[10.0, -2.0], [10.0, 2.0]]),
        lap_length=90.0,
        car_length=2.9,
        car_width=1.4,
    )
    poses = [Pose2D(px, 0.0, 0.0) for px in np.arange(90.0, 110.0, 0.01)]
    rc.start(0.0, poses[0])
    for k in range(1, len(poses)):
        rc.update((k - 1) * 0.01, k * 0.01, poses[k - 1], poses[k])
    events = rc.state.off_track
    assert len(events) == 1 and events[0].end is None
    assert_allclose(poses[round(events[0].start / 0.01)].x, 102.7, atol=0.011)
    assert rc.is_off_track_at(poses[-1]) and not rc.is_off_track_at(Pose2D(101.0, 0.0, 0.0))


def test_lateral_is_the_distance_to_the_foot_point() -> None:
    """On a straight from (0, 0) to (10, 0): (5, 2) is 2 m left; (13, 4), past
    the end, is 5 m from it (3-4-5), with the side's sign; (-3, -4) is -5 m."""
    line = np.column_stack([np.arange(0.0, 10.5, 0.5), np.zeros(21)])
    for point, lateral in (((5.0, 2.0), 2.0), ((13.0, 4.0), 5.0), ((-3.0, -4.0), -5.0)):
        walked, fresh = PolylineProgress(Polyline(line)), PolylineProgress(Polyline(line))
        walked.project((5.0, 0.0))  # the next query walks
        assert walked.project_xy(*point)[1] == pytest.approx(lateral, abs=1e-12)
        assert fresh.project(point).lateral[0] == pytest.approx(lateral, abs=1e-12)


def test_segment_crossing_fraction() -> None:
    """A step from (0,-1) to (0,3) crosses the x axis a quarter of the way."""
    u = segment_crossing(
        np.array([0.0, -1.0]), np.array([0.0, 3.0]), np.array([-1.0, 0.0]), np.array([1.0, 0.0])
    )
    assert u == pytest.approx(0.25)
    assert (
        segment_crossing(np.zeros(2), np.ones(2), np.array([5.0, 0.0]), np.array([6.0, 0.0]))
        is None
    )


def test_bad_rules_rejected() -> None:
    """Out-of-range rules name the field."""
    with pytest.raises(ValueError, match="min_lap_fraction"):
        RaceRules(min_lap_fraction=0.0)


def test_off_track_needs_all_four_corners_outside() -> None:
    """Car 1.4 m wide along the edge: CG 2.5 m out (inner corners 1.8 m) is on; 2.8 m is off."""
    for offset, expected in ((0.5, False), (0.8, True)):
        rc = circle_control()
        prev = pose_on_circle(1.0)
        rc.start(0.0, prev)
        pose = pose_on_circle(1.0 + 1e-3, R + 2.0 + offset)  # half width 2 m + offset
        rc.update(0.0, 0.005, prev, pose)
        assert rc.state.is_off_track is expected


def test_quick_rejections_answer_as_the_full_tests() -> None:
    """The per-step shortcuts change no answer: a CG more than a corner's reach
    (hypot(1.45, 0.7) = 1.61 m, + 1 cm) inside the 2 m half width is on the
    track, as placing the four corners says; a step outside the timing line's
    box (grown by 1 cm) does not cross the line, as the crossing test says."""
    rc = circle_control()
    assert rc._corner_reach == pytest.approx(math.hypot(1.45, 0.7) + 0.01)
    rng = np.random.default_rng(8)
    quick = 0
    for _ in range(3000):
        lateral, yaw, heading = rng.uniform(-3.5, 3.5), rng.uniform(-4, 4), rng.uniform(-4, 4)
        tx, ty = math.cos(heading), math.sin(heading)
        c, sn = math.cos(yaw), math.sin(yaw)
        lats = [
            lateral + (c * cx - sn * cy) * -ty + (sn * cx + c * cy) * tx
            for cx, cy in ((1.45, 0.7), (1.45, -0.7), (-1.45, 0.7), (-1.45, -0.7))
        ]
        full = all(v > 2.0 for v in lats) or all(v < -2.0 for v in lats)
        assert rc._off(lateral, 0, tx, ty, yaw) is full
        quick += abs(lateral) + rc._corner_reach < 2.0
        p0 = (R + rng.uniform(-3.0, 3.0), rng.uniform(-0.5, 0.5))
        p1 = (p0[0] + rng.normal(0.0, 0.1), p0[1] + rng.normal(0.0, 0.1))
        if race_control._outside(p0, p1, rc._line_box):
            assert segment_crossing_xy(p0, p1, rc._line_xy) is None
    assert quick > 300  # the shortcut was taken


def test_off_track_quick_answers_are_the_corner_test() -> None:
    """Both quick answers of ``_off`` (well inside, well beyond) agree with the four corners."""
    rc = circle_control()
    rng = np.random.default_rng(3)
    hl, hw = rc._half_footprint
    half = rc._half_widths_list[0]
    for lateral, yaw, angle in zip(
        rng.uniform(-3 * half, 3 * half, 4000),
        rng.uniform(-math.pi, math.pi, 4000),
        rng.uniform(-math.pi, math.pi, 4000),
        strict=True,
    ):
        tx, ty = math.cos(angle), math.sin(angle)
        full = bool(race_control._corners_off(lateral, tx, ty, yaw, half, hl, hw))
        assert rc._off(float(lateral), 0, tx, ty, float(yaw)) == full
