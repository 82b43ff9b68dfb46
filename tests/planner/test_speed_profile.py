"""Speed profile: v = sqrt(a_lat R) on circles, v^2 = 2 a s ramps, the drive pass, curvature.

The worked numbers of the steps the package has no entry point for (the
brake and friction-ellipse passes alone, the jerk limit alone) are checked
on their numpy reference, which the kernels match bit for bit
(``tests/planner/kernels/test_speed_profile.py``).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from numpy.testing import assert_allclose, assert_array_equal

from conesim.planner import SpeedProfileConfig, speed_profile
from conesim.planner.speed_profile import forward_pass, profile_curvature

# The worked numbers use 6 m/s^2 lateral and braking, no friction ellipse and
# no cut near full lock (each tested on its own).
LIMITS = {
    "lock_radius": 0.0,
    "steering_rate_max": math.inf,
    "a_lat_max": 6.0,
    "a_lat_aero": 0.0,
    "a_brake": 6.0,
    "friction_ellipse": False,
    "lateral_jerk_max": math.inf,
}
FREE = SpeedProfileConfig(v_max=100.0, horizon_stop=False, curvature_window=0.0, **LIMITS)
POINTWISE = SpeedProfileConfig(curvature_window=0.0)  # the curvature point by point


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
    assert_allclose(profile_curvature(arc(8.0, 20.0), POINTWISE), 1.0 / 8.0, rtol=1e-9)
    right = profile_curvature(arc(8.0, 20.0, left=False), POINTWISE)
    assert_allclose(right, -1.0 / 8.0, rtol=1e-9)
    line = np.column_stack([np.arange(10.0), np.zeros(10)])
    assert_allclose(profile_curvature(line, POINTWISE), 0.0)
    assert profile_curvature(np.zeros((2, 2))).tolist() == [0.0, 0.0]  # too few for a circle


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
    assert profile_curvature(points, FREE)[100] == pytest.approx(1.0 / 20.0, rel=1e-3)
    distance = 10.0 + 2 * 10.0 * math.sin(0.025)  # to x = 0, then the 0.5 m arc's chord
    assert v[80] == pytest.approx(math.sqrt(60.0 + 2 * 6.0 * distance), rel=1e-12)  # x = -10 m
    assert_allclose(v[101:], math.sqrt(60.0), rtol=1e-9)


def test_drive_pass_is_the_sequential_loop() -> None:
    """The closed-form drive pass equals the textbook loop on random limits; from rest
    on a straight at 3 m/s^2, 6 m/s after 6 m; the limits are not changed."""
    rng = np.random.default_rng(0)
    s = np.cumsum(rng.uniform(0.1, 1.0, 200))
    limit = rng.uniform(1.0, 20.0, 200)
    fwd = limit.copy()
    for i in range(1, 200):
        fwd[i] = min(fwd[i], math.sqrt(fwd[i - 1] ** 2 + 2 * 3.0 * (s[i] - s[i - 1])))
    given = limit.copy()
    assert_allclose(forward_pass(s, limit, 3.0), fwd, rtol=1e-9)
    assert_array_equal(limit, given)
    ramp = forward_pass(np.array([0.0, 1.5, 6.0]), np.array([0.0, 50.0, 50.0]), 3.0)
    assert_allclose(ramp, [0.0, 3.0, 6.0], rtol=1e-12)
    assert forward_pass(np.zeros(0), np.zeros(0), 3.0).shape == (0,)
    with pytest.raises(ValueError, match="alike"):
        forward_pass(np.zeros(3), np.zeros(4), 3.0)


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
    free = {**free, "lock_radius": 0.0}
    point_by_point = speed_profile(zigzag, SpeedProfileConfig(curvature_window=0.0, **free))
    windowed = speed_profile(zigzag, SpeedProfileConfig(curvature_window=3.2, **free))
    k = abs(profile_curvature(zigzag, POINTWISE)[10])
    assert_allclose(point_by_point[2:-2], math.sqrt(6.0 / k), rtol=1e-9)
    assert_allclose(windowed[8:-8], math.sqrt(6.0 * 7 / k), rtol=1e-9)


def test_speed_profile_uses_the_ellipse_when_asked() -> None:
    """From rest on R = 10 m: 5.36 m/s at 5 m with the ellipse, sqrt(30) = 5.48 without."""
    pts = arc(10.0, 12.0, step=0.05)
    cfg = SpeedProfileConfig(v_max=100.0, horizon_stop=False, curvature_window=0.0, **LIMITS)
    plain = speed_profile(pts, cfg, v_start=0.0)
    ellipse = speed_profile(pts, dataclasses.replace(cfg, friction_ellipse=True), v_start=0.0)
    assert plain[100] == pytest.approx(math.sqrt(2 * 3.0 * 5.0), rel=1e-3)
    assert ellipse[100] == pytest.approx(math.sqrt(60.0 * math.sin(0.5)), rel=5e-3)


def test_a_wider_drive_ellipse_accelerates_harder_in_the_corner() -> None:
    """d(v^2)/ds = 2 a sqrt(1 - (v^2 / (R q a_lat))^2) from rest gives
    v^2 = R q a_lat sin(2 a s / (R q a_lat)): on R = 10 m at 5 m, q = 2 (an
    ellipse of 12 m/s^2 around the 6 planned) 120 sin(0.25) = 29.69, v = 5.449 m/s,
    where q = 1 gives 5.36; the corner's own limit, sqrt(60), stays."""
    pts = arc(10.0, 40.0, step=0.05)
    cfg = dataclasses.replace(FREE, friction_ellipse=True)
    wide = speed_profile(pts, dataclasses.replace(cfg, drive_lateral_share=2.0), v_start=0.0)
    assert wide[100] == pytest.approx(math.sqrt(120.0 * math.sin(0.25)), rel=5e-3)
    assert speed_profile(pts, cfg, v_start=0.0)[100] < wide[100] - 0.08
    assert wide.max() == pytest.approx(math.sqrt(60.0), rel=1e-6)


def test_downforce_raises_the_corner_speed() -> None:
    """v^2 |kappa| = a_lat_max + a_lat_aero v^2: R = 20 m, 6 m/s^2, 0.01 1/m gives
    v = sqrt(6 / (0.05 - 0.01)) = 12.247 m/s (a_lat 7.5 = 6 + 0.01 * 150), turning
    either way; where |kappa| <= a_lat_aero + a_lat_max / v_max^2 = 0.0167 1/m
    (R >= 60 m: here 100 m), v_max."""
    cfg = dataclasses.replace(FREE, a_lat_aero=0.01, v_max=30.0)
    for left in (True, False):
        v = speed_profile(arc(20.0, 30.0, left=left), cfg)
        assert_allclose(v, math.sqrt(150.0), rtol=1e-9)
        assert v[5] ** 2 * 0.05 == pytest.approx(6.0 + 0.01 * v[5] ** 2)
    assert_allclose(speed_profile(arc(100.0, 30.0), cfg), 30.0, rtol=1e-12)


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
