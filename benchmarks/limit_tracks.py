"""Hand-made loops for ``bench_limit.py``: rings, tight hairpins and an S-bend.

Each is a closed lane of constant width built from a centreline: blue cones
on the left, yellow on the right, ``spacing`` apart, four big orange cones
at the start line, the car 3 m behind it. They test the limit where the
shipped tracks do not reach: constant corners of several radii (where the
minimum-curvature line is not the fastest), hairpins below the FS minimum,
and an S-bend. Written as conesim track files (``write_hand_made``) so that
``conesim run`` reads them like any other.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from conesim.core.polyline import Polyline
from conesim.core.pose import Pose2D
from conesim.tracks import ConeKind, Layout, Track, write_track

FloatArray = NDArray[np.float64]


def lane_track(name: str, centre: FloatArray, width: float = 3.0, spacing: float = 3.0) -> Track:
    """A loop of ``width`` [m] about the closed ``centre`` (n, 2) [m], run in its order."""
    line = Polyline(centre, True).resample(0.2)
    pts, tangent = line.points, line.tangents()
    normal = np.column_stack([-tangent[:, 1], tangent[:, 0]])
    cones, kinds = [], []
    for side, kind in ((1.0, ConeKind.BLUE), (-1.0, ConeKind.YELLOW)):
        edge = Polyline(pts + side * width / 2 * normal, True).resample(spacing).points
        keep = np.hypot(*(edge - pts[0]).T) > 1.0  # the big orange cones stand there
        cones.append(edge[keep])
        kinds += [kind] * int(keep.sum())
    for side in (1.0, -1.0):
        for along in (-0.3, 0.3):
            cones.append((pts[0] + along * tangent[0] + side * width / 2 * normal[0])[None])
            kinds.append(ConeKind.BIG_ORANGE)
    start = pts[0] - 3.0 * tangent[0]
    yaw = math.atan2(tangent[0][1], tangent[0][0])
    pose = Pose2D(float(start[0]), float(start[1]), yaw)
    return Track(name, np.vstack(cones), tuple(kinds), pose, Layout.CLOSED)


def ring(radius: float) -> FloatArray:
    """A counter-clockwise circle of ``radius`` [m], starting at its bottom."""
    a = np.linspace(0.0, 2 * math.pi, 400, endpoint=False) - math.pi / 2
    return radius * np.column_stack([np.cos(a), np.sin(a)])


def stadium(straight: float, radius: float) -> FloatArray:
    """Two straights of ``straight`` [m] joined by half circles of ``radius`` [m]."""
    x = np.linspace(0.0, straight, 80, endpoint=False)
    a = np.linspace(-math.pi / 2, math.pi / 2, 120, endpoint=False)
    return np.vstack([
        np.column_stack([x, np.full_like(x, -radius)]),
        np.column_stack([straight + radius * np.cos(a), radius * np.sin(a)]),
        np.column_stack([straight - x, np.full_like(x, radius)]),
        np.column_stack([-radius * np.cos(a), -radius * np.sin(a)]),
    ])  # fmt: skip


def s_bend(straight: float = 120.0, radius: float = 12.0) -> FloatArray:
    """A stadium whose first straight carries two periods of a 3 m, 30 m sine."""
    pts = stadium(straight, radius)
    bend = (np.abs(pts[:, 1] + radius) < 1e-9) & (pts[:, 0] > 20.0) & (pts[:, 0] < 80.0)
    pts[bend, 1] += 3.0 * np.sin(2 * math.pi * (pts[bend, 0] - 20.0) / 30.0)
    return pts


def hand_made() -> list[Track]:
    """Rings of 6, 12 and 25 m, a stadium of 4.5 m hairpins, an S-bend loop; 3 m wide."""
    return [
        lane_track("ring6", ring(6.0)),
        lane_track("ring12", ring(12.0)),
        lane_track("ring25", ring(25.0)),
        lane_track("hairpins", stadium(50.0, 4.5)),
        lane_track("sbend", s_bend()),
    ]


def write_hand_made(directory: Path) -> list[Path]:
    """Write the hand-made tracks to ``directory`` (created); their paths."""
    directory.mkdir(parents=True, exist_ok=True)
    return [write_track(track, directory / f"{track.name}.yaml") for track in hand_made()]
