"""The kernel chains (``planner.kernel_chains``) give what the steps give one by one, exactly."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from numpy.testing import assert_array_equal

from conesim.planner import MidlineConfig, SpeedProfileConfig, kernel_chains, kernels
from conesim.planner.bridges import (
    ConeSet,
    boundary_edges,
    delaunay_edges,
    delaunay_simplices,
    find_bridges,
    pair_table,
    virtual_partners,
)
from conesim.planner.geometry import arc_length
from conesim.planner.midline import boundary_cones, bridges_and_midpoints, cones_with_partners
from conesim.planner.speed_profile import profile_speeds, speed_profile
from tests.planner.kernels.helpers import joined, random_cones, ref_track


def turned(rng: np.random.Generator, cones: ConeSet) -> ConeSet:
    """The cones with unit tangents up to 0.5 rad off the x axis (partners move diagonally)."""
    angle = rng.uniform(-0.5, 0.5, len(cones))
    tangent = np.column_stack([np.cos(angle), np.sin(angle)])
    return dataclasses.replace(cones, tangent=tangent)


def test_partner_points_are_the_numpy_shift() -> None:
    """``kernels.partner_points``: ``points - side * width * (-t_y, t_x)``, as numpy computes it."""
    rng = np.random.default_rng(40)
    for _ in range(50):
        cones = turned(rng, random_cones(rng, int(rng.integers(1, 40)), closed=False))
        rows = np.flatnonzero(rng.random(len(cones)) < 0.5).astype(np.intp)
        width = float(rng.uniform(2.5, 6.0))
        t, side = cones.tangent[rows], cones.side[rows]
        shift = side[:, None] * width * (t[:, ::-1] * np.array([-1.0, 1.0]))
        points, new_side, offset = kernels.partner_points(
            cones.points, cones.side, cones.offset, cones.tangent, rows, width
        )
        assert_array_equal(points, cones.points[rows] - shift)
        assert_array_equal(new_side, (-side).astype(np.int8))
        assert_array_equal(offset, cones.offset[rows] - side * width)


@pytest.mark.parametrize("closed", [True, False])
def test_chains_are_the_steps(closed: bool) -> None:
    """``cones_with_partners`` and ``bridges_and_midpoints`` against the steps composed."""
    rng = np.random.default_rng(41)
    for trial in range(150):
        cones = turned(rng, random_cones(rng, int(rng.integers(0, 70)), closed, trial % 3 == 0))
        config = MidlineConfig(bridge_selection="all" if trial % 5 == 0 else "shortest")
        real, pairs, track, dropped = boundary_cones(cones, config)
        want = joined(real, virtual_partners(real, pairs, config, track))
        got, got_track, got_dropped = cones_with_partners(cones, config)
        assert (got_track, got_dropped) == (track, dropped)
        for field in ("points", "side", "offset", "station", "tangent", "virtual"):
            assert_array_equal(getattr(got, field), getattr(want, field), err_msg=field)
            assert getattr(got, field).dtype == getattr(want, field).dtype, field

        edges = delaunay_edges(want.points)
        sensor_station = float(rng.uniform(0.0, 10.0))
        bridges, boundary, midpoints, length = bridges_and_midpoints(
            got, delaunay_simplices(got.points), config, track, sensor_station
        )
        want_bridges = find_bridges(want, edges, config, track)
        for field in dataclasses.fields(bridges):
            name = field.name
            assert_array_equal(getattr(bridges, name), getattr(want_bridges, name), err_msg=name)
        assert_array_equal(boundary, want.points[boundary_edges(want, edges, config)])
        want_mid = kernels.ordered_midpoints(
            bridges.used, bridges.midpoints, bridges.station, sensor_station,
            want.axis.length, want.axis.closed, config.ordering_settings,
        )  # fmt: skip
        assert_array_equal(midpoints, want_mid)
        assert length == float(arc_length(want_mid)[-1])


def test_no_cones_in_view() -> None:
    """The chains on an empty view: no cones, nominal track, no bridges."""
    cones = random_cones(np.random.default_rng(42), 0, closed=False)
    got, track, dropped = cones_with_partners(cones, MidlineConfig())
    assert (len(got), track.measured, dropped) == (0, False, 0)
    assert len(pair_table(got, MidlineConfig()).left) == 0
    assert track == ref_track(got, MidlineConfig())


@pytest.mark.parametrize("profile", [True, False])
def test_check_and_limit_is_the_steps(profile: bool) -> None:
    """``kernel_chains.check_and_limit`` and ``profile_speeds``: the arc length, the start
    distance (``np.hypot``, also from 1 mm to 1 km), the crossing test and
    ``speed_profile``'s speeds, for paths that cross the boundary and not."""
    rng = np.random.default_rng(43)
    configs = [
        SpeedProfileConfig(),
        SpeedProfileConfig(friction_ellipse=False, lateral_jerk_max=math.inf),
        SpeedProfileConfig(horizon_stop=False, curvature_window=0.0),
    ]
    for trial in range(60):
        n = int(rng.integers(1, 60))
        path = np.cumsum(rng.normal(0.5, 0.2, (n, 2)), axis=0)
        path[0] *= 10.0 ** rng.uniform(-3.0, 3.0)
        boundary = rng.uniform(-5.0, 30.0, (int(rng.integers(0, 8)), 2, 2))
        config = configs[trial % len(configs)]
        s, length, start, crosses, limits = kernel_chains.check_and_limit(
            path, boundary, profile, config.limit_settings
        )
        assert_array_equal(s, arc_length(path))
        assert length == s[-1]
        assert start == float(np.hypot(path[0, 0], path[0, 1]))
        assert crosses == kernels.crosses_boundary(path, boundary)
        if profile:
            v_start = None if trial % 2 else float(rng.uniform(0.0, 10.0))
            got = profile_speeds(limits, config, v_start)
            assert_array_equal(got, speed_profile(path, config, v_start, s=arc_length(path)))
