"""Step 2: the boundary cones in view, their pair table and the track estimate.

The cones in view (``midline.in_view``); the table of every left-right pair
(``bridges.pair_table``) and its sub-table for a subset of the cones; the
track's width and centre from each cone's nearest partner across
(``bridges.estimate_track``, with ``median``, ``numpy.median``'s number); each cone's offset from
its boundary line; and all of step 2 in one call (``boundary_cones``).
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
_compiled = cached_njit(_probe, "conesim.planner.kernels.track")


@_compiled
def in_view(points, offset, view):
    """``midline.in_view``: (n,) mask of cones in range and at a boundary's offset.

    ``view`` is a ``settings.ViewSettings``.
    """
    min_x = view.min_x
    max_range = view.max_range
    min_offset = view.min_boundary_offset
    max_offset = view.max_boundary_offset
    n = len(offset)
    keep = np.empty(n, np.bool_)
    for i in range(n):
        x = points[i, 0]
        y = points[i, 1]
        o = abs(offset[i])
        keep[i] = x >= min_x and np.hypot(x, y) <= max_range and o >= min_offset and o <= max_offset
    return keep


@_compiled
def pair_table(  # noqa: PLR0917
    points, side, offset, station, length, closed, max_gap
):
    """``bridges.pair_table``: left, right, dist, same_stretch, span, middle.

    The distance (``np.hypot``, the slow part) only where ``same_stretch``,
    inf elsewhere: every use of it is on the same stretch.
    """
    n = len(side)
    a = 0
    for i in range(n):
        if side[i] > 0:
            a += 1
    b = 0
    for i in range(n):
        if side[i] < 0:
            b += 1
    left = np.empty(a, np.intp)
    right = np.empty(b, np.intp)
    a = 0
    b = 0
    for i in range(n):
        if side[i] > 0:
            left[a] = i
            a += 1
    for i in range(n):
        if side[i] < 0:
            right[b] = i
            b += 1
    dist = np.empty((a, b))
    same = np.empty((a, b), np.bool_)
    span = np.empty((a, b))
    middle = np.empty((a, b))
    for r in range(a):
        li = left[r]
        for c in range(b):
            ri = right[c]
            same[r, c] = (
                abs(wrapped_difference(station[ri] - station[li], length, closed)) <= max_gap
            )
            if same[r, c]:
                dx = points[li, 0] - points[ri, 0]
                dist[r, c] = np.hypot(dx, points[li, 1] - points[ri, 1])
            else:
                dist[r, c] = math.inf
            span[r, c] = offset[li] - offset[ri]
            middle[r, c] = 0.5 * (offset[li] + offset[ri])
    return left, right, dist, same, span, middle


@_compiled
def sub_table(keep, n, left, right, dist, same, span, middle):  # noqa: PLR0917
    """The pair table of the cones ``keep`` (sorted rows of n cones) from their full table.

    The same numbers as ``pair_table`` on the kept cones (each entry depends
    on its two cones only), with the cones renumbered.
    """
    row = np.full(n, -1, np.intp)
    col = np.full(n, -1, np.intp)
    for r in range(len(left)):
        row[left[r]] = r
    for c in range(len(right)):
        col[right[c]] = c
    a = 0
    b = 0
    for q in range(len(keep)):
        if row[keep[q]] >= 0:
            a += 1
        elif col[keep[q]] >= 0:
            b += 1
    rows = np.empty(a, np.intp)
    cols = np.empty(b, np.intp)
    new_left = np.empty(a, np.intp)
    new_right = np.empty(b, np.intp)
    a = 0
    b = 0
    for q in range(len(keep)):
        r = row[keep[q]]
        c = col[keep[q]]
        if r >= 0:
            rows[a] = r
            new_left[a] = q
            a += 1
        elif c >= 0:
            cols[b] = c
            new_right[b] = q
            b += 1
    d = np.empty((a, b))
    s = np.empty((a, b), np.bool_)
    w = np.empty((a, b))
    m = np.empty((a, b))
    for i in range(a):
        for j in range(b):
            d[i, j] = dist[rows[i], cols[j]]
            s[i, j] = same[rows[i], cols[j]]
            w[i, j] = span[rows[i], cols[j]]
            m[i, j] = middle[rows[i], cols[j]]
    return new_left, new_right, d, s, w, m


@_compiled
def median(values):
    """``numpy.median`` of (n,) values, n >= 1: the middle one or ``(a + b) / 2``; NaN if any."""
    ordered = np.sort(values)
    n = len(ordered)
    half = n // 2
    if math.isnan(ordered[n - 1]):
        return math.nan
    if n % 2:
        return ordered[half]
    return (ordered[half - 1] + ordered[half]) / 2.0


@_compiled
def estimate_track(dist, same, span, middle, view):
    """``bridges.estimate_track``: (width, centre, measured) [m, m, -].

    Not measured: the nominal width and centre 0. ``view`` is a
    ``settings.ViewSettings`` (its span, length, sample count and nominal width).
    """
    min_width = view.min_track_width
    max_width = view.max_track_width
    max_length = view.max_bridge_length
    min_samples = view.min_width_samples
    a, b = dist.shape
    # One pass: each row's nearest valid partner and each column's (first of
    # equals: rows and columns are visited in increasing order).
    row_best = np.full(a, -1, np.intp)
    col_best = np.full(b, -1, np.intp)
    for r in range(a):
        for c in range(b):
            if (
                same[r, c]
                and span[r, c] >= min_width
                and span[r, c] <= max_width
                and dist[r, c] <= max_length
            ):
                if row_best[r] < 0 or dist[r, c] < dist[r, row_best[r]]:
                    row_best[r] = c
                if col_best[c] < 0 or dist[r, c] < dist[col_best[c], c]:
                    col_best[c] = r
    picks_r = np.empty(a + b, np.intp)
    picks_c = np.empty(a + b, np.intp)
    rows = 0
    for r in range(a):
        if row_best[r] >= 0:
            picks_r[rows] = r
            picks_c[rows] = row_best[r]
            rows += 1
    m = rows
    for c in range(b):
        if col_best[c] >= 0:
            picks_r[m] = col_best[c]
            picks_c[m] = c
            m += 1
    if rows == 0 or m < min_samples:
        return view.nominal_track_width, 0.0, False
    widths = np.empty(m)
    centres = np.empty(m)
    for q in range(m):
        widths[q] = span[picks_r[q], picks_c[q]]
        centres[q] = middle[picks_r[q], picks_c[q]]
    return median(widths), median(centres), True


@_compiled
def boundary_offset(side, offset, centre, width):
    """(n,) how far each cone lies outside its boundary line, as seen from its side [m].

    ``side * (offset - centre) - width / 2`` for the track's centre offset and
    width [m]: 0 on the boundary, < 0 inside the track, > 0 outside; a cone
    labelled against its position is far inside.
    """
    n = len(side)
    out = np.empty(n)
    half = 0.5 * width
    for i in range(n):
        out[i] = side[i] * (offset[i] - centre) - half
    return out


@_compiled
def boundary_cones(points, side, offset, station, length, closed, view):  # noqa: PLR0917
    """``midline.boundary_cones``: kept rows, the pair table, (width, centre, measured).

    The cones in view; their pair table and the track estimate; when
    measured, the cones more than ``view.boundary_tolerance`` inside their
    boundary line dropped and the pair table rebuilt. The width and centre
    are the nominal width and 0 when not measured. ``view`` is a
    ``settings.ViewSettings``.
    """
    keep = true_rows(in_view(points, offset, view))
    pts = points[keep]
    sd = side[keep]
    off = offset[keep]
    st = station[keep]
    left, right, dist, same, span, middle = pair_table(
        pts, sd, off, st, length, closed, view.max_station_gap
    )
    width, centre, measured = estimate_track(dist, same, span, middle, view)
    if measured:
        outside = boundary_offset(sd, off, centre, width)
        on = outside >= -view.boundary_tolerance
        if not on.all():
            inner = true_rows(on)
            keep = keep[inner]
            left, right, dist, same, span, middle = sub_table(
                inner, len(sd), left, right, dist, same, span, middle
            )
    return keep, left, right, dist, same, span, middle, width, centre, measured
