"""Projection onto the global path, station arithmetic, segment crossings, resampling."""

from __future__ import annotations

import math

import numpy as np
from numpy.testing import assert_allclose

from conesim.planner.geometry import PathProjector, crosses_boundary
from conesim.tracks.global_path import global_path_from_centreline
from tests.planner.kernels.geometry_reference import axis_difference, window_mask


def brute_force(points: np.ndarray, xy: np.ndarray, closed: bool, allowed=None) -> np.ndarray:
    """Distance to the nearest (allowed) segment, testing every segment."""
    ring = np.vstack([xy, xy[:1]]) if closed else xy
    a, d = ring[:-1], np.diff(ring, axis=0)
    if allowed is not None:
        a, d = a[allowed], d[allowed]
    rel = points[:, None, :] - a[None]
    t = np.clip(np.einsum("mki,ki->mk", rel, d) / np.einsum("ki,ki->k", d, d), 0.0, 1.0)
    gap = rel - t[..., None] * d[None]
    return np.sqrt(np.min(np.einsum("mki,mki->mk", gap, gap), axis=1))


def test_seed_projection_on_one_segment() -> None:
    """The ROS pipeline's rule on (0,0)->(10,0): foot, station, signed offset, side, 1e-8 m."""
    path = global_path_from_centreline([[0.0, 0.0], [10.0, 0.0]], closed=False)
    proj = PathProjector(path.polyline).project(np.array([[4.0, 2.0], [4.0, -1.0], [12.0, 1.0]]))
    assert_allclose(proj.foot, [[4.0, 0.0], [4.0, 0.0], [10.0, 0.0]], atol=1e-8)
    assert_allclose(proj.station, [4.0, 4.0, 10.0], atol=1e-8)
    # + left; beyond the end the offset is still the distance from the segment's line.
    assert_allclose(proj.offset, [2.0, -1.0, 1.0], atol=1e-8)
    assert_allclose(proj.distance, [2.0, 1.0, math.hypot(2.0, 1.0)], atol=1e-8)
    assert_allclose(proj.tangent, [[1.0, 0.0]] * 3, atol=1e-12)


def test_projection_is_the_exact_nearest_segment() -> None:
    """The bounded search finds the same nearest distance as testing every segment."""
    rng = np.random.default_rng(0)
    s = np.linspace(0.0, 2 * math.pi, 400, endpoint=False)
    xy = np.column_stack([30 * np.cos(s) + 3 * np.cos(7 * s), 20 * np.sin(s)])
    path = global_path_from_centreline(xy, closed=True)
    projector = PathProjector(path.polyline)
    points = xy[rng.integers(0, 400, 300)] + rng.normal(0.0, 4.0, (300, 2))
    proj = projector.project(points)
    assert_allclose(proj.distance, brute_force(points, path.xy, True), atol=1e-9)
    assert_allclose(np.hypot(*(points - proj.foot).T), proj.distance, atol=1e-9)


def test_windowed_projection_is_the_nearest_segment_in_the_window() -> None:
    """With a station window, the nearest allowed segment, exactly; stations stay inside."""
    rng = np.random.default_rng(0)
    s = np.linspace(0.0, 2 * math.pi, 400, endpoint=False)
    xy = np.column_stack([30 * np.cos(s), 20 * np.sin(s)])
    path = global_path_from_centreline(xy, closed=True)
    projector = PathProjector(path.polyline)
    points = rng.uniform(-35.0, 35.0, (200, 2))
    lo, hi = projector.length - 20.0, projector.length + 30.0  # wraps past the start
    allowed = window_mask(projector, lo, hi)
    proj = projector.project(points, (lo, hi))
    assert_allclose(proj.distance, brute_force(points, path.xy, True, allowed), atol=1e-9)
    ahead = axis_difference(projector.axis, proj.station, 0.5 * (lo + hi))
    longest = float(np.max(path.polyline.segment_lengths))  # a segment overlapping an edge
    assert np.all(np.abs(ahead) <= 25.0 + longest)


def test_crossing_the_boundary() -> None:
    """Against the segment (0, 2) -> (2, 0): a proper X crosses; touching it at an
    end, running along it and stopping short do not; a polyline crosses when one
    of its steps does; one point, or no segments, never."""
    boundary = np.array([[[0.0, 2.0], [2.0, 0.0]]])
    cases = {
        ((0.0, 0.0), (2.0, 2.0)): True,  # an X through (1, 1)
        ((0.0, 0.0), (2.0, 0.0)): False,  # ends on the segment's end
        ((0.0, 0.0), (1.0, 0.0)): False,  # stops short
        ((0.0, 0.0), (1.0, 1.0)): False,  # ends on the segment
        ((0.5, 1.5), (1.5, 0.5)): False,  # along it (collinear)
        ((0.0, 0.0), (0.5, 0.0), (0.5, 3.0)): True,  # the second step crosses
    }
    for path, expected in cases.items():
        assert crosses_boundary(np.array(path), boundary) is expected, path
    assert not crosses_boundary(np.array([[1.0, 1.0]]), boundary)
    assert not crosses_boundary(np.array([[0.0, 0.0], [2.0, 2.0]]), np.zeros((0, 2, 2)))
