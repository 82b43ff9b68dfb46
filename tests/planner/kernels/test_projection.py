"""The projection onto the global path (``planner.kernels.projection``) is the
exhaustive numpy search, bit for bit."""

from __future__ import annotations

import math

import numpy as np
import pytest
from numpy.testing import assert_array_equal

from conesim.planner import geometry, kernels
from conesim.planner.geometry import PathProjector, Projection
from tests.planner.kernels.geometry_reference import axis_difference
from tests.planner.kernels.helpers import loop_projector


def ref_projection(
    projector: PathProjector, points: np.ndarray, prefer: tuple[float, float, float] | None
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Every segment measured with numpy; least score, then nearest midpoint, then index."""
    table = projector._table
    rx = points[:, 0, None] - table[:, 0]
    ry = points[:, 1, None] - table[:, 1]
    dx, dy = table[:, 2], table[:, 3]
    t = (rx * dx + ry * dy) * table[:, 4]
    np.maximum(t, 0.0, out=t)
    np.minimum(t, 1.0, out=t)
    gx, gy = rx - t * dx, ry - t * dy
    d2 = gx * gx + gy * gy
    score = d2
    if prefer is not None:
        centre, half, penalty = prefer
        away = np.abs(axis_difference(projector.axis, table[:, 5], centre))
        score = np.sqrt(d2) + np.where(away <= half + table[:, 6], 0.0, penalty)
    mx = points[:, 0, None] - (table[:, 0] + 0.5 * dx)
    my = points[:, 1, None] - (table[:, 1] + 0.5 * dy)
    mid2 = mx * mx + my * my
    seg = np.array(
        [np.lexsort((np.arange(len(table)), mid2[i], score[i]))[0] for i in range(len(points))],
        dtype=np.intp,
    )
    rows = np.arange(len(points))
    return seg, t[rows, seg], d2[rows, seg]


def searched(
    projector: PathProjector, points: np.ndarray, prefer: tuple[float, float, float] | None
) -> Projection:
    """The kernels' search and projection with the window ``prefer`` (centre, half width,
    penalty) [m], None for none, as ``kernel_chains.project_window`` calls them."""
    centre, half, penalty = (0.0, 0.0, 0.0) if prefer is None else prefer
    table = projector._table
    seg, t, d2 = kernels.nearest_segments(
        points, table, projector._blocks, geometry._BLOCK, prefer is not None, centre, half,
        penalty, projector.length, projector.closed,
    )  # fmt: skip
    foot, station, offset, tangent, distance = kernels.project_rows(points, seg, t, d2, table)
    return Projection(foot, seg, station, offset, tangent, distance)


@pytest.mark.parametrize("closed", [True, False])
@pytest.mark.parametrize("grid", [False, True])
@pytest.mark.parametrize("prefer", [None, (5.0, 27.5, 2.0), (150.0, 27.5, math.inf), (0, 3, 0.5)])
def test_nearest_segments_is_the_exhaustive_search(
    closed: bool, grid: bool, prefer: tuple[float, float, float] | None
) -> None:
    """Least score over every segment; ties to the nearer midpoint, then the lower index."""
    projector = loop_projector(closed, grid)
    rng = np.random.default_rng(20)
    for _ in range(10):
        points = rng.uniform(-45.0, 45.0, (60, 2))
        if grid:
            points = np.round(points * 2.0) / 2.0
        got = searched(projector, np.ascontiguousarray(points), prefer)
        seg, t, d2 = ref_projection(projector, points, prefer)
        assert_array_equal(got.segment, seg)
        assert_array_equal(got.distance, np.sqrt(d2))
        table = projector._table.take(seg, axis=0)
        assert_array_equal(got.station, table[:, 8] + t * table[:, 7])
        assert_array_equal(got.foot, table[:, 0:2] + t[:, None] * table[:, 2:4])
