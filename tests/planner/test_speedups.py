"""The code written for speed gives the same numbers as the straightforward code.

Each test compares a shortcut of the planner's hot path with the plain
formulation it replaces (kept here as the reference), exactly: same
floating-point operations per element, so the results are bit for bit equal.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from numpy.testing import assert_array_equal
from scipy.interpolate import BSpline, splev, splprep
from scipy.spatial import Delaunay

from conesim.core.messages import Header
from conesim.core.polyline import Polyline
from conesim.core.pose import Pose2D
from conesim.localization.frames import Buffer, TransformStamped
from conesim.planner import MidlineConfig, SpeedProfileConfig, kernels
from conesim.planner.bridges import ConeSet, delaunay_edges
from conesim.planner.classify import LEFT, RIGHT, ClassifiedCones, side_of_path
from conesim.planner.geometry import PathProjector, StationAxis, arc_length, crosses_boundary
from conesim.planner.midline import check_path, cones_to_sensor
from conesim.planner.speed_profile import profile_curvature, speed_profile
from conesim.tracks.global_path import global_path_from_centreline
from tests.planner.kernels.geometry_reference import axis_difference, segments_cross, window_mask


def loop_path(closed: bool = True) -> PathProjector:
    """A wobbly loop (or its open version) of 400 points."""
    s = np.linspace(0.0, 2 * math.pi, 400, endpoint=False)
    xy = np.column_stack([30 * np.cos(s) + 3 * np.cos(7 * s), 20 * np.sin(s)])
    return PathProjector(global_path_from_centreline(xy, closed=closed).polyline)


@pytest.mark.parametrize("closed", [True, False])
@pytest.mark.parametrize("penalty", [0.0, 2.0, math.inf])
@pytest.mark.parametrize("hint", [None, 5.0, 150.0])
def test_project_around_is_the_two_step_projection(
    closed: bool, penalty: float, hint: float | None
) -> None:
    """``project_around`` in one call: the sensor projected alone, then all with the window."""
    projector = loop_path(closed)
    rng = np.random.default_rng(1)
    for _ in range(20):
        points = rng.uniform(-40.0, 40.0, (30, 2))
        centre = hint
        if centre is None and penalty > 0.0:
            centre = float(projector.project(points[-1:]).station[0])
        window = None if centre is None else (centre - 20.0, centre + 35.0)
        expected = projector.project(points, window, penalty)
        got = projector.project_around(points, 20.0, 35.0, penalty, hint)
        for name in ("foot", "segment", "station", "offset", "tangent", "distance"):
            assert_array_equal(getattr(got, name), getattr(expected, name), err_msg=name)


@pytest.mark.parametrize("closed", [True, False])
def test_window_shortcut_is_the_segment_mask(closed: bool) -> None:
    """A window is applied exactly when it overlaps a segment, near the ends and beyond too."""
    projector = loop_path(closed)
    length = projector.length
    rng = np.random.default_rng(10)
    centres = np.concatenate(
        [rng.uniform(-30.0, length + 30.0, 300), [0.0, length, -1e-9, length + 1e-9]]
    )
    for centre in centres:
        for back, ahead in ((20.0, 35.0), (0.0, 0.0), (0.05, 0.05), (0.0, 1e-3), (3.0, 0.0)):
            window = (centre - back, centre + ahead)
            expected = bool(window_mask(projector, *window).any())
            table, half_max = projector._table, projector._half_max
            got = kernels.window_overlaps(*window, table, length, closed, half_max)
            assert got == expected, window


def test_cones_to_sensor_maps_points_and_tangents_in_one_call() -> None:
    """Cones and tangent tips stacked into one transform: the numbers of two calls."""
    buffer = Buffer()
    buffer.set_transform(
        TransformStamped.from_pose2d("reference", "os_sensor", 1.0, Pose2D(3.0, -2.0, 0.7))
    )
    rng = np.random.default_rng(11)
    axis = StationAxis(100.0, False)
    for n in (0, 1, 2, 7, 33, 120):
        tangent = rng.normal(size=(n, 2))
        tangent /= np.hypot(tangent[:, 0], tangent[:, 1])[:, None]
        cones = ClassifiedCones(
            header=Header(1.0, "reference"),
            points=rng.uniform(-40.0, 40.0, (n, 2)),
            side=np.where(rng.random(n) > 0.5, 1, -1).astype(np.int8),
            offset=rng.normal(size=n),
            station=rng.uniform(0.0, 100.0, n),
            tangent=tangent,
            index=np.arange(n),
            by_colour=np.zeros(n, dtype=bool),
            sensor_station=10.0,
            axis=axis,
        )
        got, _ = cones_to_sensor(cones, buffer, 1.0, "os_sensor")
        transform = buffer.lookup_transform("os_sensor", "reference", 1.0)
        points = transform.transform_points(cones.points)
        assert_array_equal(got.points, points)
        assert_array_equal(got.tangent, transform.transform_points(cones.points + tangent) - points)


def test_crossing_test_is_any_segment_crossing() -> None:
    """The straddle prefilter finds exactly the crossings of the full pairwise test."""
    rng = np.random.default_rng(2)
    for trial in range(300):
        path = np.cumsum(rng.normal(0.0, 1.0, (rng.integers(1, 40), 2)), axis=0)
        b0 = rng.uniform(-8.0, 8.0, (rng.integers(0, 30), 2))
        b1 = b0 + rng.normal(0.0, 3.0, b0.shape)
        if trial % 3 == 0 and len(b0) and len(path) > 1:  # touching: ends on the path
            b0[0] = path[1]
        expected = len(path) > 1 and bool(np.any(segments_cross(path[:-1], path[1:], b0, b1)))
        assert crosses_boundary(path, np.stack([b0, b1], axis=1)) == expected


def test_bspline_evaluation_is_splev() -> None:
    """``BSpline.construct_fast`` on splprep's knots gives splev's numbers, bit for bit."""
    rng = np.random.default_rng(3)
    for trial in range(200):
        m = int(rng.integers(4, 30))
        x = np.cumsum(rng.uniform(1.0, 5.0, m))
        y = np.cumsum(rng.normal(0.0, 1.0, m))
        k = min(int(rng.integers(1, 4)), m - 1)
        tck, _ = splprep(np.vstack([x, y]), s=0.0 if trial % 2 else 0.01 * m, k=k)
        u = np.concatenate([np.linspace(0.0, 1.0, 4 * m), rng.uniform(0.0, 1.0, 20)])
        spline = BSpline.construct_fast(tck[0], np.column_stack(tck[1]), tck[2])
        assert_array_equal(spline(u), np.column_stack(splev(u, tck)))


def test_median_is_numpy_median() -> None:
    """``kernels.median``: odd and even counts, repeated values and NaN."""
    rng = np.random.default_rng(4)
    for n in range(1, 40):
        values = np.round(rng.normal(0.0, 2.0, n), 1 if n % 3 else 6)
        assert kernels.median(values) == float(np.median(values))
    assert math.isnan(kernels.median(np.array([1.0, math.nan, 2.0])))


def test_arc_length_small_and_random() -> None:
    """``Polyline.stations`` bit for bit, [0] for no or one point."""
    assert arc_length(np.zeros((0, 2))).tolist() == [0.0]
    assert arc_length(np.ones((1, 2))).tolist() == [0.0]
    points = np.random.default_rng(5).normal(0.0, 3.0, (50, 2))
    assert_array_equal(arc_length(points), Polyline(points).stations)


def test_cone_set_select() -> None:
    """Mask and indices select what fancy indexing does, in the same dtypes."""
    rng = np.random.default_rng(6)
    n = 12
    cones = ConeSet(
        points=rng.normal(size=(n, 2)),
        side=np.where(rng.random(n) > 0.5, 1, -1).astype(np.int8),
        offset=rng.normal(size=n),
        station=rng.uniform(0.0, 50.0, n),
        tangent=rng.normal(size=(n, 2)),
        virtual=rng.random(n) > 0.7,
        axis=StationAxis(100.0, False),
    )
    mask = rng.random(n) > 0.4
    for keep in (mask, np.flatnonzero(mask)):
        picked = cones.select(keep)
        for name in ("points", "side", "offset", "station", "tangent", "virtual"):
            assert_array_equal(getattr(picked, name), getattr(cones, name)[keep], err_msg=name)
            assert getattr(picked, name).dtype == getattr(cones, name).dtype


def test_delaunay_edges_in_scipy_neighbour_order() -> None:
    """Each vertex's neighbours j > i, in ``vertex_neighbor_vertices`` order."""
    rng = np.random.default_rng(7)
    angle = np.linspace(0.0, 2.0 * np.pi, 40, endpoint=False)
    fan = np.vstack([[0.0, 0.0], np.column_stack([np.cos(angle), np.sin(angle)])])
    samples = [rng.uniform(0.0, 30.0, (n, 2)) for n in (3, 10, 40)]
    # A vertex with 40 neighbours above it: the lists' capacity grows (three times: 8, 16, 32, 64).
    for points in [*samples, fan + rng.normal(0.0, 1e-3, fan.shape)]:
        n = len(points)
        indptr, indices = Delaunay(points).vertex_neighbor_vertices
        rows = np.repeat(np.arange(n), np.diff(indptr))
        keep = rows < indices
        expected = np.column_stack([rows[keep], indices[keep]]).astype(np.intp)
        got = delaunay_edges(points)
        assert got.dtype == np.intp
        assert_array_equal(got, expected)


def reference_chain(
    midpoints: np.ndarray, station: np.ndarray, first: int, axis: StationAxis, config: MidlineConfig
) -> list[int]:
    """The ordering walk as first written: full rows as lists, a generator per step."""
    x, y = midpoints[:, 0], midpoints[:, 1]
    dist = np.hypot(np.subtract.outer(x, x), np.subtract.outer(y, y))
    advance = axis_difference(axis, station[None, :], station[:, None])
    step = np.where(
        (dist <= config.max_step)
        & (advance <= config.max_station_step)
        & (advance >= -config.station_back_tolerance)
        & (advance >= config.min_step_advance * dist),
        dist,
        np.inf,
    )
    ranked = np.argsort(step, axis=1, kind="stable").tolist()
    allowed = np.isfinite(step).sum(axis=1).tolist()
    candidates = [row[:count] for row, count in zip(ranked, allowed, strict=True)]
    lengths = step.tolist()
    visited = [False] * len(midpoints)
    visited[first] = True
    order, current = [first], first
    while True:
        nxt = next((j for j in candidates[current] if not visited[j]), None)
        if nxt is None:
            return order
        visited[nxt] = True
        if lengths[current][nxt] < config.min_midpoint_spacing:
            continue
        order.append(nxt)
        current = nxt


def test_chain_nearest_is_the_reference_walk() -> None:
    """Dense, sparse, tied (on a grid) and wrapped midpoints."""
    rng = np.random.default_rng(8)
    config = MidlineConfig()
    for trial in range(200):
        m = int(rng.integers(1, 60))
        if trial % 4 == 0:  # on a 0.5 m grid: exact distance ties
            mid = rng.integers(0, 20, (m, 2)) * 0.5
        else:
            mid = np.column_stack([rng.uniform(0.0, 40.0, m), rng.normal(0.0, 1.5, m)])
        axis = StationAxis(60.0, closed=trial % 2 == 0)
        station = mid[:, 0] + rng.normal(0.0, 0.3, m)
        first = int(rng.integers(0, m))
        got = kernels.chain_nearest(
            mid, station, first, axis.length, axis.closed, config.ordering_settings
        ).tolist()
        assert got == reference_chain(mid, station, first, axis, config)


def test_menger_curvature_and_known_arc_length() -> None:
    """The profile's pointwise curvature is ``Polyline.curvature`` bit for bit,
    repeated points included; the profile given its s."""
    rng = np.random.default_rng(9)
    for n in (0, 1, 2, 3, 10, 60):
        points = np.cumsum(rng.normal(0.0, 0.5, (n, 2)), axis=0)
        if n > 4:
            points[3] = points[2]  # a zero step: no curvature there
        pointwise = SpeedProfileConfig(curvature_window=0.0)
        expected = Polyline(points).curvature() if n else np.zeros(0)
        assert_array_equal(profile_curvature(points, pointwise), expected)
        assert_array_equal(speed_profile(points, s=arc_length(points)), speed_profile(points))


def test_check_path_with_known_length() -> None:
    """Passing the path's length changes nothing."""
    config = MidlineConfig()
    path = np.column_stack([np.linspace(0.5, 20.0, 40), np.zeros(40)])
    boundary = np.array([[[5.2, -1.0], [5.2, 1.0]], [[0.0, 1.5], [20.0, 1.5]]])
    for edges in (boundary, boundary[1:], boundary[:0]):
        expected = check_path(path, 10, edges, config)
        assert check_path(path, 10, edges, config, float(arc_length(path)[-1])) == expected
    assert check_path(path, 10, boundary, config) == "path crosses a track boundary"


def test_ground_points_and_sides_are_the_numpy_steps() -> None:
    """``kernels.ground_points``: rows with finite x and y, then the origin;
    ``side_of_path``: ``where(offset > 0, LEFT, RIGHT)`` (NaN and -0.0 are right)."""
    rng = np.random.default_rng(11)
    for n in (0, 1, 5, 40):
        points = rng.uniform(-30.0, 30.0, (n, 3))
        bad = rng.random((n, 3)) < 0.1
        points[bad] = rng.choice([np.nan, np.inf, -np.inf], int(bad.sum()))
        xy = points[:, :2]
        finite = np.isfinite(xy).all(axis=1)
        ground, got_finite = kernels.ground_points(points)
        assert_array_equal(got_finite, finite)
        assert_array_equal(ground, np.concatenate([xy[finite], np.zeros((1, 2))]))
        offset = np.concatenate([points[:, 0], [0.0, -0.0, np.nan]])
        want = np.where(offset > 0.0, np.int8(LEFT), np.int8(RIGHT))
        got = side_of_path(offset)
        assert got.dtype == np.int8
        assert_array_equal(got, want)
