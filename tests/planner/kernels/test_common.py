"""The kernels' shared helpers (``planner.kernels._common``): the station wrap."""

from __future__ import annotations

import math

import numpy as np
from numpy.testing import assert_array_equal

from conesim.planner.geometry import station_difference
from conesim.planner.kernels._common import wrapped_difference


def test_station_wrap_is_numpy_remainder() -> None:
    """The fmod-free wrap gives ``station_difference``'s numbers, edges included."""
    rng = np.random.default_rng(21)
    for length in (60.0, 0.1, 1234.5678, 3.0):
        diff = np.concatenate(
            [
                rng.uniform(-2 * length, 2 * length, 2000),
                [0.0, -0.0, 0.5 * length, -0.5 * length, length, -length, 1.5 * length],
                [2 * length, -2 * length, 1e300, math.nan, math.inf],
            ]
        )
        with np.errstate(invalid="ignore"):  # the NaN and inf rows
            expected = station_difference(diff, 0.0, length, True)
        got = np.array([wrapped_difference(d, length, True) for d in diff])
        assert_array_equal(got, expected)
    assert wrapped_difference(5.0, 0.0, True) == 5.0
