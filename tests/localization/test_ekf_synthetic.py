"""The fusion EKF on a synthetic car: consistency (NEES, NIS), late messages, dropout, outliers.

Truth and sensors come from ``localization.ekf.synthetic`` (white noise with
the stated variances, fixed seeds). Consistency is the fast version of issue
4's Monte Carlo: the mean NEES and mean GPS NIS over the runs must sit in
their chi-square 95 % band for that number of runs on >= 90 % of the fixes.
That fraction is a noisy statistic: one run's NEES stays high or low for
seconds (the filter averages many fixes), so what steadies it is the length
of the runs more than their number. Measured over blocks of seeds: 15 runs of
40 s passed in ten of ten blocks, 20 runs of 30 s in nine of ten, 40 runs of
12 s in three of eight, although the mean NEES was 3.0 +- 0.2 in all of them.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from numpy.typing import NDArray
from scipy.stats import chi2

from conesim.core.messages import NavSatFix
from conesim.localization.ekf import EkfConfig, FusionEkf, RejectReason, Sensor
from conesim.localization.ekf.synthetic import Path, SensorNoise, Truth, make_truth, messages

# The filter as the synthetic sensors need it: no model error beyond the IMU's
# stated noise, biases drawn once per run from the filter's own priors.
FILTER = EkfConfig(
    accel_model_density=0.0,
    yaw_model_density=0.0,
    gyro_bias_walk=1e-7,
    wheel_scale_walk=1e-7,
    init_gyro_bias_sigma=SensorNoise().gyro_bias,
    init_wheel_scale_sigma=SensorNoise().wheel_scale,
)


@dataclasses.dataclass
class Run:
    """One run's record at each fix: NEES and error of the estimate, the fix's NIS."""

    ekf: FusionEkf
    stamps: NDArray[np.float64]
    nees: NDArray[np.float64]
    nis: NDArray[np.float64]
    error: NDArray[np.float64]  # (n, 3): dx, dy [m], dyaw [rad]
    position_sigma: NDArray[np.float64]  # sqrt(trace of the position covariance) [m]


def run(
    truth: Truth,
    seed: int,
    noise: SensorNoise | None = None,
    config: EkfConfig = FILTER,
    **kwargs: object,
) -> Run:
    """Feed one run's messages in delivery order; record at every fix delivered."""
    ekf = FusionEkf(config)
    rng = np.random.default_rng(seed)
    rows: list[tuple[float, float, float, float, float, float, float]] = []
    for _, msg in messages(truth, noise or SensorNoise(), rng, **kwargs):  # type: ignore[arg-type]
        result = ekf.process(msg)
        if isinstance(msg, NavSatFix) and ekf.initialised and result is not None:
            stamp = msg.header.stamp
            est = ekf.estimate(stamp)
            e = est.pose_error(truth.pose(stamp))
            nis = result.nis if result.nis is not None else math.nan
            sigma = math.sqrt(est.pose_covariance[0, 0] + est.pose_covariance[1, 1])
            rows.append((stamp, est.nees(truth.pose(stamp)), nis, *e, sigma))
    a = np.array(rows)
    return Run(ekf, a[:, 0], a[:, 1], a[:, 2], a[:, 3:6], a[:, 6])


def band(n_runs: int, dof: int) -> tuple[float, float]:
    """95 % band of the mean of ``n_runs`` chi2(dof) values: chi2(n dof) / n."""
    lo, hi = chi2.ppf([0.025, 0.975], n_runs * dof)
    return float(lo / n_runs), float(hi / n_runs)


def rms_position(r: Run, after: float = 2.0) -> float:
    """RMS position error over the fixes after ``after`` seconds [m]."""
    keep = r.stamps >= after
    return float(np.sqrt(np.mean(np.sum(r.error[keep, :2] ** 2, axis=1))))


@pytest.fixture(scope="module")
def truth() -> Truth:
    return make_truth(Path(), duration=40.0)


def test_band_matches_the_references_figures() -> None:
    """The band formula gives REFERENCES.md's N = 50 bands."""
    np.testing.assert_allclose(band(50, 3), (2.36, 3.72), atol=0.006)
    np.testing.assert_allclose(band(50, 2), (1.48, 2.59), atol=0.006)


def test_mean_nees_and_nis_inside_the_95_percent_band(truth: Truth) -> None:
    """15 runs of 40 s: mean NEES (3 dof) and GPS NIS (2 dof) in their bands on >= 90 % of fixes."""
    n_runs = 15
    runs = [run(truth, seed) for seed in range(n_runs)]
    nees = np.array([r.nees for r in runs])[:, 1:]  # the first fix initialises
    nis = np.array([r.nis for r in runs])[:, 1:]
    (lo3, hi3), (lo2, hi2) = band(n_runs, 3), band(n_runs, 2)
    mean_nees, mean_nis = nees.mean(axis=0), nis.mean(axis=0)
    in_nees = float(np.mean((mean_nees >= lo3) & (mean_nees <= hi3)))
    in_nis = float(np.mean((mean_nis >= lo2) & (mean_nis <= hi2)))
    print(f"NEES: {in_nees:.1%} of fixes in [{lo3:.2f}, {hi3:.2f}], mean {mean_nees.mean():.2f}")
    print(f"NIS: {in_nis:.1%} of fixes in [{lo2:.2f}, {hi2:.2f}], mean {mean_nis.mean():.2f}")
    assert in_nees >= 0.9
    assert in_nis >= 0.9
    assert 2.7 < mean_nees.mean() < 3.3
    assert 1.8 < mean_nis.mean() < 2.2


def test_yaw_crossing_pi_causes_no_jump(truth: Truth) -> None:
    """The truth crosses +-pi many times; the estimate follows it with no jump."""
    r = run(truth, seed=100)
    true_yaw = np.asarray([truth.pose(s).yaw for s in r.stamps])
    crossings = np.sum(np.abs(np.diff(true_yaw)) > math.pi)
    assert crossings >= 4
    est_yaw = true_yaw + r.error[:, 2]
    assert np.all(np.abs(r.error[:, 2]) < math.radians(0.5))
    assert np.all((est_yaw >= -math.pi - 1e-3) & (est_yaw <= math.pi + 1e-3))
    assert np.all(np.abs(r.error[:, :2]) < 0.1)


def test_late_messages_give_the_on_time_result(truth: Truth) -> None:
    """GPS 0.12 s and heading 0.05 s late: the same state and covariance as on time, to 1e-9."""
    short = make_truth(Path(), duration=6.0)
    late = SensorNoise(gps_latency=0.12, heading_latency=0.05)
    on_time = run(short, seed=7)
    delayed = run(short, seed=7, noise=late)
    a, b = on_time.ekf.estimate(6.0), delayed.ekf.estimate(6.0)
    np.testing.assert_allclose(b.state, a.state, rtol=0.0, atol=1e-9)
    np.testing.assert_allclose(b.covariance, a.covariance, rtol=0.0, atol=1e-9)
    np.testing.assert_allclose(delayed.nis, on_time.nis, rtol=0.0, atol=1e-9)
    assert delayed.ekf.health.replays > 0
    assert on_time.ekf.health.replays == 0
    assert delayed.ekf.health.accepted == on_time.ekf.health.accepted


def test_gps_dropout_dead_reckons_and_recovers(truth: Truth) -> None:
    """5 s without GPS at 8-12 m/s: error < 1 m and covered by the covariance; nominal 3 s after."""
    gap = (20.0, 25.0)
    nominal = run(truth, seed=3)
    r = run(truth, seed=3, gps_gap=gap)
    ekf = FusionEkf(FILTER)
    sigmas, errors = [], []
    checks = iter([*np.arange(gap[0], gap[1], 0.5), gap[1] - 0.005])  # to just before the fix
    check = next(checks)
    for delivery, msg in messages(truth, SensorNoise(), np.random.default_rng(3), gps_gap=gap):
        if delivery > check:  # all messages up to ``check`` are in
            est = ekf.estimate(check)
            sigmas.append(math.sqrt(est.pose_covariance[0, 0] + est.pose_covariance[1, 1]))
            errors.append(float(np.hypot(*est.pose_error(truth.pose(check))[:2])))
            check = next(checks, math.inf)
        ekf.process(msg)
    assert np.all(np.diff(sigmas) > 0.0), "position covariance grows through the dropout"
    assert errors[-1] < 1.0
    assert errors[-1] < 3.0 * sigmas[-1]
    after = r.stamps >= gap[1] + 3.0
    nominal_rms = rms_position(nominal)
    recovered = float(np.sqrt(np.mean(np.sum(r.error[after, :2] ** 2, axis=1))))
    print(f"end of gap {errors[-1]:.3f} m (sigma {sigmas[-1]:.3f}); after 3 s {recovered:.4f} m")
    assert recovered < 1.5 * nominal_rms
    assert r.ekf.health.count(RejectReason.NIS_GATE, Sensor.GPS) <= 1


def test_multipath_fixes_are_all_rejected(truth: Truth) -> None:
    """1 % of fixes 20 m off: every one gated and counted; RMSE within 1.1 x nominal."""
    outliers = frozenset({3.3, 9.7, 17.1, 26.5})  # 4 of the 400 fixes
    nominal = run(truth, seed=11)
    r = run(truth, seed=11, outliers=outliers)
    gated = {round(s, 3) for s, nis in zip(r.stamps, r.nis, strict=True) if nis > 13.8}
    assert {round(s, 3) for s in outliers} <= gated
    assert r.ekf.health.count(RejectReason.NIS_GATE, Sensor.GPS) >= len(outliers)
    assert rms_position(r) <= 1.1 * rms_position(nominal)
