"""Longitudinal control: PI on the speed error with the profile's acceleration fed forward.

At each control step, with target speed v_ref, the profile's planned
acceleration a_ff there, and measured speed v::

    e     = v_ref - v
    I     = clip(I + e dt, -integral_limit, integral_limit)   (not while saturated
                                                               in the direction of e)
    a_cmd = clip(feed_forward * a_ff + kp e + ki I, -max_decel, max_accel)

``target_on_path`` reads v_ref and a_ff off the waypoints: at the arc length
of the path point nearest the rear axle plus a preview of
max(preview_min, preview_time * v), where a_ff = (v_{i+1}^2 - v_i^2) / (2 ds),
the acceleration the profile's forward and backward passes planned.
"""

from __future__ import annotations

import math

import numpy as np

from conesim.planner.config import SpeedControlConfig
from conesim.planner.geometry import FloatArray, arc_length


def target_on_path(
    path: FloatArray,
    speeds: FloatArray,
    centre: FloatArray,
    speed: float,
    config: SpeedControlConfig,
) -> tuple[float, float]:
    """Target speed [m/s] and planned acceleration [m/s^2] a preview ahead of ``centre``.

    Args:
        path: (n, 2) waypoints [m], n >= 1.
        speeds: (n,) their target speeds [m/s].
        centre: (2,) the rear axle in the path's frame [m].
        speed: current speed [m/s].
        config: preview settings.
    """
    if len(path) == 1:
        return float(speeds[0]), 0.0
    s = arc_length(path)
    nearest = int(np.argmin(np.hypot(path[:, 0] - centre[0], path[:, 1] - centre[1])))
    preview = max(config.preview_min, config.preview_time * abs(speed))
    at = min(float(s[nearest]) + preview, float(s[-1]))
    v_ref = float(np.interp(at, s, speeds))
    i = min(int(np.searchsorted(s, at, side="right")) - 1, len(s) - 2)
    ds = float(s[i + 1] - s[i])
    a_ff = float(speeds[i + 1] ** 2 - speeds[i] ** 2) / (2.0 * ds) if ds > 0.0 else 0.0
    return v_ref, a_ff


def ellipse_limits(
    a_lat: float, config: SpeedControlConfig, speed: float = 0.0
) -> tuple[float, float]:
    """The acceleration and deceleration limits [m/s^2] left by a corner.

    Inside the friction ellipse, with the lateral grip
    ``G = lateral_grip + grip_aero v^2`` at speed v [m/s], cornering at
    ``a_lat`` leaves the fraction ``sqrt(1 - (a_lat / G)^2)`` of the
    longitudinal limits, and at least ``ellipse_floor`` of the braking limit.
    Braking at the full -10 m/s^2 while turning at the lateral limit asks the
    tyres for more than they have and the car slides (seen on the
    trackdrive's S-bend at 17 m/s: the profile brakes for the next corner
    while the car is still turning out of the last). The floor keeps some
    braking however hard the steering asks (which then slows the car); at
    the grip there is no drive left, so the car does not push on.
    """
    c = config
    if not c.lateral_grip < float("inf"):
        return c.max_accel, c.max_decel
    ratio = min(abs(a_lat) / (c.lateral_grip + c.grip_aero * speed * speed), 1.0)
    scale = (1.0 - ratio * ratio) ** 0.5
    return c.max_accel * scale, c.max_decel * max(c.ellipse_floor, scale)


class SpeedController:
    """PI speed controller with feed-forward and anti-windup (module docstring).

    Args:
        config: gains and limits.

    Attributes:
        integral: the integrated speed error [m].
    """

    def __init__(self, config: SpeedControlConfig | None = None) -> None:
        self.config = config or SpeedControlConfig()
        self.integral = 0.0

    def reset(self) -> None:
        """Forget the integrated error."""
        self.integral = 0.0

    def step(
        self, v_ref: float, speed: float, dt: float, a_ff: float = 0.0, a_lat: float = 0.0
    ) -> float:
        """One control step: the acceleration command [m/s^2].

        Args:
            v_ref: target speed [m/s].
            speed: measured speed [m/s].
            dt: time since the last step [s].
            a_ff: planned acceleration to feed forward [m/s^2]; none of it
                upwards while the car is faster than ``v_ref``.
            a_lat: lateral acceleration the steering asks for now [m/s^2]
                (``ellipse_limits``).

        Raises:
            ValueError: an argument is not finite, or ``dt`` is negative: one
                NaN would stay in the integral and make every later command NaN.
        """
        finite = math.isfinite(v_ref) and math.isfinite(speed) and math.isfinite(a_ff)
        if not (finite and math.isfinite(a_lat) and math.isfinite(dt) and dt >= 0.0):
            raise ValueError(
                "SpeedController.step: arguments must be finite and dt >= 0, got "
                f"v_ref={v_ref!r}, speed={speed!r}, dt={dt!r}, a_ff={a_ff!r}, a_lat={a_lat!r}"
            )
        c = self.config
        max_accel, max_decel = ellipse_limits(a_lat, c, speed)
        error = v_ref - speed
        if error < -1e-6:  # too fast (beyond rounding): no speeding up with the plan
            a_ff = min(a_ff, 0.0)
        base = c.feed_forward * a_ff + c.kp * error
        saturated_up = base + c.ki * self.integral >= max_accel and error > 0.0
        saturated_down = base + c.ki * self.integral <= -max_decel and error < 0.0
        outside_band = abs(error) > c.integral_band
        if not (saturated_up or saturated_down or outside_band):
            limit = c.integral_limit
            self.integral = min(max(self.integral + error * dt, -limit), limit)
        command = base + c.ki * self.integral
        return min(max(command, -max_decel), max_accel)
