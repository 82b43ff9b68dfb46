"""Deriving a track's geometry, layout and start pose from its cones.

``build_geometry`` dispatches on the layout: loops and lanes (lanes.py), the
skidpad (skidpad.py). ``detect_layout`` tells them apart for formats that do
not say (fssim, EUFS, FSDS); ``derive_start_pose`` places the car for formats
or files that give no start pose.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from conesim.core.polyline import Polyline
from conesim.core.pose import Pose2D
from conesim.tracks.derived import TrackGeometry
from conesim.tracks.errors import TrackGeometryError
from conesim.tracks.kinds import ConeKind, Layout
from conesim.tracks.lanes import MIN_SIDE_CONES, lane_geometry
from conesim.tracks.ordering import order_loop
from conesim.tracks.skidpad import find_circles, skidpad_geometry

FloatArray = NDArray[np.float64]

OPEN_GAP_FRACTION = 0.2  # a boundary whose longest gap exceeds this share of its tour is open
MAX_CONES = 5000  # more cones than this is not a cone track (ordering is O(n^2) in memory)


def build_geometry(
    cones: FloatArray, kinds: tuple[ConeKind, ...], layout: Layout, start_pose: Pose2D | None
) -> TrackGeometry:
    """The centreline, widths, boundaries and timing lines of a track.

    Args:
        cones: (n, 2) cone positions in `reference` [m].
        kinds: (n,) their kinds.
        layout: closed, open or skidpad.
        start_pose: where the car starts; None derives the driving direction
            from the cone colours (blue on the left).

    Raises:
        TrackGeometryError: cones from which no geometry can be derived.
    """
    if len(cones) > MAX_CONES:
        raise TrackGeometryError(f"{len(cones)} cones: more than {MAX_CONES} is not a cone track")
    try:
        if layout == Layout.SKIDPAD:
            return skidpad_geometry(cones, kinds, start_pose)
        return lane_geometry(cones, kinds, layout == Layout.CLOSED, start_pose)
    except (ValueError, ArithmeticError, np.linalg.LinAlgError) as exc:
        if isinstance(exc, TrackGeometryError):
            raise
        raise TrackGeometryError(f"cannot derive the track geometry: {exc}") from None


def detect_layout(cones: FloatArray, kinds: tuple[ConeKind, ...]) -> Layout:
    """Guess the layout of a track file that does not state it.

    Skidpad: the blue and yellow cones form two pairs of concentric rings.
    Open: the shortest closed tour through the blue cones (and through the
    yellow ones) has one gap longer than 20 % of the tour, the jump back from
    the end of a lane to its start. Otherwise closed.
    """
    if len(cones) > MAX_CONES:
        raise TrackGeometryError(f"{len(cones)} cones: more than {MAX_CONES} is not a cone track")
    kind = np.array([str(k) for k in kinds])
    blue, yellow = cones[kind == ConeKind.BLUE], cones[kind == ConeKind.YELLOW]
    if find_circles(blue, yellow) is not None:
        return Layout.SKIDPAD
    if len(blue) < MIN_SIDE_CONES or len(yellow) < MIN_SIDE_CONES:
        return Layout.CLOSED  # the geometry will say what is missing
    if _has_open_gap(blue) and _has_open_gap(yellow):
        return Layout.OPEN
    return Layout.CLOSED


def _has_open_gap(points: FloatArray) -> bool:
    tour = points[order_loop(points)]
    steps = np.hypot(*np.diff(np.vstack([tour, tour[:1]]), axis=0).T)
    return bool(steps.max() > OPEN_GAP_FRACTION * Polyline(tour, True).end_station)


def derive_start_pose(cones: FloatArray, kinds: tuple[ConeKind, ...], layout: Layout) -> Pose2D:
    """A start pose for a track that comes without one.

    The car stands at the middle of the start/finish line between the big
    orange cones, heading along the centreline in the direction that puts
    the blue cones on the left.

    Raises:
        TrackGeometryError: there are no big orange cones to place it by, or
            no geometry can be derived.
    """
    if not any(k == ConeKind.BIG_ORANGE for k in kinds):
        raise TrackGeometryError(
            "no start pose given and no big orange cones to derive one from "
            "(add a start pose, or big orange cones at the start line)"
        )
    geometry = build_geometry(cones, kinds, layout, None)
    centre = geometry.start_finish.mean(axis=0)
    yaw = math.atan2(float(geometry.direction[1]), float(geometry.direction[0]))
    return Pose2D(float(centre[0]), float(centre[1]), yaw)
