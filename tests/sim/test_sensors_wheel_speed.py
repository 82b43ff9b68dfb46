"""Tests for sim.sensors.wheel_speed: per-episode scale error and white noise."""

from __future__ import annotations

import numpy as np
from numpy.testing import assert_allclose

from conesim.core.pose import Pose2D
from conesim.sim.sensors.truth import TruthSample
from conesim.sim.sensors.wheel_speed import WheelSpeedConfig, WheelSpeedSensor


def test_scale_error_is_fixed_per_episode_with_configured_spread() -> None:
    """Scale 1 +- 0.5 %: std over 20,000 episodes 0.005 within 5 %; fixed within one."""
    cfg = WheelSpeedConfig(white_sigma=0.0, scale_sigma=0.005)
    scales = np.array([WheelSpeedSensor(cfg, seed).scale for seed in range(20_000)])
    assert_allclose(scales.std(), 0.005, rtol=0.05)
    assert abs(scales.mean() - 1.0) < 2e-4
    sensor = WheelSpeedSensor(cfg, 3)
    speeds = [
        sensor.capture(TruthSample(k / 50, Pose2D(0, 0, 0), speed=10.0)).speed for k in range(10)
    ]
    assert_allclose(speeds, 10.0 * sensor.scale, rtol=1e-15)


def test_white_noise_std_and_variance() -> None:
    """0.05 m/s white over 20,000 samples at 12 m/s; stated variance 0.0025 m^2/s^2."""
    sensor = WheelSpeedSensor(WheelSpeedConfig(white_sigma=0.05, scale_sigma=0.0), 0)
    v = np.array(
        [
            sensor.capture(TruthSample(k / 50, Pose2D(0, 0, 0), speed=12.0)).speed
            for k in range(20_000)
        ]
    )
    assert_allclose(v.std(), 0.05, rtol=0.05)
    assert abs(v.mean() - 12.0) < 0.002
    m = sensor.capture(TruthSample(0.0, Pose2D(0, 0, 0)))
    assert_allclose(m.variance, 0.0025)
    assert m.header.frame_id == "gps_antenna"


def test_reset_draws_a_new_scale_reproducibly() -> None:
    """reset(seed) gives the scale a fresh sensor built with that seed gets."""
    cfg = WheelSpeedConfig()
    sensor = WheelSpeedSensor(cfg, 1)
    sensor.reset(2)
    assert sensor.scale == WheelSpeedSensor(cfg, 2).scale != WheelSpeedSensor(cfg, 1).scale


def test_slip_noise_is_a_share_of_the_speed_and_not_stated() -> None:
    """Slip 0.02 at 15 m/s: 0.3 m/s spread over 20,000 samples (chi-square, 4 sigma:
    2 %), none at rest, the stated variance the encoder's alone."""
    cfg = WheelSpeedConfig(white_sigma=0.0, scale_sigma=0.0, slip_sigma=0.02)
    sensor = WheelSpeedSensor(cfg, 0)
    v = np.array([sensor.capture(TruthSample(k / 50, Pose2D(0, 0, 0), speed=15.0)).speed
                  for k in range(20_000)])  # fmt: skip
    assert_allclose(v.std(), 0.3, rtol=0.02)
    at_rest = sensor.capture(TruthSample(400.0, Pose2D(0, 0, 0), speed=0.0))
    assert at_rest.speed == 0.0 and at_rest.variance == 0.0
