"""Tests for sim.sensors.imu: white sigma from the noise density, bias walk, variances."""

from __future__ import annotations

import math

import numpy as np
from numpy.testing import assert_allclose

from conesim.core.pose import Pose2D
from conesim.sim.sensors.imu import ImuConfig, ImuSensor
from conesim.sim.sensors.profiles import get_profile
from conesim.sim.sensors.truth import TruthSample

G = 9.80665


def imu_errors(config: ImuConfig, n: int) -> np.ndarray:
    """(n, 3) errors of gyro z, accel x, accel y for a truth of (0.4 rad/s, 1.5, -2.0 m/s^2)."""
    imu = ImuSensor(config, seed=0)
    out = np.empty((n, 3))
    pose = Pose2D(0.0, 0.0, 0.0)
    for k in range(n):
        truth = TruthSample(k / config.rate, pose, 8.0, 0.4, 1.5, -2.0)
        m = imu.capture(truth)
        out[k] = (m.yaw_rate - 0.4, m.accel_x - 1.5, m.accel_y + 2.0)
    return out


def test_adis16448_white_sigma_is_density_over_sqrt_dt() -> None:
    """At 100 Hz: gyro 0.0135 deg/s/sqrt(Hz) * 10 = 0.135 deg/s; accel 0.23 mg * 10 = 2.3 mg."""
    cfg = ImuConfig(rate=100.0)  # ADIS16448 densities, no bias walk
    gyro, accel = math.radians(0.135), 2.3e-3 * G
    assert_allclose([cfg.gyro_sigma, cfg.accel_sigma], [gyro, accel], rtol=1e-12)
    err = imu_errors(cfg, 20_000)
    assert_allclose(err.std(axis=0), [gyro, accel, accel], rtol=0.05)  # SE 0.5 %
    assert np.all(np.abs(err.mean(axis=0)) < 0.03 * np.array([gyro, accel, accel]) * 4)


def test_mpu6000_white_sigma_and_stated_variance() -> None:
    """MPU-6000 at 100 Hz: 0.30 deg/sqrt(h) -> 0.05 deg/s; 0.24 mg/sqrt(Hz) -> 2.4 mg."""
    cfg = get_profile("consumer").imu
    m = ImuSensor(cfg, 0).capture(TruthSample(0.0, Pose2D(0.0, 0.0, 0.0)))
    assert_allclose(m.yaw_rate_variance, math.radians(0.05) ** 2, rtol=1e-12)
    assert_allclose(m.accel_variance, (2.4e-3 * G) ** 2, rtol=1e-12)
    assert m.header.frame_id == "gps_antenna"


def test_white_sigma_scales_with_rate() -> None:
    """The same density at 400 Hz doubles the discrete sigma of 100 Hz."""
    assert_allclose(ImuConfig(rate=400.0).gyro_sigma, 2 * ImuConfig(rate=100.0).gyro_sigma)


def test_bias_random_walk_drifts_as_k_sqrt_t() -> None:
    """White noise off, K = 1e-3 rad/s/sqrt(s): after 100 s the gyro bias std over 1,000
    seeds is K sqrt(100 s) = 0.01 rad/s."""
    k_walk = 1e-3
    cfg = ImuConfig(
        rate=0.5, gyro_noise_density=0.0, accel_noise_density=0.0, gyro_bias_walk=k_walk
    )
    finals = []
    for seed in range(1000):
        imu = ImuSensor(cfg, seed)
        for k in range(51):
            m = imu.capture(TruthSample(2.0 * k, Pose2D(0.0, 0.0, 0.0)))
        finals.append(m.yaw_rate)
        assert m.accel_x == 0.0
    assert_allclose(np.std(finals), k_walk * 10.0, rtol=0.1)  # SE 2.2 %


def test_ideal_imu_is_exact() -> None:
    """The ideal profile returns the truth and zero variances."""
    m = ImuSensor(get_profile("ideal").imu, 5).capture(
        TruthSample(0.3, Pose2D(1.0, 2.0, 3.0), 5.0, -0.2, 0.7, 3.3)
    )
    assert (m.yaw_rate, m.accel_x, m.accel_y) == (-0.2, 0.7, 3.3)
    assert m.yaw_rate_variance == 0.0 and m.accel_variance == 0.0


def test_integrating_imu_reports_the_interval_mean() -> None:
    """At 100 Hz over 200 Hz steps a sample is the mean of the two steps it covers."""
    imu = ImuSensor(get_profile("ideal").imu, seed=0)
    pose = Pose2D(0.0, 0.0, 0.0)
    steps = [(0.005, 1.0, 2.0, -1.0), (0.010, 3.0, 4.0, 1.0)]
    for t, w, ax, ay in steps:
        imu.observe(TruthSample(t, pose, yaw_rate=w, accel_x=ax, accel_y=ay))
    msg = imu.capture(TruthSample(0.010, pose, yaw_rate=3.0, accel_x=4.0, accel_y=1.0))
    assert_allclose([msg.yaw_rate, msg.accel_x, msg.accel_y], [2.0, 3.0, 0.0])
    imu.observe(TruthSample(0.015, pose, yaw_rate=5.0))
    imu.observe(TruthSample(0.020, pose, yaw_rate=7.0))
    msg = imu.capture(TruthSample(0.020, pose, yaw_rate=7.0))
    assert msg.yaw_rate == 6.0  # only the steps since the last capture


def test_constant_bias_adds_to_every_sample() -> None:
    """White noise and walks off, gyro bias 0.02 rad/s, accel bias (0.3, -0.2) m/s^2:
    every error is exactly the bias."""
    cfg = ImuConfig(gyro_noise_density=0.0, accel_noise_density=0.0, gyro_bias=0.02,
                    accel_bias=(0.3, -0.2))  # fmt: skip
    assert_allclose(imu_errors(cfg, 100), np.tile([0.02, 0.3, -0.2], (100, 1)), atol=1e-12)


def test_noise_scale_widens_the_noise_not_the_stated_variance() -> None:
    """ADIS16448 at 100 Hz times 3: 0.405 deg/s gyro spread (5 % over 20,000), the
    message still states (0.135 deg/s)^2; scale 1 is the plain sensor bit for bit."""
    err = imu_errors(ImuConfig(noise_scale=3.0), 20_000)
    assert_allclose(err[:, 0].std(), 3 * math.radians(0.135), rtol=0.05)
    m = ImuSensor(ImuConfig(noise_scale=3.0), 0).capture(TruthSample(0.0, Pose2D(0, 0, 0)))
    assert_allclose(m.yaw_rate_variance, math.radians(0.135) ** 2, rtol=1e-12)
    assert np.array_equal(imu_errors(ImuConfig(noise_scale=1.0), 50), imu_errors(ImuConfig(), 50))
