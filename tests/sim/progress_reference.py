"""The projection walk's readable formulation, the reference its kernel is checked against.

``sim.progress`` walks from segment to segment in a numba kernel; these are
the plain-Python functions it replaced (``PolylineProgress._walk`` on the
segments as tuples of floats, and ``_offset``), kept here so that
``test_step_fast_paths.py`` compares the kernel with them bit for bit.
"""

from __future__ import annotations

import math


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
