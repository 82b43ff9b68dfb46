"""Tests for sim.world: stepping physics and sensors by the clock."""

from __future__ import annotations

import math
from collections import Counter
from dataclasses import astuple

import numpy as np
import pytest
from numpy.testing import assert_allclose

from conesim.core.geodesy import gps_to_local_cartesian
from conesim.core.messages import ConeDetections, Message, NavSatFix
from conesim.core.pose import Pose2D
from conesim.sim.world import World, WorldConfig
from conesim.tracks import load_track


def flatten(messages: list[Message]) -> list[tuple[object, ...]]:
    """Messages as plain tuples of numbers and strings, for exact comparison."""
    out = []
    for m in messages:
        row = []
        for value in astuple(m):
            if isinstance(value, np.ndarray):
                row.append(tuple(value.ravel().tolist()))
            else:
                row.append(value)
        out.append((type(m).__name__, *row))
    return out


def test_acceleration_run_times_the_75_m() -> None:
    """Full throttle at 3 m/s^2 from 2 m behind the line covers 75 m in 6.010 s."""
    # t = sqrt(2 * 77 / 3) - sqrt(2 * 2 / 3): the CG starts 2 m behind the line.
    world = World(load_track("acceleration"), WorldConfig(sensors="ideal"))
    world.set_command(0.0, 3.0)
    while world.race_state.laps_completed == 0 and world.time < 15.0:
        world.step()
    expected = math.sqrt(2 * 77 / 3) - math.sqrt(2 * 2 / 3)
    assert world.race_state.laps_completed == 1
    assert_allclose(world.race_state.lap_times[0], expected, rtol=5e-3)
    assert not world.cones.hit_ids
    assert not world.race_state.off_track
    assert world.cones.awake_count == 0  # untouched cones stayed asleep


def test_same_seed_same_run_bit_for_bit() -> None:
    """Two worlds with the same seed give identical messages and states."""
    runs = []
    for _ in range(2):
        world = World(load_track("trackdrive"), seed=7)
        msgs: list[Message] = []
        for k in range(600):
            world.set_command(0.2 * math.sin(k / 50), 2.0)
            msgs += world.step().messages
        runs.append((flatten(msgs), world.state))
    assert runs[0] == runs[1]


def test_other_seed_other_noise() -> None:
    """A different seed changes the GPS noise."""
    fixes = []
    for seed in (1, 2):
        world = World(load_track("trackdrive"), seed=seed)
        fixes.append([m.latitude for m in world.advance(1.0) if isinstance(m, NavSatFix)])
    assert fixes[0] != fixes[1]


def test_messages_in_stamp_order_at_their_rates() -> None:
    """Two seconds of rtk sensors: each step's deliveries in stamp order, counts from rates."""
    world = World(load_track("trackdrive"), seed=0)
    msgs = world.reset(0)
    latency = {"NavSatFix": 0.05, "HeadingStamped": 0.05, "ConeDetections": 0.2}
    for _ in range(400):
        delivered = world.step().messages
        stamps = [m.header.stamp for m in delivered]
        assert stamps == sorted(stamps)
        for m in delivered:
            lag = world.time - m.header.stamp
            assert_allclose(lag, latency.get(type(m).__name__, 0.0), atol=1e-9)
        msgs += delivered
    counts = Counter(type(m).__name__ for m in msgs)
    # Captures at k / rate for t <= 2.0 - latency (rtk: GPS 0.05 s, heading 0.05 s,
    # IMU 0, wheel speed 0, cones 0.2 s).
    assert counts["NavSatFix"] == 20
    assert counts["HeadingStamped"] == 40
    assert counts["Imu"] == 201
    assert counts["WheelSpeed"] == 101
    assert counts["ConeDetections"] == 19


def test_ideal_fix_is_the_antenna_position() -> None:
    """With ideal sensors a fix maps back to the antenna's true position to 1e-6 m."""
    world = World(load_track("trackdrive"), WorldConfig(sensors="ideal"))
    world.set_command(0.1, 2.0)
    for _ in range(300):
        for m in world.step().messages:
            if isinstance(m, NavSatFix):
                x, y = gps_to_local_cartesian(m.latitude, m.longitude)
                antenna = world.state.antenna_pose()
                assert math.hypot(float(x) - antenna.x, float(y) - antenna.y) < 1e-6


def test_ideal_detections_are_the_cones_in_the_sensor_frame() -> None:
    """Ideal detections equal the cone positions seen from the antenna, exactly."""
    world = World(load_track("trackdrive"), WorldConfig(sensors="ideal"))
    scans = [m for m in world.advance(0.2) if isinstance(m, ConeDetections)]
    assert scans
    antenna = world.state.antenna_pose()
    local = antenna.inverse_transform_points(world.cones.positions)
    for point in scans[-1].points:
        assert np.min(np.hypot(*(local - point[:2]).T)) < 1e-9


def test_driving_into_cones_counts_hits_and_doo() -> None:
    """Driving down the left cone line knocks cones out and counts each cone once."""
    track = load_track("acceleration")
    left = track.left_boundary
    start = Pose2D(float(left[0, 0]) - 3.0, float(left[0, 1]), 0.0)
    world = World(track, WorldConfig(sensors="ideal"), start_pose=start)
    world.set_command(0.0, 3.0)
    world.advance(4.0)
    hits = world.cones.hit_ids
    assert {0, 1} <= hits  # the first two cones of the left line
    # Knocked out, and cones they were pushed into as well (cone-cone contact).
    assert {0, 1} <= world.cones.doo_ids
    assert len(world.cones.doo_events) == len(world.cones.doo_ids)
    assert all(track.kinds[i] in ("blue", "big_orange", "orange") for i in hits)


def test_bad_config_rejected() -> None:
    """A physics rate of 0 names the field; an unknown sensor profile lists the names."""
    with pytest.raises(ValueError, match="physics_rate"):
        WorldConfig(physics_rate=0.0)
    with pytest.raises((KeyError, ValueError), match="rtk"):
        World(load_track("trackdrive"), WorldConfig(sensors="nope"))
