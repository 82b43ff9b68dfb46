"""Tests for sim.sensors.heading: noise, bias, wrapping, frame."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
from numpy.testing import assert_allclose

from conesim.core.pose import Pose2D, wrap_angle
from conesim.sim.sensors.heading import HeadingConfig, HeadingSensor
from conesim.sim.sensors.profiles import get_profile
from conesim.sim.sensors.truth import TruthSample


def heading_errors(config: HeadingConfig, yaw: float, n: int) -> np.ndarray:
    """(n,) wrapped heading errors [rad] for a constant true yaw."""
    sensor = HeadingSensor(config, seed=0)
    out = np.empty(n)
    for k in range(n):
        m = sensor.capture(TruthSample(k / config.rate, Pose2D(0.0, 0.0, yaw)))
        assert -math.pi <= m.yaw < math.pi
        out[k] = wrap_angle(m.yaw - yaw)
    return out


def test_rtk_heading_sigma_and_variance() -> None:
    """rtk: 0.25 deg white over 20,000 samples, stated variance (0.25 deg)^2, frame reference."""
    cfg = get_profile("rtk").heading
    err = heading_errors(cfg, 0.5, 20_000)
    assert_allclose(err.std(), math.radians(0.25), rtol=0.05)
    m = HeadingSensor(cfg, 0).capture(TruthSample(0.0, Pose2D(0.0, 0.0, 0.0)))
    assert_allclose(m.variance, math.radians(0.25) ** 2, rtol=1e-12)
    assert m.header.frame_id == "reference"


def test_heading_wraps_near_pi() -> None:
    """A true yaw of pi - 0.001 with 2 deg noise stays in [-pi, pi) and errors stay small."""
    err = heading_errors(HeadingConfig(white_sigma=math.radians(2.0)), math.pi - 0.001, 5000)
    assert np.max(np.abs(err)) < math.radians(10.0)
    assert_allclose(err.std(), math.radians(2.0), rtol=0.05)


def test_consumer_heading_bias_and_stated_variance() -> None:
    """consumer: stated variance (1 deg)^2 + (2 deg)^2; the error is mostly a slow bias."""
    cfg = get_profile("consumer").heading
    m = HeadingSensor(cfg, 0).capture(TruthSample(0.0, Pose2D(0.0, 0.0, 0.0)))
    assert_allclose(m.variance, math.radians(1.0) ** 2 + math.radians(2.0) ** 2, rtol=1e-12)
    err = heading_errors(cfg, 0.0, 3000)
    # Mean square of steps: 2 w^2 + 2 b^2 (1 - e^-dt/tau) = 2 + 8 (1 - e^-0.1/60) = 2.0133 deg^2
    # (a white heading with the same total would give 10 deg^2).
    step_ms = np.mean(np.diff(np.degrees(err)) ** 2)
    assert_allclose(step_ms, 2.0133, rtol=0.1)  # SE 2.6 %


def test_dropout_publishes_nothing_and_changes_no_other_heading() -> None:
    """A window (1 s, 0.5 s) at 20 Hz: the 10 captures stamped in [1, 1.5) give
    nothing; every other heading is the one without the window."""
    cfg = get_profile("rtk").heading
    clean, faulty = HeadingSensor(cfg, 2), HeadingSensor(replace(cfg, dropouts=((1.0, 0.5),)), 2)
    pose = Pose2D(0.0, 0.0, 0.3)
    pairs = [(clean.capture(TruthSample(k / 20, pose)), faulty.capture(TruthSample(k / 20, pose)))
             for k in range(60)]  # fmt: skip
    lost = [k for k, (_, m) in enumerate(pairs) if m is None]
    assert lost == list(range(20, 30))
    assert all(m == c for c, m in pairs if m is not None)
