"""Speed profile: v = sqrt(a_lat R) on circles, v^2 = 2 a s ramps, the vectorised passes."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from numpy.testing import assert_allclose

from conesim.planner import SpeedProfileConfig, speed_profile
from conesim.planner.speed_profile import (
    backward_pass,
    curvature_limit,
    ellipse_backward_pass,
    ellipse_forward_pass,
    forward_pass,
    jerk_limit,
    menger_curvature,
)

# The worked numbers use 6 m/s^2 lateral and braking and no friction ellipse
# (tested on its own below).
LIMITS = {
    "a_lat_max": 6.0,
    "a_lat_aero": 0.0,
    "a_brake": 6.0,
    "friction_ellipse": False,
    "lateral_jerk_max": math.inf,
}
FREE = SpeedProfileConfig(v_max=100.0, horizon_stop=False, curvature_window=0.0, **LIMITS)


def arc(radius: float, length: float, step: float = 0.5, left: bool = True) -> np.ndarray:
    """Points every ``step`` [m] on a circle of ``radius`` through the origin heading +x."""
    a = np.arange(0.0, length, step) / radius
    y = radius * (1.0 - np.cos(a))
    return np.column_stack([radius * np.sin(a), y if left else -y])


@pytest.mark.parametrize("radius", [5.0, 10.0, 40.0])
def test_circle_speed_is_sqrt_a_lat_r(radius: float) -> None:
    """On a circle: v = sqrt(a_lat_max R); R = 10 m, 6 m/s^2 gives 7.7460 m/s."""
    v = speed_profile(arc(radius, 30.0), FREE)
    assert_allclose(v, math.sqrt(6.0 * radius), rtol=1e-9)


def test_menger_curvature_is_one_over_r_with_sign() -> None:
    """Any three points on a circle give 1/R exactly; + for left turns."""
    assert_allclose(menger_curvature(arc(8.0, 20.0)), 1.0 / 8.0, rtol=1e-9)
    assert_allclose(menger_curvature(arc(8.0, 20.0, left=False)), -1.0 / 8.0, rtol=1e-9)
    assert_allclose(menger_curvature(np.column_stack([np.arange(10.0), np.zeros(10)])), 0.0)


def test_straight_from_standstill_and_the_cap() -> None:
    """From rest: v = sqrt(2 a_drive s), 6 m/s at s = 6 m with 3 m/s^2, capped at v_max."""
    config = SpeedProfileConfig(v_max=9.0, horizon_stop=False, **LIMITS)
    s = np.arange(0.0, 40.0, 0.5)
    v = speed_profile(np.column_stack([s, np.zeros_like(s)]), config, v_start=0.0)
    assert_allclose(v, np.minimum(np.sqrt(2 * 3.0 * s), 9.0), rtol=1e-12)
    assert v[12] == pytest.approx(6.0)


def test_horizon_stop_brakes_to_zero_at_the_end() -> None:
    """With horizon_stop: v = sqrt(2 a_brake (L - s)) near the end; 6 m/s^2, 3 m left: 6 m/s."""
    s = np.arange(0.0, 30.5, 0.5)
    v = speed_profile(
        np.column_stack([s, np.zeros_like(s)]), SpeedProfileConfig(v_max=15.0, **LIMITS)
    )
    assert v[-1] == 0.0
    assert v[-7] == pytest.approx(6.0)
    tail = s > 30.0 - 15.0**2 / (2 * 6.0)  # where braking from v_max = 15 m/s binds
    assert_allclose(v[tail], np.sqrt(2 * 6.0 * (30.0 - s[tail])), rtol=1e-12)


def test_braking_into_a_corner() -> None:
    """50 m straight into R = 10 m: at x = -10 m, v = sqrt(6*10 + 2*6*10.49995) = 13.638 m/s.

    The three-point curvature at the junction is 1/(2R); the full 1/R (and the
    limit sqrt(60) m/s) starts at the first point inside the arc, 0.5 m in: the
    car brakes at 6 m/s^2 over 10.5 m.
    """
    straight = np.column_stack([np.arange(-50.0, 0.0, 0.5), np.zeros(100)])
    points = np.vstack([straight, arc(10.0, 20.0)])
    v = speed_profile(points, FREE)
    assert menger_curvature(points)[100] == pytest.approx(1.0 / 20.0, rel=1e-3)
    distance = 10.0 + 2 * 10.0 * math.sin(0.025)  # to x = 0, then the 0.5 m arc's chord
    assert v[80] == pytest.approx(math.sqrt(60.0 + 2 * 6.0 * distance), rel=1e-12)  # x = -10 m
    assert_allclose(v[101:], math.sqrt(60.0), rtol=1e-9)


def test_vectorised_passes_equal_the_sequential_loops() -> None:
    """The cumulative-minimum passes equal the textbook loops on random limits."""
    rng = np.random.default_rng(0)
    s = np.cumsum(rng.uniform(0.1, 1.0, 200))
    limit = rng.uniform(1.0, 20.0, 200)
    fwd = limit.copy()
    for i in range(1, 200):
        fwd[i] = min(fwd[i], math.sqrt(fwd[i - 1] ** 2 + 2 * 3.0 * (s[i] - s[i - 1])))
    bwd = fwd.copy()
    for i in range(198, -1, -1):
        bwd[i] = min(bwd[i], math.sqrt(bwd[i + 1] ** 2 + 2 * 6.0 * (s[i + 1] - s[i])))
    assert_allclose(forward_pass(s, limit, 3.0), fwd, rtol=1e-9)
    assert_allclose(backward_pass(s, forward_pass(s, limit, 3.0), 6.0), bwd, rtol=1e-9)


def test_empty_and_single_point() -> None:
    """Degenerate paths give empty or single speeds."""
    assert speed_profile(np.zeros((0, 2))).shape == (0,)
    assert speed_profile(np.zeros((1, 2)), FREE).tolist() == [100.0]


def test_curvature_window_averages_wiggles_but_keeps_a_circle() -> None:
    """A window keeps sqrt(a R) on a circle; on a zig-zag it averages 7 samples.

    Alternating curvature +-k over 7 samples averages to k / 7, so the
    curvature limit rises from sqrt(6 / k) to sqrt(6 * 7 / k).
    """
    cfg = SpeedProfileConfig(horizon_stop=False, curvature_window=3.0, **LIMITS)
    v = speed_profile(arc(10.0, 60.0), cfg)
    assert_allclose(v[4:-4], math.sqrt(6.0 * 10.0), rtol=1e-6)
    x = np.arange(0.0, 30.0, 0.5)
    zigzag = np.column_stack([x, 0.02 * (-1.0) ** np.arange(len(x))])
    free = {**LIMITS, "a_drive": 1000.0, "a_brake": 1000.0, "horizon_stop": False}
    point_by_point = speed_profile(zigzag, SpeedProfileConfig(curvature_window=0.0, **free))
    windowed = speed_profile(zigzag, SpeedProfileConfig(curvature_window=3.2, **free))
    k = abs(menger_curvature(zigzag)[10])
    assert_allclose(point_by_point[2:-2], math.sqrt(6.0 / k), rtol=1e-9)
    assert_allclose(windowed[8:-8], math.sqrt(6.0 * 7 / k), rtol=1e-9)


def test_friction_ellipse_on_a_circle_from_rest() -> None:
    """On R = 10 m (V^2 = a_lat R = 60), dv^2/ds = 2 a_d sqrt(1 - (v^2 / V^2)^2) from rest.

    So arcsin(v^2 / V^2) = 2 a_d s / V^2: at s = 5 m, v^2 = 60 sin(0.5) = 28.77,
    v = 5.363 m/s (a straight line gives sqrt(30) = 5.477); V is reached at
    s = pi V^2 / (4 a_d) = 15.71 m. Fine steps: Euler error < 0.5 %.
    """
    s = np.arange(0.0, 30.0, 0.01)
    kappa = np.full_like(s, 0.1)
    limit = np.full_like(s, math.sqrt(60.0))
    limit[0] = 0.0
    v = ellipse_forward_pass(s, limit, kappa, 3.0, a_lat_max=6.0)
    assert v[500] == pytest.approx(math.sqrt(60.0 * math.sin(0.5)), rel=5e-3)
    assert v[1500] < math.sqrt(60.0) < v[1600] + 1e-9


def test_friction_ellipse_brakes_less_in_the_corner() -> None:
    """Braking to 5 m/s at the end of R = 10 m: the ellipse leaves less than a_brake.

    Backwards from v^2 = 25 at the end: dv^2/ds = 2 a_b sqrt(1 - (v^2 / 60)^2),
    so arcsin(v^2 / 60) grows by 2 a_b ds / 60 = 0.2 rad per metre with a_b = 6:
    1 m back v^2 = 60 sin(arcsin(25 / 60) + 0.2) = 35.87 (without: 37).
    On a straight (kappa = 0) the loops equal the closed-form passes.
    """
    s = np.arange(0.0, 10.001, 0.001)
    limit = np.full_like(s, math.sqrt(60.0))
    limit[-1] = 5.0
    v = ellipse_backward_pass(s, limit, np.full_like(s, 0.1), 6.0, a_lat_max=6.0)
    expected = 60.0 * math.sin(math.asin(25.0 / 60.0) + 0.2)
    assert v[-1001] ** 2 == pytest.approx(expected, rel=1e-3)
    rng = np.random.default_rng(0)
    s = np.cumsum(rng.uniform(0.1, 1.0, 100))
    lim = rng.uniform(1.0, 20.0, 100)
    zero = np.zeros(100)
    assert_allclose(
        ellipse_forward_pass(s, lim, zero, 3.0, a_lat_max=6.0), forward_pass(s, lim, 3.0)
    )
    assert_allclose(
        ellipse_backward_pass(s, lim, zero, 6.0, a_lat_max=6.0), backward_pass(s, lim, 6.0)
    )


def test_speed_profile_uses_the_ellipse_when_asked() -> None:
    """From rest on R = 10 m: 5.36 m/s at 5 m with the ellipse, sqrt(30) = 5.48 without."""
    pts = arc(10.0, 12.0, step=0.05)
    cfg = SpeedProfileConfig(v_max=100.0, horizon_stop=False, curvature_window=0.0, **LIMITS)
    plain = speed_profile(pts, cfg, v_start=0.0)
    ellipse = speed_profile(pts, dataclasses.replace(cfg, friction_ellipse=True), v_start=0.0)
    assert plain[100] == pytest.approx(math.sqrt(2 * 3.0 * 5.0), rel=1e-3)
    assert ellipse[100] == pytest.approx(math.sqrt(60.0 * math.sin(0.5)), rel=5e-3)


def test_downforce_raises_the_corner_speed() -> None:
    """v^2 |kappa| = a_lat_max + a_lat_aero v^2: R = 20 m, 6 m/s^2, 0.01 1/m gives
    v = sqrt(6 / (0.05 - 0.01)) = 12.247 m/s (a_lat 7.5 = 6 + 0.01 * 150); where
    |kappa| <= a_lat_aero + a_lat_max / v_max^2 = 0.0167 1/m (R >= 60 m), v_max."""
    cfg = SpeedProfileConfig(a_lat_max=6.0, a_lat_aero=0.01, v_max=30.0)
    v = curvature_limit(np.array([0.05, -0.05, 0.01, 0.0]), cfg)
    assert_allclose(v[:2], math.sqrt(150.0), rtol=1e-12)
    assert_allclose(v[2:], 30.0)
    assert v[0] ** 2 * 0.05 == pytest.approx(6.0 + 0.01 * v[0] ** 2)


def test_jerk_limit_on_a_curvature_ramp() -> None:
    """Curvature rising 0.01 1/m per metre: v <= (60 / 0.01)^(1/3) = 18.17 m/s.

    Samples 0.5 m apart, the slope over a 4 m window (8 steps); flat curvature:
    no limit. With J = inf there is none at all.
    """
    kappa = np.concatenate([np.zeros(20), 0.005 * np.arange(1, 21), np.full(20, 0.1)])
    cfg = SpeedProfileConfig(lateral_jerk_max=60.0, jerk_window=4.0)
    v = jerk_limit(kappa, 0.5, cfg)
    assert v is not None
    assert_allclose(v[28:32], (60.0 / 0.01) ** (1 / 3), rtol=1e-9)
    assert v[28] == pytest.approx(18.17, abs=0.01)
    assert np.all(np.isinf(v[:15])) and np.all(np.isinf(v[-15:]))
    assert jerk_limit(kappa, 0.5, SpeedProfileConfig(lateral_jerk_max=math.inf)) is None


def test_no_waypoints_give_no_speeds() -> None:
    """An empty list or (0, 2) array of waypoints: no speeds, whatever s says."""
    assert speed_profile([]).shape == (0,)  # type: ignore[arg-type]
    assert speed_profile(np.zeros((0, 2)), s=np.zeros(1)).shape == (0,)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"points": np.zeros(4)}, r"points must be \(n, 2\)"),
        ({"points": np.array([[0.0, 0.0], [1.0, math.nan], [2.0, 0.0]])}, "finite"),
        ({"s": np.arange(10.0)}, r"s must be \(3,\)"),
        ({"v_start": math.nan}, "v_start must be a finite speed"),
        ({"v_end": math.inf}, "v_end must be a finite speed"),
    ],
)
def test_bad_inputs_are_named(kwargs: dict[str, object], message: str) -> None:
    """A NaN point or start speed (which would pass every limit and read as
    top speed) or an arc length of the wrong length (read out of bounds by
    the compiled kernel) is a ValueError naming it."""
    args: dict[str, object] = {"points": np.array([[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]])}
    args.update(kwargs)
    points = args.pop("points")
    with pytest.raises(ValueError, match=message):
        speed_profile(points, **args)  # type: ignore[arg-type]
