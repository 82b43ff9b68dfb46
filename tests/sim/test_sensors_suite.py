"""Tests for sim.sensors.suite and sim.sensors.timing: rates, latencies, streams, faults."""

from __future__ import annotations

import math
from collections import defaultdict

import numpy as np
import pytest
from numpy.testing import assert_allclose

from conesim.core.messages import Imu, Message, NavSatFix, NavSatStatus
from conesim.core.pose import Pose2D
from conesim.sim.sensors.profiles import get_profile, override
from conesim.sim.sensors.suite import SensorSuite
from conesim.sim.sensors.timing import CaptureClock
from conesim.sim.sensors.truth import TruthSample

ANGLES = np.linspace(0.0, 2 * math.pi, 150, endpoint=False)
CONES = np.vstack([r * np.column_stack([np.cos(ANGLES), np.sin(ANGLES)]) for r in (28.0, 32.0)])
KINDS = ("blue",) * 150 + ("yellow",) * 150
TYPES = {"NavSatFix": 0, "HeadingStamped": 1, "Imu": 2, "WheelSpeed": 3, "ConeDetections": 4}


def circle_truth(t: float) -> TruthSample:
    """Driving a 30 m circle at 10 m/s between two rings of 150 cones."""
    theta = t / 3.0
    pose = Pose2D(30.0 * math.cos(theta), 30.0 * math.sin(theta), theta + math.pi / 2)
    return TruthSample(t, pose, 10.0, 1 / 3.0, 0.0, 10.0 / 3.0, CONES, KINDS)


def run(suite: SensorSuite, seconds: float, hz: float = 200.0) -> list[tuple[float, Message]]:
    """(delivery time, message) of every message over ``seconds`` of physics at ``hz``."""
    out: list[tuple[float, Message]] = []
    for k in range(round(seconds * hz)):
        t = k / hz
        out.extend((t, m) for m in suite.step(circle_truth(t)))
    return out


def fixes_of(delivered: list[tuple[float, Message]]) -> list[NavSatFix]:
    """The GPS fixes among delivered messages."""
    return [m for _, m in delivered if isinstance(m, NavSatFix)]


def key(message: Message) -> tuple:
    """A bit-exact, comparable image of a message."""
    fields = []
    for name in message.__dataclass_fields__:
        value = getattr(message, name)
        fields.append(value.tobytes() if isinstance(value, np.ndarray) else value)
    return (type(message).__name__, *fields)


def by_type(delivered: list[tuple[float, Message]]) -> dict[str, list[tuple[float, Message]]]:
    """Group (delivery time, message) pairs by message type."""
    groups: dict[str, list[tuple[float, Message]]] = defaultdict(list)
    for t, m in delivered:
        groups[type(m).__name__].append((t, m))
    return groups


@pytest.mark.parametrize(
    ("profile", "rates", "latencies"),
    [
        ("rtk", (10, 20, 100, 50, 10), (0.05, 0.05, 0.0, 0.0, 0.2)),
        ("consumer", (5, 10, 100, 50, 10), (0.12, 0.12, 0.0, 0.0, 0.2)),
    ],
)
def test_rates_and_latencies_are_exact_at_200_hz(
    profile: str, rates: tuple[int, ...], latencies: tuple[float, ...]
) -> None:
    """Per simulated second exactly `rate` messages, stamps 1/rate apart, delivered at +latency."""
    groups = by_type(run(SensorSuite(profile, seed=0), 5.0))
    for name, index in TYPES.items():
        rate, latency = rates[index], latencies[index]
        pairs = groups[name]
        stamps = np.array([m.header.stamp for _, m in pairs])
        delivered = np.array([t for t, _ in pairs])
        for second in (1, 2, 3):
            assert np.sum((stamps >= second - 1e-9) & (stamps < second + 1 - 1e-9)) == rate
        assert_allclose(np.diff(stamps), 1.0 / rate, atol=1e-9)
        assert_allclose(stamps, np.arange(len(stamps)) / rate, atol=1e-9)
        assert_allclose(delivered - stamps, latency, atol=1e-9)


DELIVERY = {"Imu": 0, "WheelSpeed": 1, "HeadingStamped": 2, "NavSatFix": 3, "ConeDetections": 4}


@pytest.mark.parametrize("profile", ["rtk", "ideal"])
def test_messages_are_sorted_by_stamp_then_delivery_rank(profile: str) -> None:
    """Within one step's output: (stamp, imu < wheel_speed < heading < gps < cones). With
    the ideal profile's zero latencies the heading and the fix share stamps with
    the IMU: they come after it."""
    suite = SensorSuite(profile, seed=0)
    for k in range(400):
        out = suite.step(circle_truth(k / 200))
        keys = [(m.header.stamp, DELIVERY[type(m).__name__]) for m in out]
        assert keys == sorted(keys)
    ideal = SensorSuite("ideal", seed=0)
    for k in range(21):
        out = ideal.step(circle_truth(k / 200))
    assert [type(m).__name__ for m in out] == [  # t = 0.1: every sensor captures
        "Imu", "WheelSpeed", "HeadingStamped", "NavSatFix", "ConeDetections",
    ]  # fmt: skip
    # t = 0.15: heading and gps of 0.1 (latency 0.05), then imu of 0.15;
    # t = 0.2: cones of 0.0 (latency 0.2) come first
    fresh = SensorSuite("rtk", seed=0)
    seen: dict[int, list[tuple[str, float]]] = {}
    for k in range(41):
        seen[k] = [(type(m).__name__, m.header.stamp) for m in fresh.step(circle_truth(k / 200))]
    assert seen[30] == [("HeadingStamped", 0.1), ("NavSatFix", 0.1), ("Imu", 0.15)]
    assert seen[40] == [
        ("ConeDetections", 0.0),
        ("HeadingStamped", 0.15),
        ("Imu", 0.2),
        ("WheelSpeed", 0.2),
    ]


def test_capture_quantised_to_the_next_physics_step() -> None:
    """Physics 64 Hz, GPS 10 Hz: stamp = ceil(6.4 k) / 64; delivery within one step after +0.05."""
    groups = by_type(run(SensorSuite("rtk", seed=0), 3.0, hz=64.0))
    fixes = groups["NavSatFix"]
    stamps = np.array([m.header.stamp for _, m in fixes])
    assert_allclose(stamps, np.ceil(6.4 * np.arange(len(stamps)) - 1e-9) / 64.0, atol=1e-12)
    delay = np.array([t for t, _ in fixes]) - stamps
    assert np.all((delay >= 0.05 - 1e-9) & (delay < 0.05 + 1 / 64))


def test_sensor_faster_than_physics_skips_and_counts() -> None:
    """IMU at 100 Hz under 64 Hz physics: one sample per step, the other nominal times skipped."""
    suite = SensorSuite("rtk", seed=0)
    groups = by_type(run(suite, 1.0, hz=64.0))
    assert len(groups["Imu"]) == 64
    # 100 nominal captures in [0, 1): 64 taken, 35 skipped, 0.99 s still ahead at t = 63/64
    assert suite.skipped_captures["imu"] == 35


def test_capture_clock_phase() -> None:
    """rate 10 Hz, phase 0.03 s at 200 Hz: captures at 0.03, 0.13, 0.23."""
    clock = CaptureClock(10.0, phase=0.03)
    due = [k / 200 for k in range(50) if clock.due(k / 200)]
    assert_allclose(due, [0.03, 0.13, 0.23], atol=1e-12)


def test_same_seed_bit_identical_and_reset_reproduces() -> None:
    """Two suites with seed 3 agree bit for bit; reset(3) after a seed-4 run repeats them."""
    a = [key(m) for _, m in run(SensorSuite("rtk", seed=3), 2.0)]
    b_suite = SensorSuite("rtk", seed=4)
    b4 = [key(m) for _, m in run(b_suite, 2.0)]
    b_suite.reset(3)
    assert a == [key(m) for _, m in run(b_suite, 2.0)]
    assert a != b4


def test_each_sensor_stream_is_independent() -> None:
    """Changing the IMU's noise (and the heading's) leaves GPS, wheel speed, cones bit-identical."""
    rtk = get_profile("rtk")
    changed = override(rtk, {"imu.gyro_noise_density": 1e-2, "heading.white_sigma": 0.1})
    base = by_type(run(SensorSuite(rtk, seed=1), 2.0))
    other = by_type(run(SensorSuite(changed, seed=1), 2.0))
    for name in ("NavSatFix", "WheelSpeed", "ConeDetections"):
        assert [key(m) for _, m in base[name]] == [key(m) for _, m in other[name]]
    for name in ("Imu", "HeadingStamped"):
        assert [key(m) for _, m in base[name]] != [key(m) for _, m in other[name]]
    # the accelerometer channels have their own streams too
    accel = [(m.accel_x, m.accel_y) for _, m in base["Imu"] if isinstance(m, Imu)]
    assert accel == [(m.accel_x, m.accel_y) for _, m in other["Imu"] if isinstance(m, Imu)]


def test_disable_and_enable_a_sensor() -> None:
    """GPS off for 1 s gives no fixes then; back on, it resumes on its 0.1 s grid."""
    suite = SensorSuite("rtk", seed=0)
    fixes = []
    for k in range(600):
        t = k / 200
        if k == 200:
            suite.set_enabled("gps", False)
        if k == 400:
            suite.set_enabled("gps", True)
        fixes += [m for m in suite.step(circle_truth(t)) if isinstance(m, NavSatFix)]
    stamps = np.array([m.header.stamp for m in fixes])
    assert_allclose(stamps, np.r_[np.arange(10) * 0.1, 2.0 + np.arange(10) * 0.1], atol=1e-9)
    assert suite.profile.gps.enabled
    with pytest.raises(ValueError, match="gps, heading, imu, wheel_speed, cones"):
        suite.set_enabled("lidar", False)


def test_injected_dropout_at_speed_and_multipath() -> None:
    """A 0.5 s dropout from 1.0 s gives 5 NO_FIX messages; other fixes are unchanged."""
    clean = fixes_of(run(SensorSuite("rtk", seed=2), 3.0))
    suite = SensorSuite("rtk", seed=2)
    suite.inject_gps_dropout(1.0, 0.5)
    faulty = fixes_of(run(suite, 3.0))
    assert len(clean) == len(faulty)
    lost = [m for m in faulty if m.status == NavSatStatus.NO_FIX]
    assert_allclose([m.header.stamp for m in lost], [1.0, 1.1, 1.2, 1.3, 1.4], atol=1e-9)
    for a, b in zip(clean, faulty, strict=True):
        if b.status != NavSatStatus.NO_FIX:
            assert key(a) == key(b)
    suite.set_gps_multipath(0.01, 20.0)
    assert suite.profile.gps.multipath_probability == 0.01
    assert suite.profile.gps.dropouts == ((1.0, 0.5),)


def test_time_must_increase() -> None:
    """Calling step twice with the same time is an error."""
    suite = SensorSuite("ideal", seed=0)
    suite.step(circle_truth(0.0))
    with pytest.raises(ValueError, match="time must increase"):
        suite.step(circle_truth(0.0))
