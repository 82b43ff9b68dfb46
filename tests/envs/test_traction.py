"""Tests for envs.traction: the g-g limits against the physics' own formulas."""

from __future__ import annotations

import math

import numpy as np
from numpy.testing import assert_allclose

from conesim.envs.traction import AxleLimits
from conesim.sim.vehicle_dynamics import axle_loads, resistance_magnitude
from conesim.sim.vehicle_params import VehicleParams


def test_corner_speed_is_the_tyre_peak_on_the_loads() -> None:
    """Defaults (lf = lr, downforce split like the weight): v^2 kappa = mu D (g + k v^2)."""
    p = VehicleParams()
    k = 0.5 * p.air_density * p.lift_area / p.mass
    kappa = np.array([1 / 5.0, 1 / 10.0, 1 / 20.0])
    mu_d = p.mu * p.tyre_front.D
    expected = np.sqrt(mu_d * p.gravity / (kappa - mu_d * k))
    assert_allclose(AxleLimits(p).corner_speed(kappa, 1e9), expected, rtol=1e-12)


def test_straight_line_limits_are_the_demand_limits() -> None:
    """On a straight at 10 m/s the tyres give more than +3 / -10 m/s^2 ask."""
    limits = AxleLimits(VehicleParams())
    assert limits.drive(10.0, 0.0) == 3.0
    assert limits.brake(10.0, 0.0) == 10.0


def test_braking_in_a_corner_stops_at_the_rear_axles_ellipse() -> None:
    """At 12 m/s on R = 12 m the rear axle, unloaded by the braking and braking 40 %,
    limits the deceleration: there Fx_r^2 + Fy_r^2 = (mu D Fz_r)^2 on the loads of
    sim.vehicle_dynamics.axle_loads, and the front axle is inside its ellipse."""
    p = VehicleParams()
    v, kappa = 12.0, 1 / 12.0
    b = AxleLimits(p).brake(v, kappa)
    assert 0.0 < b < p.max_decel
    loads = axle_loads(p, v, -b)
    brake = p.mass * b - resistance_magnitude(p, v, loads)  # the demand less the resistances
    ay = v * v * kappa
    fy_f, fy_r = p.mass * ay * p.cg_to_rear / p.wheelbase, p.mass * ay * p.cg_to_front / p.wheelbase
    rear = math.hypot((1 - p.brake_front_share) * brake, fy_r) / (p.mu_rear * loads.rear)
    front = math.hypot(p.brake_front_share * brake, fy_f) / (p.mu_front * loads.front)
    assert_allclose(rear, 1.0, rtol=1e-9)
    assert front < 1.0


def test_no_longitudinal_grip_left_at_the_cornering_limit() -> None:
    """At the corner speed the lateral force takes all the grip: no drive, no brake."""
    limits = AxleLimits(VehicleParams())
    kappa = 1 / 10.0
    v = float(limits.corner_speed(np.array([kappa]), 1e9)[0])
    assert limits.brake(v, kappa) < 1e-6
    assert limits.drive(v, kappa) < 1e-6
