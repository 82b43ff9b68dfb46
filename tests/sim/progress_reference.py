"""The projection's readable formulations, the references its kernels are checked against.

``sim.progress`` walks from segment to segment and searches the whole line in
numba kernels; these are the functions they replaced (``PolylineProgress._walk``
on the segments as tuples of floats, ``_offset``, and the numpy search),
kept here so that ``test_step_fast_paths.py`` compares the kernels with them
bit for bit.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray


def walk(
    segments: list[tuple[float, float, float, float, float]],
    closed: bool,
    px: float,
    py: float,
    i: int,
) -> tuple[int, float, float, float]:
    """From segment i on to each neighbour while it is nearer: (segment,
    distance^2, the foot's arc position u, perpendicular offset).

    Plain floats, the segment's foot written out: it runs every physics step.
    """
    n = len(segments)
    sx, sy, tx, ty, length = segments[i]
    rx, ry = px - sx, py - sy
    u = min(max(rx * tx + ry * ty, 0.0), length)
    fx, fy = rx - tx * u, ry - ty * u
    best_d2, best_u, best_lat = fx * fx + fy * fy, u, tx * fy - ty * fx
    for di in (1, -1):
        while True:
            j = i + di
            if closed:
                j %= n
            elif not 0 <= j < n:
                break
            sx, sy, tx, ty, length = segments[j]
            rx, ry = px - sx, py - sy
            u = min(max(rx * tx + ry * ty, 0.0), length)
            fx, fy = rx - tx * u, ry - ty * u
            d2 = fx * fx + fy * fy
            if d2 >= best_d2:
                break
            i, best_d2, best_u, best_lat = j, d2, u, tx * fy - ty * fx
    return i, best_d2, best_u, best_lat


def offset(lateral: float, d2: float, u: float, length: float) -> float:
    """The signed offset of a point from its foot at ``u`` on a segment of
    ``length`` [m]: ``lateral`` (perpendicular) with the foot inside the
    segment, else the distance sqrt(``d2``) to the end it lies at, with
    ``lateral``'s sign (a car past an open polyline's end is that far off it)."""
    if 0.0 < u < length:
        return lateral
    return math.copysign(math.sqrt(d2), lateral)


def search(
    vertices: NDArray[np.float64],
    segments: NDArray[np.float64],
    px: float,
    py: float,
    *,
    window: int,
    closed: bool,
) -> tuple[int, float, float, float]:
    """The nearest of the segments (n, 5: start, unit tangent, length) within
    ``window`` segments of the vertex (m, 2) nearest to (px, py): (segment,
    distance^2, the foot's arc position u, perpendicular offset), in numpy."""
    p = np.array([px, py])
    n = len(segments)
    starts, tangents, lengths = segments[:, :2], segments[:, 2:4], segments[:, 4]
    nearest = int(np.argmin(np.sum((vertices - p) ** 2, axis=1)))
    idx = np.arange(nearest - window, nearest + window + 1)
    idx = np.mod(idx, n) if closed else idx[(idx >= 0) & (idx < n)]
    rel = p - starts[idx]
    u = np.clip(np.einsum("ij,ij->i", rel, tangents[idx]), 0.0, lengths[idx])
    foot = starts[idx] + tangents[idx] * u[:, None]
    d2 = np.sum((p - foot) ** 2, axis=1)
    k = int(np.argmin(d2))
    seg = int(idx[k])
    t = tangents[seg]
    r = p - foot[k]
    return seg, float(d2[k]), float(u[k]), float(t[0] * r[1] - t[1] * r[0])
