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

Written for speed: the start and the walk are compiled loops
(``kernels.start_index``, ``kernels.chain_nearest``) that compute each step's
distance and station advance when the walk looks at it, instead of a step
matrix, a row ``argsort`` and a Python walk. The nearest unvisited allowed
step, lowest index of equals, is the one the stable row ``argsort`` ranked
first (``tests/planner/test_speedups.py`` keeps that walk as the reference).
"""

from __future__ import annotations

import numpy as np

from conesim.planner import kernels
from conesim.planner.bridges import Bridges
from conesim.planner.config import MidlineConfig
from conesim.planner.geometry import FloatArray, IntArray, StationAxis


def start_index(
    midpoints: FloatArray,
    station: FloatArray,
    sensor_station: float,
    axis: StationAxis,
    config: MidlineConfig,
) -> int | None:
    """Index of the nearest midpoint in front of the sensor, or None."""
    first = kernels.start_index(
        midpoints,
        station,
        sensor_station,
        axis.length,
        axis.closed,
        config.ordering_settings,
    )
    return None if first < 0 else int(first)


def chain_nearest(
    midpoints: FloatArray,
    station: FloatArray,
    first: int,
    axis: StationAxis,
    config: MidlineConfig,
) -> IntArray:
    """Indices of the chain of nearest neighbours from ``first`` (see module docstring)."""
    order: IntArray = kernels.chain_nearest(
        midpoints,
        station,
        first,
        axis.length,
        axis.closed,
        config.ordering_settings,
    )
    return order


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
    """The used bridges' midpoints (m, 2) [m], in driving order from the one in front.

    ``order_midpoints`` on the used bridges, in one compiled call.
    """
    ordered: FloatArray = kernels.ordered_midpoints(
        bridges.used,
        bridges.midpoints,
        bridges.station,
        sensor_station,
        axis.length,
        axis.closed,
        config.ordering_settings,
    )
    return ordered
