"""A closed track from a loop's segments: the centreline, its cones, its gate, its start.

``loop_track`` closes the segments (centreline.py), starts the loop at its
start/finish line heading east from the origin, places the blue cones at
+w/2 (left) and the yellow at -w/2 (right) with cones.py's spacing, four big
orange cones at the line, and the car ``START_BEHIND_LINE`` behind it (a
standing start). ``scripts/make_tracks.py`` builds the shipped loops with it
and ``tracks.generate`` the random ones.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from conesim.core.pose import Pose2D
from conesim.tracks.generate.centreline import STEP, Segment, close_loop
from conesim.tracks.generate.cones import MAX_SPACING, MIN_SPACING, gate_cones, place_cones
from conesim.tracks.kinds import ConeKind, Layout
from conesim.tracks.model import Track

FloatArray = NDArray[np.float64]

START_BEHIND_LINE = 4.0  # [m] standing start behind the start/finish line
GATE_ON_EDGE = 0.25  # [m] a gate closer than this to the edge replaces the edge's cone on the line


@dataclass(frozen=True)
class LoopCentreline:
    """A closed centreline sampled every STEP from its start/finish line.

    Attributes:
        points: (n, 2) [m]; the first is the line's middle, at the origin.
        heading: (n,) [rad], 0 (east) at the line.
        curvature: (n,) [1/m], left positive.
    """

    points: FloatArray
    heading: FloatArray
    curvature: FloatArray

    @property
    def length(self) -> float:
        """One lap [m]."""
        return len(self.points) * STEP


def loop_centreline(segments: Sequence[Segment], line_at: float) -> LoopCentreline:
    """The closed loop of ``segments``, starting ``line_at`` [m] into the first.

    Raises:
        LoopClosureError: the free straights cannot close the loop.
    """
    points, heading, kappa = close_loop(segments)
    shift = round(line_at / STEP)
    points, heading, kappa = (np.roll(a, -shift, axis=0) for a in (points, heading, kappa))
    # Smoothing leaks a little of the last corner's turn past the start; turn
    # the whole loop so that it starts exactly eastwards at the origin.
    c, s = math.cos(heading[0]), math.sin(heading[0])
    points = (points - points[0]) @ np.array([[c, -s], [s, c]])
    heading = heading - heading[0]
    return LoopCentreline(points, heading, kappa)


def loop_cones(
    loop: LoopCentreline,
    width: float,
    *,
    gate_offset: float = 0.0,
    min_spacing: float = MIN_SPACING,
    max_spacing: float = MAX_SPACING,
    spacing_window: float = 0.0,
) -> tuple[FloatArray, tuple[ConeKind, ...]]:
    """The cones (n, 2) [m] and kinds of a loop ``width`` [m] wide.

    The big orange cones stand ``gate_offset`` [m] outside the edges at the
    line; on the edge (closer than ``GATE_ON_EDGE``), the edge's own cone on
    the line gives way to them. Spacing follows the tightest curvature
    within ``spacing_window`` [m] (0: the local one; ``place_cones``).
    """
    window = max(1, round(spacing_window / STEP))
    points, heading, kappa = loop.points, loop.heading, loop.curvature
    normal = np.column_stack([-np.sin(heading), np.cos(heading)])
    gate = gate_cones(points[0], float(heading[0]), width / 2, gate_offset)
    cones, kinds = [], []
    for sign, kind, big in ((1.0, ConeKind.BLUE, gate[:2]), (-1.0, ConeKind.YELLOW, gate[2:])):
        offset = sign * width / 2
        edge = points + offset * normal
        edge_kappa = kappa / (1.0 - kappa * offset)
        placed = place_cones(edge, edge_kappa, min_spacing, max_spacing, window)
        if gate_offset < GATE_ON_EDGE:
            placed = placed[1:]  # the cone on the line gives way to the big orange ones
        cones += [placed, big]
        kinds += [kind] * len(placed) + [ConeKind.BIG_ORANGE] * len(big)
    return np.vstack(cones), tuple(kinds)


def start_pose(loop: LoopCentreline) -> Pose2D:
    """The car's standing start, ``START_BEHIND_LINE`` behind the line on the centreline."""
    back = -round(START_BEHIND_LINE / STEP)
    return Pose2D(
        float(loop.points[back, 0]), float(loop.points[back, 1]), float(loop.heading[back])
    )


def loop_track(
    name: str, segments: list[Segment], width: float, line_at: float, description: str
) -> Track:
    """A closed track from segments, the start/finish line ``line_at`` [m] from the start."""
    loop = loop_centreline(segments, line_at)
    cones, kinds = loop_cones(loop, width)
    return Track(name, cones, kinds, start_pose(loop), Layout.CLOSED, description=description)
