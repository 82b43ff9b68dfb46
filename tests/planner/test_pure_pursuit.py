"""Pure pursuit: the bicycle geometry on circular paths, the lookahead law, limits."""

from __future__ import annotations

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose

from conesim.planner import PurePursuitConfig, lookahead_distance, pure_pursuit
from conesim.planner.pure_pursuit import find_lookahead_point, pure_pursuit_angle, rear_slip_angle

CONFIG = PurePursuitConfig()  # L = 1.53 m, rear axle at x = -0.465 m in os_sensor
# The geometry alone: no rear-axle slip and no feed-forward (tested on their own below).
GEOMETRIC = PurePursuitConfig(slip_stiffness=math.inf, feedforward=False)


def circle_through_axle(radius: float, left: bool = True) -> np.ndarray:
    """A circle of ``radius`` through the rear axle, tangent to the heading, every ~1 cm."""
    a = np.arange(0.0, math.pi, 0.01 / radius)
    y = radius * (1.0 - np.cos(a))
    return np.column_stack([CONFIG.rear_axle_x + radius * np.sin(a), y if left else -y])


@pytest.mark.parametrize("radius", [6.0, 10.0, 25.0])
@pytest.mark.parametrize("left", [True, False])
@pytest.mark.parametrize("speed", [0.0, 8.0])
def test_circle_gives_the_geometric_angle(radius: float, left: bool, speed: float) -> None:
    """On a circle of R through the axle: delta = atan(2 L sin(alpha) / L_d) = atan(L / R)."""
    result = pure_pursuit(circle_through_axle(radius, left), speed, GEOMETRIC)
    target = result.target - [GEOMETRIC.rear_axle_x, 0.0]
    alpha = math.atan2(target[1], target[0])
    distance = math.hypot(*target)
    expected = math.atan(2 * GEOMETRIC.wheelbase * math.sin(alpha) / distance)
    assert result.steering == pytest.approx(expected, abs=1e-12)
    assert distance == pytest.approx(lookahead_distance(speed, GEOMETRIC), abs=1e-9)
    # A chord of the circle: alpha = asin(L_d / 2R), so delta = atan(L / R) (1 cm chords).
    assert abs(result.steering) == pytest.approx(math.atan(GEOMETRIC.wheelbase / radius), abs=1e-6)
    assert math.copysign(1.0, result.steering) == (1.0 if left else -1.0)


def test_lookahead_grows_with_speed_within_limits() -> None:
    """L_d = 2 + 0.4 v, clipped to [2, 10] m."""
    assert lookahead_distance(0.0, CONFIG) == 2.0
    assert lookahead_distance(10.0, CONFIG) == pytest.approx(6.0)
    assert lookahead_distance(50.0, CONFIG) == 10.0


def test_steering_is_clipped() -> None:
    """A target 90 degrees to the left asks for more than max_steer: clipped to 0.47 rad."""
    path = np.array([[CONFIG.rear_axle_x, 0.0], [CONFIG.rear_axle_x, 3.0]])
    result = pure_pursuit(path, 0.0, CONFIG)
    assert pure_pursuit_angle(result.target - [CONFIG.rear_axle_x, 0.0], 1.53)[0] > 0.47
    assert result.steering == CONFIG.max_steer


def test_straight_path_ahead_steers_straight() -> None:
    """A path along the x axis: zero steering, target L_d ahead of the axle."""
    x = np.arange(0.0, 20.0, 0.5)
    result = pure_pursuit(np.column_stack([x, np.zeros_like(x)]), 5.0, CONFIG)
    assert result.steering == 0.0
    assert_allclose(result.target, [CONFIG.rear_axle_x + 4.0, 0.0], atol=1e-12)


def test_target_when_the_path_is_short_or_starts_far() -> None:
    """All of the path inside the circle: its last point; all outside: its first point."""
    centre = np.zeros(2)
    short = np.array([[0.5, 0.0], [1.0, 0.5]])
    far = np.array([[5.0, 1.0], [6.0, 1.0]])
    assert_allclose(find_lookahead_point(short, centre, 3.0)[0], [1.0, 0.5])
    assert_allclose(find_lookahead_point(far, centre, 3.0)[0], [5.0, 1.0])


def test_rear_slip_turns_the_pursuit_further() -> None:
    """R = 10 m at 10 m/s: a_lat = v^2 2 sin(alpha) / L_d = 10 m/s^2 on the circle.

    alpha_r = 10 / (27.7 (9.81 + 0.01 * 100)) = 0.03340 rad, and the steering
    is atan(2 L sin(alpha + alpha_r) / L_d), more than atan(L / R) = 0.1519.
    """
    path = circle_through_axle(10.0)
    result = pure_pursuit(path, 10.0, CONFIG)
    target = result.target - [CONFIG.rear_axle_x, 0.0]
    alpha, distance = math.atan2(target[1], target[0]), math.hypot(*target)
    assert 2 * 100.0 * math.sin(alpha) / distance == pytest.approx(10.0, rel=1e-4)
    slip = rear_slip_angle(10.0, alpha, distance, CONFIG)
    assert slip == pytest.approx(10.0 / (27.7 * 10.81), rel=1e-4)
    expected = math.atan(2 * CONFIG.wheelbase * math.sin(alpha + slip) / distance)
    assert result.steering == pytest.approx(expected, abs=1e-12)
    assert result.steering == pytest.approx(0.1676, abs=1e-4)  # L_d = 6 m, alpha = asin(0.3)
    right = pure_pursuit(circle_through_axle(10.0, left=False), 10.0, CONFIG)
    assert right.steering == pytest.approx(-result.steering, abs=1e-9)
    assert rear_slip_angle(0.0, alpha, distance, CONFIG) == 0.0


def test_lookahead_cap() -> None:
    """A 3 m cap shortens the 6 m lookahead of 10 m/s; a cap below 2 m gives lookahead_min."""
    x = np.arange(0.0, 20.0, 0.5)
    path = np.column_stack([x, np.zeros_like(x)])
    assert pure_pursuit(path, 10.0, CONFIG).distance == pytest.approx(6.0)
    assert pure_pursuit(path, 10.0, CONFIG, lookahead_cap=3.0).distance == pytest.approx(3.0)
    assert pure_pursuit(path, 10.0, CONFIG, lookahead_cap=0.5).distance == pytest.approx(2.0)


def test_bad_path_or_speed_is_refused() -> None:
    """An empty path, a NaN waypoint and a NaN speed are ValueErrors, not a
    NaN steering angle past the clip."""
    path = np.array([[1.0, 0.0], [5.0, 0.0], [10.0, 0.0]])
    with pytest.raises(ValueError, match=r"path must be \(n, 2\) \[m\] with n >= 1"):
        pure_pursuit(np.zeros((0, 2)), 8.0, CONFIG)
    with pytest.raises(ValueError, match="must be finite"):
        pure_pursuit(np.array([[1.0, 0.0], [5.0, math.nan]]), 8.0, CONFIG)
    with pytest.raises(ValueError, match="must be finite"):
        pure_pursuit(path, math.nan, CONFIG)
    assert pure_pursuit(path, 8.0, CONFIG).steering == pytest.approx(0.0)


FEEDFORWARD = PurePursuitConfig(slip_stiffness=math.inf, feedforward=True, feedforward_preview=0.1)


def straight_into_circle(gap: float, radius: float) -> tuple[np.ndarray, np.ndarray]:
    """From 1 m behind the rear axle, straight along x for ``gap`` [m] past it, then
    a left circle of ``radius``: points every 1 cm and their curvature [1/m]."""
    x0 = FEEDFORWARD.rear_axle_x
    line = np.column_stack([np.arange(x0 - 1.0, x0 + gap, 0.01), np.zeros(round((gap + 1) / 0.01))])
    a = np.arange(0.01 / radius, math.pi / 2, 0.01 / radius)
    arc = np.column_stack([x0 + gap + radius * np.sin(a), radius * (1.0 - np.cos(a))])
    kappa = np.concatenate([np.zeros(len(line)), np.full(len(arc), 1.0 / radius)])
    return np.vstack([line, arc]), kappa


def test_feedforward_does_not_turn_in_before_the_corner() -> None:
    """On the path 3 m before a R 8 m corner at 10 m/s (L_d 6 m, preview 1 m): pure
    pursuit's chord already bends left; the feed-forward steers straight."""
    path, kappa = straight_into_circle(3.0, 8.0)
    plain = pure_pursuit(path, 10.0, GEOMETRIC, curvature=kappa)
    assert plain.steering > 0.04  # 0.049 rad: the chord to (5.5, 0.57) m
    assert pure_pursuit(path, 10.0, FEEDFORWARD, curvature=kappa).steering == pytest.approx(
        0.0, abs=1e-9
    )
    # 0.5 m before the corner the preview reaches it: the corner's own angle.
    path, kappa = straight_into_circle(0.5, 8.0)
    result = pure_pursuit(path, 10.0, FEEDFORWARD, curvature=kappa)
    assert result.steering == pytest.approx(math.atan(FEEDFORWARD.wheelbase / 8.0), abs=1e-3)


@pytest.mark.parametrize("radius", [6.0, 25.0])
def test_feedforward_on_a_circle_is_the_circle(radius: float) -> None:
    """On a circle through the axle both terms are the circle's: atan(L / R)."""
    path = circle_through_axle(radius)
    result = pure_pursuit(path, 8.0, FEEDFORWARD, curvature=np.full(len(path), 1.0 / radius))
    assert result.steering == pytest.approx(math.atan(FEEDFORWARD.wheelbase / radius), abs=1e-6)


def test_feedforward_off_a_straight_path_is_pure_pursuit() -> None:
    """0.4 m right of a straight path: the on-path terms vanish, pure pursuit's correction stays."""
    x = np.arange(-2.0, 20.0, 0.5)
    path = np.column_stack([x, np.full_like(x, 0.4)])
    plain = pure_pursuit(path, 8.0, GEOMETRIC).steering
    assert plain > 0.0
    assert pure_pursuit(path, 8.0, FEEDFORWARD, curvature=np.zeros(len(x))).steering == (
        pytest.approx(plain, abs=1e-12)
    )
