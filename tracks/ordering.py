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

The two improvement searches are numba kernels (scalar loops over the
distance matrix; scipy has no TSP heuristic): in numpy they took about
0.15 s of every generated track's 0.3-0.5 s, which an env with
``track="random"`` pays at each reset onto a new track. They make the same
moves as the array form they replaced: the first best move in the same
scan order, the same sums.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray
from scipy.spatial import distance_matrix

from conesim.core.compiled import cached_njit

IntArray = NDArray[np.intp]
FloatArray = NDArray[np.float64]

_EPS = 1e-9  # [m] minimum improvement that counts
_NN_STARTS = 4  # nearest-neighbour tours from this many spread-out starting cones


def _probe() -> None:
    """Nothing: what ``cached_njit`` asks numba to cache, from this file's directory."""


_compiled = cached_njit(_probe, "conesim.tracks.ordering")


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
    return bool(_two_opt_kernel(dist, t, _EPS))


@_compiled
def _two_opt_kernel(dist, t, eps):
    """:func:`_two_opt`: for each edge (a, b) in turn, the best edge (c, d) after it
    (the first of equal ones), reversed between them if that saves more than ``eps``."""
    n = t.shape[0]
    changed_any = False
    changed = True
    while changed:
        changed = False
        for i in range(n - 2):
            a, b = t[i], t[i + 1]
            best, best_j = np.inf, -1
            for j in range(i + 2, n if i > 0 else n - 1):
                c, d = t[j], t[(j + 1) % n]
                delta = dist[a, c] + dist[b, d] - dist[a, b] - dist[c, d]
                if delta < best:
                    best, best_j = delta, j
            if best_j >= 0 and best < -eps:
                lo, hi = i + 1, best_j
                while lo < hi:
                    t[lo], t[hi] = t[hi], t[lo]
                    lo += 1
                    hi -= 1
                changed = changed_any = True
    return changed_any


def _or_opt(dist: FloatArray, t: IntArray) -> tuple[IntArray, bool]:
    """Move runs of 1-3 cones to their best place; returns the tour and whether it changed.

    Taking the run first..last out from between p and q gains
    d(p, first) + d(last, q) - d(p, q); putting it into the edge (c, d),
    forward or reversed, costs d(c, first) + d(last, d) - d(c, d). Each step
    makes the best move over all runs and edges.
    """
    changed = False
    while True:
        run, start, edge, reverse = _best_run_move(dist, t, _EPS)
        if run == 0:
            return t, changed
        t = _move_run(t, (start + np.arange(run)) % len(t), edge, reverse)
        changed = True


@_compiled
def _best_run_move(dist, t, eps):
    """(run length, its first tour position, target edge, reversed) of the best move
    gaining more than ``eps``, the first of equal ones scanning runs of 1, 2, 3, then
    their starts, then the edges; run length 0: none."""
    n = t.shape[0]
    best_gain = eps
    best_run, best_start, best_edge, best_reverse = 0, 0, 0, False
    for run in (1, 2, 3):
        if n < run + 3:
            continue
        for s in range(n):
            first, last = t[s], t[(s + run - 1) % n]
            p, q = t[(s - 1) % n], t[(s + run) % n]
            gain = dist[p, first] + dist[last, q] - dist[p, q]
            for e in range(n):
                if (e - s + 1) % n <= run:  # an edge at the run itself
                    continue
                c, d = t[e], t[(e + 1) % n]
                forward = dist[c, first] + dist[last, d]
                backward = dist[c, last] + dist[first, d]
                net = gain - (min(forward, backward) - dist[c, d])
                if net > best_gain:
                    best_gain = net
                    best_run, best_start, best_edge = run, s, e
                    best_reverse = backward < forward
    return best_run, best_start, best_edge, best_reverse


def _move_run(t: IntArray, pos: IntArray, edge: int, reverse: bool) -> IntArray:
    """The tour with the cones at positions ``pos`` moved into edge ``edge``
    (between tour positions edge and edge + 1)."""
    n = len(t)
    after = t[(edge + 1) % n]
    piece = t[pos][::-1] if reverse else t[pos]
    rest = np.delete(t, pos)
    at = int(np.nonzero(rest == after)[0][0])
    return np.concatenate([rest[:at], piece, rest[at:]])
