"""Tests for planner.lap_map: the lap-1 map and the racing line through it."""

from __future__ import annotations

import numpy as np

from conesim.planner.classify import LEFT, RIGHT
from conesim.planner.config import SpeedProfileConfig
from conesim.planner.lap_map import LapMap
from conesim.tracks.global_path import global_path_from_centreline

R_IN, R_OUT = 8.5, 11.5  # [m] a ring lane 3 m wide about a centre of 10 m


def ring(radius: float, count: int) -> np.ndarray:
    a = np.linspace(0.0, 2.0 * np.pi, count, endpoint=False)
    return radius * np.column_stack([np.cos(a), np.sin(a)])


def ring_map(sightings: int, seed: int = 0) -> LapMap:
    """The ring's cones seen ``sightings`` times each with 5 cm of noise, driven
    anticlockwise (left = inside), and one ghost cone seen once."""
    rng = np.random.default_rng(seed)
    inner, outer = ring(R_IN, 18), ring(R_OUT, 24)
    lap_map = LapMap()
    for _ in range(sightings):
        pts = np.vstack([inner, outer]) + rng.normal(0.0, 0.05, (42, 2))
        lap_map.add(pts, np.array([LEFT] * 18 + [RIGHT] * 24, dtype=np.int8))
    lap_map.add(np.array([[10.0, 0.0]]), np.array([LEFT], dtype=np.int8))
    return lap_map


def test_sightings_merge_and_a_ghost_stays_out() -> None:
    """42 cones seen 3 times are 42 map cones at their mean (within the noise's
    0.05 / sqrt(3) m), a cone seen once is not one, and seen twice none is."""
    points, sides = ring_map(3).cones()
    assert len(points) == 42 and (sides == LEFT).sum() == 18
    radii = np.hypot(points[:, 0], points[:, 1])
    assert np.allclose(radii[sides == LEFT], R_IN, atol=0.12)
    assert np.allclose(radii[sides == RIGHT], R_OUT, atol=0.12)
    assert len(ring_map(2)) == 0


def test_the_racing_line_on_a_ring_is_its_inner_circle() -> None:
    """On a ring of constant width the fastest line is the innermost circle
    (lap time 2 pi sqrt(r / a_lat) grows with r): the line keeps the clearance
    from the inner cones' polygon and runs at about R_IN + clearance."""
    clearance = 1.1
    centre = ring(10.0, 126)
    path = ring_map(3).racing_path(
        global_path_from_centreline(centre, True), clearance, SpeedProfileConfig()
    )
    r = np.hypot(path.xy[:, 0], path.xy[:, 1])
    assert r.min() >= R_IN + clearance - 0.05  # the polygon's chords lie inside the circle
    assert r.max() <= R_OUT - clearance
    assert abs(float(np.median(r)) - (R_IN + clearance)) < 0.15


def test_a_gate_cone_wider_than_the_lane_bounds_nothing() -> None:
    """Two cones 1 m wide of the inner ring's cones at one place (a start gate
    wider than the lane), each seen 3 times: the line still runs along the
    inner circle there, as if they were not mapped."""
    lap_map = ring_map(3)
    gate = np.array([[R_IN - 1.0, 0.3], [R_IN - 1.0, -0.3]])
    for _ in range(3):
        lap_map.add(gate, np.array([LEFT, LEFT], dtype=np.int8))
    assert len(lap_map) == 44
    clearance = 1.1
    path = lap_map.racing_path(
        global_path_from_centreline(ring(10.0, 126), True), clearance, SpeedProfileConfig()
    )
    r = np.hypot(path.xy[:, 0], path.xy[:, 1])
    assert r.min() >= R_IN + clearance - 0.05
