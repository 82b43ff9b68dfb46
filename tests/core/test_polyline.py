"""``Polyline`` on a 2 m square, a circle of R = 10 m and a straight, worked by hand."""

from __future__ import annotations

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose, assert_array_equal

from conesim.core.polyline import Polyline

SQUARE = np.array([[0.0, 0.0], [2.0, 0.0], [2.0, 2.0], [0.0, 2.0]])  # counter-clockwise


def circle(radius: float, n: int = 360, clockwise: bool = False) -> Polyline:
    """n points on a circle about the origin, from (radius, 0); closed."""
    t = np.linspace(0.0, 2.0 * math.pi, n, endpoint=False)
    if clockwise:
        t = -t
    return Polyline(np.column_stack([radius * np.cos(t), radius * np.sin(t)]), True)


def test_points_are_a_read_only_copy() -> None:
    """The caller's array may change afterwards; the polyline's may not."""
    points = SQUARE.copy()
    line = Polyline(points, True)
    points[0] = 9.0
    assert line.points[0].tolist() == [0.0, 0.0]
    assert not line.points.flags.writeable
    assert len(line) == 4
    with pytest.raises(ValueError, match=r"\(n, 2\)"):
        Polyline(np.zeros(3))
    with pytest.raises(ValueError, match=r"\(n, 2\)"):
        Polyline(np.zeros((0, 2)))


def test_stations_of_the_square_closed_and_open() -> None:
    """Closed: 4 segments of 2 m, stations 0..8, the ring back at (0, 0). Open: 3 segments."""
    closed, open_ = Polyline(SQUARE, True), Polyline(SQUARE, False)
    assert closed.stations.tolist() == [0.0, 2.0, 4.0, 6.0, 8.0]
    assert closed.ring.tolist()[-1] == [0.0, 0.0]
    assert closed.segment_lengths.tolist() == [2.0] * 4
    assert closed.length == closed.end_station == 8.0
    assert open_.stations.tolist() == [0.0, 2.0, 4.0, 6.0]
    assert open_.deltas.tolist() == [[2.0, 0.0], [0.0, 2.0], [-2.0, 0.0]]
    assert open_.length == open_.end_station == 6.0
    assert Polyline(SQUARE[:1]).stations.tolist() == [0.0]


def test_length_is_the_pairwise_sum_and_end_station_the_running_one() -> None:
    """Over 1000 segments of 0.1 m the two sums agree to rounding; each is numpy's own."""
    x = np.arange(1001) * 0.1
    line = Polyline(np.column_stack([x, np.zeros_like(x)]))
    assert line.length == float(np.sum(line.segment_lengths))
    assert line.end_station == float(np.cumsum(line.segment_lengths)[-1])
    assert line.length == pytest.approx(100.0, abs=1e-9)
    assert line.end_station == pytest.approx(100.0, abs=1e-9)


def test_points_at_stations_wrap_on_a_loop_and_clamp_on_a_lane() -> None:
    """Station 9 on the 8 m square is 1 m along again; -1 m is 1 m before the end."""
    closed, open_ = Polyline(SQUARE, True), Polyline(SQUARE, False)
    assert_allclose(closed.at([1.0, 3.0, 9.0, -1.0]), [[1, 0], [2, 1], [1, 0], [0, 1]])
    assert_allclose(open_.at([-1.0, 5.0, 7.0]), [[0, 0], [1, 2], [0, 2]])
    assert_allclose(closed.interpolate([0.0, 10.0, 20.0, 30.0, 40.0], [1.0, 7.0, 9.0]), [5, 35, 5])


def test_resample_the_square_evenly() -> None:
    """0.5 m on the 8 m loop: 16 points, the last gap back to the first 0.5 m too;
    0.7 m: round(8 / 0.7) = 11 points 8/11 m apart; the open 6 m path keeps its ends."""
    loop = Polyline(SQUARE, True).resample(0.5)
    assert loop.closed and len(loop) == 16
    assert_allclose(loop.segment_lengths, 0.5, atol=1e-12)
    square = Polyline(SQUARE, True)
    assert_allclose(square.resample(0.7).points, square.at(np.arange(11) * 8 / 11))
    assert_allclose(Polyline(SQUARE, True).resample(0.5, start=1.0).points[0], [1.0, 0.0])
    lane = Polyline(SQUARE, False).resample(0.5)
    assert not lane.closed and len(lane) == 13
    assert_allclose(lane.points[[0, -1]], [[0.0, 0.0], [0.0, 2.0]])
    assert_allclose(lane.segment_lengths, 0.5, atol=1e-12)


def test_resample_a_circle_keeps_its_spacing() -> None:
    """R = 10 m, 360 chords (62.83 m): 0.5 m gives round(L / 0.5) = 126 points,
    each L / 126 of arc length from the next."""
    line = circle(10.0)
    dense = line.resample(0.5)
    assert len(dense) == round(line.length / 0.5) == 126
    assert_allclose(np.diff(dense.stations), line.length / 126, rtol=1e-3)


def test_sample_every_keeps_the_spacing_and_the_end() -> None:
    """An L of 3 m + 1.2 m: every 0.5 m of arc length from the start, then the end (4.2 m)."""
    line = Polyline(np.array([[0.0, 0.0], [3.0, 0.0], [3.0, 1.2]]))
    out = line.sample_every(0.5)
    assert not out.closed and len(out) == 10  # 0, 0.5, ..., 4.0 and 4.2
    assert_allclose(out.points[6], [3.0, 0.0])
    assert_allclose(out.points[-1], [3.0, 1.2])
    assert_allclose(out.stations[:-1], np.arange(9) * 0.5, atol=1e-12)
    # Once round a loop, back to its first point.
    assert_allclose(
        Polyline(SQUARE, True).sample_every(3.0).points, [[0, 0], [2, 1], [0, 2], [0, 0]]
    )
    assert Polyline(np.zeros((3, 2))).sample_every(0.5).points.tolist() == [[0.0, 0.0]]


def test_projection_onto_the_square() -> None:
    """(1, 0.5) is 0.5 m left of the first side (inside the counter-clockwise square),
    (1, -0.5) 0.5 m right; (3, -1), outside the corner (2, 0), is sqrt(2) m from it
    and 1 m right of the first side's line; (-0.5, 1) is 0.5 m right of the last side."""
    proj = Polyline(SQUARE, True).project([[1.0, 0.5], [1.0, -0.5], [3.0, -1.0], [-0.5, 1.0]])
    assert proj.segment.tolist() == [0, 0, 0, 3]
    assert_allclose(proj.station, [1.0, 1.0, 2.0, 7.0])
    assert_allclose(proj.foot, [[1, 0], [1, 0], [2, 0], [0, 1]])
    assert_allclose(proj.offset, [0.5, -0.5, -1.0, -0.5])
    assert_allclose(proj.distance, [0.5, 0.5, math.sqrt(2.0), 0.5])
    assert_allclose(proj.lateral, [0.5, -0.5, -math.sqrt(2.0), -0.5])
    assert_allclose(proj.tangent, [[1, 0], [1, 0], [1, 0], [0, -1]])


def test_projection_beyond_an_open_end() -> None:
    """(13, 4) past the end of (0, 0) -> (10, 0): 5 m from the end (3-4-5) at station 10;
    with the ends extended, 4 m left of the line at station 13."""
    line = Polyline(np.array([[0.0, 0.0], [5.0, 0.0], [10.0, 0.0]]))
    plain, extended = line.project([13.0, 4.0]), line.project([13.0, 4.0], extend_ends=True)
    assert (plain.station[0], plain.offset[0], plain.distance[0]) == (10.0, 4.0, 5.0)
    assert plain.lateral[0] == 5.0
    assert (extended.station[0], extended.lateral[0]) == (13.0, 4.0)
    assert_allclose(line.project([-3.0, -4.0]).lateral, [-5.0])


def test_projection_onto_a_circle() -> None:
    """R = 10 m: a point at 12 m from the centre is 2 m right of the counter-clockwise
    circle (outside), one at 8 m 2 m left, to the chords' sag (R (1 - cos 0.5 deg))."""
    sag = 10.0 * (1.0 - math.cos(math.radians(0.5)))
    a = np.radians([10.25, 100.5, 200.0])
    unit = np.column_stack([np.cos(a), np.sin(a)])
    line = circle(10.0)
    assert_allclose(line.project(12.0 * unit).lateral, -2.0, atol=sag)
    assert_allclose(line.project(8.0 * unit).lateral, 2.0, atol=sag)
    assert_allclose(line.project(10.0 * unit).station, 10.0 * a, rtol=1e-4)


def test_curvature_of_a_circle_is_one_over_r() -> None:
    """Every vertex of a regular polygon lies on its circle: Menger gives 1/R exactly
    (to the rounding of the vertices, 1e-11), + counter-clockwise, - clockwise; an
    open arc's ends repeat their neighbours'."""
    assert_allclose(circle(10.0).curvature(), 0.1, rtol=1e-11)
    assert_allclose(circle(10.0, clockwise=True).curvature(), -0.1, rtol=1e-11)
    assert_allclose(circle(4.0, n=7).curvature(), 0.25, rtol=1e-11)
    arc = Polyline(circle(10.0).points[:40])
    assert_allclose(arc.curvature(), 0.1, rtol=1e-11)


def test_curvature_of_the_square_and_of_degenerate_lines() -> None:
    """A corner of the 2 m square with its neighbours lies on the circle of R = sqrt(2)
    through three corners; a straight has none; fewer than 3 points, or a repeated
    point, give 0."""
    assert_allclose(Polyline(SQUARE, True).curvature(), 1.0 / math.sqrt(2.0), rtol=1e-15)
    assert_allclose(Polyline(SQUARE, False).curvature(), 1.0 / math.sqrt(2.0), rtol=1e-15)
    straight = Polyline(np.column_stack([np.arange(5.0), np.zeros(5)]))
    assert straight.curvature().tolist() == [0.0] * 5
    assert Polyline(SQUARE[:2]).curvature().tolist() == [0.0, 0.0]
    assert Polyline(SQUARE[:2], True).curvature().tolist() == [0.0, 0.0]
    repeated = Polyline(np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 0.0], [1.0, 1.0]]))
    assert repeated.curvature().tolist() == [0.0] * 4


def test_tangents_by_central_differences() -> None:
    """At the square's corners the tangent bisects the two sides; an open end is one-sided."""
    h = 1.0 / math.sqrt(2.0)
    assert_allclose(Polyline(SQUARE, True).tangents(), [[h, -h], [h, h], [-h, h], [-h, -h]])
    assert_allclose(Polyline(SQUARE, False).tangents()[[0, -1]], [[1, 0], [-1, 0]])


def test_crossings_and_signed_area() -> None:
    """A bow tie crosses itself once (segments 0 and 2); the square does not, but
    crosses itself shifted by (0.5, 0.5) twice; counter-clockwise area +4 m^2."""
    bow = Polyline(np.array([[0.0, 0.0], [2.0, 2.0], [2.0, 0.0], [0.0, 2.0]]), True)
    square = Polyline(SQUARE, True)
    assert bow.crossings() == [(0, 2)]
    assert square.crossings() == []
    assert square.crossings(Polyline(SQUARE + 0.5, True)) == [(1, 0), (2, 3)]
    assert square.signed_area() == 4.0
    assert Polyline(SQUARE[::-1], True).signed_area() == -4.0


def test_projection_select_keeps_rows() -> None:
    """``select`` picks the same rows of every array."""
    proj = Polyline(SQUARE, True).project([[1.0, 0.5], [3.0, -1.0], [-0.5, 1.0]])
    picked = proj.select(np.array([2, 0]))
    assert picked.segment.tolist() == [3, 0]
    assert_array_equal(picked.station, proj.station[[2, 0]])
    assert_array_equal(picked.lateral, proj.lateral[[2, 0]])


def test_side_at_an_acute_vertex_is_the_vertex_own() -> None:
    """A spike (0, 0) -> (0.3, 0.5) -> (0.6, 0) on a line along +x: (1.4, 1.66) is
    nearest the tip, 1.66 m above the line and 0.5 + 1.16 m above the tip, so on
    its left; left of the second segment, right of the first one's direction
    (cross((0.3, 0.5), (1.1, 1.16)) = -0.2): the vertex decides, not the segment
    a tie picks. A point on the right of both stays right."""
    line = Polyline(np.array([[-5.0, 0.0], [0.0, 0.0], [0.3, 0.5], [0.6, 0.0], [5.0, 0.0]]))
    proj = line.project(np.array([[1.4, 1.66], [0.3, 0.2]]))
    assert proj.lateral[0] == pytest.approx(np.hypot(1.1, 1.16))
    assert proj.lateral[1] < 0.0  # below the tip, inside the spike's notch
