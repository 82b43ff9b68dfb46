"""The fusion EKF's behaviour message by message: initialisation, updates, bad input, history."""

from __future__ import annotations

import logging
import math

import numpy as np
import pytest

from conesim.core.messages import (
    FRAME_GPS_ANTENNA,
    FRAME_OS_SENSOR,
    FRAME_REFERENCE,
    ConeDetections,
    Header,
    HeadingStamped,
    Imu,
    Message,
    NavSatFix,
    NavSatStatus,
    WheelSpeed,
)
from conesim.localization.ekf import (
    EkfConfig,
    FusionEkf,
    NotInitialisedError,
    RejectReason,
    Sensor,
    for_profile,
)
from conesim.localization.ekf.measurements import from_fix, from_heading
from conesim.localization.ekf.synthetic import fix_message

GPS_SIGMA = 1.0  # [m] wide, so that test measurements pass the gate


def imu(t: float, w: float = 0.0, ax: float = 0.0, ay: float = 0.0) -> Imu:
    return Imu(Header(t, FRAME_GPS_ANTENNA), w, ax, ay, 1e-6, 1e-4)


def heading(t: float, yaw: float, variance: float = 1e-4) -> HeadingStamped:
    return HeadingStamped(Header(t, FRAME_REFERENCE), yaw, variance)


def wheel(t: float, speed: float, variance: float = 0.01) -> WheelSpeed:
    return WheelSpeed(Header(t, FRAME_GPS_ANTENNA), speed, variance)


def started(config: EkfConfig | None = None, until: float = 0.5) -> FusionEkf:
    """A filter initialised at t = 0 at (10, 20), yaw 0.3, 5 m/s, then IMU to ``until``."""
    ekf = FusionEkf(config or EkfConfig())
    for msg in (imu(0.0), wheel(0.0, 5.0), heading(0.0, 0.3), fix_message(0.0, 10, 20, GPS_SIGMA)):
        ekf.process(msg)
    for k in range(1, round(until * 100) + 1):
        ekf.process(imu(k / 100))
    return ekf


def test_waits_for_a_fix_and_a_heading_then_starts_from_them() -> None:
    """No estimate before both; then the fix's position, the heading and the wheel speed."""
    ekf = FusionEkf()
    ekf.process(imu(0.0))
    ekf.process(wheel(0.0, 5.0))
    ekf.process(fix_message(0.0, 10.0, 20.0, GPS_SIGMA))
    assert not ekf.initialised
    with pytest.raises(NotInitialisedError):
        ekf.estimate()
    ekf.process(heading(0.02, 0.3))
    assert ekf.initialised
    est = ekf.estimate()
    assert est.stamp == 0.0
    np.testing.assert_allclose([est.pose.x, est.pose.y, est.pose.yaw], [10, 20, 0.3], atol=1e-9)
    assert est.speed == pytest.approx(5.0)
    assert est.pose_covariance[0, 0] == pytest.approx(GPS_SIGMA**2)
    assert est.pose_covariance[2, 2] == pytest.approx(1e-4 + (2.0 * 0.02) ** 2)
    assert est.covariance.shape == (7, 7)
    assert est.names[:3] == ("x", "y", "yaw")


def test_a_heading_too_far_from_the_fix_does_not_initialise() -> None:
    """Fix and heading 0.5 s apart (tolerance 0.1 s): still waiting."""
    ekf = FusionEkf()
    ekf.process(fix_message(0.0, 10.0, 20.0, GPS_SIGMA))
    ekf.process(heading(2.5, 0.3))
    assert not ekf.initialised


def test_messages_after_the_first_fix_are_replayed_at_initialisation() -> None:
    """A late fix initialises at its stamp; the IMU samples after it are applied."""
    ekf = FusionEkf()
    for k in range(20):
        ekf.process(imu(k / 100, w=0.5))
    ekf.process(heading(0.05, 0.3))
    ekf.process(fix_message(0.05, 10.0, 20.0, GPS_SIGMA))
    assert ekf.time == pytest.approx(0.19)
    assert ekf.estimate().pose.yaw == pytest.approx(0.3 + 0.5 * 0.14, abs=1e-9)


@pytest.mark.parametrize("sensor", ["gps", "heading", "wheel_speed"])
def test_a_tiny_covariance_pulls_the_state_onto_the_measurement(sensor: str) -> None:
    """A measurement with a 1e-12 variance replaces the estimate of what it measures."""
    ekf = started(EkfConfig(gps_sigma_floor=1e-9, heading_sigma_floor=1e-9, speed_sigma_floor=1e-9))
    t = 0.5
    if sensor == "gps":
        before = ekf.estimate()
        target = (before.pose.x + 0.4, before.pose.y - 0.3)
        ekf.process(fix_message(t, *target, 1e-6))
        est = ekf.estimate()
        np.testing.assert_allclose([est.pose.x, est.pose.y], target, atol=1e-6)
        assert est.pose_covariance[0, 0] < 1e-11
    elif sensor == "heading":
        ekf.process(heading(t, 0.31, 1e-12))
        est = ekf.estimate()
        assert est.pose.yaw == pytest.approx(0.31, abs=1e-6)
        assert est.pose_covariance[2, 2] < 1e-11
    else:  # h = scale * vx is bilinear: the update lands on its linearisation
        before = ekf.estimate()
        ekf.process(wheel(t, 5.2, 1e-12))
        est = ekf.estimate()
        ds, dv = est.state[6] - before.state[6], est.speed - before.speed
        assert est.state[6] * est.speed - 5.2 == pytest.approx(ds * dv, abs=1e-9)
        assert abs(ds * dv) < 2e-3


def test_zero_motion_leaves_the_pose_unchanged() -> None:
    """At rest with a still IMU for 2 s, the pose does not move (and P grows)."""
    ekf = FusionEkf()
    for msg in (imu(0.0), wheel(0.0, 0.0), heading(0.0, -2.0), fix_message(0.0, 3.0, 4.0, 0.5)):
        ekf.process(msg)
    start = ekf.estimate()
    for k in range(1, 201):
        ekf.process(imu(k / 100))
    end = ekf.estimate()
    np.testing.assert_array_equal(end.state, start.state)
    assert end.pose_covariance[0, 0] > start.pose_covariance[0, 0]


def test_heading_across_pi_moves_the_estimate_the_short_way() -> None:
    """Estimate at pi - 0.01, measurement at -pi + 0.01: yaw ends near +-pi, not near 0."""
    ekf = FusionEkf()
    for msg in (imu(0.0), heading(0.0, math.pi - 0.01, 1e-2), fix_message(0.0, 0.0, 0.0, 0.5)):
        ekf.process(msg)
    ekf.process(heading(0.01, -math.pi + 0.01, 1e-2))
    yaw = ekf.estimate().pose.yaw
    assert abs(abs(yaw) - math.pi) < 0.011
    assert -math.pi <= yaw < math.pi


def bad_fix(stamp: float = 2.5, **changes: object) -> NavSatFix:
    good = fix_message(stamp, 10.0, 20.0, GPS_SIGMA)
    fields = {
        "header": good.header,
        "latitude": good.latitude,
        "longitude": good.longitude,
        "altitude": 0.0,
        "position_covariance": good.position_covariance,
        "status": good.status,
    }
    fields.update(changes)
    return NavSatFix(**fields)  # type: ignore[arg-type]


NON_SYMMETRIC = np.array([[1.0, 0.3, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 4.0]])
BAD_INPUT: list[tuple[str, Message, Sensor, RejectReason]] = [
    ("fix NaN latitude", bad_fix(latitude=math.nan), Sensor.GPS, RejectReason.NON_FINITE),
    ("fix inf longitude", bad_fix(longitude=math.inf), Sensor.GPS, RejectReason.NON_FINITE),
    ("fix latitude 91 deg", bad_fix(latitude=91.0), Sensor.GPS, RejectReason.OUT_OF_RANGE),
    ("fix longitude -180.5 deg", bad_fix(longitude=-180.5), Sensor.GPS,
     RejectReason.OUT_OF_RANGE),
    ("fix NaN stamp", bad_fix(header=Header(math.nan, FRAME_GPS_ANTENNA)), Sensor.GPS,
     RejectReason.NON_FINITE),
    ("fix NO_FIX", bad_fix(status=NavSatStatus.NO_FIX), Sensor.GPS, RejectReason.NO_FIX),
    ("fix NaN covariance", bad_fix(position_covariance=np.full((3, 3), math.nan)), Sensor.GPS,
     RejectReason.NON_FINITE),
    ("fix negative variance", bad_fix(position_covariance=np.diag([-1.0, 1.0, 4.0])),
     Sensor.GPS, RejectReason.BAD_COVARIANCE),
    ("fix indefinite covariance",
     bad_fix(position_covariance=np.array([[1.0, 2.0, 0.0], [2.0, 1.0, 0.0], [0.0, 0.0, 4.0]])),
     Sensor.GPS, RejectReason.BAD_COVARIANCE),
    ("fix non-symmetric covariance", bad_fix(position_covariance=NON_SYMMETRIC), Sensor.GPS,
     RejectReason.BAD_COVARIANCE),
    ("fix in os_sensor", bad_fix(header=Header(2.5, FRAME_OS_SENSOR)), Sensor.GPS,
     RejectReason.WRONG_FRAME),
    ("fix 50 m off", fix_message(2.5, 60.0, 20.0, 0.03), Sensor.GPS, RejectReason.NIS_GATE),
    ("fix before the history", fix_message(-5.0, 10.0, 20.0, GPS_SIGMA), Sensor.GPS,
     RejectReason.TOO_OLD),
    ("imu 18 s ahead (a leap-second offset)", imu(3.0 + 18.0), Sensor.IMU,
     RejectReason.TOO_NEW),
    ("heading NaN", heading(2.5, math.nan), Sensor.HEADING, RejectReason.NON_FINITE),
    ("heading inf variance", heading(2.5, 0.3, math.inf), Sensor.HEADING,
     RejectReason.NON_FINITE),
    ("heading negative variance", heading(2.5, 0.3, -1e-4), Sensor.HEADING,
     RejectReason.BAD_COVARIANCE),
    ("heading 90 deg off", heading(2.5, 0.3 + math.pi / 2), Sensor.HEADING,
     RejectReason.NIS_GATE),
    ("wheel speed inf", wheel(2.5, math.inf), Sensor.WHEEL_SPEED, RejectReason.NON_FINITE),
    ("wheel speed negative variance", wheel(2.5, 5.0, -0.01), Sensor.WHEEL_SPEED,
     RejectReason.BAD_COVARIANCE),
    ("imu NaN yaw rate", imu(0.6, w=math.nan), Sensor.IMU, RejectReason.NON_FINITE),
    ("imu negative variance",
     Imu(Header(0.6, FRAME_GPS_ANTENNA), 0.0, 0.0, 0.0, 1e-6, -1e-4), Sensor.IMU,
     RejectReason.BAD_COVARIANCE),
]  # fmt: skip


@pytest.mark.parametrize(
    ("msg", "sensor", "reason"), [b[1:] for b in BAD_INPUT], ids=[b[0] for b in BAD_INPUT]
)
def test_bad_input_is_rejected_counted_logged_and_leaves_the_state_bit_identical(
    msg: Message, sensor: Sensor, reason: RejectReason, caplog: pytest.LogCaptureFixture
) -> None:
    """The reason is returned, counted and logged; state, covariance and time do not change."""
    ekf = started(EkfConfig(history_window=1.0), until=3.0)
    before, ahead = ekf.estimate(), ekf.estimate(3.5)
    with caplog.at_level(logging.WARNING, logger="conesim.localization.ekf"):
        result = ekf.process(msg)
    assert result is not None
    assert not result.accepted
    assert (result.sensor, result.reason) == (sensor, reason)
    assert ekf.health.rejected[(sensor, reason)] == 1
    assert ekf.health.count() == 1
    assert reason.value in caplog.text
    after = ekf.estimate()
    assert ekf.time == before.stamp
    np.testing.assert_array_equal(after.state, before.state)
    np.testing.assert_array_equal(after.covariance, before.covariance)
    np.testing.assert_array_equal(ekf.estimate(3.5).covariance, ahead.covariance)


def test_bad_input_before_initialisation_is_rejected_too() -> None:
    """A NO_FIX fix cannot initialise the filter."""
    ekf = FusionEkf()
    ekf.process(heading(0.0, 0.3))
    result = ekf.process(bad_fix(0.0, status=NavSatStatus.NO_FIX))
    assert result is not None
    assert result.reason == RejectReason.NO_FIX
    assert not ekf.initialised


def test_repeated_gated_fixes_reset_the_filter() -> None:
    """After max_consecutive_gps_rejections gated fixes the filter starts again."""
    ekf = started(EkfConfig(max_consecutive_gps_rejections=5), until=1.0)
    for k in range(5):
        ekf.process(fix_message(0.5 + 0.1 * k, 500.0, 20.0, 0.03))
    assert ekf.health.resets == 1
    assert not ekf.initialised
    ekf.process(heading(1.1, 0.3))
    ekf.process(fix_message(1.1, 500.0, 20.0, 0.03))
    assert ekf.estimate().pose.x == pytest.approx(500.0)


def test_one_message_from_the_future_leaves_the_fixes_in_use() -> None:
    """An IMU sample stamped 18 s ahead is rejected as too new; the filter's
    time stays, and the fixes that follow are applied, not rejected as too old."""
    ekf = started(until=1.0)
    assert ekf.process(imu(19.0)).reason == RejectReason.TOO_NEW  # type: ignore[union-attr]
    assert ekf.time == 1.0
    for k in range(1, 11):
        ekf.process(imu(1.0 + k / 100))
        if k % 5 == 0:
            result = ekf.process(fix_message(1.0 + k / 100, 10.0, 20.0, GPS_SIGMA))
            assert result is not None and result.accepted
    assert ekf.health.count(RejectReason.TOO_OLD) == 0 and ekf.health.resets == 0


@pytest.mark.parametrize("jump", [100.0, -10.0])
def test_a_clock_jump_resets_the_filter(jump: float) -> None:
    """All messages 100 s ahead (or 10 s back): the first clock_jump_messages
    are rejected as too new (too old), then the filter resets and initialises
    from the next fix and heading at the new time."""
    ekf = started(EkfConfig(clock_jump_messages=5), until=1.0)
    t0 = 1.0 + jump
    reason = RejectReason.TOO_NEW if jump > 0 else RejectReason.TOO_OLD
    for k in range(5):
        assert ekf.process(imu(t0 + k / 100)).reason == reason  # type: ignore[union-attr]
    assert ekf.health.resets == 1 and not ekf.initialised
    ekf.process(heading(t0 + 0.05, 0.3))
    ekf.process(fix_message(t0 + 0.05, 40.0, 20.0, GPS_SIGMA))
    assert ekf.initialised and ekf.time == pytest.approx(t0 + 0.05)
    assert ekf.estimate().pose.x == pytest.approx(40.0, abs=0.01)


def test_a_message_from_the_future_before_initialisation() -> None:
    """Held for initialisation, a message 50 s ahead of the others is rejected
    (it would push them out of the window) and the filter still starts."""
    ekf = FusionEkf()
    ekf.process(heading(0.0, 0.3))
    assert ekf.process(imu(50.0)).reason == RejectReason.TOO_NEW  # type: ignore[union-attr]
    ekf.process(fix_message(0.05, 10.0, 20.0, GPS_SIGMA))
    assert ekf.initialised and ekf.time == pytest.approx(0.05)


def test_a_frame_name_with_tf2s_leading_slash_is_the_same_frame() -> None:
    """A fix in '/gps_antenna' is a fix in 'gps_antenna' (tf2 strips the slash)."""
    ekf = started(until=0.5)
    good = fix_message(0.5, 10.0, 20.0, GPS_SIGMA)
    slashed = bad_fix(0.5, header=Header(0.5, "/" + good.header.frame_id))
    result = ekf.process(slashed)
    assert result is not None and result.accepted


def test_estimate_at_a_stamp_that_is_not_finite() -> None:
    """estimate(nan) is a ValueError naming the stamp."""
    ekf = started(until=0.5)
    for stamp in (math.nan, math.inf):
        with pytest.raises(ValueError, match="stamp must be finite"):
            ekf.estimate(stamp)


def test_estimate_ahead_and_in_the_past() -> None:
    """Ahead: predicted with a growing covariance; in the past: from the history; too old: error."""
    ekf = started(until=2.0)
    now, ahead = ekf.estimate(), ekf.estimate(3.0)
    assert ahead.stamp == 3.0
    assert ahead.pose.x > now.pose.x  # 5 m/s at yaw 0.3 rad
    assert np.trace(ahead.pose_covariance) > np.trace(now.pose_covariance)
    past = ekf.estimate(1.5)
    assert past.stamp == 1.5
    assert past.pose.x < now.pose.x
    with pytest.raises(ValueError, match="before the oldest state"):
        ekf.estimate(0.2)


def test_message_types_the_filter_does_not_use_are_ignored() -> None:
    """Cone detections return None and change nothing."""
    ekf = started()
    msg = ConeDetections(Header(0.5, FRAME_OS_SENSOR), np.zeros((0, 3)))
    assert ekf.process(msg) is None
    assert ekf.health.count() == 0


def test_modelled_bias_is_taken_out_of_the_stated_variance() -> None:
    """consumer: the receiver states 2.12 m; 2.0 m of it is the bias state, the rest is R."""
    cfg = for_profile("consumer")
    fix = fix_message(0.0, 1.0, 2.0, 2.12)
    np.testing.assert_allclose(from_fix(fix, cfg).cov, (2.12**2 - 4.0) * np.eye(2))
    np.testing.assert_allclose(from_fix(fix, cfg).z, [[1.0], [2.0]], atol=1e-9)
    stated = math.radians(1.0) ** 2 + math.radians(2.0) ** 2
    meas = from_heading(heading(0.0, 4.0, stated), cfg)
    assert meas.cov[0, 0] == pytest.approx(math.radians(1.0) ** 2)
    assert meas.z[0, 0] == pytest.approx(4.0 - 2 * math.pi)


def test_profiles_and_their_state_sizes() -> None:
    """Each sensor profile has settings; the correlated ones carry their bias states."""
    sizes = {name: FusionEkf(for_profile(name)).layout.n for name in ("ideal", "rtk", "consumer")}
    assert sizes == {"ideal": 7, "rtk": 7, "consumer": 10}
    assert for_profile("rtk", gate_probability=0.99).gate_probability == 0.99


def test_unknown_profile_or_setting_lists_the_allowed_ones() -> None:
    """Unknown names raise with the allowed keys; out-of-range values raise."""
    with pytest.raises(ValueError, match="allowed: ideal, rtk, consumer, consumer_white"):
        for_profile("gps_only")
    with pytest.raises(ValueError, match="allowed: imu_rate"):
        for_profile("rtk", gps_sigma=1.0)
    with pytest.raises(ValueError, match="gate_probability"):
        EkfConfig(gate_probability=1.5)
    with pytest.raises(ValueError, match="history_window"):
        EkfConfig(history_window=0.0)
