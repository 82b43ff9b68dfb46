"""Compiled kernels (numba) for the planner's per-detection glue.

Why hand-written compiled code exists here: the planning step (classify +
plan + speed profile, issue 5: median <= 0.5 ms with 80 cones in view) runs
on a few dozen cones, where numpy's cost is per call, not per element. With
the numpy glue already tuned, the step measured 0.96-1.03 ms at 80 cones;
a perf profile gave the Python interpreter 34 %, numpy's per-call overhead
23 %, arithmetic 7.6 %, qhull 16 %, malloc 9 %, the k-d tree 3 %. Each
kernel below replaces a chain of small numpy calls (masks, outer products,
gathers, argmins, a Python walk) with one loop over the elements, compiled
once (``cache=True``: later processes load the machine code from the cache
next to this file, or from ``NUMBA_CACHE_DIR`` or the user's cache directory
when the package directory is not writable, e.g. a system install; with no
writable cache directory at all they compile in each process, with a
warning). Compiling all of them from a cold cache takes about 12 s on the
2-core development machine, loading them from the cache about 0.25 s.

Every kernel does the same IEEE operations per element, in the same order,
as the numpy code it replaces (no ``fastmath``, so no reassociation or
fused multiply-add): the results are bit for bit the same, including which
element wins a tie (first in the order numpy's ``argmin`` or stable
``argsort`` would see). ``tests/planner/test_speedups.py`` and
``test_kernels.py`` keep the numpy formulations as references and compare
exactly.

The speed profile's kernels (``profile_limits``, ``profile_passes``) replace
its numpy steps and the Python loops of its friction-ellipse passes: 0.10 ms
per plan on 60 waypoints, 7.6 us compiled (``speed_profile``'s docstring).
Their one exception to "same operations": the jerk limit's cube root is left
to ``numpy.cbrt`` between them, as numpy's SIMD (SVML) cube root is not libm's.

The kernels are called through typed Python wrappers in ``geometry``,
``bridges``, ``ordering``, ``midline`` and ``speed_profile``; they take plain
arrays and scalars (no dataclasses) and are untyped for mypy (``numba`` has no
stubs). Integer index arrays are ``intp``, sides ``int8``, flags ``bool``, all
C-contiguous, so each kernel compiles to one specialisation.
"""

from __future__ import annotations

import math

import numpy as np

from localization.compiled import cached_njit


def _probe() -> None:
    """Nothing: what ``cached_njit`` asks numba to cache, from this file's directory."""


# Cached beside this file (or under NUMBA_CACHE_DIR); with no writable cache
# directory, compiled in every process (a cold compile: see the module docstring).
_compiled = cached_njit(_probe, "planner.kernels")

# Columns of ``PathProjector``'s segment table (``geometry``).
_SX, _SY, _DX, _DY, _INV_LEN2, _MID_STATION, _HALF_LENGTH, _LENGTH, _STATION0 = range(9)


@_compiled
def _wrap(diff, length, closed):
    """``station_difference``'s wrap of one difference: ``(x % length) - length / 2``.

    With ``x = diff + length / 2``, Python's (and numpy's) float ``x % length``
    is ``fmod`` moved onto the divisor's sign; ``fmod`` is exact, and for x in
    [-length, 2 length) it is x, x (then + length) or x - length (exact by
    Sterbenz's lemma). Those cases are written out (``fmod`` is slow); a zero
    remainder is +0 as in Python. Anything else takes ``%``.
    """
    if closed and length > 0.0:
        x = diff + 0.5 * length
        if 0.0 < x < length:
            r = x
        elif -length <= x < 0.0:
            r = x + length
        elif length <= x < 2.0 * length:
            r = x - length
        elif x == 0.0:
            r = 0.0
        else:
            r = x % length
        return r - 0.5 * length
    return diff


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
            away = abs(_wrap(table[s, _MID_STATION] - centre, length, closed))
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
def ground_points(points):
    """``classify``'s ground points: the rows with finite x and y, then the origin.

    Args:
        points: (n, >= 2) detections; x and y are the first two columns.

    Returns:
        (k + 1, 2) the finite rows' x and y followed by (0, 0), and the (n,)
        mask of the finite rows (``numpy.isfinite`` of x and y, both).
    """
    n = len(points)
    finite = np.empty(n, np.bool_)
    k = 0
    for i in range(n):
        finite[i] = math.isfinite(points[i, 0]) and math.isfinite(points[i, 1])
        if finite[i]:
            k += 1
    ground = np.zeros((k + 1, 2))
    k = 0
    for i in range(n):
        if finite[i]:
            ground[k, 0] = points[i, 0]
            ground[k, 1] = points[i, 1]
            k += 1
    return ground, finite


@_compiled
def with_tips(points, tangent):
    """``midline.cones_to_sensor``'s input: (2n, 2) the points, then ``points + tangent``."""
    n = len(points)
    out = np.empty((2 * n, 2))
    for i in range(n):
        out[i, 0] = points[i, 0]
        out[i, 1] = points[i, 1]
        out[n + i, 0] = points[i, 0] + tangent[i, 0]
        out[n + i, 1] = points[i, 1] + tangent[i, 1]
    return out


@_compiled
def side_of_path(offset):
    """``classify.side_of_path``: (n,) int8, +1 where the offset is > 0, else -1."""
    side = np.empty(len(offset), np.int8)
    for i in range(len(offset)):
        side[i] = 1 if offset[i] > 0.0 else -1
    return side


@_compiled
def window_overlaps(lo, hi, table, length, closed, half_max):  # noqa: PLR0917
    """``PathProjector._preference``'s test: some segment overlaps stations [lo, hi] [m].

    Where the segments tile the window (on a closed path, or well inside an
    open one, and wider than ``half_max``, half the longest segment) without
    looking; otherwise ``window_mask(lo, hi).any()``: a segment whose
    mid-station lies within the window's half width plus its half length
    of the window's middle (``station_difference``'s wrap).
    """
    inside = closed or (lo < length - half_max and hi > half_max)
    if inside and hi - lo > half_max:
        return True
    centre = 0.5 * (lo + hi)
    half = 0.5 * (hi - lo)
    for s in range(table.shape[0]):
        reach = half + table[s, _HALF_LENGTH]
        if abs(_wrap(table[s, _MID_STATION] - centre, length, closed)) <= reach:
            return True
    return False


@_compiled
def in_view(  # noqa: PLR0917
    points, offset, min_x, max_range, min_offset, max_offset
):
    """``midline.in_view``: (n,) mask of cones in range and at a boundary's offset."""
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
            same[r, c] = abs(_wrap(station[ri] - station[li], length, closed)) <= max_gap
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
    """``bridges.median``: middle value or ``(a + b) / 2`` of the sorted values; NaN if any."""
    ordered = np.sort(values)
    n = len(ordered)
    half = n // 2
    if math.isnan(ordered[n - 1]):
        return math.nan
    if n % 2:
        return ordered[half]
    return (ordered[half - 1] + ordered[half]) / 2.0


@_compiled
def estimate_track(  # noqa: PLR0917
    dist, same, span, middle, min_width, max_width, max_length, min_samples
):
    """``bridges.estimate_track``: (width, centre, measured); measured False gives (0, 0)."""
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
        return 0.0, 0.0, False
    widths = np.empty(m)
    centres = np.empty(m)
    for q in range(m):
        widths[q] = span[picks_r[q], picks_c[q]]
        centres[q] = middle[picks_r[q], picks_c[q]]
    return median(widths), median(centres), True


@_compiled
def boundary_offset(side, offset, centre, width):
    """``TrackEstimate.boundary_offset``: ``side * (offset - centre) - width / 2``."""
    n = len(side)
    out = np.empty(n)
    half = 0.5 * width
    for i in range(n):
        out[i] = side[i] * (offset[i] - centre) - half
    return out


@_compiled
def _rows(mask):
    """``mask.nonzero()[0]``."""
    out = np.empty(len(mask), np.intp)
    m = 0
    for i in range(len(mask)):
        if mask[i]:
            out[m] = i
            m += 1
    return out[:m]


@_compiled
def boundary_cones(  # noqa: PLR0917
    points,
    side,
    offset,
    station,
    length,
    closed,
    min_x,
    max_range,
    min_offset,
    max_offset,
    max_gap,
    min_width,
    max_width,
    max_bridge,
    min_samples,
    tolerance,
):
    """``midline.boundary_cones``: kept rows, the pair table, (width, centre, measured).

    The cones in view; their pair table and the track estimate; when
    measured, the cones more than ``tolerance`` inside their boundary line
    dropped and the pair table rebuilt. The width and centre are 0 when not
    measured (the caller puts in the nominal track).
    """
    keep = _rows(in_view(points, offset, min_x, max_range, min_offset, max_offset))
    pts = points[keep]
    sd = side[keep]
    off = offset[keep]
    st = station[keep]
    left, right, dist, same, span, middle = pair_table(pts, sd, off, st, length, closed, max_gap)
    width, centre, measured = estimate_track(
        dist, same, span, middle, min_width, max_width, max_bridge, min_samples
    )
    if measured:
        outside = boundary_offset(sd, off, centre, width)
        on = outside >= -tolerance
        if not on.all():
            inner = _rows(on)
            keep = keep[inner]
            left, right, dist, same, span, middle = sub_table(
                inner, len(sd), left, right, dist, same, span, middle
            )
    return keep, left, right, dist, same, span, middle, width, centre, measured


@_compiled
def partners_needed(  # noqa: PLR0917
    side, offset, left, right, same, dist, radius, centre, width, tolerance
):
    """``virtual_partners``' selection: rows of the cones that get a virtual partner."""
    n = len(side)
    near = np.zeros(n, np.bool_)
    a, b = dist.shape
    for r in range(a):
        for c in range(b):
            if same[r, c] and dist[r, c] <= radius:
                near[left[r]] = True
                near[right[c]] = True
    outside = boundary_offset(side, offset, centre, width)
    need = np.empty(n, np.bool_)
    for i in range(n):
        need[i] = not near[i] and abs(outside[i]) <= tolerance
    return _rows(need)


@_compiled
def partner_points(points, side, offset, tangent, rows, width):  # noqa: PLR0917
    """``virtual_partners``' new cones: (v, 2) points, (v,) sides and offsets.

    The cones ``rows`` moved one ``width`` across the track, along the left
    normal (-t_y, t_x) of their tangent, away from their own side: the
    numpy version's ``points - (side * width) * normal`` and
    ``offset - side * width``, element by element.
    """
    v = len(rows)
    out = np.empty((v, 2))
    out_side = np.empty(v, np.int8)
    out_offset = np.empty(v)
    for q in range(v):
        i = rows[q]
        across = side[i] * width
        out[q, 0] = points[i, 0] - across * (tangent[i, 1] * -1.0)
        out[q, 1] = points[i, 1] - across * (tangent[i, 0] * 1.0)
        out_side[q] = -side[i]
        out_offset[q] = offset[i] - across
    return out, out_side, out_offset


@_compiled
def _upper_neighbours(simplices, n, cap):
    """Each vertex's neighbours above it, in the order scipy's lists meet them.

    Returns:
        (n,) counts and the (n, cap) lists; False when a vertex has more than
        ``cap`` (the lists are then incomplete: call again with a larger cap).
    """
    count = np.zeros(n, np.intp)
    lists = np.empty((n, cap), np.intp)
    for i in range(simplices.shape[0]):
        for j in range(3):
            u = simplices[i, j]
            for k in range(3):
                v = simplices[i, k]
                if v <= u:
                    continue
                found = False
                for q in range(count[u]):
                    if lists[u, q] == v:
                        found = True
                        break
                if not found:
                    if count[u] == cap:
                        return count, lists, False
                    lists[u, count[u]] = v
                    count[u] += 1
    return count, lists, True


@_compiled
def delaunay_edges(simplices, n):
    """Unique edges (e, 2), i < j, in the order of ``Delaunay.vertex_neighbor_vertices``.

    scipy builds each vertex's neighbour list by walking the simplices and
    their vertex pairs (j, k), appending k to j's list when not yet in it
    (``setlist.add``); the CSR rows are these lists. Rows in vertex order,
    each keeping its neighbours above the vertex, give the edges. Only the
    neighbours above are kept (``_upper_neighbours``): leaving the others
    out changes neither which ones above are met first nor their order.
    Two points (no simplices) give their one edge.
    """
    if n == 2 and simplices.shape[0] == 0:
        return np.array([[0, 1]], dtype=np.intp)
    cap = 8  # a Delaunay vertex has 6 neighbours on average, 3 above it
    count, lists, complete = _upper_neighbours(simplices, n, cap)
    while not complete:  # a vertex with many neighbours
        cap *= 2
        count, lists, complete = _upper_neighbours(simplices, n, cap)
    edges = np.empty((count.sum(), 2), np.intp)
    e = 0
    for u in range(n):
        for q in range(count[u]):
            edges[e, 0] = u
            edges[e, 1] = lists[u, q]
            e += 1
    return edges


@_compiled
def find_bridges(  # noqa: PLR0917
    edges,
    points,
    side,
    offset,
    station,
    virtual,
    length,
    closed,
    min_width,
    max_width,
    max_bridge,
    max_gap,
    check_width,
    width,
    width_tolerance,
    shortest,
):
    """``bridges.find_bridges``: left, right, length, valid, used, midpoints, station."""
    e = edges.shape[0]
    m = 0
    for q in range(e):
        if side[edges[q, 0]] != side[edges[q, 1]]:
            m += 1
    left = np.empty(m, np.intp)
    right = np.empty(m, np.intp)
    size = np.empty(m)
    valid = np.empty(m, np.bool_)
    mid = np.empty((m, 2))
    mid_station = np.empty(m)
    m = 0
    for q in range(e):
        i = edges[q, 0]
        j = edges[q, 1]
        if side[i] == side[j]:
            continue
        if side[i] < 0:
            i, j = j, i
        left[m] = i
        right[m] = j
        vx = points[j, 0] - points[i, 0]
        vy = points[j, 1] - points[i, 1]
        size[m] = np.hypot(vx, vy)
        span = offset[i] - offset[j]
        ds = _wrap(station[j] - station[i], length, closed)
        ok = (
            span >= min_width
            and span <= max_width
            and size[m] <= max_bridge
            and abs(ds) <= max_gap
            and not (virtual[i] and virtual[j])
        )
        if check_width:
            ok = ok and abs(span - width) <= width_tolerance
        valid[m] = ok
        mid[m, 0] = points[i, 0] + 0.5 * vx
        mid[m, 1] = points[i, 1] + 0.5 * vy
        mid_station[m] = station[i] + 0.5 * ds
        m += 1
    used = valid.copy()
    if shortest and valid.any():
        best = np.full(len(side), math.inf)
        for q in range(m):
            if valid[q]:
                best[left[q]] = min(best[left[q]], size[q])
                best[right[q]] = min(best[right[q]], size[q])
        for q in range(m):
            used[q] = valid[q] and (size[q] <= best[left[q]] or size[q] <= best[right[q]])
    return left, right, size, valid, used, mid, mid_station


@_compiled
def boundary_edges(  # noqa: PLR0917
    edges, side, offset, station, length, closed, min_width, max_gap
):
    """``bridges.boundary_edges``: rows of the same-side edges along one boundary."""
    e = edges.shape[0]
    along = np.zeros(e, np.bool_)
    for q in range(e):
        i = edges[q, 0]
        j = edges[q, 1]
        if side[i] == side[j]:
            along[q] = (
                abs(offset[i] - offset[j]) < min_width
                and abs(_wrap(station[j] - station[i], length, closed)) <= max_gap
            )
    return _rows(along)


@_compiled
def start_index(  # noqa: PLR0917
    midpoints, station, sensor_station, length, closed, start_min_x, start_back, start_ahead
):
    """``ordering.start_index``: the nearest midpoint in front (first of equals), or -1."""
    first = -1
    best = math.inf
    for i in range(len(station)):
        ahead = _wrap(station[i] - sensor_station, length, closed)
        x = midpoints[i, 0]
        if x > start_min_x and ahead >= -start_back and ahead <= start_ahead:
            h = np.hypot(x, midpoints[i, 1])
            if first < 0 or h < best or (math.isnan(h) and not math.isnan(best)):
                first = i
                best = h
    return first


@_compiled
def chain_nearest(  # noqa: PLR0917
    midpoints,
    station,
    first,
    length,
    closed,
    max_step,
    max_station_step,
    back_tolerance,
    min_advance,
    min_spacing,
):
    """``ordering.chain_nearest``: the nearest-neighbour chain from ``first``.

    Each step goes to the nearest unvisited allowed midpoint, the first index
    of equals: the first unvisited one in a stable ``argsort`` of the row.
    The station advance is tested first: a midpoint it rules out needs no
    distance (the same choice, fewer ``np.hypot``).
    """
    m = len(station)
    visited = np.zeros(m, np.bool_)
    visited[first] = True
    order = np.empty(m, np.intp)
    order[0] = first
    count = 1
    current = first
    while True:
        nxt = -1
        step = math.inf
        cx = midpoints[current, 0]
        cy = midpoints[current, 1]
        for j in range(m):
            if visited[j]:
                continue
            advance = _wrap(station[j] - station[current], length, closed)
            if not (advance <= max_station_step and advance >= -back_tolerance):
                continue  # not allowed whatever the distance: skip the hypot
            d = np.hypot(cx - midpoints[j, 0], cy - midpoints[j, 1])
            if (
                d <= max_step
                and advance >= min_advance * d
                and d < math.inf
                and (nxt < 0 or d < step)
            ):
                nxt = j
                step = d
        if nxt < 0:
            break
        visited[nxt] = True
        if step < min_spacing:
            continue
        current = nxt
        order[count] = current
        count += 1
    return order[:count]


@_compiled
def polyline_crosses(points, b0, b1):
    """``geometry.polyline_crosses``: the polyline properly crosses a segment ``b0 b1``."""
    p = len(points)
    k = len(b0)
    for c in range(k):
        dbx = b1[c, 0] - b0[c, 0]
        dby = b1[c, 1] - b0[c, 1]
        cb = dbx * b0[c, 1] - dby * b0[c, 0]
        prev = points[0, 1] * dbx - points[0, 0] * dby - cb
        for j in range(p - 1):
            nxt = points[j + 1, 1] * dbx - points[j + 1, 0] * dby - cb
            if prev * nxt < 0.0:
                ax = points[j, 0]
                ay = points[j, 1]
                dax = points[j + 1, 0] - ax
                day = points[j + 1, 1] - ay
                ca = dax * ay - day * ax
                o0 = dax * b0[c, 1] - day * b0[c, 0] - ca
                o1 = dax * b1[c, 1] - day * b1[c, 0] - ca
                if o0 * o1 < 0.0:
                    return True
            prev = nxt
    return False


@_compiled
def _half_window(window, spacing, n, rounded):
    """The half width [samples] of a ``window`` [m] at ``spacing`` [m], capped at n.

    ``int(x)`` (``window_mean``) or Python's ``round(x)`` (half to even,
    ``jerk_limit``) of ``x = window / (2 spacing)``, 0 unless spacing > 0. A
    half of n or more averages (or spans) the whole path, as any larger
    half does: the cap only keeps the conversion to an integer defined.
    """
    if not spacing > 0.0:
        return 0
    x = window / (2.0 * spacing)
    if not x < n:  # also NaN
        return n
    return round(x) if rounded else int(x)


@_compiled
def profile_limits(  # noqa: PLR0917
    points,
    s,
    has_s,
    window,
    a_lat,
    a_lat_aero,
    floor,
    v_max,
    jerk_max,
    jerk_window,
):
    """``speed_profile`` up to the jerk limit's cube root, for n >= 1 points.

    The arc length (unless ``has_s``; ``numpy.cumsum`` of the ``np.hypot``
    steps), ``_menger``, ``window_mean`` when ``window > 0`` and n > 2,
    ``curvature_limit`` (``floor = a_lat / v_max**2``) and ``jerk_limit``'s
    ratio ``jerk_max / slope`` (inf where the slope is 0), each with the
    numpy version's operations in its order.

    Returns:
        s (n,) [m], the curvature kappa (n,) [1/m] the passes read, the
        curvature limit v (n,) [m/s], and the ratio (n,) [m^3/s^3] (empty
        when ``jerk_limit`` gives None). Its cube root is left to
        ``numpy.cbrt``: on CPUs with AVX-512 numpy takes it from SVML, whose
        last bit differs from libm's (and numba's) in about half the cases.
    """
    n = len(points)
    step_length = np.empty(max(n - 1, 0))
    for i in range(n - 1):
        step_length[i] = np.hypot(points[i + 1, 0] - points[i, 0], points[i + 1, 1] - points[i, 1])
    if not has_s:
        s = np.zeros(n)
        if n > 1:
            s[1] = step_length[0]
        for i in range(2, n):
            s[i] = s[i - 1] + step_length[i - 1]
    kappa = np.zeros(n)
    if n >= 3:
        for i in range(1, n - 1):
            abx = points[i, 0] - points[i - 1, 0]
            aby = points[i, 1] - points[i - 1, 1]
            bcx = points[i + 1, 0] - points[i, 0]
            bcy = points[i + 1, 1] - points[i, 1]
            cross = abx * bcy - aby * bcx
            denom = (
                step_length[i - 1]
                * step_length[i]
                * np.hypot(points[i + 1, 0] - points[i - 1, 0], points[i + 1, 1] - points[i - 1, 1])
            )
            if denom > 0.0:
                kappa[i] = 2.0 * cross / denom
        kappa[0] = kappa[1]
        kappa[n - 1] = kappa[n - 2]
    spacing = s[n - 1] / (n - 1) if n > 2 else 0.0
    if window > 0.0 and n > 2:
        half = _half_window(window, spacing, n, False)
        if half >= 1:
            c = np.empty(n + 1)  # numpy.concatenate([[0.0], numpy.cumsum(kappa)])
            c[0] = 0.0
            c[1] = kappa[0]
            for i in range(1, n):
                c[i + 1] = c[i] + kappa[i]
            smooth = np.empty(n)
            for i in range(n):
                lo = min(max(i - half, 0), n)
                hi = min(max(i + half + 1, 0), n)
                smooth[i] = (c[hi] - c[lo]) / (hi - lo)
            kappa = smooth
    v = np.empty(n)
    for i in range(n):
        k = abs(kappa[i]) - a_lat_aero
        v[i] = math.sqrt(a_lat / k) if k > floor else v_max
    ratio = np.empty(0)
    half = _half_window(jerk_window, spacing, n, True) if n > 2 else 0
    if jerk_max < math.inf and half >= 1 and n >= 2 * half + 1:
        slope = np.zeros(n)
        run = 2 * half * spacing
        for i in range(half, n - half):
            slope[i] = abs(kappa[i + half] - kappa[i - half]) / run
        for i in range(half):
            slope[i] = slope[half]
        for i in range(n - half, n):
            slope[i] = slope[n - half - 1]
        ratio = np.empty(n)
        for i in range(n):
            # numpy's jerk_max / slope: +inf at a zero slope (jerk_max > 0)
            ratio[i] = jerk_max / slope[i] if slope[i] != 0.0 else math.inf
    return s, kappa, v, ratio


@_compiled
def _ellipse_scale(v, kappa, a_lat_max, a_lat_aero):
    """``speed_profile._ellipse_scale``: sqrt(1 - (v^2 |kappa| / a_lat(v))^2), 0 beyond."""
    v2 = v * v
    lat = v2 * abs(kappa) / (a_lat_max + a_lat_aero * v2)
    return math.sqrt(1.0 - lat * lat) if lat < 1.0 else 0.0


@_compiled
def profile_passes(  # noqa: PLR0917
    s,
    kappa,
    v,
    jerk,
    has_start,
    v_start,
    ellipse,
    a_drive,
    a_brake,
    a_lat,
    a_lat_aero,
    horizon_stop,
    has_end,
    v_end,
):
    """The rest of ``speed_profile``: speeds (n,) [m/s] for n >= 1 waypoints.

    ``numpy.minimum`` of the curvature limit ``v`` (changed in place) and
    ``jerk`` (skipped when empty), the start speed, the forward pass
    (``ellipse_forward_pass`` or ``forward_pass``), the horizon stop and the
    backward pass, each with the numpy or Python version's operations: the
    closed-form passes' running minima in the same direction; Python's
    ``min`` and ``max`` (the first argument unless the second is strictly
    less or greater) for the start and end speeds and in the ellipse passes.
    """
    n = len(v)
    if len(jerk):
        for i in range(n):
            if not math.isnan(v[i]) and (math.isnan(jerk[i]) or jerk[i] < v[i]):
                v[i] = jerk[i]
    if has_start:
        start = 0.0 if v_start < 0.0 else v_start  # Python's max(v_start, 0.0)
        if start < v[0]:  # noqa: PLR1730 (Python's min(v[0], start))
            v[0] = start
    if ellipse:
        for i in range(1, n):
            u = v[i - 1]
            a = a_drive * _ellipse_scale(u, kappa[i - 1], a_lat, a_lat_aero)
            x = math.sqrt(u * u + 2.0 * a * (s[i] - s[i - 1]))
            if x < v[i]:  # noqa: PLR1730 (Python's min(v[i], x))
                v[i] = x
    else:
        # sqrt(max(reach + running min of (v^2 - reach), 0))
        reach_d = 2.0 * a_drive
        low = math.inf
        for i in range(n):
            reach = reach_d * s[i]
            w = v[i] * v[i] - reach
            if i == 0 or w < low or math.isnan(w):
                low = w if not math.isnan(low) else low
            x = reach + low
            v[i] = math.sqrt(x if x >= 0.0 or math.isnan(x) else 0.0)
    if horizon_stop:
        if has_end:
            end = 0.0 if v_end < 0.0 else v_end
            if end < v[n - 1]:  # noqa: PLR1730
                v[n - 1] = end
        else:
            v[n - 1] = 0.0
    out = np.empty(n)
    if ellipse:
        out[n - 1] = v[n - 1]
        for i in range(n - 2, -1, -1):
            u = out[i + 1]
            a = a_brake * _ellipse_scale(u, kappa[i], a_lat, a_lat_aero)
            x = math.sqrt(u * u + 2.0 * a * (s[i + 1] - s[i]))
            out[i] = x if x < v[i] else v[i]
        return out
    # sqrt(max(running min from the end of (v^2 + reach) - reach, 0))
    reach_b = 2.0 * a_brake
    low = math.inf
    for i in range(n - 1, -1, -1):
        reach = reach_b * s[i]
        w = v[i] * v[i] + reach
        if i == n - 1 or w < low or math.isnan(w):
            low = w if not math.isnan(low) else low
        x = low - reach
        out[i] = math.sqrt(x if x >= 0.0 or math.isnan(x) else 0.0)
    return out


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


@_compiled
def arc_length(points):
    """``geometry.arc_length``: 0, then the running sum of the step lengths (``np.hypot``)."""
    n = len(points)
    s = np.zeros(max(n, 1))
    total = 0.0
    for i in range(1, n):
        total += np.hypot(points[i, 0] - points[i - 1, 0], points[i, 1] - points[i - 1, 1])
        s[i] = total
    return s


@_compiled
def crosses_boundary(points, boundary):
    """``polyline_crosses(points, boundary[:, 0], boundary[:, 1])`` for (e, 2, 2) edges."""
    if len(points) < 2 or len(boundary) == 0:
        return False
    return polyline_crosses(points, boundary[:, 0], boundary[:, 1])


@_compiled
def ordered_midpoints(  # noqa: PLR0917
    used,
    midpoints,
    station,
    sensor_station,
    length,
    closed,
    start_min_x,
    start_back,
    start_ahead,
    max_step,
    max_station_step,
    back_tolerance,
    min_advance,
    min_spacing,
):
    """``ordering.ordered_midpoints``: the used bridges' midpoints in driving order."""
    rows = _rows(used)
    mid = midpoints[rows]
    st = station[rows]
    first = start_index(
        mid, st, sensor_station, length, closed, start_min_x, start_back, start_ahead
    )
    if first < 0:
        return np.zeros((0, 2))
    order = chain_nearest(
        mid, st, first, length, closed, max_step, max_station_step, back_tolerance, min_advance,
        min_spacing,
    )  # fmt: skip
    return mid[order]
