"""Tests for planner.racing_line: the minimum-curvature QP against worked geometry."""

from __future__ import annotations

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose

from conesim.core.polyline import Polyline
from conesim.planner.racing_line import (
    Corridor,
    offset_bounds,
    racing_lines,
    shortest_path_offsets,
    sweep,
)
from conesim.tracks import load_track

CLEARANCE = 0.95  # [m] half the default car's 1.4 m and the 0.25 m margin


def ring(radius: float, n: int = 720) -> np.ndarray:
    """n points on a counter-clockwise circle of ``radius`` [m] at the origin."""
    a = np.arange(n) * 2 * math.pi / n
    return radius * np.column_stack([np.cos(a), np.sin(a)])


def ring_corridor(radius: float, width: float) -> Corridor:
    """A counter-clockwise ring lane: the left boundary inside, the right outside."""
    return Corridor(
        ring(radius, 400),
        Polyline(ring(radius - width / 2), True),
        Polyline(ring(radius + width / 2), True),
        CLEARANCE,
    )


@pytest.mark.parametrize(("radius", "width"), [(9.0, 3.0), (20.0, 4.0), (45.0, 3.5)])
def test_min_curvature_line_of_a_ring_is_its_outermost_circle(radius: float, width: float) -> None:
    """On a ring of constant width the least curvature is the widest circle the car
    may drive, R + (w/2 - d) with d = half width + margin; the shortest is R - (w/2 - d)."""
    lines = racing_lines(ring_corridor(radius, width))
    slack = width / 2 - CLEARANCE
    assert_allclose(np.hypot(*lines.line(0.0).T), radius + slack, atol=5e-3)
    assert_allclose(np.hypot(*lines.line(1.0).T), radius - slack, atol=5e-3)


def test_lines_stay_inside_their_bounds_on_the_shipped_loops() -> None:
    """Both QPs' offsets lie within the box (to OSQP's tolerance), and the box keeps the
    clearance from both cone polylines: every point of every blend is >= d from them."""
    for name in ("trackdrive", "autocross"):
        track = load_track(name)
        left = Polyline(track.left_boundary, True)
        right = Polyline(track.right_boundary, True)
        lines = racing_lines(Corridor(np.asarray(track.centreline), left, right, CLEARANCE))
        for alpha in (lines.min_curvature, lines.shortest):
            assert np.all(alpha >= lines.lower - 1e-6) and np.all(alpha <= lines.upper + 1e-6)
        for blend in (0.0, 0.5, 1.0):
            pts = lines.line(blend)
            assert -left.project(pts).lateral.min() >= CLEARANCE - 1e-5, name
            assert right.project(pts).lateral.min() >= CLEARANCE - 1e-5, name


def test_min_curvature_line_has_less_curvature_than_the_centreline() -> None:
    """On trackdrive the line's sum of squared curvatures is well below the centreline's."""
    track = load_track("trackdrive")
    corridor = Corridor(
        np.asarray(track.centreline),
        Polyline(track.left_boundary, True),
        Polyline(track.right_boundary, True),
        CLEARANCE,
    )
    centre = Polyline(corridor.centre, True).resample(1.0)
    line = Polyline(racing_lines(corridor).line(0.0), True).resample(1.0)
    assert np.sum(line.curvature() ** 2) < 0.7 * np.sum(centre.curvature() ** 2)


def test_a_lane_narrower_than_the_car_holds_the_line_in_its_middle() -> None:
    """Where 2 d exceeds the width, both bounds are the middle: the line is the centre."""
    corridor = ring_corridor(20.0, 1.5)
    normals, lower, upper = offset_bounds(Polyline(corridor.centre, True).points, corridor)
    assert_allclose(lower, upper)
    assert_allclose(lower, 0.0, atol=1e-3)
    assert_allclose(np.hypot(*racing_lines(corridor).line(0.3).T), 20.0, atol=1e-3)
    assert_allclose(np.hypot(*normals.T), 1.0)


def test_shortest_path_of_a_straight_lane_is_its_centre() -> None:
    """Offsets bounded by +-1 m on a straight reference: moving sideways only lengthens."""
    x = np.arange(0.0, 50.0, 1.0)
    ref = np.column_stack([x, np.zeros_like(x)])
    normals = np.tile([0.0, 1.0], (len(x), 1))
    alpha = shortest_path_offsets(ref, normals, np.full(len(x), -1.0), np.full(len(x), 1.0))
    assert_allclose(alpha, 0.0, atol=1e-6)


def test_a_lane_too_narrow_for_the_clearance_gives_a_smooth_line() -> None:
    """A 3 m ring of R 9 m bounded by chords between cones ~3 m apart, with a
    clearance of half the lane: the chords scallop the lane by the sagitta
    (3^2 / (8 R), 0.1-0.2 m) at the cones' spacing. Held to the raw middle the
    line would zigzag with it (|kappa| up to ~0.4 1/m, a few m/s off every
    corner); held to the middle of the smoothed bounds it is a circle."""
    radius, width = 9.0, 3.0
    inner = ring(radius - width / 2, round(2 * math.pi * (radius - width / 2) / 3.0))
    outer = ring(radius + width / 2, round(2 * math.pi * (radius + width / 2) / 3.0))
    corridor = Corridor(ring(radius, 400), Polyline(inner, True), Polyline(outer, True), 1.5)
    line = Polyline(racing_lines(corridor).line(0.5), True)
    assert_allclose(line.curvature(), 1.0 / np.mean(np.hypot(*line.points.T)), atol=0.01)


def test_the_front_corner_sweeps_out_of_a_turn() -> None:
    """Rear axle on 3.0 m at full lock, half width 0.7 m, front 2.28 m ahead of the
    axle: the front corner runs on sqrt(3.7^2 + 2.28^2) = 4.346 m, 0.646 m wider
    than the side at the axle; nothing on a straight."""
    assert_allclose(sweep(np.array([1.0 / 3.0, 0.0]), 0.7, 2.28), [math.hypot(3.7, 2.28) - 3.7, 0])
    assert sweep(np.array([1.0 / 3.0]), 0.7, 2.28)[0] == pytest.approx(0.646, abs=1e-3)


def test_the_line_keeps_the_sweep_from_the_outer_boundary() -> None:
    """A R 20 m ring 5 m wide: the outermost circle the car's centre may drive is
    21.55 m; with the body's 2.28 m front it keeps sqrt((r + 0.7)^2 + 2.28^2) - r - 0.7
    (0.117 m) more from the outer cones, and the inner bound is as before."""
    radius, width = 20.0, 5.0
    corridor = ring_corridor(radius, width)
    body = Corridor(corridor.centre, corridor.left, corridor.right, CLEARANCE, 0.7, 2.28)
    lines = racing_lines(body)
    r = float(np.mean(np.hypot(*lines.line(0.0).T)))
    expected = radius + width / 2 - CLEARANCE - (math.hypot(r + 0.7, 2.28) - r - 0.7)
    assert_allclose(np.hypot(*lines.line(0.0).T), expected, atol=5e-3)
    assert_allclose(np.hypot(*lines.line(1.0).T), radius - (width / 2 - CLEARANCE), atol=5e-3)


def stadium(offset: float, step: float) -> np.ndarray:
    """A counter-clockwise stadium (straights y = 0 and y = 20 from x = -20 to 20,
    ends of R 10 m) moved ``offset`` [m] outward, every ~``step`` [m] from
    (0, -offset) on."""
    r = 10.0 + offset
    x = np.linspace(-20.0, 20.0, 400, endpoint=False)
    a = np.linspace(0.0, math.pi, 400, endpoint=False)
    points = np.vstack([
        np.column_stack([x, np.full_like(x, 10.0 - r)]),
        np.column_stack([20.0 + r * np.sin(a), 10.0 - r * np.cos(a)]),
        np.column_stack([-x, np.full_like(x, 10.0 + r)]),
        np.column_stack([-20.0 - r * np.sin(a), 10.0 + r * np.cos(a)]),
    ])  # fmt: skip
    return Polyline(points, True).resample(step, start=20.0).points


def test_a_lane_cone_between_wider_gate_cones_bounds_the_lane() -> None:
    """A start gate on a stadium 3.3 m wide, cones 4.5 m apart: big orange cones
    0.5 m wider 0.3 m either side of the right row's lane cone at (0, -1.65). At
    that acute vertex the chosen segment's side is wrong: a point of the centre
    line 1-2.7 m after it read as 2 m outside the lane, both bounds crossed,
    and the line was held 0.4 m from the cone (generated track 9150). With the
    vertex's own side (``Polyline.project``) the lane is as wide there as
    elsewhere, and the lines keep the clearance from the lane cone."""
    half = 1.65
    right = stadium(half, 4.5)
    right = np.vstack([[[0.3, -half - 0.5]], right[1:], [[-0.3, -half - 0.5], [0.0, -half]]])
    corridor = Corridor(
        stadium(0.0, 0.5), Polyline(stadium(-half, 4.5), True), Polyline(right, True), CLEARANCE
    )
    _, lower, upper = offset_bounds(Polyline(corridor.centre, True).resample(1.0).points, corridor)
    assert np.all(lower < upper)
    for blend in (0.0, 1.0):
        line = racing_lines(corridor).line(blend)
        assert np.min(np.hypot(line[:, 0], line[:, 1] + half)) >= CLEARANCE - 1e-3
