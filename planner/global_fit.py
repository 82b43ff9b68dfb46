"""The global path as the planner reads it: smoothed as much as its own scatter says.

A surveyed global path is not exact (``tracks.survey``): each point has its
own error. The planner reads the path's curvature (``planner.global_speed``:
the speed plan; the lookahead cap), and a point-to-point error of 0.2 m
every 0.5 m reads as a curvature of metres^-1: the speed plan would crawl.
``smoothed_global_path`` fits scipy's smoothing B-spline (``splprep``,
periodic for a loop) with ``s = n sigma^2``, sigma the scatter estimated
from the path itself: the median absolute second difference of its points,
which for a smooth path of curvature kappa sampled every h is h^2 kappa
(0.03 m at h = 0.5 m in R 8 m), and for independent errors of sigma per
axis the median of a Rayleigh variable of scale sqrt(6) sigma:

    sigma = median |p_{i-1} - 2 p_i + p_{i+1}| / (sqrt(6) sqrt(2 ln 2))

A path whose scatter is below ``min_sigma`` is returned as it is.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.interpolate import splev, splprep

from conesim.planner.geometry import FloatArray
from conesim.tracks.global_path import GlobalPath, global_path_from_centreline

_MAD_SCALE = math.sqrt(6.0 * 2.0 * math.log(2.0))  # median |second difference| per sigma


def path_scatter(xy: FloatArray) -> float:
    """The points' own scatter sigma [m] (module docstring), 0 for fewer than 3."""
    if len(xy) < 3:
        return 0.0
    second = xy[:-2] - 2.0 * xy[1:-1] + xy[2:]
    return float(np.median(np.hypot(second[:, 0], second[:, 1]))) / _MAD_SCALE


def smoothed_global_path(path: GlobalPath, min_sigma: float, spacing: float = 0.5) -> GlobalPath:
    """``path`` smoothed by its scatter, resampled about every ``spacing`` [m]; as it is
    when the scatter is below ``min_sigma`` [m] or the fit fails."""
    xy = np.asarray(path.xy, dtype=float)
    sigma = path_scatter(xy)
    if not sigma > min_sigma or len(xy) < 8:
        return path
    pts = np.vstack([xy, xy[:1]]) if path.closed else xy
    try:
        ((knots, coeffs, k), _), _, ier, _ = splprep(
            pts.T, s=len(pts) * sigma**2, k=3, per=int(path.closed), full_output=True
        )
    except (ValueError, TypeError):
        return path
    if ier > 0:
        return path
    length = float(np.sum(np.hypot(*np.diff(pts, axis=0).T)))
    count = max(int(length / spacing), 8)
    u = np.linspace(0.0, 1.0, count, endpoint=not path.closed)
    x, y = splev(u, (knots, coeffs, k))
    cov = float(np.mean(path.cov)) + sigma**2
    return global_path_from_centreline(
        np.column_stack([x, y]), closed=path.closed, origin=path.origin, cov=cov
    )
