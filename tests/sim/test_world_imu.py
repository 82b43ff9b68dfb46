"""The world's IMU integrates to the true motion (what the EKF relies on)."""

from __future__ import annotations

import math

from conesim.core.messages import Imu, WheelSpeed
from conesim.sim.world import World, WorldConfig
from conesim.tracks import load_track


def test_ideal_gyro_integrates_to_the_true_heading_change() -> None:
    """Summing ideal gyro samples x period reproduces the heading change to 1e-9 rad."""
    world = World(load_track("trackdrive"), WorldConfig(sensors="ideal"))
    yaw0 = world.state.antenna_pose().yaw
    world.set_command(0.3, 2.0)
    total = 0.0
    for _ in range(800):  # 4 s of a tightening turn
        for m in world.step().messages:
            if isinstance(m, Imu) and m.header.stamp > 0.0:
                total += m.yaw_rate * 0.01
    yaw1 = world.state.antenna_pose().yaw
    assert abs(math.remainder(yaw1 - yaw0 - total, 2 * math.pi)) < 1e-9


def test_ideal_wheel_speed_is_the_positions_own_speed() -> None:
    """Accelerating at the drive limit on the start straight, the ideal wheel
    speed equals the central difference of the antenna positions around its
    stamp, (p[k+1] - p[k-1]) / 2 dt, to 1e-6 m/s. Before the truth speed was
    the positions' own it ran dt/2 x 3 m/s^2 = 7.5 mm/s ahead."""
    world = World(load_track("trackdrive"), WorldConfig(sensors="ideal"))
    world.set_command(0.0, 3.0)
    poses = {0: world.state.antenna_pose()}
    speeds: dict[int, float] = {}
    for k in range(1, 301):  # 1.5 s
        for m in world.step().messages:
            if isinstance(m, WheelSpeed):
                speeds[round(m.header.stamp / world.dt)] = m.speed
        poses[k] = world.state.antenna_pose()
    checked = 0
    for k, speed in speeds.items():
        if 50 <= k < 300:
            a, b = poses[k - 1], poses[k + 1]
            central = math.hypot(b.x - a.x, b.y - a.y) / (2 * world.dt)
            assert abs(speed - central) < 1e-6
            checked += 1
    assert checked == 62  # 50 Hz over 250 steps of 5 ms


def test_ideal_accelerometer_integrates_to_the_positions_velocity_change() -> None:
    """In a steady turn (about 0.75 rad/s, 7 m/s^2), 1 s of ideal IMU samples,
    turned into the world frame at each sample's mid-interval heading, add up
    to the change of the positions' central-difference velocity to 1 mm/s. With
    the step's own velocity change (half a step ahead of the positions) they
    were 12 mm/s apart: dt w |a| / 2 per second."""
    world = World(load_track("trackdrive"), WorldConfig(sensors="ideal"))
    world.set_command(0.0, 3.0)
    poses = {0: world.state.antenna_pose()}
    samples: list[Imu] = []
    for k in range(1, 1402):
        if k == 600:
            world.set_command(0.12, 0.3)
        samples += [m for m in world.step().messages if isinstance(m, Imu)]
        poses[k] = world.state.antenna_pose()
    dt = world.dt

    def velocity(k: int) -> tuple[float, float]:
        a, b = poses[k - 1], poses[k + 1]
        return (b.x - a.x) / (2 * dt), (b.y - a.y) / (2 * dt)

    k0, k1 = 1000, 1200  # 5 s to 6 s: the turn has settled
    yaw = poses[k0].yaw
    sx = sy = 0.0
    for m in samples:
        if k0 * dt + 1e-9 < m.header.stamp <= k1 * dt + 1e-9:
            mid = yaw + 0.5 * m.yaw_rate * 0.01
            sx += 0.01 * (math.cos(mid) * m.accel_x - math.sin(mid) * m.accel_y)
            sy += 0.01 * (math.sin(mid) * m.accel_x + math.cos(mid) * m.accel_y)
            yaw += m.yaw_rate * 0.01
    (ux, uy), (vx, vy) = velocity(k0), velocity(k1)
    assert math.hypot(vx - ux, vy - uy) > 6.0  # the velocity turned through ~0.75 rad
    assert math.hypot(sx - (vx - ux), sy - (vy - uy)) < 1e-3
