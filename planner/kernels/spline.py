"""Step 5: the fitted B-spline sampled along its length (``spline.spline_through``).

scipy's interval search and de Boor evaluation, written out as scipy runs
them, and the path: the spline at even parameters, their arc length, and
the spline again at even stations along it.
"""

from __future__ import annotations

import math

import numpy as np

from conesim.core.compiled import cached_njit


def _probe() -> None:
    """Nothing: what ``cached_njit`` asks numba to cache, from this file's directory."""


# Cached beside this file (or under NUMBA_CACHE_DIR); with no writable cache
# directory, compiled in every process (a cold compile: see the package docstring).
_compiled = cached_njit(_probe, "conesim.planner.kernels.spline")


@_compiled
def _find_interval(t, k, x, prev):
    """scipy's ``_find_interval`` (extrapolating): l with t[l] <= x < t[l + 1], k <= l < n."""
    n = len(t) - k - 1
    if math.isnan(x):
        return -1
    l = prev if k < prev < n else k  # noqa: E741 (scipy's name)
    while x < t[l] and l != k:
        l -= 1  # noqa: E741
    l += 1  # noqa: E741
    while x >= t[l] and l != n:
        l += 1  # noqa: E741
    return l - 1


@_compiled
def _spline_at(t, c, k, x, out, row, prev, work):  # noqa: PLR0917
    """``out[row]`` = the B-spline (t, c (n, 2), k) at x, as ``BSpline.__call__`` computes it.

    scipy's ``evaluate_spline``: the interval, de Boor's recursion for the
    k + 1 non-zero basis functions (``_deBoor_D``, no derivative), then each
    coordinate summed from 0.0 in basis order. Returns the interval (the
    next search's start).
    """
    ell = _find_interval(t, k, x, prev)
    if ell < 0:
        out[row, 0] = math.nan
        out[row, 1] = math.nan
        return prev
    work[0] = 1.0
    for j in range(1, k + 1):
        for q in range(j):
            work[k + 1 + q] = work[q]
        work[0] = 0.0
        for q in range(1, j + 1):
            xb = t[ell + q]
            xa = t[ell + q - j]
            if xb == xa:
                work[q] = 0.0
                continue
            w = work[k + 1 + q - 1] / (xb - xa)
            work[q - 1] += w * (xb - x)
            work[q] = w * (x - xa)
    for d in range(2):
        total = 0.0
        for a in range(k + 1):
            total = total + c[ell + a - k, d] * work[a]
        out[row, d] = total
    return ell


@_compiled
def spline_path(t, c, k, count, spacing):
    """``spline.spline_through`` after the fit: points every ``spacing`` along the spline.

    The spline at ``count`` parameters ``i / (count - 1)`` (the last exactly
    1), the arc length of that polyline (``arc_length``), the stations
    ``numpy.arange(0, length, spacing)`` plus the end when more than 1e-9
    beyond, their parameters by ``numpy.interp`` and the spline there. Each
    step as numpy and scipy compute it. An empty result when a point is not
    finite.
    """
    work = np.empty(2 * k + 2)
    samples = np.empty((count, 2))
    inv = 1.0 / (count - 1)
    u = np.empty(count)
    prev = k
    for i in range(count):
        u[i] = i * inv
    u[count - 1] = 1.0
    for i in range(count):
        prev = _spline_at(t, c, k, u[i], samples, i, prev, work)
    s = np.zeros(count)
    total = 0.0
    for i in range(1, count):
        total += np.hypot(samples[i, 0] - samples[i - 1, 0], samples[i, 1] - samples[i - 1, 1])
        s[i] = total
    end = s[count - 1]
    if not (math.isfinite(end) and end > 0.0):  # numpy.arange fails: no path
        return np.zeros((0, 2))
    m = math.ceil(end / spacing)  # len(numpy.arange(0.0, end, spacing))
    extra = 1 if end - (m - 1) * spacing > 1e-9 else 0
    stations = np.empty(m + extra)
    for i in range(m):
        stations[i] = i * spacing
    if extra:
        stations[m] = end
    path = np.empty((len(stations), 2))
    j = 0
    prev = k
    for i in range(len(stations)):
        x = stations[i]
        # numpy.interp(x, s, u): s is non-decreasing, x within [0, end]
        if x > s[count - 1]:
            ux = u[count - 1]
        elif x < s[0]:
            ux = u[0]
        else:
            while j + 1 < count and s[j + 1] <= x:
                j += 1
            while j > 0 and s[j] > x:
                j -= 1
            if j == count - 1 or s[j] == x:
                ux = u[j]
            else:
                slope = (u[j + 1] - u[j]) / (s[j + 1] - s[j])
                ux = slope * (x - s[j]) + u[j]
                if math.isnan(ux):
                    ux = slope * (x - s[j + 1]) + u[j + 1]
                    if math.isnan(ux) and u[j] == u[j + 1]:
                        ux = u[j]
        prev = _spline_at(t, c, k, ux, path, i, prev, work)
        if not (math.isfinite(path[i, 0]) and math.isfinite(path[i, 1])):
            return np.zeros((0, 2))
    return path
