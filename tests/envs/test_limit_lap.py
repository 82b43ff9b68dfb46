"""Tests for envs.limit_lap: the quasi-steady-state yardstick, against worked numbers."""

from __future__ import annotations

import math

import numpy as np
from numpy.testing import assert_allclose

from conesim.envs.limit_lap import (
    _top_speed,
    centreline_grid,
    limit_lap_time,
    qss_speed_profile,
)
from conesim.envs.runner import timed_limit_lap
from conesim.sim.vehicle_params import VehicleParams
from conesim.tracks import load_track


def circle(radius: float, n: int = 400) -> np.ndarray:
    """n points on a counter-clockwise circle."""
    t = np.linspace(0.0, 2 * math.pi, n, endpoint=False)
    return np.column_stack([radius * np.cos(t), radius * np.sin(t)])


def test_curvature_of_a_circle_is_one_over_r() -> None:
    """The curvature along the spline through a 400-gon of R = 20 m is 1/R to 1e-4."""
    _, kappa = centreline_grid(circle(20.0), closed=True)
    assert_allclose(kappa, 1 / 20.0, rtol=1e-4)


def test_circle_lap_at_the_friction_limit() -> None:
    """No downforce: v = sqrt(mu D g R), lap = 2 pi R / v (R = 20 m: 7.0925 s)."""
    p = VehicleParams(lift_area=0.0)
    for radius in (10.0, 20.0):
        v = math.sqrt(p.mu * p.tyre_front.D * p.gravity * radius)
        assert_allclose(
            limit_lap_time(circle(radius), True, p), 2 * math.pi * radius / v, rtol=1e-4
        )


def test_downforce_raises_the_cornering_speed() -> None:
    """With downforce, v^2 / R = mu D (g + k v^2): v = sqrt(mu D g / (1/R - mu D k))."""
    p = VehicleParams()
    mu_d = p.mu * p.tyre_front.D
    k = 0.5 * p.air_density * p.lift_area / p.mass
    radius = 10.0
    v = math.sqrt(mu_d * p.gravity / (1 / radius - mu_d * k))
    assert_allclose(limit_lap_time(circle(radius), True, p), 2 * math.pi * radius / v, rtol=1e-4)


def test_standing_start_on_a_straight_is_sqrt_2l_over_a() -> None:
    """From rest at 3 m/s^2 (below the power limit): 75 m in sqrt(2 * 75 / 3) = 7.07 s."""
    lane = np.column_stack([np.linspace(0.0, 100.0, 201), np.zeros(201)])
    t = limit_lap_time(lane, False, timed_to_s=75.0)
    assert_allclose(t, math.sqrt(2 * 75 / 3.0), rtol=1e-3)


def test_braking_before_a_hairpin() -> None:
    """The backward pass brakes at 10 m/s^2 into a slow corner: v^2 = v_c^2 + 2 a d."""
    p = VehicleParams(lift_area=0.0)
    s = np.arange(0.0, 60.0, 0.25)
    kappa = np.where(s >= 50.0, 1 / 5.0, 0.0)
    v = qss_speed_profile(s, kappa, False, p, v_start=25.0)
    v_corner = math.sqrt(p.mu * p.tyre_front.D * p.gravity * 5.0)
    i = int(np.searchsorted(s, 40.0))
    assert_allclose(v[i], math.sqrt(v_corner**2 + 2 * p.max_decel * 10.0), rtol=1e-3)


def test_top_speed_where_power_meets_drag() -> None:
    """P / v = 0.5 rho CdA v^2 + Crr m g at the top speed (29.7 m/s for the defaults)."""
    p = VehicleParams()
    v = _top_speed(p)
    resist = 0.5 * p.air_density * p.drag_area * v**2 + p.rolling_resistance * p.mass * p.gravity
    assert_allclose(p.max_power / v, resist, rtol=1e-6)


def test_acceleration_limit_matches_full_throttle_physics() -> None:
    """The acceleration lane's limit is the 6.010 s full-throttle run from 2 m behind the line
    (3 m/s^2 stays below the power limit over 77 m), to 2e-5: the spline's stations
    and the track's polyline ones differ by under a millimetre."""
    expected = math.sqrt(2 * 77 / 3) - math.sqrt(2 * 2 / 3)
    assert_allclose(timed_limit_lap(load_track("acceleration")), expected, rtol=2e-5)


def test_open_path_starts_from_rest_exactly_at_start_s() -> None:
    """A start between grid stations (10.1 m on a 0.25 m grid) is not rounded up:
    75 m from rest at 3 m/s^2 takes sqrt(2 * 75 / 3) = 7.0711 s to 1e-6."""
    lane = np.column_stack([np.linspace(0.0, 100.0, 201), np.zeros(201)])
    t = limit_lap_time(lane, False, start_s=10.1, timed_to_s=85.1)
    assert_allclose(t, math.sqrt(2 * 75 / 3.0), rtol=1e-6)
