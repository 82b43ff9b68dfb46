"""The midpoints' ordering (``planner.kernels.ordering``) is the numpy code's choice."""

from __future__ import annotations

import numpy as np

from conesim.planner import MidlineConfig, kernels
from conesim.planner.geometry import StationAxis
from tests.planner.kernels.geometry_reference import axis_difference


def test_start_index_is_the_masked_argmin() -> None:
    """The nearest midpoint in front within the station window, first of equals."""
    rng = np.random.default_rng(24)
    config = MidlineConfig()
    for trial in range(300):
        m = int(rng.integers(0, 30))
        mid = rng.integers(-4, 20, (m, 2)) * 0.5 if trial % 2 else rng.normal(5.0, 6.0, (m, 2))
        axis = StationAxis(50.0, closed=trial % 3 == 0)
        station = mid[:, 0] + rng.normal(0.0, 3.0, m) + 45.0
        sensor = 45.0 + rng.normal(0.0, 2.0)
        expected = -1
        if m:
            ahead = axis_difference(axis, station, sensor)
            ok = (
                (mid[:, 0] > config.start_min_x)
                & (ahead >= -config.start_station_back)
                & (ahead <= config.start_station_ahead)
            )
            if ok.any():
                expected = int(np.where(ok, np.hypot(mid[:, 0], mid[:, 1]), np.inf).argmin())
        got = kernels.start_index(
            mid, station, sensor, axis.length, axis.closed, config.ordering_settings
        )
        assert got == expected
