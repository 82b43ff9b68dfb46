"""Longitudinal PI with feed-forward: convergence, ramp tracking, anti-windup, the target."""

from __future__ import annotations

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose

from conesim.planner import SpeedControlConfig, SpeedController, target_on_path
from conesim.planner.speed_control import ellipse_limits

DT = 0.02  # [s] 50 Hz


def test_pi_converges_without_steady_state_error() -> None:
    """Plant dv/dt = a - 0.1 v: v -> 10 m/s and the integral holds the drag, I = 0.1*10/ki = 2 m."""
    controller = SpeedController(SpeedControlConfig(ki=0.5))
    v = 0.0
    for _ in range(int(40.0 / DT)):
        a = controller.step(10.0, v, DT)
        v += (a - 0.1 * v) * DT
    assert v == pytest.approx(10.0, abs=1e-3)
    assert controller.integral == pytest.approx(0.1 * 10.0 / 0.5, rel=1e-2)


def test_feed_forward_tracks_a_ramp_exactly() -> None:
    """Plant dv/dt = a, reference v = 2 t with a_ff = 2 m/s^2: the error stays zero."""
    controller = SpeedController()
    v = 0.0
    for k in range(100):
        a = controller.step(2.0 * k * DT, v, DT, a_ff=2.0)
        v += a * DT
    assert v == pytest.approx(2.0 * 100 * DT, abs=1e-12)
    assert abs(controller.integral) < 1e-12


def test_anti_windup_while_saturated() -> None:
    """A 0 -> 20 m/s step saturates at 3 m/s^2 without winding up; overshoot < 0.5 m/s."""
    controller = SpeedController()
    v, peak = 0.0, 0.0
    for _ in range(int(30.0 / DT)):
        a = controller.step(20.0, v, DT)
        assert -10.0 <= a <= 3.0
        v += a * DT
        peak = max(peak, v)
    assert v == pytest.approx(20.0, abs=1e-3)
    assert peak < 20.5


def test_target_on_path_reads_the_preview() -> None:
    """Straight path with v = s + 2: at rest the preview is 1 m (v_ref 3); at 10 m/s, 3 m (5)."""
    s = np.arange(0.0, 20.5, 0.5)
    path = np.column_stack([s, np.zeros_like(s)])
    speeds = s + 2.0
    v_ref, a_ff = target_on_path(path, speeds, np.zeros(2), 0.0, SpeedControlConfig())
    assert v_ref == pytest.approx(3.0)
    # a = (v1^2 - v0^2) / (2 ds) = ((3.5)^2 - 3^2) / 1.0 = 3.25 m/s^2 on the segment from s = 1 m.
    assert a_ff == pytest.approx(3.25)
    v_ref, _ = target_on_path(path, speeds, np.array([2.0, 0.3]), 10.0, SpeedControlConfig())
    assert v_ref == pytest.approx(2.0 + 2.0 + 3.0)
    assert_allclose(
        target_on_path(path[:1], speeds[:1], np.zeros(2), 0.0, SpeedControlConfig()), (2.0, 0.0)
    )


def test_integral_waits_for_a_small_error() -> None:
    """With integral_band = 1 m/s, a 5 m/s error is not integrated; a 0.5 m/s one is, e dt."""
    controller = SpeedController(SpeedControlConfig(integral_band=1.0))
    controller.step(10.0, 5.0, DT, a_ff=-8.0)  # unsaturated (-8 + 7.5), but outside the band
    assert controller.integral == 0.0
    controller.step(10.0, 9.5, DT)
    assert controller.integral == pytest.approx(0.5 * DT)


def test_ellipse_limits_share_the_grip_with_the_corner() -> None:
    """G = 15 m/s^2: at a_lat 12 (0.8 G) sqrt(1 - 0.64) = 0.6 of +3 / -10; at >= G no drive,
    braking the floor 0.3; with downforce G(10 m/s) = 15 + 0.05 * 100 = 20: a_lat 12 is 0.6 G,
    0.8 of the limits."""
    config = SpeedControlConfig(max_accel=3.0, lateral_grip=15.0, grip_aero=0.0, ellipse_floor=0.3)
    assert ellipse_limits(0.0, config) == (3.0, 10.0)
    assert_allclose(ellipse_limits(-12.0, config), (1.8, 6.0), rtol=1e-12)
    assert_allclose(ellipse_limits(20.0, config), (0.0, 3.0), rtol=1e-12)
    aero = SpeedControlConfig(max_accel=3.0, lateral_grip=15.0, grip_aero=0.05)
    assert_allclose(ellipse_limits(12.0, aero, speed=10.0), (2.4, 8.0), rtol=1e-12)
    controller = SpeedController(config)
    assert controller.step(0.0, 10.0, DT, a_lat=12.0) == pytest.approx(-6.0)
    assert controller.step(20.0, 10.0, DT, a_lat=12.0) == pytest.approx(1.8)
    free = SpeedControlConfig(max_accel=3.0, lateral_grip=float("inf"))
    assert ellipse_limits(30.0, free) == (3.0, 10.0)


@pytest.mark.parametrize(
    "args", [(10.0, math.nan, DT), (math.inf, 5.0, DT), (10.0, 5.0, math.nan), (10.0, 5.0, -DT)]
)
def test_non_finite_input_or_negative_dt_is_refused(args: tuple[float, float, float]) -> None:
    """A NaN speed or dt is refused and leaves the integral as it was (it
    would otherwise stay in it and make every later command NaN)."""
    controller = SpeedController(SpeedControlConfig())
    controller.step(10.0, 9.5, DT)
    before = controller.integral
    with pytest.raises(ValueError, match="must be finite and dt >= 0"):
        controller.step(*args)
    assert controller.integral == before
    assert math.isfinite(controller.step(10.0, 9.5, DT))
