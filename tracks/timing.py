"""Timing lines: start/finish lines between big orange cones.

FS puts big orange cones at the start/finish line, usually two on each side
(REFERENCES.md: 4 of them; some layouts have 2). Along the centreline the big
orange cones form clusters, one per timing line (acceleration has two: start
and the 75 m finish). A line runs from the mean of a cluster's cones on the
left to the mean of those on the right. A cluster with cones on one side only,
or a track without big orange cones, gets a line perpendicular to the
centreline spanning the boundaries.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from conesim.core.polyline import Polyline
from conesim.tracks.midline import Midline

FloatArray = NDArray[np.float64]

CLUSTER_GAP = 5.0  # [m] big orange cones further apart than this along the track are separate lines


@dataclass(frozen=True)
class TimingLine:
    """A timing line across the track.

    Attributes:
        s: arc length of its crossing with the dense centreline [m].
        ends: (2, 2) its left and right end points [m].
    """

    s: float
    ends: FloatArray


def big_orange_lines(big: FloatArray, mid: Midline) -> list[TimingLine]:
    """One timing line per cluster of big orange cones, ordered by ``s``.

    Args:
        big: (b, 2) big orange cones [m].
        mid: the dense centreline and boundary curves.
    """
    if len(big) == 0:
        return []
    proj = mid.line.project(big, extend_ends=not mid.closed)
    s, lateral = proj.station, proj.lateral
    lines = []
    for members in _clusters(s, mid.line.end_station, mid.closed):
        left, right = big[members][lateral[members] > 0], big[members][lateral[members] <= 0]
        if len(left) and len(right):
            ends = np.vstack([left.mean(axis=0), right.mean(axis=0)])
            centre_s = mid.line.project(ends.mean(axis=0)).station
            lines.append(TimingLine(float(centre_s[0]), ends))
        else:
            lines.append(perpendicular_line(mid, _circular_mean(s[members], mid)))
    return sorted(lines, key=lambda line: line.s)


def perpendicular_line(mid: Midline, s: float) -> TimingLine:
    """The line across the track perpendicular to the centreline at arc length ``s`` [m]."""
    line = mid.line
    total = line.end_station
    s = s % total if mid.closed else min(max(s, 0.0), total)
    point = line.at([s])
    tangent = Polyline(line.at([s - 0.05, s, s + 0.05])).tangents()[1]
    normal = np.array([-tangent[1], tangent[0]])
    dl, dr = mid.half_widths(point)
    ends = np.vstack([point[0] + normal * dl[0], point[0] - normal * dr[0]])
    return TimingLine(s, ends)


def _clusters(s: FloatArray, total: float, closed: bool) -> list[NDArray[np.intp]]:
    order = np.argsort(s)
    gaps = np.diff(s[order])
    if closed:
        gaps = np.append(gaps, s[order[0]] + total - s[order[-1]])
        first = (int(np.argmax(gaps)) + 1) % len(s)
        order = np.roll(order, -first)
        gaps = np.roll(gaps, -first)[:-1]
    breaks = np.nonzero(gaps > CLUSTER_GAP)[0] + 1
    return [np.asarray(c, dtype=np.intp) for c in np.split(order, breaks)]


def _circular_mean(s: FloatArray, mid: Midline) -> float:
    if not mid.closed:
        return float(np.mean(s))
    total = mid.line.end_station
    angle = np.angle(np.mean(np.exp(2j * np.pi * s / total)))
    return float(angle / (2 * np.pi) * total) % total
