"""Tests for planner.global_speed and the speed profile's end speed."""

from __future__ import annotations

import math

import numpy as np
from numpy.testing import assert_allclose

from conesim.planner.config import SpeedProfileConfig
from conesim.planner.global_speed import GlobalSpeedPlan
from conesim.planner.speed_profile import speed_profile
from conesim.tracks.global_path import global_path_from_centreline


def test_circle_speed_is_sqrt_a_lat_r_everywhere() -> None:
    """A closed circle of R = 10 m: sqrt(a_lat R) = sqrt(60) = 7.75 m/s at every station."""
    t = np.linspace(0.0, 2 * math.pi, 200, endpoint=False)
    path = global_path_from_centreline(np.column_stack([10 * np.cos(t), 10 * np.sin(t)]), True)
    plan = GlobalSpeedPlan(path, SpeedProfileConfig(a_lat_max=6.0, a_lat_aero=0.0, lock_radius=0.0))
    for station in (0.0, 17.0, 40.0, plan.length + 3.0):
        assert_allclose(plan.speed_at(station), math.sqrt(6.0 * 10.0), rtol=1e-3)
    # With downforce, v^2 / R = 6 + 0.02 v^2: v = sqrt(6 / (0.1 - 0.02)) = 8.66 m/s.
    aero_config = SpeedProfileConfig(a_lat_max=6.0, a_lat_aero=0.02, lock_radius=0.0)
    aero = GlobalSpeedPlan(path, aero_config)
    assert_allclose(aero.speed_at(17.0), math.sqrt(6.0 / 0.08), rtol=1e-3)
    assert_allclose(plan.curvature_at(np.array([0.0, 17.0, plan.length + 3.0])), 0.1, rtol=1e-3)


def test_open_path_brakes_to_its_end() -> None:
    """A 200 m straight: v_max far from the end, sqrt(2 a_b d) within d of it."""
    x = np.linspace(0.0, 200.0, 401)
    path = global_path_from_centreline(np.column_stack([x, np.zeros_like(x)]), False)
    cfg = SpeedProfileConfig()
    plan = GlobalSpeedPlan(path, cfg)
    assert_allclose(plan.speed_at(100.0), cfg.v_max, rtol=1e-6)
    assert_allclose(plan.speed_at(195.0), math.sqrt(2 * cfg.a_brake * 5.0), rtol=1e-3)
    assert plan.speed_at(200.0) == 0.0


def test_local_profile_ends_at_the_given_speed() -> None:
    """With horizon_stop and v_end = 8 m/s, a 20 m straight ends at 8, not 0."""
    pts = np.column_stack([np.arange(0.0, 20.01, 0.5), np.zeros(41)])
    v = speed_profile(pts, SpeedProfileConfig(), v_start=10.0, v_end=8.0)
    assert_allclose(v[-1], 8.0)
    stop = speed_profile(pts, SpeedProfileConfig(), v_start=10.0)
    assert stop[-1] == 0.0 and np.all(stop <= v + 1e-12)


def test_speeds_at_wraps_a_closed_path() -> None:
    """speeds_at equals speed_at point by point, stations past the length wrapping."""
    t = np.linspace(0.0, 2 * math.pi, 200, endpoint=False)
    xy = np.column_stack([10 * np.cos(t), 5 * np.sin(t)])  # an ellipse: speeds vary
    plan = GlobalSpeedPlan(global_path_from_centreline(xy, True), SpeedProfileConfig())
    stations = np.array([0.0, 3.0, 20.0, plan.length + 3.0, 2 * plan.length + 20.0])
    expected = [plan.speed_at(s) for s in stations]
    assert_allclose(plan.speeds_at(stations), expected, rtol=1e-12)
    assert plan.speeds_at(stations)[1] == plan.speeds_at(stations)[3]


def test_points_at_wraps_a_loop_and_holds_an_open_end() -> None:
    """On a circle of R 20 m (720 points) a station s is the point at angle
    s / R (of the polygon's arc length), within 1 mm: a point on a chord lies
    up to R (1 - cos(pi / 720)) = 0.19 mm inside the circle and a little off
    its angle; the same point one lap on; an open straight holds its end."""
    a = np.arange(720) * 2.0 * math.pi / 720
    loop = GlobalSpeedPlan(
        global_path_from_centreline(20.0 * np.column_stack([np.cos(a), np.sin(a)]), closed=True),
        SpeedProfileConfig(),
    )
    s = np.array([0.0, 10.0, 31.4, 100.0])
    pts = loop.points_at(s)
    angle = 2.0 * math.pi * s / loop.length  # a share of the polygon's perimeter
    assert_allclose(pts, 20.0 * np.column_stack([np.cos(angle), np.sin(angle)]), atol=1e-3)
    assert_allclose(loop.points_at(s + loop.length), pts, atol=1e-9)
    x = np.arange(0.0, 50.5, 0.5)
    lane = GlobalSpeedPlan(
        global_path_from_centreline(np.column_stack([x, np.zeros_like(x)]), closed=False),
        SpeedProfileConfig(),
    )
    assert_allclose(lane.points_at(np.array([12.25, 50.0, 60.0])), [[12.25, 0], [50, 0], [50, 0]])
