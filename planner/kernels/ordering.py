"""Step 4: the bridges' midpoints in driving order (``ordering``).

The first midpoint (the nearest in front of the sensor), the
nearest-neighbour chain from it, and both for the used bridges in one call.
"""

from __future__ import annotations

import math

import numpy as np

from conesim.core.compiled import cached_njit
from conesim.planner.kernels._common import true_rows, wrapped_difference


def _probe() -> None:
    """Nothing: what ``cached_njit`` asks numba to cache, from this file's directory."""


# Cached beside this file (or under NUMBA_CACHE_DIR); with no writable cache
# directory, compiled in every process (a cold compile: see the package docstring).
_compiled = cached_njit(_probe, "conesim.planner.kernels.ordering")


@_compiled
def start_index(midpoints, station, sensor_station, length, closed, ordering):  # noqa: PLR0917
    """``ordering.start_index``: the nearest midpoint in front (first of equals), or -1."""
    start_min_x = ordering.start_min_x
    start_back = ordering.start_station_back
    start_ahead = ordering.start_station_ahead
    first = -1
    best = math.inf
    for i in range(len(station)):
        ahead = wrapped_difference(station[i] - sensor_station, length, closed)
        x = midpoints[i, 0]
        if x > start_min_x and ahead >= -start_back and ahead <= start_ahead:
            h = np.hypot(x, midpoints[i, 1])
            if first < 0 or h < best or (math.isnan(h) and not math.isnan(best)):
                first = i
                best = h
    return first


@_compiled
def chain_nearest(midpoints, station, first, length, closed, ordering):  # noqa: PLR0917
    """``ordering.chain_nearest``: the nearest-neighbour chain from ``first``.

    Each step goes to the nearest unvisited allowed midpoint, the first index
    of equals: the first unvisited one in a stable ``argsort`` of the row.
    The station advance is tested first: a midpoint it rules out needs no
    distance (the same choice, fewer ``np.hypot``).
    """
    max_step = ordering.max_step
    max_station_step = ordering.max_station_step
    back_tolerance = ordering.station_back_tolerance
    min_advance = ordering.min_step_advance
    min_spacing = ordering.min_midpoint_spacing
    m = len(station)
    visited = np.zeros(m, np.bool_)
    visited[first] = True
    order = np.empty(m, np.intp)
    order[0] = first
    count = 1
    current = first
    while True:
        nxt = -1
        step = math.inf
        cx = midpoints[current, 0]
        cy = midpoints[current, 1]
        for j in range(m):
            if visited[j]:
                continue
            advance = wrapped_difference(station[j] - station[current], length, closed)
            if not (advance <= max_station_step and advance >= -back_tolerance):
                continue  # not allowed whatever the distance: skip the hypot
            d = np.hypot(cx - midpoints[j, 0], cy - midpoints[j, 1])
            if (
                d <= max_step
                and advance >= min_advance * d
                and d < math.inf
                and (nxt < 0 or d < step)
            ):
                nxt = j
                step = d
        if nxt < 0:
            break
        visited[nxt] = True
        if step < min_spacing:
            continue
        current = nxt
        order[count] = current
        count += 1
    return order[:count]


@_compiled
def ordered_midpoints(used, midpoints, station, sensor_station, length, closed, ordering):  # noqa: PLR0917
    """``ordering.ordered_midpoints``: the used bridges' midpoints in driving order."""
    rows = true_rows(used)
    mid = midpoints[rows]
    st = station[rows]
    first = start_index(mid, st, sensor_station, length, closed, ordering)
    if first < 0:
        return np.zeros((0, 2))
    order = chain_nearest(mid, st, first, length, closed, ordering)
    return mid[order]
