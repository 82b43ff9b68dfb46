"""The path kept in the lane with the car's body (planner.lane, kernels.lane_room/lane_path)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose

from conesim.planner import MidlineConfig, kernels
from conesim.planner.bridges import TrackEstimate
from conesim.planner.lane import keep_in_lane

CONFIG = MidlineConfig()  # body 0.7 m half width, 2.28 m front, 0.25 m clearance


def edges(points: np.ndarray) -> np.ndarray:
    """(k - 1, 2, 2) the segments joining consecutive (k, 2) points."""
    return np.stack([points[:-1], points[1:]], axis=1)


def straight_lane(half_width: float = 1.5, gap: tuple[float, float] | None = None) -> np.ndarray:
    """Both edges of a straight lane along +x, cones every 2 m; ``gap`` leaves the left
    edge's segments out between those x [m] (a knocked cone)."""
    x = np.arange(-2.0, 30.0, 2.0)
    left = edges(np.column_stack([x, np.full_like(x, half_width)]))
    right = edges(np.column_stack([x, np.full_like(x, -half_width)]))
    if gap is not None:
        keep = (left[:, 1, 0] <= gap[0]) | (left[:, 0, 0] >= gap[1])
        left = left[keep]
    return np.concatenate([left, right])


def test_room_is_the_half_lane_less_the_body_on_a_straight() -> None:
    """A 3 m lane: 1.5 - 0.7 - 0.25 = 0.55 m of room each side of its middle."""
    path = np.column_stack([np.arange(0.0, 20.0, 0.5), np.zeros(40)])
    left, right, normal = kernels.lane_room(path, straight_lane(), 1.5, CONFIG.lane_settings)
    assert_allclose(left, 0.55, atol=1e-12)
    assert_allclose(right, 0.55, atol=1e-12)
    assert_allclose(normal, np.tile([0.0, 1.0], (40, 1)), atol=1e-12)


def test_a_path_near_a_cone_line_is_pushed_back_into_the_lane() -> None:
    """A fitted path 0.9 m left of the middle ends up within 0.55 m of it."""
    path = np.column_stack([np.arange(0.0, 20.0, 0.5), np.full(40, 0.9)])
    moved = keep_in_lane(path, straight_lane(), TrackEstimate(3.0, 0.0, True), CONFIG)
    assert np.max(moved[:, 1]) <= 0.55 + 1e-12
    assert_allclose(moved[:, 1], 0.55, atol=1e-9)  # a straight stays straight
    assert_allclose(moved[:, 0], path[:, 0])


def test_front_end_sweep_outside_a_3_m_turn() -> None:
    """Rear axle on R 3 m: the front corner runs on sqrt(3.7^2 + 2.28^2) = 4.346 m, 0.646 m
    outside the body's side; in a lane whose edges are 1.5 m either side the room
    outside is 1.5 - 0.7 - 0.25 - 0.646 = -0.096 m: the path must move 0.096 m in."""
    a = np.linspace(0.0, math.pi / 2, 60)
    path = np.column_stack([3.0 * np.sin(a), 3.0 - 3.0 * np.cos(a)])  # a left turn, R 3 m
    inner = np.column_stack([1.5 * np.sin(a), 3.0 - 1.5 * np.cos(a)])
    outer = np.column_stack([4.5 * np.sin(a), 3.0 - 4.5 * np.cos(a)])
    segments = np.concatenate([edges(inner[::4]), edges(outer[::2])])
    left, right, _ = kernels.lane_room(path, segments, 1.5, CONFIG.lane_settings)
    sweep = math.hypot(3.7, 2.28) - 3.7
    assert sweep == pytest.approx(0.646, abs=1e-3)
    middle = slice(10, 50)
    # the inner room: to the chords between inner cones, a little less than 1.5 m
    assert np.all(left[middle] <= 0.55 + 1e-9) and np.all(left[middle] > 0.5)
    assert_allclose(right[middle], 1.5 - 0.95 - sweep, atol=0.01)
    moved = keep_in_lane(path, segments, TrackEstimate(3.0, 0.0, True), CONFIG)
    radius = np.hypot(moved[:, 0], moved[:, 1] - 3.0)
    assert np.all(radius[middle] <= 3.0 - 0.09)  # the rear axle inside 2.91 m


def test_a_knocked_cone_gap_is_no_way_out() -> None:
    """Where two left cones (6 m of edge) are missing, the room left is still
    1.5 - 0.95 = 0.55 m (the lane's half width where no edge is met), not the
    open infield: the path through the gap keeps to the lane."""
    lane = straight_lane(gap=(6.0, 12.0))
    path = np.column_stack([np.arange(0.0, 20.0, 0.5), np.zeros(40)])
    left, right, _ = kernels.lane_room(path, lane, 1.5, CONFIG.lane_settings)
    assert_allclose(left, 0.55, atol=1e-12)
    assert_allclose(right, 0.55, atol=1e-12)
    moved = keep_in_lane(path, lane, TrackEstimate(3.0, 0.0, True), CONFIG)
    assert np.max(np.abs(moved[:, 1])) <= 0.55 + 1e-9
