"""The true centreline between two ordered boundaries.

Steps (``centreline_between``):

1. ``boundary_curves``: an interpolating cubic spline through each boundary's
   cones (periodic for a loop), sampled every 2 cm. Splines, not the straight
   lines between cones: on a 20 m radius with cones 3 m apart the chords sag
   5 cm inside the arc.
2. ``midpoints``: from every 10 cm of the left curve, the midpoint to the
   nearest point of the right curve, and the same from right to left (both
   directions, so that neither boundary's corners dominate). On concentric
   arcs the nearest point is radial, so the midpoints are exact.
3. ``order_midpoints``: sort them by the mean of their normalised progress
   along the two boundaries and average them in 25 cm bins.
4. a smoothing spline (``splprep``, 3 mm RMS) through the bins, sampled every
   2 cm: the dense centreline, in the direction of the left boundary.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
from numpy.typing import NDArray
from scipy.spatial import cKDTree

from conesim.core.polyline import Polyline
from conesim.tracks.errors import TrackGeometryError
from conesim.tracks.spline import spline_curve

FloatArray = NDArray[np.float64]

DENSE_STEP = 0.02  # [m] spacing of the dense boundary and centreline curves
SOURCE_EVERY = 5  # midpoints from every 5th dense sample (10 cm)
BIN_LENGTH = 0.25  # [m] midpoints are averaged over this much of the track
MIDLINE_SIGMA = 0.001  # [m] RMS tolerance of the centreline smoothing spline


@dataclass(frozen=True)
class Midline:
    """A dense centreline with the dense boundary curves it was built from.

    Attributes:
        centre: (k, 2) centreline samples ~2 cm apart [m], in the direction
            of the boundaries.
        left: (p, 2) dense spline through the left boundary cones [m].
        right: (q, 2) dense spline through the right boundary cones [m].
        closed: whether the three curves are loops.
    """

    centre: FloatArray
    left: FloatArray
    right: FloatArray
    closed: bool

    @cached_property
    def line(self) -> Polyline:
        """The dense centreline as a polyline."""
        return Polyline(self.centre, self.closed)

    def half_widths(self, points: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Distances from ``points`` (n, 2) to the left and right curves [m]."""
        dl, _ = cKDTree(self.left).query(points)
        dr, _ = cKDTree(self.right).query(points)
        return np.asarray(dl, dtype=float), np.asarray(dr, dtype=float)


def centreline_between(left: FloatArray, right: FloatArray, closed: bool) -> Midline:
    """The centreline between two boundaries ordered in the same direction.

    Args:
        left: (n, 2) left boundary cones in order [m]. For a loop, its first
            cone should lie near the first cone of ``right``.
        right: (m, 2) right boundary cones in the same direction [m].
        closed: whether the boundaries are loops.

    Raises:
        TrackGeometryError: degenerate boundaries.
    """
    left_curve = spline_curve(left, closed, DENSE_STEP)
    right_curve = spline_curve(right, closed, DENSE_STEP)
    points, keys = midpoints(left_curve, right_curve, closed)
    approx_len = 0.5 * (
        Polyline(left_curve, closed).end_station + Polyline(right_curve, closed).end_station
    )
    bins = order_midpoints(points, keys, approx_len)
    if len(bins) < 4:
        raise TrackGeometryError("the boundaries are too short to derive a centreline")
    if not closed:
        bins = extend_to_ends(bins, 0.5 * (left[0] + right[0]), 0.5 * (left[-1] + right[-1]))
    centre = spline_curve(bins, closed, DENSE_STEP, sigma=MIDLINE_SIGMA)
    return Midline(centre=centre, left=left_curve, right=right_curve, closed=closed)


def midpoints(
    left_curve: FloatArray, right_curve: FloatArray, closed: bool
) -> tuple[FloatArray, FloatArray]:
    """Midpoints to the nearest point of the other curve, both ways.

    Returns:
        (k, 2) midpoints [m] and (k,) their progress key in [0, 1): the mean
        of the normalised arc length along each curve of the two end points
        (unwrapped across the seam of a loop).
    """
    prog_l = _progress(left_curve, closed)
    prog_r = _progress(right_curve, closed)
    src_l = np.arange(0, len(left_curve), SOURCE_EVERY)
    src_r = np.arange(0, len(right_curve), SOURCE_EVERY)
    _, near_r = cKDTree(right_curve).query(left_curve[src_l])
    _, near_l = cKDTree(left_curve).query(right_curve[src_r])
    points = np.vstack(
        [
            0.5 * (left_curve[src_l] + right_curve[near_r]),
            0.5 * (right_curve[src_r] + left_curve[near_l]),
        ]
    )
    pl = np.concatenate([prog_l[src_l], prog_l[near_l]])
    pr = np.concatenate([prog_r[near_r], prog_r[src_r]])
    if closed:
        diff = pr - pl
        diff -= np.round(diff)
        keys = np.mod(pl + 0.5 * diff, 1.0)
    else:
        keys = 0.5 * (pl + pr)
    return points, keys


def order_midpoints(points: FloatArray, keys: FloatArray, length: float) -> FloatArray:
    """Midpoints sorted by key and averaged in bins of ~``BIN_LENGTH`` [m].

    Returns:
        (b, 2) bin means [m] in order (empty bins dropped).
    """
    count = max(4, int(np.ceil(length / BIN_LENGTH)))
    index = np.minimum((keys * count).astype(int), count - 1)
    sums = np.zeros((count, 2))
    np.add.at(sums, index, points)
    hits = np.bincount(index, minlength=count)
    filled = hits > 0
    return sums[filled] / hits[filled, None]


def extend_to_ends(bins: FloatArray, start: FloatArray, end: FloatArray) -> FloatArray:
    """An open centreline's bins extended to the middle of the first and last cone pairs.

    Binning trims a few centimetres off each end of a lane; a lane's
    centreline runs from the middle of its first pair of cones to the middle
    of its last. An end is only added if it lies beyond the bins.
    """
    head = bins[1] - bins[0]
    if np.dot(start - bins[0], head) < -1e-3:
        bins = np.vstack([start, bins])
    tail = bins[-1] - bins[-2]
    if np.dot(end - bins[-1], tail) > 1e-3:
        bins = np.vstack([bins, end])
    return bins


def _progress(curve: FloatArray, closed: bool) -> FloatArray:
    cum = Polyline(curve, closed).stations
    total = max(float(cum[-1]), 1e-12)
    return cum[: len(curve)] / total
