"""Step 3: the triangulation's edges, the bridges across the track and the boundary edges.

The unique edges of scipy's Delaunay triangles in scipy's own neighbour
order, the bridges among them (left-right edges, checked and their
midpoints; ``bridges.find_bridges``) and the same-side edges along a
boundary (``bridges.boundary_edges``).
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
_compiled = cached_njit(_probe, "conesim.planner.kernels.bridges")


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
    edges, points, side, offset, station, virtual, length, closed, check_width, width, checks
):
    """``bridges.find_bridges``: left, right, length, valid, used, midpoints, station.

    ``checks`` is a ``settings.BridgeSettings``; the span is checked against
    ``width`` only when ``check_width``.
    """
    min_width = checks.min_track_width
    max_width = checks.max_track_width
    max_bridge = checks.max_bridge_length
    max_gap = checks.max_station_gap
    width_tolerance = checks.width_tolerance
    shortest = checks.shortest
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
        ds = wrapped_difference(station[j] - station[i], length, closed)
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
def boundary_edges(edges, side, offset, station, length, closed, checks):  # noqa: PLR0917
    """``bridges.boundary_edges``: rows of the same-side edges along one boundary.

    ``checks`` is a ``settings.BridgeSettings`` (its minimum span and station gap).
    """
    min_width = checks.min_track_width
    max_gap = checks.max_station_gap
    e = edges.shape[0]
    along = np.zeros(e, np.bool_)
    for q in range(e):
        i = edges[q, 0]
        j = edges[q, 1]
        if side[i] == side[j]:
            along[q] = (
                abs(offset[i] - offset[j]) < min_width
                and abs(wrapped_difference(station[j] - station[i], length, closed)) <= max_gap
            )
    return true_rows(along)
