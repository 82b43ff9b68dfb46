"""Numpy references of the planner's geometry kernels: station wrap, window, crossings.

The formulations the compiled code (``planner.kernels``) was written from,
as they stood: ``tests/planner/kernels/`` and ``tests/planner/test_speedups.py``
compare the kernels with them exactly.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from conesim.planner.geometry import FloatArray, PathProjector, StationAxis


def station_difference(
    s_to: FloatArray | float, s_from: FloatArray | float, length: float, closed: bool
) -> FloatArray:
    """Station difference ``s_to - s_from`` [m], wrapped on a closed path of ``length``.

    >>> float(station_difference(1.0, 99.0, 100.0, True))
    2.0
    >>> float(station_difference(1.0, 99.0, 100.0, False))
    -98.0
    """
    diff = np.subtract(s_to, s_from, dtype=float)
    if closed and length > 0.0:
        diff = (diff + 0.5 * length) % length - 0.5 * length
    return diff


def axis_difference(
    axis: StationAxis, s_to: FloatArray | float, s_from: FloatArray | float
) -> FloatArray:
    """``s_to - s_from`` [m] on ``axis``, wrapped into [-length/2, length/2) when closed."""
    return station_difference(s_to, s_from, axis.length, axis.closed)


def window_mask(projector: PathProjector, lo: float, hi: float) -> NDArray[np.bool_]:
    """(k,) True for the segments overlapping stations [lo, hi] [m] (wrapped if closed).

    A segment whose mid-station lies within the window's half width plus its
    own half length of the window's middle (the segment table's columns 5 and 6).
    """
    table = projector._table
    centre = 0.5 * (lo + hi)
    reach = 0.5 * (hi - lo) + table[:, 6]
    return np.abs(axis_difference(projector.axis, table[:, 5], centre)) <= reach


def _orientation(d: FloatArray, c: FloatArray, r: FloatArray) -> FloatArray:
    """(m, k) cross(d_i, r_j - p_i) = cross(d_i, r_j) - c_i, given c_i = cross(d_i, p_i)."""
    return np.multiply.outer(d[:, 0], r[:, 1]) - np.multiply.outer(d[:, 1], r[:, 0]) - c[:, None]


def segments_cross(
    a0: FloatArray, a1: FloatArray, b0: FloatArray, b1: FloatArray
) -> NDArray[np.bool_]:
    """Whether segments ``a0 a1`` (m, 2) properly cross segments ``b0 b1`` (k, 2).

    Proper crossing: each segment's end points lie strictly on opposite sides
    of the other's line (touching and collinear overlap do not count).

    Returns:
        (m, k) boolean matrix.
    """
    da, db = a1 - a0, b1 - b0
    ca = da[:, 0] * a0[:, 1] - da[:, 1] * a0[:, 0]
    cb = db[:, 0] * b0[:, 1] - db[:, 1] * b0[:, 0]
    b_straddles = _orientation(da, ca, b0) * _orientation(da, ca, b1) < 0.0
    a_straddles = _orientation(db, cb, a0) * _orientation(db, cb, a1) < 0.0
    return b_straddles & a_straddles.T
