"""Cubic B-splines through a track's cones and midpoints, sampled densely.

The points are an (n, 2) array [m]; ``closed`` says whether the last joins
the first (a closed curve never repeats its first point).
"""

from __future__ import annotations

import warnings

import numpy as np
from numpy.typing import NDArray
from scipy.interpolate import splev, splprep

from conesim.core.polyline import Polyline
from conesim.tracks.errors import TrackGeometryError

FloatArray = NDArray[np.float64]

MAX_SAMPLES = 250_000  # a dense curve of more samples (5 km at 2 cm) is not a cone track


def spline_curve(points: FloatArray, closed: bool, step: float, sigma: float = 0.0) -> FloatArray:
    """A cubic B-spline through (or, with ``sigma`` > 0, near) the points, sampled densely.

    Args:
        points: (n, 2) ordered points [m], no two consecutive ones equal.
        closed: fit a periodic spline.
        step: approximate spacing of the returned samples [m].
        sigma: allowed RMS distance of the spline from the points [m]; 0
            interpolates them (``splprep`` smoothing s = n * sigma^2).

    Returns:
        (m, 2) samples along the spline [m] (a closed curve does not repeat
        its first sample).

    Raises:
        TrackGeometryError: too few or degenerate points.
    """
    pts = _drop_repeats(points, closed)
    if len(pts) < 3:
        raise TrackGeometryError(
            f"a boundary or centreline needs at least 3 distinct points, got {len(pts)}"
        )
    line = Polyline(pts, closed)
    data = line.ring
    k = min(3, len(data) - 1)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # fitpack's "maxit reached" is harmless here
            tck, _ = splprep(data.T, s=len(data) * sigma**2, k=k, per=int(closed), quiet=1)
    except (ValueError, TypeError, ArithmeticError) as exc:
        raise TrackGeometryError(f"cannot fit a spline through the points: {exc}") from None
    length = line.end_station
    count = max(8, int(np.ceil(length / step)))
    if count > MAX_SAMPLES:
        raise TrackGeometryError(
            f"a boundary or centreline of {length:.0f} m is too long for a cone track"
        )
    u = np.linspace(0.0, 1.0, count + 1 if closed else count)
    curve = np.column_stack(splev(u, tck))
    if closed:
        curve = curve[:-1]
    if not np.all(np.isfinite(curve)):
        raise TrackGeometryError("spline fit through the points is not finite")
    return curve


def _drop_repeats(points: FloatArray, closed: bool, tol: float = 1e-6) -> FloatArray:
    """Remove points closer than ``tol`` [m] to the previous one."""
    keep = np.ones(len(points), dtype=bool)
    keep[1:] = np.hypot(*np.diff(points, axis=0).T) > tol
    pts = points[keep]
    if closed and len(pts) > 1 and np.hypot(*(pts[-1] - pts[0])) <= tol:
        pts = pts[:-1]
    return pts
