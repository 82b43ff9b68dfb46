"""The vehicle TF broadcaster: raw (the ROS pipeline), fused (the EKF) and truth modes."""

from __future__ import annotations

import math

import numpy as np
import pytest

from conesim.core.messages import (
    FRAME_GPS_ANTENNA,
    FRAME_REFERENCE,
    Header,
    HeadingStamped,
    Imu,
    PointStamped,
)
from conesim.core.pose import Pose2D
from conesim.localization.broadcaster import BroadcasterConfig, VehicleTfBroadcaster
from conesim.localization.ekf import FusionEkf
from conesim.localization.ekf.synthetic import fix_message
from conesim.localization.frames import Buffer, TransformStamped
from conesim.localization.modes import LocalizationMode


def raw(buffer: Buffer) -> VehicleTfBroadcaster:
    return VehicleTfBroadcaster(buffer, BroadcasterConfig(mode=LocalizationMode.RAW))


def seed_quaternion(yaw: float) -> list[float]:
    """tf2::Quaternion::setRPY(0, 0, yaw) as (x, y, z, w)."""
    return [0.0, 0.0, math.sin(yaw / 2), math.cos(yaw / 2)]


def test_raw_reproduces_the_seeds_transform() -> None:
    """Translation from /local_xy, rotation setRPY(0, 0, yaw), os_sensor 0.1 m below."""
    buffer = Buffer()
    node = raw(buffer)
    node.on_local_xy(PointStamped(Header(0.9, FRAME_REFERENCE), 100.0, 50.0, 0.0))
    node.on_global_yaw(HeadingStamped(Header(0.95, FRAME_REFERENCE), math.pi / 2, 1e-4))
    sent = node.step(1.0)
    assert sent is not None
    t = buffer.lookup_transform("reference", "gps_antenna", 1.0)
    assert (t.frame_id, t.child_frame_id, t.stamp) == ("reference", "gps_antenna", 1.0)
    np.testing.assert_array_equal(t.translation, [100.0, 50.0, 0.0])
    np.testing.assert_allclose(t.rotation, seed_quaternion(math.pi / 2), atol=1e-15)
    s = buffer.lookup_transform("reference", "os_sensor", 1.0)
    np.testing.assert_allclose(s.translation, [100.0, 50.0, -0.1], atol=1e-12)
    np.testing.assert_allclose(s.rotation, seed_quaternion(math.pi / 2), atol=1e-15)
    # A point 1 m ahead of the sensor (x forward) is 1 m north of it at yaw 90 deg.
    ahead = buffer.transform_points("reference", "os_sensor", [[1.0, 0.0, 0.0]], 1.0)
    np.testing.assert_allclose(ahead, [[100.0, 51.0, -0.1]], atol=1e-12)


def test_raw_sends_the_last_values_and_nothing_before_both() -> None:
    """Nothing until both topics arrived; then always the latest cached pair."""
    buffer = Buffer()
    node = raw(buffer)
    node.on_local_xy(PointStamped(Header(0.0, FRAME_REFERENCE), 1.0, 2.0))
    assert node.step(0.0) is None
    node.on_global_yaw(HeadingStamped(Header(0.0, FRAME_REFERENCE), 0.5, 1e-4))
    node.on_local_xy(PointStamped(Header(0.0, FRAME_REFERENCE), 3.0, 4.0))
    node.on_local_xy(PointStamped(Header(0.0, FRAME_REFERENCE), math.nan, 4.0))  # dropped
    sent = node.step(0.05)
    assert sent is not None
    assert sent.to_pose2d() == Pose2D(3.0, 4.0, 0.5)


def test_static_link_sent_once_and_dynamic_at_20_hz() -> None:
    """Stepping at 200 Hz for 1 s publishes 20 dynamic transforms; the static one once."""

    class CountingBuffer(Buffer):
        static_calls = 0

        def set_transform_static(self, transform: TransformStamped, authority: str = "a") -> bool:
            CountingBuffer.static_calls += 1
            return super().set_transform_static(transform, authority)

    buffer = CountingBuffer()
    node = raw(buffer)
    node.on_local_xy(PointStamped(Header(0.0, FRAME_REFERENCE), 1.0, 2.0))
    node.on_global_yaw(HeadingStamped(Header(0.0, FRAME_REFERENCE), 0.5, 1e-4))
    stamps = [s.stamp for k in range(200) if (s := node.step(k / 200)) is not None]
    np.testing.assert_allclose(stamps, np.arange(20) / 20, atol=1e-12)
    assert CountingBuffer.static_calls == 1
    info = buffer.frames()
    assert info["os_sensor"].static
    assert info["os_sensor"].parent == "gps_antenna"
    assert info["gps_antenna"].length == 20


def test_fused_publishes_the_ekf_estimate_at_the_broadcast_time() -> None:
    """Fused mode sends the filter's pose predicted to t; nothing before it initialises."""
    buffer = Buffer()
    ekf = FusionEkf()
    node = VehicleTfBroadcaster(buffer, ekf=ekf)
    assert node.config.mode == LocalizationMode.FUSED
    assert node.step(0.0) is None
    ekf.process(Imu(Header(0.0, FRAME_GPS_ANTENNA), 0.2, 0.0, 0.0, 1e-6, 1e-4))
    ekf.process(HeadingStamped(Header(0.0, FRAME_REFERENCE), 1.0, 1e-4))
    ekf.process(fix_message(0.0, 5.0, 6.0, 0.05))
    sent = node.step(0.05)
    assert sent is not None
    expected = ekf.estimate(0.05).pose
    pose = buffer.lookup_pose2d("reference", "gps_antenna", 0.05)
    np.testing.assert_allclose([pose.x, pose.y, pose.yaw], [expected.x, expected.y, expected.yaw])
    assert pose.yaw == pytest.approx(1.0 + 0.2 * 0.05)


def test_truth_mode_publishes_the_given_pose() -> None:
    """Truth mode sends what the caller passes, and needs it."""
    buffer = Buffer()
    node = VehicleTfBroadcaster(buffer, BroadcasterConfig(mode=LocalizationMode.TRUTH))
    node.step(0.0, truth=Pose2D(1.0, 2.0, -3.0))
    assert buffer.lookup_pose2d("reference", "gps_antenna", 0.0) == Pose2D(1.0, 2.0, -3.0)
    with pytest.raises(ValueError, match="truth"):
        node.step(0.05)


def test_bad_settings_raise_with_the_allowed_values() -> None:
    """Unknown mode lists the modes; fused without a filter raises."""
    with pytest.raises(ValueError, match="allowed: \\['fused', 'raw', 'truth', 'cones', 'slam'\\]"):
        BroadcasterConfig(mode="gps")  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="needs the FusionEkf"):
        VehicleTfBroadcaster(Buffer())
    assert BroadcasterConfig(mode="raw").mode is LocalizationMode.RAW  # type: ignore[arg-type]


def test_prefixed_frames_for_a_second_car() -> None:
    """Frame names come from the config (seed 003: car1/gps_antenna)."""
    buffer = Buffer()
    cfg = BroadcasterConfig(
        mode=LocalizationMode.TRUTH, antenna_frame="car1/gps_antenna", sensor_frame="car1/os_sensor"
    )
    VehicleTfBroadcaster(buffer, cfg).step(0.0, truth=Pose2D(1.0, 0.0, 0.0))
    t = buffer.lookup_transform("reference", "car1/os_sensor", 0.0)
    np.testing.assert_allclose(t.translation, [1.0, 0.0, -0.1])
