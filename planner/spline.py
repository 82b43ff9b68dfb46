"""The path through the ordered midpoints: a B-spline, resampled by arc length.

``fit_path`` fits scipy's parametric B-spline (``splprep``, chord-length
parameter, degree ``spline_degree``, smoothing ``s = m * spline_sigma^2``)
through m ordered midpoints, then places points every ``spacing`` of arc
length (spec 000: 0.5 m) on it: the spline is sampled every ``spacing / 2``, the
arc length of that polyline gives the parameter of each output point
(``numpy.interp``), and the spline is evaluated there. The points lie on the
spline; their spacing is off by the polyline's chord error, relative
``(h kappa)^2 / 24``, 1e-3 at h = 0.25 m and R = 3 m. With fewer than
``min_spline_points`` midpoints, or when ``splprep`` fails or warns (FITPACK's
``ier > 0``, read from ``full_output`` rather than by turning warnings into
errors), the midpoints are joined by straight lines instead (the ROS pipeline's
fallback).

Written for speed: after ``splprep``, the sampling, its arc length, the
stations, ``numpy.interp`` and the second evaluation run in one compiled
loop (``planner.kernels.spline_path``), which evaluates the spline the way
scipy's ``BSpline`` and ``splev`` do (interval search, de Boor's recursion
for the basis, the sum in basis order) and interpolates the way
``numpy.interp`` does: the same numbers, checked bit for bit against
``splev`` and against the numpy steps by tests. A path whose length is not
a positive finite number has no spline path (numpy's ``arange`` would fail).
"""

from __future__ import annotations

import numpy as np
from scipy.interpolate import splprep

from conesim.core.polyline import Polyline
from conesim.planner import kernels
from conesim.planner.config import MidlineConfig
from conesim.planner.geometry import FloatArray, arc_length

_SAMPLES_PER_STEP = 2  # spline samples per output step, for the arc length


def spline_through(
    points: FloatArray, config: MidlineConfig, length: float | None = None
) -> FloatArray | None:
    """Points (p, 2) every ``spacing`` along the B-spline through (m, 2) points, or None.

    ``length`` is the points' polyline length [m] if known (``arc_length(points)[-1]``).
    """
    m = len(points)
    degree = min(config.spline_degree, m - 1)
    if length is None:
        length = float(arc_length(points)[-1])
    count = max(int(length * _SAMPLES_PER_STEP / config.spacing) + 2, 2 * m)
    try:
        # full_output: FITPACK's flag instead of a warning (ier 1-3) or an
        # exception (ier > 3); ier <= 0 is a sound fit.
        ((knots, coefficients, k), _), _, ier, _ = splprep(
            points.T, s=m * config.spline_sigma**2, k=degree, full_output=True
        )
    except (ValueError, TypeError):
        return None
    if ier > 0:
        return None
    path: FloatArray = kernels.spline_path(
        np.ascontiguousarray(knots, dtype=float),
        np.column_stack(coefficients).astype(float, copy=False),
        int(k),
        count,
        float(config.spacing),
    )
    return path if len(path) else None


def fit_path(
    midpoints: FloatArray, config: MidlineConfig, length: float | None = None
) -> FloatArray:
    """The local path (p, 2) [m]: spline (or polyline) through midpoints, every ``spacing``.

    Args:
        midpoints: (m, 2) ordered midpoints [m]; duplicates must be merged.
        config: spline and spacing settings.
        length: the midpoints' polyline length [m] if known.

    Returns:
        Points every ``config.spacing`` of arc length from the first midpoint,
        the last one at the end; ``midpoints`` unchanged when m < 2.
    """
    if len(midpoints) < 2:
        return np.array(midpoints, dtype=float).reshape(-1, 2)
    if len(midpoints) >= config.min_spline_points:
        path = spline_through(midpoints, config, length)
        if path is not None:
            return path
    return np.array(Polyline(midpoints).sample_every(config.spacing).points)
