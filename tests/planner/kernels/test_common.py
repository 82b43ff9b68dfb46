"""The kernels' shared helpers (``planner.kernels._common``): the station wrap."""

from __future__ import annotations

import math

import numpy as np
from numpy.testing import assert_array_equal

from conesim.planner.kernels._common import wrapped_difference
from tests.planner.kernels.geometry_reference import station_difference


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


def test_station_wrap_on_a_closed_path() -> None:
    """On a 100 m loop 99 m -> 1 m is 2 m ahead and 1 m -> 60 m is 41 m behind
    (wrapped into [-50, 50)); on an open path the plain difference."""
    assert wrapped_difference(1.0 - 99.0, 100.0, True) == 2.0
    assert wrapped_difference(60.0 - 99.0, 100.0, True) == -39.0
    assert wrapped_difference(60.0 - 1.0, 100.0, True) == -41.0
    assert wrapped_difference(50.0, 100.0, True) == -50.0
    assert wrapped_difference(1.0 - 99.0, 100.0, False) == -98.0
