"""Polyline geometry of step 6 (``geometry``): arc length and crossing tests.

The running arc length of a polyline, and whether it properly crosses any
of a set of segments (the path against the boundary edges).
"""

from __future__ import annotations

import numpy as np

from conesim.core.compiled import cached_njit


def _probe() -> None:
    """Nothing: what ``cached_njit`` asks numba to cache, from this file's directory."""


# Cached beside this file (or under NUMBA_CACHE_DIR); with no writable cache
# directory, compiled in every process (a cold compile: see the package docstring).
_compiled = cached_njit(_probe, "conesim.planner.kernels.polyline")


@_compiled
def polyline_crosses(points, b0, b1):
    """Whether the polyline (p, 2) properly crosses a segment ``b0 b1`` (k, 2), p >= 1 [m]."""
    p = len(points)
    k = len(b0)
    for c in range(k):
        dbx = b1[c, 0] - b0[c, 0]
        dby = b1[c, 1] - b0[c, 1]
        cb = dbx * b0[c, 1] - dby * b0[c, 0]
        prev = points[0, 1] * dbx - points[0, 0] * dby - cb
        for j in range(p - 1):
            nxt = points[j + 1, 1] * dbx - points[j + 1, 0] * dby - cb
            if prev * nxt < 0.0:
                ax = points[j, 0]
                ay = points[j, 1]
                dax = points[j + 1, 0] - ax
                day = points[j + 1, 1] - ay
                ca = dax * ay - day * ax
                o0 = dax * b0[c, 1] - day * b0[c, 0] - ca
                o1 = dax * b1[c, 1] - day * b1[c, 0] - ca
                if o0 * o1 < 0.0:
                    return True
            prev = nxt
    return False


@_compiled
def arc_length(points):
    """``geometry.arc_length``: 0, then the running sum of the step lengths (``np.hypot``)."""
    n = len(points)
    s = np.zeros(max(n, 1))
    total = 0.0
    for i in range(1, n):
        total += np.hypot(points[i, 0] - points[i - 1, 0], points[i, 1] - points[i - 1, 1])
        s[i] = total
    return s


@_compiled
def crosses_boundary(points, boundary):
    """``geometry.crosses_boundary``: ``polyline_crosses`` against (e, 2, 2) edges [m]."""
    if len(points) < 2 or len(boundary) == 0:
        return False
    return polyline_crosses(points, boundary[:, 0], boundary[:, 1])
