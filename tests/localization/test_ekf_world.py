"""The fusion EKF on ``sim.world``: 15 s of autocross with the rtk sensors, late GPS included."""

from __future__ import annotations

import math

import numpy as np

from conesim.core.messages import NavSatFix
from conesim.localization.ekf import FusionEkf, RejectReason, for_profile
from conesim.sim.sensors import get_profile, override
from conesim.sim.world import World, WorldConfig
from conesim.tracks import load_track


def test_rtk_lap_start_tracks_the_truth() -> None:
    """Pure pursuit on the true centreline; the estimate stays within a few cm and 0.2 deg."""
    track = load_track("autocross")
    sensors = override(get_profile("rtk"), {"cones.enabled": False})
    world = World(track, WorldConfig(sensors=sensors), seed=1)
    path = np.asarray(track.geometry.centreline)
    ekf = FusionEkf(for_profile("rtk"))
    for msg in world.reset(1):
        ekf.process(msg)
    errors, yaw_errors, nis = [], [], []
    i = 0
    while world.time < 15.0:
        s = world.state
        window = (i + np.arange(-10, 40)) % len(path)
        i = int(window[np.argmin(np.hypot(*(path[window] - (s.x, s.y)).T))])
        target = path[(i + 8) % len(path)] - (s.x, s.y)
        alpha = math.atan2(target[1], target[0]) - s.yaw
        world.set_command(math.atan2(2 * 1.53 * math.sin(alpha), 4.0), 2.0 * (8.0 - s.vx))
        for msg in world.step().messages:
            result = ekf.process(msg)
            if isinstance(msg, NavSatFix) and result is not None and result.nis is not None:
                nis.append(result.nis)
        if world.steps % 20 == 0 and world.time > 2.0:
            est = ekf.estimate(world.time)
            e = est.pose_error(world.state.antenna_pose())
            errors.append(math.hypot(e[0], e[1]))
            yaw_errors.append(e[2])
    assert math.sqrt(np.mean(np.square(errors))) < 0.05
    assert math.degrees(math.sqrt(np.mean(np.square(yaw_errors)))) < 0.2
    assert 1.0 < np.mean(nis) < 3.0
    assert ekf.health.replays > 0  # GPS and heading arrive 0.05 s late
    assert ekf.health.count() == ekf.health.count(RejectReason.NIS_GATE) <= 2
