"""Points projected onto a polyline: where each one lies along it and beside it.

The one answer of every projector in conesim: ``Polyline.project`` (exact,
brute force), race control's tracking walk (``sim.progress``) and the
planner's compiled nearest-segment search (``planner.geometry``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.intp]


@dataclass(frozen=True, slots=True)
class Projection:
    """n points projected onto their nearest segments of a polyline.

    Attributes:
        foot: (n, 2) nearest point of the polyline [m].
        segment: (n,) index of the segment the foot lies on.
        station: (n,) arc length from the polyline's start to the foot [m].
        offset: (n,) signed distance from that segment's line, + left of
            the direction of travel [m] (where the foot is the segment's
            end, still the distance from its line).
        tangent: (n, 2) unit direction of that segment.
        distance: (n,) distance to the foot [m], >= 0.
    """

    foot: FloatArray
    segment: IntArray
    station: FloatArray
    offset: FloatArray
    tangent: FloatArray
    distance: FloatArray

    @property
    def lateral(self) -> FloatArray:
        """(n,) signed distance to the foot, + left [m]: ``distance`` with the sign of ``offset``.

        Where the foot lies inside its segment this is the offset; beyond
        either end of an open polyline, or outside a corner, it is the
        distance to the end (a point past an open polyline's end is that far
        off it).
        """
        lateral: FloatArray = np.sign(self.offset) * self.distance
        return lateral

    def select(self, rows: slice | IntArray) -> Projection:
        """The projections of some of the points (``rows`` of each array)."""
        return Projection(
            self.foot[rows],
            self.segment[rows],
            self.station[rows],
            self.offset[rows],
            self.tangent[rows],
            self.distance[rows],
        )
