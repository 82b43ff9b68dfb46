"""Cones along a loop's edges, spaced by curvature, and the start/finish gate.

REFERENCES.md, "Formula Student tracks": cone spacing <= 5 m along each
side; 4 big orange cones at the start/finish line. Cones stand closer in
corners, so that the boundary drawn through them follows the bend: the
spacing is 0.9 sqrt(R) on an edge of local radius R, from ``min_spacing``
in the tightest corners to ``max_spacing`` on straights.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray
from scipy.ndimage import maximum_filter1d

FloatArray = NDArray[np.float64]

MAX_SPACING = 4.5  # [m] cone spacing on straights (FS: <= 5 m)
MIN_SPACING = 1.5  # [m] cone spacing in the tightest corners
BIG_ORANGE_HALF_GAP = 0.3  # [m] big orange cones stand +-0.3 m from the line (fssim)


def cone_spacing(
    radius: FloatArray, min_spacing: float = MIN_SPACING, max_spacing: float = MAX_SPACING
) -> FloatArray:
    """Cone spacing [m] on a boundary of local radius ``radius`` [m]: 0.9 sqrt(R),
    clipped to [min_spacing, max_spacing] (FS: <= 5 m)."""
    return np.clip(0.9 * np.sqrt(radius), min_spacing, max_spacing)


def place_cones(
    edge: FloatArray,
    edge_kappa: FloatArray,
    min_spacing: float = MIN_SPACING,
    max_spacing: float = MAX_SPACING,
    window: int = 1,
) -> FloatArray:
    """Cones along a closed edge (n, 2) [m], starting at its first point.

    The cone density 1/spacing is integrated along the edge and the cones
    stand at equal steps of it, so that spacing follows the curvature
    ``edge_kappa`` (n,) [1/m] and the last gap equals its neighbours. With
    ``window`` > 1 samples, the spacing follows the tightest curvature
    within the window around each point: an S-bend's cones stay close
    through its change of direction, where the curvature passes zero.
    """
    seg = np.hypot(*np.diff(np.vstack([edge, edge[:1]]), axis=0).T)
    tightest = maximum_filter1d(np.abs(edge_kappa), window, mode="wrap")
    radius = 1.0 / np.maximum(tightest, 1e-6)
    density = 1.0 / cone_spacing(radius, min_spacing, max_spacing)
    cum = np.concatenate([[0.0], np.cumsum(density * seg)])
    count = math.ceil(cum[-1])
    s_edge = np.concatenate([[0.0], np.cumsum(seg)])
    s = np.interp(np.arange(count) * cum[-1] / count, cum, s_edge)
    ring = np.vstack([edge, edge[:1]])
    return np.column_stack([np.interp(s, s_edge, ring[:, 0]), np.interp(s, s_edge, ring[:, 1])])


def gate_cones(
    point: FloatArray, heading: float, half_width: float, offset: float = 0.0
) -> FloatArray:
    """(4, 2) big orange cones [m] of a start/finish line at ``point`` (2,) [m].

    Two on each side, ``BIG_ORANGE_HALF_GAP`` before and after the line,
    ``offset`` [m] outside the lane's edge (``half_width`` [m] from its
    centre), left side first: on real tracks the gate stands wider than the
    lane, for the timekeeping.
    """
    along = np.array([math.cos(heading), math.sin(heading)])
    normal = np.array([-along[1], along[0]])
    cones = [
        point + side * (half_width + offset) * normal + d * along
        for side in (1.0, -1.0)
        for d in (-BIG_ORANGE_HALF_GAP, BIG_ORANGE_HALF_GAP)
    ]
    return np.array(cones)
