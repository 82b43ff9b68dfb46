"""Step 2 and the virtual partners (``planner.kernels.track``, ``partners``) give
the numpy code's numbers, bit for bit."""

from __future__ import annotations

import numpy as np
import pytest
from numpy.testing import assert_array_equal

from conesim.planner import MidlineConfig
from conesim.planner.bridges import (
    estimate_track,
    pair_table,
    virtual_partners,
)
from conesim.planner.midline import boundary_cones, in_view
from tests.planner.kernels.helpers import (
    random_cones,
    ref_boundary_offset,
    ref_pairs,
    ref_track,
)


@pytest.mark.parametrize("closed", [True, False])
def test_boundary_cones_pairs_track_and_partners(closed: bool) -> None:
    """In view, pair table (on the same stretch), track estimate, boundary filter, partners."""
    rng = np.random.default_rng(22)
    config = MidlineConfig()
    for trial in range(150):
        cones = random_cones(rng, int(rng.integers(0, 60)), closed, grid=trial % 3 == 0)
        keep = (
            (cones.points[:, 0] >= config.min_x)
            & (np.hypot(cones.points[:, 0], cones.points[:, 1]) <= config.max_range)
            & (np.abs(cones.offset) >= config.min_boundary_offset)
            & (np.abs(cones.offset) <= config.max_boundary_offset)
        )
        assert_array_equal(in_view(cones, config), keep)
        real = cones.select(keep)
        track = ref_track(real, config)
        assert estimate_track(pair_table(real, config), config) == track
        if track.measured:
            real = real.select(ref_boundary_offset(track, real) >= -config.boundary_tolerance)
        got, pairs, got_track, dropped = boundary_cones(cones, config)
        assert got_track == track
        assert dropped == len(cones) - len(real)
        assert_array_equal(got.points, real.points)
        left, right, dist, same, span, middle = ref_pairs(real, config)
        for name, value in zip(
            ("left", "right", "same_stretch", "span", "middle"),
            (left, right, same, span, middle),
            strict=True,
        ):
            assert_array_equal(getattr(pairs, name), value, err_msg=name)
        assert_array_equal(pairs.dist[same], dist[same])
        assert np.isinf(pairs.dist[~same]).all()
        # Virtual partners: nobody across within the radius, on the boundary line.
        close = same & (dist <= config.partner_radius)
        near = np.zeros(len(real), dtype=bool)
        near[left] = close.any(axis=1)
        near[right] = close.any(axis=0)
        outside = ref_boundary_offset(track, real)
        need = ~near & (np.abs(outside) <= config.partner_offset_tolerance)
        partners = virtual_partners(got, pairs, config, track)
        assert_array_equal(partners.station, real.station[need])
