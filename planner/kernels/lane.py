"""Step 5b (``planner.lane``): the path kept inside the lane less the car's body, smoothed.

``lane_room``: how far each path point may move left and right, from the
boundary edges met along its normal; ``lane_path``: the elastic band that
moves the points along their normals, within that room, towards the
smoothest path.
"""

from __future__ import annotations

import math

import numpy as np

from conesim.core.compiled import cached_njit


def _probe() -> None:
    """Nothing: what ``cached_njit`` asks numba to cache, from this file's directory."""


# Cached beside this file (or under NUMBA_CACHE_DIR); with no writable cache
# directory, compiled in every process (a cold compile: see the package docstring).
_compiled = cached_njit(_probe, "conesim.planner.kernels.lane")


@_compiled
def _normals(path):
    """(n, 2) unit left normals of an (n, 2) path [m], from central differences."""
    n = len(path)
    out = np.zeros((n, 2))
    for i in range(n):
        a = max(i - 1, 0)
        b = min(i + 1, n - 1)
        tx = path[b, 0] - path[a, 0]
        ty = path[b, 1] - path[a, 1]
        norm = math.hypot(tx, ty)
        if norm > 0.0:
            out[i, 0] = -ty / norm
            out[i, 1] = tx / norm
    return out


@_compiled
def _ray_hit(px, py, dx, dy, segments, limit):  # noqa: PLR0917
    """The distance [m] along the ray p + t d (t > 0) to the nearest segment, at most ``limit``."""
    best = limit
    for q in range(segments.shape[0]):
        ax = segments[q, 0, 0]
        ay = segments[q, 0, 1]
        ex = segments[q, 1, 0] - ax
        ey = segments[q, 1, 1] - ay
        det = ex * dy - ey * dx
        if det == 0.0:
            continue
        rx = ax - px
        ry = ay - py
        t = (ex * ry - ey * rx) / det
        u = (dx * ry - dy * rx) / det
        if 0.0 <= u <= 1.0 and 0.0 < t < best:
            best = t
    return best


@_compiled
def lane_room(path, segments, default_half_width, lane):
    """Room (n,) left and (n,) right [m] of each point of an (n, 2) path for the car's
    rear axle, and the path's (n, 2) left normals.

    Along each point's normal, the nearest boundary edge of (e, 2, 2)
    ``segments`` on either side (``default_half_width`` [m] when none is
    nearer), less the body's clearance: half the car's width plus
    ``lane.clearance`` inside a turn, and outside it the front corner's
    sweep too, sqrt((R + w/2)^2 + f^2) - R for a turn of radius R at the
    rear axle and ``lane.body_front`` f [m]. ``lane`` is a
    ``settings.LaneSettings``.
    """
    n = len(path)
    normal = _normals(path)
    left = np.zeros(n)
    right = np.zeros(n)
    half = lane.body_half_width
    limit = default_half_width
    for i in range(n):
        px = path[i, 0]
        py = path[i, 1]
        nx = normal[i, 0]
        ny = normal[i, 1]
        to_left = _ray_hit(px, py, nx, ny, segments, limit)
        to_right = _ray_hit(px, py, -nx, -ny, segments, limit)
        kappa = 0.0
        if 0 < i < n - 1:
            a = path[i] - path[i - 1]
            b = path[i + 1] - path[i]
            la = math.hypot(a[0], a[1])
            lb = math.hypot(b[0], b[1])
            lc = math.hypot(path[i + 1, 0] - path[i - 1, 0], path[i + 1, 1] - path[i - 1, 1])
            if la * lb * lc > 0.0:
                kappa = 2.0 * (a[0] * b[1] - a[1] * b[0]) / (la * lb * lc)
        sweep = 0.0
        if abs(kappa) > 1e-6:
            radius = 1.0 / abs(kappa)
            sweep = math.hypot(radius + half, lane.body_front) - radius - half
        outside_left = kappa < 0.0  # a right turn: the body sweeps out to the left
        left[i] = to_left - half - lane.clearance - (sweep if outside_left else 0.0)
        right[i] = to_right - half - lane.clearance - (0.0 if outside_left else sweep)
    return left, right, normal


@_compiled
def lane_path(path, left, right, normal, lane):
    """The path (n, 2) [m] moved along its ``normal`` (n, 2), within ``left`` and
    ``right`` (n,) [m] of room, towards the path of least curvature from the car.

    First each point is clipped into its room (where the room is negative,
    the lane narrower than the car needs, it keeps the middle of the two
    limits); then ``lane.iterations`` Gauss-Seidel sweeps move each point
    but the first two and the last two to where the squared second
    differences it is part of are least,
    q_i = (4 (q_{i-1} + q_{i+1}) - (q_{i-2} + q_{i+2})) / 6, along its
    normal, clipped to its room.
    """
    n = len(path)
    offset = np.zeros(n)
    lo = np.empty(n)
    hi = np.empty(n)
    for i in range(n):
        if left[i] + right[i] >= 0.0:
            lo[i] = -right[i]
            hi[i] = left[i]
        else:
            lo[i] = hi[i] = 0.5 * (left[i] - right[i])
        offset[i] = min(max(0.0, lo[i]), hi[i])
    q = path.copy()
    for i in range(n):
        q[i, 0] = path[i, 0] + offset[i] * normal[i, 0]
        q[i, 1] = path[i, 1] + offset[i] * normal[i, 1]
    for _ in range(lane.iterations):
        for i in range(2, n - 2):
            bx, by = q[i - 1, 0], q[i - 1, 1]
            cx, cy = q[i - 2, 0], q[i - 2, 1]
            tx = (4.0 * (bx + q[i + 1, 0]) - (cx + q[i + 2, 0])) / 6.0
            ty = (4.0 * (by + q[i + 1, 1]) - (cy + q[i + 2, 1])) / 6.0
            move = (tx - q[i, 0]) * normal[i, 0] + (ty - q[i, 1]) * normal[i, 1]
            offset[i] = min(max(offset[i] + move, lo[i]), hi[i])
            q[i, 0] = path[i, 0] + offset[i] * normal[i, 0]
            q[i, 1] = path[i, 1] + offset[i] * normal[i, 1]
    return q
