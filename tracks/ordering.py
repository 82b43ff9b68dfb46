"""Ordering the cones of one boundary: a short tour through them.

Track files list cones roughly in order, but not always, and a hairpin puts
cones of the other leg about as close as the next cone on the same leg, so
plain nearest-neighbour chaining can jump legs. A boundary is the shortest
tour through its cones, which we approximate the way TSP heuristics do:

1. initial tours: the file order and nearest-neighbour tours from a few
   starting cones;
2. improve each with 2-opt (reverse a stretch when that shortens the tour;
   a 2-opt optimum never crosses itself) and or-opt (move a run of 1-3
   cones elsewhere, either way round), until neither helps;
3. keep the shortest.

An open boundary (a lane) is the same problem with a dummy cone at distance 0
from every cone: the tour through it, cut at the dummy, is the shortest path.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray
from scipy.spatial import distance_matrix

IntArray = NDArray[np.intp]
FloatArray = NDArray[np.float64]

_EPS = 1e-9  # [m] minimum improvement that counts
_NN_STARTS = 4  # nearest-neighbour tours from this many spread-out starting cones
_OR_OPT_ROWS = 256  # runs evaluated per array step in or-opt (bounds memory to rows x n)


def order_loop(points: FloatArray) -> IntArray:
    """Indices of ``points`` (n, 2) [m] in the order of a short closed tour.

    The tour starts at index 0 of the input and its direction is arbitrary.
    """
    n = len(points)
    if n <= 3:
        return np.arange(n)
    tour = _best_tour(distance_matrix(points, points))
    return np.roll(tour, -int(np.argmin(tour)))


def order_path(points: FloatArray) -> IntArray:
    """Indices of ``points`` (n, 2) [m] in the order of a short open path.

    The direction of the path is arbitrary.
    """
    n = len(points)
    if n <= 2:
        return np.arange(n)
    dist = np.zeros((n + 1, n + 1))
    dist[:n, :n] = distance_matrix(points, points)
    tour = _best_tour(dist)
    cut = int(np.nonzero(tour == n)[0][0])
    return np.concatenate([tour[cut + 1 :], tour[:cut]])


def tour_length(dist: FloatArray, tour: IntArray) -> float:
    """Length of the closed tour [m] under the distance matrix."""
    return float(dist[tour, np.roll(tour, -1)].sum())


def _best_tour(dist: FloatArray) -> IntArray:
    n = len(dist)
    starts = np.unique(np.linspace(0, n - 1, _NN_STARTS).astype(int))
    candidates = [np.arange(n)] + [_nearest_neighbour(dist, int(s)) for s in starts]
    best, best_len = candidates[0], np.inf
    for tour in candidates:
        improved = _improve(dist, tour)
        length = tour_length(dist, improved)
        if length < best_len - _EPS:
            best, best_len = improved, length
    return best


def _nearest_neighbour(dist: FloatArray, start: int) -> IntArray:
    n = len(dist)
    visited = np.zeros(n, dtype=bool)
    tour = np.empty(n, dtype=np.intp)
    current = start
    for k in range(n):
        tour[k] = current
        visited[current] = True
        if k < n - 1:
            row = np.where(visited, np.inf, dist[current])
            current = int(np.argmin(row))
    return tour


def _improve(dist: FloatArray, tour: IntArray) -> IntArray:
    t = tour.copy()
    while True:
        changed = _two_opt(dist, t)
        t, moved = _or_opt(dist, t)
        if not (changed or moved):
            return t


def _two_opt(dist: FloatArray, t: IntArray) -> bool:
    """Improve ``t`` in place by segment reversals; True if anything changed."""
    n = len(t)
    changed_any = False
    changed = True
    while changed:
        changed = False
        for i in range(n - 2):
            a, b = t[i], t[i + 1]
            j = np.arange(i + 2, n if i > 0 else n - 1)
            if len(j) == 0:
                continue
            c, d = t[j], t[(j + 1) % n]
            delta = dist[a, c] + dist[b, d] - dist[a, b] - dist[c, d]
            k = int(np.argmin(delta))
            if delta[k] < -_EPS:
                jj = int(j[k])
                t[i + 1 : jj + 1] = t[i + 1 : jj + 1][::-1].copy()
                changed = changed_any = True
    return changed_any


def _or_opt(dist: FloatArray, t: IntArray) -> tuple[IntArray, bool]:
    """Move runs of 1-3 cones to their best place; returns the tour and whether it changed.

    Taking the run first..last out from between p and q gains
    d(p, first) + d(last, q) - d(p, q); putting it into the edge (c, d),
    forward or reversed, costs d(c, first) + d(last, d) - d(c, d). Each step
    makes the best move over all runs and edges (evaluated as arrays).
    """
    changed = False
    while True:
        move = _best_run_move(dist, t)
        if move is None:
            return t, changed
        t = _move_run(t, *move)
        changed = True


def _best_run_move(dist: FloatArray, t: IntArray) -> tuple[IntArray, int, bool] | None:
    """(run positions, target edge, reversed) of the best improving move, or None."""
    n = len(t)
    after_edge = np.roll(t, -1)  # edge e joins tour positions e and e + 1
    base = dist[t, after_edge]
    edges = np.arange(n)
    best, best_gain = None, _EPS
    for run in (1, 2, 3):
        if n < run + 3:
            continue
        for lo in range(0, n, _OR_OPT_ROWS):
            starts = np.arange(lo, min(n, lo + _OR_OPT_ROWS))
            first, last = t[starts], t[(starts + run - 1) % n]
            p, q = t[(starts - 1) % n], t[(starts + run) % n]
            gain = dist[p, first] + dist[last, q] - dist[p, q]
            forward = dist[t[None, :], first[:, None]] + dist[last[:, None], after_edge[None, :]]
            backward = dist[t[None, :], last[:, None]] + dist[first[:, None], after_edge[None, :]]
            cost = np.minimum(forward, backward) - base[None, :]
            touching = (edges[None, :] - starts[:, None] + 1) % n <= run  # edges at the run
            net = np.where(touching, -np.inf, gain[:, None] - cost)
            row, edge = np.unravel_index(int(np.argmax(net)), net.shape)
            if net[row, edge] > best_gain:
                best_gain = float(net[row, edge])
                pos = (starts[row] + np.arange(run)) % n
                best = (pos, int(edge), bool(backward[row, edge] < forward[row, edge]))
    return best


def _move_run(t: IntArray, pos: IntArray, edge: int, reverse: bool) -> IntArray:
    """The tour with the cones at positions ``pos`` moved into edge ``edge``
    (between tour positions edge and edge + 1)."""
    n = len(t)
    after = t[(edge + 1) % n]
    piece = t[pos][::-1] if reverse else t[pos]
    rest = np.delete(t, pos)
    at = int(np.nonzero(rest == after)[0][0])
    return np.concatenate([rest[:at], piece, rest[at:]])
