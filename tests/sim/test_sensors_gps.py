"""Tests for sim.sensors.gps: fixes, white and Gauss-Markov errors, faults."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
from numpy.testing import assert_allclose

from conesim.core.geodesy import DEFAULT_ORIGIN, ReferenceOrigin, gps_to_local_cartesian
from conesim.core.messages import NavSatFix, NavSatStatus
from conesim.core.pose import Pose2D
from conesim.sim.sensors.gps import GpsConfig, GpsReceiver
from conesim.sim.sensors.profiles import get_profile
from conesim.sim.sensors.truth import TruthSample


def fix_errors(config: GpsConfig, n: int, seed: int = 0) -> np.ndarray:
    """East/north errors [m], (n, 2), of n fixes of an antenna parked at (12, -7)."""
    gps = GpsReceiver(config, seed)
    lat, lon = np.empty(n), np.empty(n)
    pose = Pose2D(12.0, -7.0, 0.3)
    for k in range(n):
        fix = gps.capture(TruthSample(k / config.rate, pose))
        assert fix is not None
        lat[k], lon[k] = fix.latitude, fix.longitude
    x, y = gps_to_local_cartesian(lat, lon)
    return np.column_stack([x - 12.0, y + 7.0])


def test_ideal_fix_maps_back_to_the_antenna() -> None:
    """Ideal fixes go through gps_to_local_cartesian back to the antenna to 1e-6 m."""
    origin = ReferenceOrigin(47.0, 8.5, 400.0)
    gps = GpsReceiver(get_profile("ideal").gps, seed=3, origin=origin)
    rng = np.random.default_rng(0)
    for x, y in rng.uniform(-500.0, 500.0, (50, 2)):
        fix = gps.capture(TruthSample(0.0, Pose2D(x, y, 1.0)))
        assert isinstance(fix, NavSatFix)
        ex, ey = gps_to_local_cartesian(fix.latitude, fix.longitude, origin)
        assert_allclose([ex, ey], [x, y], rtol=0, atol=1e-6)
        assert fix.altitude == 400.0
        assert fix.header.frame_id == "gps_antenna"


def test_white_noise_std_matches_config() -> None:
    """White 0.5 m per axis over 20,000 fixes: std 0.5 m within 5 % (SE 0.5 %), mean ~ 0."""
    err = fix_errors(GpsConfig(white_sigma=0.5), 20_000)
    assert_allclose(err.std(axis=0), [0.5, 0.5], rtol=0.05)
    assert np.all(np.abs(err.mean(axis=0)) < 0.02)  # SE 0.0035 m
    assert abs(np.corrcoef(err[:-1, 0], err[1:, 0])[0, 1]) < 0.03


def test_gauss_markov_bias_correlation_and_std() -> None:
    """Bias only, sigma 1 m, tau 0.1 s at 10 Hz: lag-1 autocorrelation e^-1 = 0.368, std 1 m."""
    err = fix_errors(GpsConfig(white_sigma=0.0, bias_sigma=1.0, bias_tau=0.1), 20_000)
    assert_allclose(err.std(axis=0), [1.0, 1.0], rtol=0.05)  # SE 0.6 %
    for axis in range(2):
        lag1 = np.corrcoef(err[:-1, axis], err[1:, axis])[0, 1]
        assert abs(lag1 - math.exp(-1.0)) < 0.02  # SE 0.0066


def test_reported_covariance_is_the_nominal_total() -> None:
    """Consumer: s = 2.5 / 1.1774 = 2.1233 m, covariance diag(s^2, s^2, (2 s)^2)."""
    cfg = get_profile("consumer").gps
    fix = GpsReceiver(cfg, 0).capture(TruthSample(0.0, Pose2D(0.0, 0.0, 0.0)))
    assert fix is not None
    s = 2.5 / 1.1774
    assert_allclose(fix.position_covariance, np.diag([s * s, s * s, 4 * s * s]), rtol=1e-12)
    stated = GpsReceiver(GpsConfig(reported_sigma=0.1), 0).capture(
        TruthSample(0.0, Pose2D(0.0, 0.0, 0.0))
    )
    assert stated is not None
    assert_allclose(stated.position_covariance[0, 0], 0.01)
    assert get_profile("rtk").gps.fix_status == NavSatStatus.GBAS_FIX


def test_consumer_error_is_bias_dominated_and_white_variant_is_not() -> None:
    """Mean square of fix-to-fix error steps: 2 w^2 + 2 b^2 (1 - e^-dt/tau) per axis.

    consumer: w = 0.713 m, b = 2 m, tau 60 s, dt 0.2 s: 1.0165 + 0.0266 = 1.043 m^2;
    consumer_white: w = 2.1233 m: 2 w^2 = 9.017 m^2. Same total sigma, 8.6x apart.
    """
    for name, expected in (("consumer", 1.043), ("consumer_white", 9.017)):
        err = fix_errors(get_profile(name).gps, 3000)
        step_ms = np.mean(np.diff(err, axis=0) ** 2)
        assert_allclose(step_ms, expected, rtol=0.1)  # SE about 2.6 %


def test_dropout_no_fix_and_silent_leave_other_fixes_unchanged() -> None:
    """A dropout [1.0, 1.5) gives 5 NO_FIX (or no) messages; all other fixes are unchanged."""
    base = GpsConfig(white_sigma=0.3, bias_sigma=0.5, bias_tau=5.0)
    pose = Pose2D(3.0, 4.0, 0.0)

    def run(cfg: GpsConfig) -> list[NavSatFix | None]:
        gps = GpsReceiver(cfg, seed=11)
        return [gps.capture(TruthSample(k / 10, pose)) for k in range(30)]

    clean = run(base)
    no_fix = run(replace(base, dropouts=((1.0, 0.5),)))
    silent = run(replace(base, dropouts=((1.0, 0.5),), dropout_mode="silent"))
    for k in range(30):
        a, b, c = clean[k], no_fix[k], silent[k]
        assert a is not None and b is not None
        if 10 <= k < 15:
            assert b.status == NavSatStatus.NO_FIX and math.isnan(b.latitude)
            assert c is None
        else:
            assert c is not None
            assert (a.latitude, a.longitude) == (b.latitude, b.longitude)
            assert (a.latitude, a.longitude) == (c.latitude, c.longitude)


def test_multipath_outliers_rate_and_size() -> None:
    """1 % of 20,000 fixes jump by exactly 20 m (white 0.02 m elsewhere)."""
    cfg = GpsConfig(white_sigma=0.02, multipath_probability=0.01, multipath_magnitude=20.0)
    norm = np.linalg.norm(fix_errors(cfg, 20_000), axis=1)
    outliers = norm > 10.0
    assert abs(outliers.mean() - 0.01) < 0.003  # SE 0.0007
    assert_allclose(norm[outliers], 20.0, atol=0.1)
    assert np.all(norm[~outliers] < 0.2)


def test_multipath_switch_leaves_base_noise_unchanged() -> None:
    """Non-outlier fixes are bit-identical with and without multipath (separate stream)."""
    clean = fix_errors(GpsConfig(white_sigma=0.5), 500, seed=4)
    faulty = fix_errors(GpsConfig(white_sigma=0.5, multipath_probability=0.2), 500, seed=4)
    same = np.all(clean == faulty, axis=1)
    assert 0.7 < same.mean() < 0.9
    assert_allclose(np.linalg.norm(faulty[~same] - clean[~same], axis=1), 20.0, rtol=1e-6)


def test_default_origin_used() -> None:
    """Without an origin the receiver uses the ROS pipeline's 37.540190, 127.076488."""
    fix = GpsReceiver(get_profile("ideal").gps, 0).capture(TruthSample(0.0, Pose2D(0, 0, 0)))
    assert fix is not None
    assert_allclose(
        [fix.latitude, fix.longitude], [DEFAULT_ORIGIN.lat_deg, DEFAULT_ORIGIN.lon_deg], atol=1e-12
    )


def test_bias_drift_grows_at_its_rate_from_its_start() -> None:
    """No noise, drift (0.2, 0.1) m/s from 1 s, 10 Hz: the error is 0 up to 1 s,
    then rate * (t - 1 s): (0.2, 0.1) m at 2 s, (1.8, 0.9) m at 10 s."""
    cfg = GpsConfig(white_sigma=0.0, drift_rate=(0.2, 0.1), drift_start=1.0)
    err = fix_errors(cfg, 101)
    t = np.arange(101) / cfg.rate
    assert_allclose(err[t <= 1.0], 0.0, atol=1e-6)
    assert_allclose(err[20], [0.2, 0.1], atol=1e-6)
    assert_allclose(err[100], [1.8, 0.9], atol=1e-6)
    assert_allclose(fix_errors(replace(cfg, white_sigma=0.05), 101, seed=4)[:10],
                    fix_errors(GpsConfig(white_sigma=0.05), 101, seed=4)[:10])  # fmt: skip
