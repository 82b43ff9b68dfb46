"""The Delaunay edges, bridges and boundary edges (``planner.kernels.bridges``)
are scipy's order and the numpy code's numbers, bit for bit."""

from __future__ import annotations

import numpy as np
import pytest
from numpy.testing import assert_array_equal
from scipy.spatial import Delaunay, QhullError

from conesim.planner import MidlineConfig
from conesim.planner.bridges import (
    ConeSet,
    TrackEstimate,
    boundary_edges,
    delaunay_edges,
    find_bridges,
    pair_table,
    virtual_partners,
)
from tests.planner.kernels.geometry_reference import axis_difference
from tests.planner.kernels.helpers import joined, random_cones, ref_track, station_gap


def ref_bridges(
    cones: ConeSet, edges: np.ndarray, config: MidlineConfig, track: TrackEstimate
) -> tuple[np.ndarray, ...]:
    """``find_bridges`` with numpy."""
    i, j = edges[:, 0], edges[:, 1]
    side_i = cones.side[i]
    across = side_i != cones.side[j]
    i, j = i[across], j[across]
    swap = side_i[across] < 0
    left, right = np.where(swap, j, i), np.where(swap, i, j)
    start = cones.points[left]
    vec = cones.points[right] - start
    length = np.hypot(vec[:, 0], vec[:, 1])
    span = cones.offset[left] - cones.offset[right]
    station = cones.station[left]
    ds = axis_difference(cones.axis, cones.station[right], station)
    valid = (
        (span >= config.min_track_width)
        & (span <= config.max_track_width)
        & (length <= config.max_bridge_length)
        & (np.abs(ds) <= config.max_station_gap)
        & ~(cones.virtual[left] & cones.virtual[right])
    )
    if track.measured:
        valid &= np.abs(span - track.width) <= config.width_tolerance
    used = valid.copy()
    if valid.any():
        best = np.full(len(cones), np.inf)
        np.minimum.at(best, left[valid], length[valid])
        np.minimum.at(best, right[valid], length[valid])
        used = valid & ((length <= best[left]) | (length <= best[right]))
    return left, right, length, valid, used, start + 0.5 * vec, station + 0.5 * ds


@pytest.mark.parametrize("closed", [True, False])
def test_delaunay_bridges_and_boundary_edges(closed: bool) -> None:
    """Edges in scipy's neighbour order; bridges and boundary edges as numpy finds them."""
    rng = np.random.default_rng(23)
    config = MidlineConfig()
    for trial in range(100):
        cones = random_cones(rng, int(rng.integers(3, 90)), closed, grid=trial % 3 == 0)
        if trial % 4 == 0:
            partners = virtual_partners(cones, pair_table(cones, config), config,
                                        ref_track(cones, config))  # fmt: skip
            cones = joined(cones, partners)
        try:
            indptr, indices = Delaunay(cones.points).vertex_neighbor_vertices
        except QhullError:  # degenerate: no triangulation either way
            continue
        rows = np.repeat(np.arange(len(cones)), np.diff(indptr))
        edges = np.column_stack([rows, indices])[rows < indices].astype(np.intp)
        assert_array_equal(delaunay_edges(cones.points), edges)
        track = ref_track(cones, config)
        got = find_bridges(cones, edges, config, track)
        names = ("left", "right", "length", "valid", "used", "midpoints", "station")
        for name, value in zip(names, ref_bridges(cones, edges, config, track), strict=True):
            assert_array_equal(getattr(got, name), value, err_msg=name)
        i, j = edges[:, 0], edges[:, 1]
        along = (
            (cones.side[i] == cones.side[j])
            & (np.abs(cones.offset[i] - cones.offset[j]) < config.min_track_width)
            & (station_gap(cones, i, j) <= config.max_station_gap)
        )
        assert_array_equal(boundary_edges(cones, edges, config), edges[along])
