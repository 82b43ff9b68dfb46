"""Step 4: the bridges' midpoints in driving order, from the nearest one in front.

The ROS pipeline sorts the midpoints "starting from the nearest in front of the
vehicle, chaining through nearest neighbours". Two guards keep the chain on
one stretch of track, using each midpoint's station along the global path
(the mean of its cones' stations; ``settings.OrderingSettings`` names the
limits):

- the start (``start_index``) is the nearest midpoint with x >
  ``start_min_x`` whose station is within [-start_station_back,
  +start_station_ahead] of the sensor's; a hairpin's far side, in front of
  the car but a stretch later, is not a start;
- each step (``chain_nearest``) goes to the nearest unvisited midpoint within
  ``max_step`` whose station advances by at most ``max_station_step``,
  regresses by at most ``station_back_tolerance``, and advances by at least
  ``min_step_advance`` times the step's length: the chain never jumps across
  an infield (a large station jump), sideways to a stray midpoint, nor turns
  back. A midpoint closer than ``min_midpoint_spacing`` to the chain's last
  one is merged into it (skipped).

The chain stops when no midpoint qualifies. ``ordered_midpoints`` runs both
on the used bridges. Of equally near midpoints the lowest index wins, the one
a stable ``argsort`` of the step lengths ranks first.
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
    """The index of the nearest midpoint in front of the sensor (first of equals), or -1.

    Args:
        midpoints: (k, 2) midpoints in ``os_sensor`` [m].
        station: (k,) their stations [m].
        sensor_station: the sensor's station [m].
        length: the station axis' length [m].
        closed: whether stations wrap.
        ordering: a ``settings.OrderingSettings`` (the start's fields).
    """
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
    """(m,) indices of the nearest-neighbour chain from index ``first``, m >= 1.

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
    """The used bridges' midpoints (m, 2) [m] in driving order; (0, 2) with none in front.

    ``used`` (k,) selects among ``midpoints`` (k, 2) and ``station`` (k,);
    then ``start_index`` and ``chain_nearest``.
    """
    rows = true_rows(used)
    mid = midpoints[rows]
    st = station[rows]
    first = start_index(mid, st, sensor_station, length, closed, ordering)
    if first < 0:
        return np.zeros((0, 2))
    order = chain_nearest(mid, st, first, length, closed, ordering)
    return mid[order]
