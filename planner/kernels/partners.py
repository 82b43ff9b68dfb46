"""Step 3a: virtual partners (``bridges.virtual_partners``).

Which boundary cones have no real partner across the track, and the
partners made for them one track width across.
"""

from __future__ import annotations

import numpy as np

from conesim.core.compiled import cached_njit
from conesim.planner.kernels._common import true_rows
from conesim.planner.kernels.track import boundary_offset


def _probe() -> None:
    """Nothing: what ``cached_njit`` asks numba to cache, from this file's directory."""


# Cached beside this file (or under NUMBA_CACHE_DIR); with no writable cache
# directory, compiled in every process (a cold compile: see the package docstring).
_compiled = cached_njit(_probe, "conesim.planner.kernels.partners")


@_compiled
def partners_needed(  # noqa: PLR0917
    side, offset, left, right, same, dist, centre, width, partners
):
    """``virtual_partners``' selection: rows of the cones that get a virtual partner.

    ``partners`` is a ``settings.PartnerSettings`` (its radius and tolerance).
    """
    radius = partners.partner_radius
    tolerance = partners.partner_offset_tolerance
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
    return true_rows(need)


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
