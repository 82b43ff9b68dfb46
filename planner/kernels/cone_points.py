"""The cones' points around classification (``classify``, ``midline.cones_to_sensor``).

The detections' ground points, each cone's side of the global path from its
offset, and the tangent tips that go through the change of frame with the cones.
"""

from __future__ import annotations

import math

import numpy as np

from conesim.core.compiled import cached_njit


def _probe() -> None:
    """Nothing: what ``cached_njit`` asks numba to cache, from this file's directory."""


# Cached beside this file (or under NUMBA_CACHE_DIR); with no writable cache
# directory, compiled in every process (a cold compile: see the package docstring).
_compiled = cached_njit(_probe, "conesim.planner.kernels.cone_points")


@_compiled
def ground_points(points):
    """``classify``'s ground points: the rows with finite x and y, then the origin.

    Args:
        points: (n, >= 2) detections; x and y are the first two columns.

    Returns:
        (k + 1, 2) the finite rows' x and y followed by (0, 0), and the (n,)
        mask of the finite rows (``numpy.isfinite`` of x and y, both).
    """
    n = len(points)
    finite = np.empty(n, np.bool_)
    k = 0
    for i in range(n):
        finite[i] = math.isfinite(points[i, 0]) and math.isfinite(points[i, 1])
        if finite[i]:
            k += 1
    ground = np.zeros((k + 1, 2))
    k = 0
    for i in range(n):
        if finite[i]:
            ground[k, 0] = points[i, 0]
            ground[k, 1] = points[i, 1]
            k += 1
    return ground, finite


@_compiled
def with_tips(points, tangent):
    """``midline.cones_to_sensor``'s input: (2n, 2) the points, then ``points + tangent``."""
    n = len(points)
    out = np.empty((2 * n, 2))
    for i in range(n):
        out[i, 0] = points[i, 0]
        out[i, 1] = points[i, 1]
        out[n + i, 0] = points[i, 0] + tangent[i, 0]
        out[n + i, 1] = points[i, 1] + tangent[i, 1]
    return out


@_compiled
def side_of_path(offset):
    """``classify.side_of_path``: (n,) int8, +1 where the offset is > 0, else -1."""
    side = np.empty(len(offset), np.int8)
    for i in range(len(offset)):
        side[i] = 1 if offset[i] > 0.0 else -1
    return side
