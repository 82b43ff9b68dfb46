"""Delaunay bridges: the edges across the track whose midpoints trace its middle.

Steps of ``reference_path_planning`` that work on cones in ``os_sensor``:

0. ``estimate_track``: the width and middle of the track in view, as the
   medians over each cone's nearest valid partner (the checks of step 3) of
   the offset difference and the mean offset. A cone more than
   ``boundary_tolerance`` inside its boundary line (``kernels.boundary_offset``)
   is then dropped: a false positive on the track, or a cone labelled against
   its position (misclassified), would otherwise take the Delaunay edges of
   the real bridges around it.
1. ``virtual_partners``: a cone with no cone of the other side within
   ``partner_radius`` (and ``max_station_gap`` of station), whose offset is
   within ``partner_offset_tolerance`` of its boundary line (a boundary cone,
   not a stray or misclassified one), gets a virtual partner one track width
   across, along the global path's normal at the cone: the estimated width,
   or the nominal 3 m (FS minimum) when fewer than ``min_width_samples`` are
   measured. This fills a gap of missing cones on one side and, when only
   one side is in view, puts the path half that width inside the visible
   boundary.
2. ``delaunay_edges``: the edges of scipy's Delaunay triangulation of all cones.
3. ``find_bridges``: the edges that join a left cone to a right cone (the
   ROS pipeline's ``/delaunay_internal_lines``), each checked:

   - ``offset_left - offset_right`` within [min_track_width, max_track_width],
     and within ``width_tolerance`` of the measured width when there is one:
     a bridge spans the track across the global path. This rejects a
     misclassified cone (it sits on the same side as the cones it would join)
     and a false positive inside the track (too narrow a span).
   - length <= ``max_bridge_length``.
   - station difference <= ``max_station_gap``: both cones belong to the same
     stretch of track. This rejects a bridge across a hairpin's infield to
     the far side, whose cones are near their own, later, stretch of the
     global path.
   - not both ends virtual.

   With ``bridge_selection == "shortest"`` only the valid bridges that are the
   shortest valid bridge of one of their cones are used: the rungs across the
   track. A diagonal's midpoint lies off the middle of a curve (by about
   ``R_in R_out dtheta^2 / (8 R)``, 0.2 m for 5 m spacing at R = 15 m), a
   rung's does not.
4. ``boundary_edges``: same-side edges along one boundary (offset difference
   below the minimum width, same stretch of track), which a sound path may not
   cross.

The functions here are the steps' typed entry points, one per kernel
(``planner.kernels``: compiled, as they run per detection); the planning
step runs them chained (``planner.kernel_chains``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.spatial import Delaunay, QhullError

from conesim.planner import kernels
from conesim.planner.config import MidlineConfig
from conesim.planner.geometry import FloatArray, IntArray, StationAxis

BoolArray = NDArray[np.bool_]

# The fields of an empty cone set (``_no_cones``).
_NO_POINTS = np.zeros((0, 2))
_NO_SIDES = np.zeros(0, dtype=np.int8)
_NO_VALUES = np.zeros(0)
_NO_FLAGS = np.zeros(0, dtype=bool)
_NO_SIMPLICES = np.zeros((0, 3), dtype=np.intc)  # scipy's simplices are C ints


@dataclass(frozen=True, slots=True)
class ConeSet:
    """Cones in ``os_sensor`` with what the classifier learnt about them.

    Attributes:
        points: (n, 2) positions [m].
        side: (n,) +1 left, -1 right.
        offset: (n,) signed offset from the global path, + left [m].
        station: (n,) station along the global path [m].
        tangent: (n, 2) unit global-path direction at the cone, in ``os_sensor``.
        virtual: (n,) True for a virtual partner.
        axis: the global path's station axis.
    """

    points: FloatArray
    side: NDArray[np.int8]
    offset: FloatArray
    station: FloatArray
    tangent: FloatArray
    virtual: BoolArray
    axis: StationAxis

    def __len__(self) -> int:
        return len(self.points)

    def located(self) -> tuple[FloatArray, NDArray[np.int8], FloatArray, FloatArray]:
        """(points, side, offset, station): the arrays the kernels take first, in that order."""
        return self.points, self.side, self.offset, self.station

    def select(self, keep: BoolArray | IntArray) -> ConeSet:
        """The cones where ``keep`` (mask or indices)."""
        if keep.dtype == np.bool_:  # compress and take: faster than [] on (n, 2)
            return ConeSet(
                points=self.points.compress(keep, axis=0),
                side=self.side.compress(keep),
                offset=self.offset.compress(keep),
                station=self.station.compress(keep),
                tangent=self.tangent.compress(keep, axis=0),
                virtual=self.virtual.compress(keep),
                axis=self.axis,
            )
        return ConeSet(
            points=self.points.take(keep, axis=0),
            side=self.side.take(keep),
            offset=self.offset.take(keep),
            station=self.station.take(keep),
            tangent=self.tangent.take(keep, axis=0),
            virtual=self.virtual.take(keep),
            axis=self.axis,
        )


@dataclass(frozen=True, slots=True)
class Bridges:
    """Left-right Delaunay edges and their checks.

    Attributes:
        left: (m,) index of each bridge's left cone.
        right: (m,) index of each bridge's right cone.
        length: (m,) [m].
        valid: (m,) passes the checks.
        used: (m,) valid and selected for the midline.
        midpoints: (m, 2) [m].
        station: (m,) station of each midpoint [m].
    """

    left: IntArray
    right: IntArray
    length: FloatArray
    valid: BoolArray
    used: BoolArray
    midpoints: FloatArray
    station: FloatArray


@dataclass(frozen=True, slots=True)
class PairTable:
    """Every (left, right) pair of real cones, for the width and partner searches.

    Attributes:
        left: (a,) indices of the left cones.
        right: (b,) indices of the right cones.
        dist: (a, b) distance [m] where ``same_stretch``, inf elsewhere (never used).
        same_stretch: (a, b) station gap <= ``max_station_gap``.
        span: (a, b) offset of the left cone minus offset of the right one [m].
        middle: (a, b) mean of the two offsets [m].
    """

    left: IntArray
    right: IntArray
    dist: FloatArray
    same_stretch: BoolArray
    span: FloatArray
    middle: FloatArray


def pair_table(cones: ConeSet, config: MidlineConfig) -> PairTable:
    """The (left, right) tables of :class:`PairTable` (compiled: ``kernels.pair_table``)."""
    axis = cones.axis
    return PairTable(
        *kernels.pair_table(
            *cones.located(),
            axis.length,
            axis.closed,
            config.max_station_gap,
        )
    )


@dataclass(frozen=True, slots=True)
class TrackEstimate:
    """The track in view, as seen across it.

    Attributes:
        width: track width [m].
        centre: offset of the track's middle from the global path, + left [m].
        measured: False when too few samples: the nominal width, centre 0.
    """

    width: float
    centre: float
    measured: bool


def estimate_track(pairs: PairTable, config: MidlineConfig) -> TrackEstimate:
    """Median width and centre offset of the track in view.

    Each cone's nearest valid partner (other side, span, length and station
    checks of ``find_bridges``) gives one sample of each: the offset
    difference and the mean offset. Fewer than ``min_width_samples`` samples
    give the nominal width and the global path as the middle. Compiled:
    ``kernels.estimate_track``.
    """
    width, centre, measured = kernels.estimate_track(
        pairs.dist, pairs.same_stretch, pairs.span, pairs.middle, config.view_settings
    )
    return TrackEstimate(float(width), float(centre), bool(measured))


def virtual_partners(
    cones: ConeSet, pairs: PairTable, config: MidlineConfig, track: TrackEstimate
) -> ConeSet:
    """Step 1: virtual partners for cones with nobody across the track.

    Args:
        cones: the real cones.
        pairs: their pair table.
        config: the settings.
        track: the width and middle in view.

    Returns:
        The virtual cones (possibly none).
    """
    # Nobody across within ``partner_radius``, and on its boundary line (a
    # stray or misclassified cone gets no partner): compiled.
    need = kernels.partners_needed(
        cones.side,
        cones.offset,
        pairs.left,
        pairs.right,
        pairs.same_stretch,
        pairs.dist,
        track.centre,
        track.width,
        config.partner_settings,
    )
    if len(need) == 0:
        return _no_cones(cones.axis)
    # One width across, along the left normal (-t_y, t_x): compiled.
    points, side, offset = kernels.partner_points(
        cones.points, cones.side, cones.offset, cones.tangent, need, track.width
    )
    return ConeSet(
        points=points,
        side=side,
        offset=offset,
        station=cones.station.take(need),
        tangent=cones.tangent.take(need, axis=0),
        virtual=np.ones(len(need), dtype=bool),
        axis=cones.axis,
    )


def _no_cones(axis: StationAxis) -> ConeSet:
    """An empty cone set (sharing arrays of no element, which nothing can change)."""
    return ConeSet(_NO_POINTS, _NO_SIDES, _NO_VALUES, _NO_VALUES, _NO_POINTS, _NO_FLAGS, axis)


def delaunay_simplices(points: FloatArray) -> NDArray[np.intc]:
    """The triangles (k, 3) of scipy's Delaunay triangulation of (n, 2) points.

    Fewer than three points, or points all on one line, have no
    triangulation: no triangles.
    """
    if len(points) < 3:
        return _NO_SIMPLICES
    try:
        simplices: NDArray[np.intc] = Delaunay(points).simplices
    except QhullError:
        return _NO_SIMPLICES
    return simplices


def delaunay_edges(points: FloatArray) -> IntArray:
    """Step 2: unique edges (e, 2), i < j, of the Delaunay triangulation of (n, 2) points.

    Fewer than three points, or points all on one line, have no triangulation:
    two points give their one edge, otherwise no edges.
    """
    # Each vertex's neighbours j > i, in the order of scipy's
    # ``vertex_neighbor_vertices`` lists, built from the simplices (compiled).
    edges: IntArray = kernels.delaunay_edges(delaunay_simplices(points), len(points))
    return edges


def find_bridges(
    cones: ConeSet, edges: IntArray, config: MidlineConfig, track: TrackEstimate | None = None
) -> Bridges:
    """Step 3: the left-right edges, their checks, selection and midpoints.

    Args:
        cones: real and virtual cones.
        edges: (e, 2) Delaunay edges.
        config: the checks.
        track: the width in view; its width is checked only when measured.
    """
    check_width = track is not None and track.measured
    left, right, length, valid, used, midpoints, station = kernels.find_bridges(
        edges,
        *cones.located(),
        cones.virtual,
        cones.axis.length,
        cones.axis.closed,
        check_width,
        track.width if track is not None else 0.0,
        config.bridge_settings,
    )
    return Bridges(left, right, length, valid, used, midpoints, station)


def boundary_edges(cones: ConeSet, edges: IntArray, config: MidlineConfig) -> IntArray:
    """Step 4: same-side edges (e, 2) that run along one boundary of one stretch of track."""
    rows = kernels.boundary_edges(
        edges,
        cones.side,
        cones.offset,
        cones.station,
        cones.axis.length,
        cones.axis.closed,
        config.bridge_settings,
    )
    return edges.take(rows, axis=0)
