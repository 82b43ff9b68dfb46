"""The world's IMU integrates to the true motion (what the EKF relies on)."""

from __future__ import annotations

import math

from localization.messages import Imu
from sim.world import World, WorldConfig
from tracks import load_track


def test_ideal_gyro_integrates_to_the_true_heading_change() -> None:
    """Summing ideal gyro samples x period reproduces the heading change to 1e-9 rad."""
    world = World(load_track("trackdrive"), WorldConfig(sensors="ideal"))
    yaw0 = world.state.antenna_pose().yaw
    world.set_command(0.3, 2.0)
    total = 0.0
    for _ in range(800):  # 4 s of a tightening turn
        for m in world.step():
            if isinstance(m, Imu) and m.header.stamp > 0.0:
                total += m.yaw_rate * 0.01
    yaw1 = world.state.antenna_pose().yaw
    assert abs(math.remainder(yaw1 - yaw0 - total, 2 * math.pi)) < 1e-9
