"""Tests for envs.limit_lap: the quasi-steady-state yardstick, against worked numbers."""

from __future__ import annotations

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose

from conesim.core.polyline import Polyline
from conesim.core.pose import Pose2D
from conesim.envs import limit_lap
from conesim.envs.limit_lap import (
    _top_speed,
    centreline_grid,
    limit_lap_time,
    qss_speed_profile,
    track_lap_limit,
)
from conesim.planner.racing_line import MARGIN_M, RacingLineError
from conesim.sim.vehicle_params import VehicleParams
from conesim.tracks import ConeKind, Layout, Track, load_track

SHIPPED_LOOPS = ("trackdrive", "autocross", "skidpad")


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
    """P / v = 0.5 rho CdA v^2 + Crr (m g + 0.5 rho ClA v^2) at the top speed (29.6 m/s
    for the defaults): rolling resistance on the aerodynamic load too, as the physics."""
    p = VehicleParams()
    v = _top_speed(p)
    down = 0.5 * p.air_density * p.lift_area * v**2
    resist = 0.5 * p.air_density * p.drag_area * v**2 + p.rolling_resistance * (
        p.mass * p.gravity + down
    )
    assert_allclose(p.max_power / v, resist, rtol=1e-6)


def test_top_speed_with_rolling_resistance_alone_is_power_over_it() -> None:
    """No air (no drag, no downforce): P / v = Crr m g, v = 20 kW / 27.96 N = 715 m/s."""
    p = VehicleParams(air_density=0.0)
    assert_allclose(_top_speed(p), p.max_power / (p.rolling_resistance * p.mass * p.gravity))


def test_a_car_with_no_resistance_has_no_top_speed_and_a_finite_lap() -> None:
    """No drag and no rolling resistance: no top speed, but the lap is still the
    standing start at 3 m/s^2 (the demand limit), 75 m in 7.07 s."""
    p = VehicleParams(drag_area=0.0, rolling_resistance=0.0)
    assert _top_speed(p) == math.inf
    lane = np.column_stack([np.linspace(0.0, 100.0, 201), np.zeros(201)])
    assert_allclose(limit_lap_time(lane, False, p, timed_to_s=75.0), math.sqrt(50.0), rtol=1e-3)


def test_acceleration_limit_matches_full_throttle_physics() -> None:
    """The acceleration lane's limit is the 6.010 s full-throttle run from 2 m behind the line
    (3 m/s^2 stays below the power limit over 77 m), to 2e-5: the spline's stations
    and the track's polyline ones differ by under a millimetre."""
    expected = math.sqrt(2 * 77 / 3) - math.sqrt(2 * 2 / 3)
    limit = track_lap_limit(load_track("acceleration"))
    assert_allclose(limit.limit_s, expected, rtol=2e-5)
    assert limit.centreline_s == limit.limit_s and limit.racing_line is None


def test_open_path_starts_from_rest_exactly_at_start_s() -> None:
    """A start between grid stations (10.1 m on a 0.25 m grid) is not rounded up:
    75 m from rest at 3 m/s^2 takes sqrt(2 * 75 / 3) = 7.0711 s to 1e-6."""
    lane = np.column_stack([np.linspace(0.0, 100.0, 201), np.zeros(201)])
    t = limit_lap_time(lane, False, start_s=10.1, timed_to_s=85.1)
    assert_allclose(t, math.sqrt(2 * 75 / 3.0), rtol=1e-6)


def ring_track(radius: float, width: float, spacing: float = 0.5) -> Track:
    """A counter-clockwise ring of cones (blue inside) ~``spacing`` [m] apart, so
    finely that the chords between them lie within 2 mm of the circles."""
    cones, kinds = [], []
    for r, kind in ((radius - width / 2, ConeKind.BLUE), (radius + width / 2, ConeKind.YELLOW)):
        n = round(2 * math.pi * r / spacing)
        a = np.arange(n) * 2 * math.pi / n
        cones.append(r * np.column_stack([np.cos(a), np.sin(a)]))
        kinds += [kind] * n
    return Track("ring", np.vstack(cones), tuple(kinds), Pose2D(radius, 0.0, math.pi / 2))


def circle_lap(radius: float, p: VehicleParams) -> float:
    """2 pi r / v with v^2 / r = mu D (g + k v^2), k = 0.5 rho ClA / m [s]."""
    mu_d = p.mu * p.tyre_front.D
    k = 0.5 * p.air_density * p.lift_area / p.mass
    return 2 * math.pi * radius / math.sqrt(mu_d * p.gravity / (1 / radius - mu_d * k))


def test_limit_of_a_small_ring_is_its_innermost_circle() -> None:
    """A lap of the circle of radius r takes 2 pi sqrt(r (1 - mu D k r) / (mu D g)),
    which grows with r below 1 / (2 mu D k) = 31 m: on R = 10 m, w = 3.5 m the
    limit is the innermost circle the car may drive, r = R - (w/2 - d), d = 0.95 m."""
    p = VehicleParams()
    limit = track_lap_limit(ring_track(10.0, 3.5), p)
    d = 0.5 * p.width + MARGIN_M
    # rtol 6e-3: a line pressed on the cones' bounds keeps a 1-2 % curvature ripple
    # (5 mm of radius), and at the friction limit the car cannot drive back up to
    # speed after its worst point (the drag takes the tyres' last grip).
    assert_allclose(limit.limit_s, circle_lap(10.0 - (1.75 - d), p), rtol=6e-3)
    assert_allclose(limit.centreline_s, circle_lap(10.0, p), rtol=6e-3)
    assert limit.blend == 1.0


def test_limit_of_a_large_ring_is_its_minimum_curvature_circle() -> None:
    """With twice the downforce (mu D k = 0.032 /m) the wider circle is the faster above
    1 / (2 mu D k) = 15.6 m (and 200 kW keeps the top speed out of the way): on
    R = 20 m the limit is the minimum-curvature line, the outermost circle R + (w/2 - d)."""
    p = VehicleParams(lift_area=2 * VehicleParams().lift_area, max_power=200_000.0)
    limit = track_lap_limit(ring_track(20.0, 3.5), p)
    # rtol 1e-2: the line's curvature ripple, as on the small ring, read twice as
    # strongly: v^2 = mu D g / (kappa - mu D k) with kappa only 1.5 times mu D k.
    assert_allclose(limit.limit_s, circle_lap(20.0 + (1.75 - 0.95), p), rtol=1e-2)
    assert limit.blend == 0.0


def test_limit_without_downforce_on_a_ring() -> None:
    """No downforce: lap = 2 pi sqrt(r / (mu D g)), fastest on the innermost circle."""
    p = VehicleParams(lift_area=0.0)
    r = 20.0 - (2.0 - 0.95)
    expected = 2 * math.pi * math.sqrt(r / (p.mu * p.tyre_front.D * p.gravity))
    assert_allclose(track_lap_limit(ring_track(20.0, 4.0), p).limit_s, expected, rtol=6e-3)


def test_limit_is_below_the_centreline_on_every_shipped_loop() -> None:
    """A loop's limit is no slower than its centreline figure, and not absurdly faster."""
    for name in SHIPPED_LOOPS:
        limit = track_lap_limit(load_track(name))
        assert 0.75 * limit.centreline_s < limit.limit_s <= limit.centreline_s, name


def test_racing_line_is_inside_the_track_everywhere() -> None:
    """Every 5 cm of the shipped loops' racing lines (the splines the QSS times) keeps
    half the car's width and the margin from both cone polylines, to 5 mm."""
    p = VehicleParams()
    clearance = 0.5 * p.width + MARGIN_M
    for name in ("trackdrive", "autocross"):
        track = load_track(name)
        line = track_lap_limit(track, p).racing_line
        assert line is not None
        dense = Polyline(line, True).resample(0.05).points
        left = Polyline(track.left_boundary, True).project(dense).lateral
        right = Polyline(track.right_boundary, True).project(dense).lateral
        assert (-left).min() >= clearance - 0.005 and right.min() >= clearance - 0.005, name


def test_skidpad_limit_is_its_inner_circle() -> None:
    """The skidpad's timed circle (R 9.1 m, below 31 m) is fastest on its inner circle."""
    track = load_track("skidpad")
    circles = track.geometry.circles
    assert circles is not None
    right = circles[0]
    p = VehicleParams()
    r = right.radius - (right.width / 2 - 0.5 * p.width - MARGIN_M)
    assert_allclose(track_lap_limit(track, p).limit_s, circle_lap(r, p), rtol=6e-3)


def test_limit_is_cached_per_track_and_car() -> None:
    """The same track and car give the same object; another car another limit."""
    track = load_track("trackdrive")
    first = track_lap_limit(track)
    assert track_lap_limit(load_track("trackdrive")) is first
    assert track_lap_limit(track, VehicleParams(mu=0.8)).limit_s > first.limit_s


def test_open_lane_has_no_racing_line() -> None:
    """An open lane is timed along its centreline from rest."""
    x = np.arange(0.0, 101.0, 2.0)
    cones = np.vstack(
        [np.column_stack([x, np.full_like(x, 1.5)]), np.column_stack([x, -np.full_like(x, 1.5)])]
    )
    kinds = (ConeKind.BLUE,) * len(x) + (ConeKind.YELLOW,) * len(x)
    lane = Track("lane", cones, kinds, Pose2D(0.0, 0.0, 0.0), Layout.OPEN)
    limit = track_lap_limit(lane)
    assert limit.racing_line is None and limit.limit_s == limit.centreline_s


def test_a_failed_qp_falls_back_to_the_centreline(
    monkeypatch: pytest.MonkeyPatch, caplog: pytest.LogCaptureFixture
) -> None:
    """Where no racing line can be found the limit is the centreline's, with a warning."""

    def fail(corridor: object) -> None:
        raise RacingLineError("the racing line's QP failed: primal infeasible")

    monkeypatch.setattr(limit_lap, "racing_lines", fail)
    limit = track_lap_limit(ring_track(15.0, 3.0), VehicleParams(mass=191.0))  # not cached
    assert limit.racing_line is None and limit.limit_s == limit.centreline_s
    assert "no racing line" in caplog.text
