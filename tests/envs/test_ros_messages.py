"""envs.ros_messages: conesim's messages as ROS 2 messages, field by field."""

from __future__ import annotations

import math

import numpy as np
from numpy.testing import assert_allclose

from conesim.core.messages import Header, HeadingStamped, Imu, WheelSpeed
from conesim.envs import ros_messages as rm

BIG = rm.UNMEASURED_VARIANCE


def test_time_is_whole_nanoseconds_split_as_ros_does() -> None:
    """sec and nanosec with 0 <= nanosec < 1e9, also below zero and at rounding edges."""
    cases = {1.25: (1, 250_000_000), -0.5: (-1, 500_000_000), 2.9999999999: (3, 0), 0.0: (0, 0)}
    for t, (sec, nanosec) in cases.items():
        stamp = rm.ros_time(t)
        assert (stamp.sec, stamp.nanosec) == (sec, nanosec), t


def test_imu_is_planar_with_gravity_and_no_orientation() -> None:
    msg = Imu(Header(1.25, "gps_antenna"), 0.3, 1.5, -2.0, 4e-4, 9e-2)
    ros = rm.imu(msg)
    assert ros.header.frame_id == "gps_antenna" and ros.header.stamp.nanosec == 250_000_000
    assert ros.orientation_covariance[0] == -1.0  # sensor_msgs/Imu: orientation not given
    assert (ros.angular_velocity.x, ros.angular_velocity.y, ros.angular_velocity.z) == (0, 0, 0.3)
    assert_allclose(ros.angular_velocity_covariance.reshape(3, 3), np.diag([0.0, 0.0, 4e-4]))
    accel = ros.linear_acceleration
    assert (accel.x, accel.y, accel.z) == (1.5, -2.0, 9.80665)
    assert_allclose(ros.linear_acceleration_covariance.reshape(3, 3), np.diag([9e-2, 9e-2, 0]))


def test_heading_is_the_antennas_orientation_with_roll_and_pitch_unmeasured() -> None:
    """A yaw of 90 deg: quaternion (0, 0, sin 45, cos 45) of gps_antenna in the
    world; yaw's variance at [2, 2], roll and pitch unmeasured."""
    ros = rm.heading_orientation(HeadingStamped(Header(2.0, "reference"), math.pi / 2, 1e-4))
    assert ros.header.frame_id == "gps_antenna" and ros.header.stamp.sec == 2
    q = ros.orientation
    assert_allclose([q.x, q.y, q.z, q.w], [0, 0, math.sqrt(0.5), math.sqrt(0.5)], atol=1e-15)
    assert_allclose(ros.orientation_covariance.reshape(3, 3), np.diag([BIG, BIG, 1e-4]))
    assert ros.angular_velocity_covariance[0] == ros.linear_acceleration_covariance[0] == -1.0


def test_wheel_speed_is_a_twist_measured_along_x_only() -> None:
    ros = rm.wheel_speed(WheelSpeed(Header(0.5, "gps_antenna"), 12.5, 0.01))
    twist = ros.twist.twist
    assert (twist.linear.x, twist.linear.y, twist.angular.z) == (12.5, 0.0, 0.0)
    cov = ros.twist.covariance.reshape(6, 6)  # row-major: x, y, z, roll, pitch, yaw
    assert_allclose(cov, np.diag([0.01, BIG, BIG, BIG, BIG, BIG]))
