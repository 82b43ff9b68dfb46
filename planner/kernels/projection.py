"""Projection onto the global path (``geometry.PathProjector``).

Each point's nearest segment of the path (a search over bounding circles of
the segments, with an optional station window), the projection's numbers
from it (foot, station, offset, tangent, distance), and the test whether a
window of stations overlaps any segment.
"""

from __future__ import annotations

import math

import numpy as np

from conesim.core.compiled import cached_njit
from conesim.planner.kernels._common import wrapped_difference


def _probe() -> None:
    """Nothing: what ``cached_njit`` asks numba to cache, from this file's directory."""


# Cached beside this file (or under NUMBA_CACHE_DIR); with no writable cache
# directory, compiled in every process (a cold compile: see the package docstring).
_compiled = cached_njit(_probe, "conesim.planner.kernels.projection")

# Columns of ``PathProjector``'s segment table (``geometry``).
_SX, _SY, _DX, _DY, _INV_LEN2, _MID_STATION, _HALF_LENGTH, _LENGTH, _STATION0 = range(9)


@_compiled
def _mid2(px, py, table, s):
    """Squared distance from (px, py) to segment s's midpoint (what a k-d tree on them ranks)."""
    mx = px - (table[s, _SX] + 0.5 * table[s, _DX])
    my = py - (table[s, _SY] + 0.5 * table[s, _DY])
    return mx * mx + my * my


@_compiled
def _beyond(best, windowed):
    """A squared distance above which a segment cannot score ``best`` or less.

    Without a window the score is the squared distance: ``best``. With one it
    is ``sqrt(d2)`` plus a penalty >= 0, which rounds to no less than
    ``sqrt(d2)``; ``d2 > (best (1 + 2^-40))^2`` (each product rounded) gives
    ``sqrt(d2) > best`` with room for the roundings, so the search skips the
    square root of such a segment, and its choice is the same. inf (no skip)
    for a best so small that its square could underflow.
    """
    if not windowed:
        return best
    if not best > 1e-100:
        return math.inf
    b = best * (1.0 + 2.0**-40)
    return b * b


@_compiled
def nearest_segments(  # noqa: PLR0917
    p, table, blocks, size, windowed, centre, half, penalty, length, closed
):
    """Each point's segment of least score: (segment, t, squared distance).

    The score is the squared distance without a window; with one, the
    distance plus ``penalty`` for a segment outside [centre - half, centre +
    half] (widened by its half length), as ``PathProjector.project``
    defines it. Ties go to the nearer segment midpoint, then the lower
    index. A point with a NaN coordinate gets segment 0 and NaN.

    The segments are grouped ``size`` at a time into blocks, each inside a
    circle ``blocks[b] = (x, y, r)``; no segment of a block is nearer than
    ``hypot(p - (x, y)) - r``. Per point: the blocks holding a window segment
    (all blocks without a window), nearest bound first, each skipped when its
    bound exceeds the best score so far (plus 1e-9 m for rounding); then,
    with a window, the other blocks only if the best score reaches
    ``penalty`` (their segments all score at least that). Exact: a skipped
    segment cannot score as low as the best; nor can a segment whose squared
    distance exceeds ``_beyond(best)``, whose score is not computed.
    """
    n = len(p)
    n_seg = table.shape[0]
    n_block = blocks.shape[0]
    cost = np.zeros(n_seg)
    first_tier = np.zeros(n_block, np.bool_)
    if windowed:
        for s in range(n_seg):
            away = abs(wrapped_difference(table[s, _MID_STATION] - centre, length, closed))
            if away <= half + table[s, _HALF_LENGTH]:
                first_tier[s // size] = True
            else:
                cost[s] = penalty
    else:
        first_tier[:] = True
    bound = np.empty(n_block)
    seg = np.zeros(n, np.intp)
    t_best = np.full(n, math.nan)
    d2_best = np.full(n, math.nan)
    for i in range(n):
        px = p[i, 0]
        py = p[i, 1]
        best = math.inf
        beyond = math.inf
        best_seg = -1
        first = -1
        low = math.inf
        for b in range(n_block):
            if first_tier[b]:
                dx = px - blocks[b, 0]
                dy = py - blocks[b, 1]
                bound[b] = math.sqrt(dx * dx + dy * dy) - blocks[b, 2]
                if bound[b] < low:
                    low = bound[b]
                    first = b
        if first < 0:
            continue  # NaN
        for tier in range(3):
            # tier 0: the nearest first-tier block; 1: the other first-tier
            # blocks; 2: with a window, the blocks outside it.
            if tier == 2 and not windowed:
                break
            reach = best if windowed else math.sqrt(best)
            reach += 1e-9 + 1e-12 * abs(reach)
            if tier == 2 and reach < penalty:
                break
            for b in range(n_block):
                if tier == 0 and b != first:
                    continue
                if tier == 1 and (b == first or not first_tier[b] or bound[b] > reach):
                    continue
                if tier == 2:
                    if first_tier[b]:
                        continue
                    dx = px - blocks[b, 0]
                    dy = py - blocks[b, 1]
                    if math.sqrt(dx * dx + dy * dy) - blocks[b, 2] + penalty > reach:
                        continue
                for s in range(b * size, min((b + 1) * size, n_seg)):
                    rx = px - table[s, _SX]
                    ry = py - table[s, _SY]
                    sdx = table[s, _DX]
                    sdy = table[s, _DY]
                    t = (rx * sdx + ry * sdy) * table[s, _INV_LEN2]
                    if t < 0.0:  # noqa: PLR1730 (np.maximum(t, 0.0))
                        t = 0.0
                    if t > 1.0:  # noqa: PLR1730 (np.minimum(t, 1.0))
                        t = 1.0
                    gx = rx - t * sdx
                    gy = ry - t * sdy
                    d2 = gx * gx + gy * gy
                    if d2 > beyond:  # sqrt(d2) > best: neither better nor a tie
                        continue
                    score = math.sqrt(d2) + cost[s] if windowed else d2
                    better = score < best or best_seg < 0
                    if not better and score == best:
                        here = _mid2(px, py, table, s)
                        there = _mid2(px, py, table, best_seg)
                        better = here < there or (here == there and s < best_seg)
                    if better:
                        best = score
                        best_seg = s
                        seg[i] = s
                        t_best[i] = t
                        d2_best[i] = d2
                        beyond = _beyond(best, windowed)
    return seg, t_best, d2_best


@_compiled
def project_rows(p, seg, t, d2, table):
    """``PathProjector._project``'s outputs: foot, station, offset, tangent, distance."""
    n = len(seg)
    foot = np.empty((n, 2))
    station = np.empty(n)
    offset = np.empty(n)
    tangent = np.empty((n, 2))
    distance = np.empty(n)
    for i in range(n):
        s = seg[i]
        ax = table[s, _SX]
        ay = table[s, _SY]
        dx = table[s, _DX]
        dy = table[s, _DY]
        length = table[s, _LENGTH]
        ti = t[i]
        foot[i, 0] = ax + ti * dx
        foot[i, 1] = ay + ti * dy
        station[i] = table[s, _STATION0] + ti * length
        offset[i] = (dx * (p[i, 1] - ay) - dy * (p[i, 0] - ax)) / length
        tangent[i, 0] = dx / length
        tangent[i, 1] = dy / length
        distance[i] = math.sqrt(d2[i])
    return foot, station, offset, tangent, distance


@_compiled
def window_overlaps(lo, hi, table, length, closed, half_max):  # noqa: PLR0917
    """``PathProjector._preference``'s test: some segment overlaps stations [lo, hi] [m].

    Where the segments tile the window (on a closed path, or well inside an
    open one, and wider than ``half_max``, half the longest segment) without
    looking; otherwise whether a segment's mid-station lies within the
    window's half width plus its half length of the window's middle (the
    station wrap of ``_common.wrapped_difference``).
    """
    inside = closed or (lo < length - half_max and hi > half_max)
    if inside and hi - lo > half_max:
        return True
    centre = 0.5 * (lo + hi)
    half = 0.5 * (hi - lo)
    for s in range(table.shape[0]):
        reach = half + table[s, _HALF_LENGTH]
        if abs(wrapped_difference(table[s, _MID_STATION] - centre, length, closed)) <= reach:
            return True
    return False
