"""Ordering the midpoints: from the nearest one in front of the car, nearest neighbours.

The seed sorts the midpoints "starting from the nearest in front of the
vehicle, chaining through nearest neighbours". Two guards keep the chain on
one stretch of track, using each midpoint's station along the global path
(the mean of its cones' stations):

- the start is the nearest midpoint with x > ``start_min_x`` whose station is
  within [-start_station_back, +start_station_ahead] of the sensor's; a
  hairpin's far side, in front of the car but a stretch later, is not a start;
- each step goes to the nearest unvisited midpoint within ``max_step`` whose
  station advances by at most ``max_station_step``, regresses by at most
  ``station_back_tolerance``, and advances by at least ``min_step_advance``
  times the step's length: the chain never jumps across an infield (a large
  station jump), sideways to a stray midpoint, nor turns back. A midpoint
  closer than ``min_midpoint_spacing`` to the chain's last one is merged into
  it (skipped).

The chain stops when no midpoint qualifies.

Written for speed: the step matrix is built with a few numpy calls and the
walk itself is plain Python over each row's allowed steps, nearest first.
Ranking only the allowed steps (one ``lexsort`` of the flat nonzeros) was
measured faster on its own but slower inside the full planning step, where
every extra numpy routine runs cold: the row ``argsort`` stays.
"""

from __future__ import annotations

import numpy as np

from planner.bridges import Bridges
from planner.config import MidlineConfig
from planner.geometry import FloatArray, IntArray, StationAxis


def start_index(
    midpoints: FloatArray,
    station: FloatArray,
    sensor_station: float,
    axis: StationAxis,
    config: MidlineConfig,
) -> int | None:
    """Index of the nearest midpoint in front of the sensor, or None."""
    if len(midpoints) == 0:
        return None
    ahead = axis.difference(station, sensor_station)
    x = midpoints[:, 0]
    ok = (
        (x > config.start_min_x)
        & (ahead >= -config.start_station_back)
        & (ahead <= config.start_station_ahead)
    )
    if not ok.any():
        return None
    return int(np.where(ok, np.hypot(x, midpoints[:, 1]), np.inf).argmin())


def chain_nearest(
    midpoints: FloatArray,
    station: FloatArray,
    first: int,
    axis: StationAxis,
    config: MidlineConfig,
) -> IntArray:
    """Indices of the chain of nearest neighbours from ``first`` (see module docstring)."""
    x, y = midpoints[:, 0], midpoints[:, 1]
    dist = np.hypot(np.subtract.outer(x, x), np.subtract.outer(y, y))
    advance = axis.difference(station[None, :], station[:, None])
    step = np.where(
        (dist <= config.max_step)
        & (advance <= config.max_station_step)
        & (advance >= -config.station_back_tolerance)
        & (advance >= config.min_step_advance * dist),
        dist,
        np.inf,
    )
    # Each row's allowed steps, nearest first, as Python lists (only as many
    # columns as the longest row allows); the walk itself is plain Python,
    # cheaper than a numpy call per step for the few dozen midpoints in view.
    allowed = np.isfinite(step).sum(axis=1)
    ranked = step.argsort(axis=1, kind="stable")[:, : int(allowed.max())]
    lengths = step[np.arange(len(step))[:, None], ranked].tolist()
    candidates = ranked.tolist()
    counts = allowed.tolist()
    visited = [False] * len(midpoints)
    visited[first] = True
    order = [first]
    current = first
    while True:
        row = candidates[current]
        for k in range(counts[current]):  # the nearest unvisited allowed step
            if not visited[row[k]]:
                break
        else:
            break
        visited[row[k]] = True
        if lengths[current][k] < config.min_midpoint_spacing:
            continue
        current = row[k]
        order.append(current)
    return np.asarray(order, dtype=np.intp)


def order_midpoints(
    midpoints: FloatArray,
    station: FloatArray,
    sensor_station: float,
    axis: StationAxis,
    config: MidlineConfig,
) -> IntArray:
    """The seed's ordering with the station guards: indices into ``midpoints``.

    Args:
        midpoints: (k, 2) bridge midpoints in ``os_sensor`` [m].
        station: (k,) their stations along the global path [m].
        sensor_station: the sensor's station [m].
        axis: the global path's station axis.
        config: the guards.

    Returns:
        (m,) indices, m <= k, empty when no midpoint is in front.
    """
    first = start_index(midpoints, station, sensor_station, axis, config)
    if first is None:
        return np.zeros(0, dtype=np.intp)
    return chain_nearest(midpoints, station, first, axis, config)


def ordered_midpoints(
    bridges: Bridges, sensor_station: float, axis: StationAxis, config: MidlineConfig
) -> FloatArray:
    """The used bridges' midpoints (m, 2) [m], in driving order from the one in front."""
    used = bridges.used.nonzero()[0]
    order = order_midpoints(
        bridges.midpoints.take(used, axis=0), bridges.station[used], sensor_station, axis, config
    )
    return bridges.midpoints.take(used[order], axis=0)
