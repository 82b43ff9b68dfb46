"""The planning step's compiled stretches: consecutive step kernels chained in one call.

``reference_path_planning`` alternates compiled steps (``planner.kernels``)
with scipy (``Delaunay``, ``splprep``), which stay Python calls. Each
function here runs the steps between two scipy calls in one compiled call,
as a call into compiled code costs about as much as a step's loop on a few
dozen cones. They call the very step kernels the steps' typed wrappers call
(numba compiles calls between jitted functions directly), so the numbers
are theirs, and each step stays a function that tests can call alone
(``tests/planner/test_kernel_chains.py``).

- ``plan_cones``: step 2 (``kernels.boundary_cones``) and step 3a's virtual
  partners (``kernels.partners_needed``, ``kernels.partner_points``), joined
  after the real cones.
- ``project_around`` (classification): the window's origin, then
  ``project_window`` (``PathProjector.project_around``).
- ``project_window``: the window's test and the search with its projections
  (``PathProjector.project``).
- ``plan_midpoints``: after the triangulation, step 3's edges and bridges
  (``kernels.delaunay_edges``, ``kernels.find_bridges``), step 4's ordering
  (``kernels.ordered_midpoints``) and the boundary edges step 6 checks against
  (``kernels.boundary_edges``, gathered into segments).
- ``check_and_limit``: after the spline, step 6's arc length, start distance
  and crossing test (``kernels.arc_length``, ``kernels.crosses_boundary``) and step 7's
  speed limits (``kernels.profile_limits``; the cube root and the passes
  follow in ``speed_profile.profile_speeds``).

The arguments are arrays, scalars and the settings groups of
``planner.settings`` (``kernels``' conventions); the callers are in
``midline`` and ``geometry``. Compiled with numba's on-disk cache like
``kernels`` (``conesim.core.compiled.cached_njit``), which follows edits of
the step kernels too.
"""

from __future__ import annotations

import math

import numpy as np

from conesim.core.compiled import cached_njit
from conesim.planner import kernels


def _probe() -> None:
    """Nothing: what ``cached_njit`` asks numba to cache, from this file's directory."""


_compiled = cached_njit(_probe, "conesim.planner.kernel_chains")


@_compiled
def plan_cones(points, side, offset, station, tangent, length, closed, view, partners):  # noqa: PLR0917
    """Steps 2 and 3a: the boundary cones in view followed by their virtual partners.

    Args:
        points: (n, 2) the cones in ``os_sensor`` [m].
        side: (n,) int8 their sides.
        offset: (n,) their offsets from the global path [m].
        station: (n,) their stations [m].
        tangent: (n, 2) the global path's direction at each.
        length: the station axis' length [m].
        closed: whether stations wrap.
        view: step 2's ``settings.ViewSettings`` (``MidlineConfig.view_settings``).
        partners: step 3a's ``settings.PartnerSettings``
            (``MidlineConfig.partner_settings``).

    Returns:
        points (k + v, 2), side (k + v,), offset, station, tangent, virtual
        (k kept real cones, then v partners); the track's width and centre
        [m] (nominal and 0 when not measured), measured, and how many cones
        were dropped (n - k).
    """
    keep, left, right, dist, same, _, _, width, centre, measured = kernels.boundary_cones(
        points, side, offset, station, length, closed, view
    )
    k = len(keep)
    real_side = side[keep]
    real_offset = offset[keep]
    real_points = points[keep]
    real_tangent = tangent[keep]
    need = kernels.partners_needed(
        real_side, real_offset, left, right, same, dist, centre, width, partners
    )
    v = len(need)
    p_points, p_side, p_offset = kernels.partner_points(
        real_points, real_side, real_offset, real_tangent, need, width
    )
    out_points = np.empty((k + v, 2))
    out_side = np.empty(k + v, np.int8)
    out_offset = np.empty(k + v)
    out_station = np.empty(k + v)
    out_tangent = np.empty((k + v, 2))
    virtual = np.zeros(k + v, np.bool_)
    for q in range(k + v):
        i = keep[q] if q < k else keep[need[q - k]]
        out_station[q] = station[i]
        out_tangent[q, 0] = tangent[i, 0]
        out_tangent[q, 1] = tangent[i, 1]
        if q < k:
            out_points[q, 0] = points[i, 0]
            out_points[q, 1] = points[i, 1]
            out_side[q] = side[i]
            out_offset[q] = offset[i]
        else:
            out_points[q, 0] = p_points[q - k, 0]
            out_points[q, 1] = p_points[q - k, 1]
            out_side[q] = p_side[q - k]
            out_offset[q] = p_offset[q - k]
            virtual[q] = True
    dropped = len(side) - k
    return (
        out_points,
        out_side,
        out_offset,
        out_station,
        out_tangent,
        virtual,
        width,
        centre,
        measured,
        dropped,
    )


@_compiled
def plan_midpoints(  # noqa: PLR0917
    simplices, points, side, offset, station, virtual, length, closed,
    check_width, width, sensor_station, checks, ordering,
):  # fmt: skip
    """Steps 3 and 4 after the triangulation: bridges, boundary segments, ordered midpoints.

    Args:
        simplices: (t, 3) scipy's Delaunay triangles of ``points`` (C ints).
        points: (n, 2) real and virtual cones [m] (``plan_cones``).
        side: (n,) int8 their sides.
        offset: (n,) their offsets [m].
        station: (n,) their stations [m].
        virtual: (n,) True for a virtual partner.
        length: the station axis' length [m].
        closed: whether stations wrap.
        check_width: whether the span is checked against ``width``.
        width: the measured width [m].
        sensor_station: the sensor's station [m].
        checks: step 3's ``settings.BridgeSettings``
            (``MidlineConfig.bridge_settings``; the boundary edges use its
            minimum span and station gap).
        ordering: step 4's ``settings.OrderingSettings``
            (``MidlineConfig.ordering_settings``).

    Returns:
        The bridges (left, right, length, valid, used, midpoints, station, as
        ``kernels.find_bridges``), the boundary segments (e, 2, 2) [m], the
        ordered midpoints (m, 2) [m] and their polyline's length [m].
    """
    edges = kernels.delaunay_edges(simplices, len(points))
    left, right, size, valid, used, mid, mid_station = kernels.find_bridges(
        edges, points, side, offset, station, virtual, length, closed, check_width, width, checks
    )
    rows = kernels.boundary_edges(edges, side, offset, station, length, closed, checks)
    boundary = np.empty((len(rows), 2, 2))
    for q in range(len(rows)):
        for end in range(2):
            boundary[q, end, 0] = points[edges[rows[q], end], 0]
            boundary[q, end, 1] = points[edges[rows[q], end], 1]
    ordered = kernels.ordered_midpoints(
        used, mid, mid_station, sensor_station, length, closed, ordering
    )
    path_length = kernels.arc_length(ordered)[-1]
    return left, right, size, valid, used, mid, mid_station, boundary, ordered, path_length


@_compiled
def project_around(  # noqa: PLR0917
    points, table, blocks, size, back, ahead, penalty, has_centre, centre, length, closed, half_max
):  # fmt: skip
    """``PathProjector.project_around`` in one call: the window's origin, the window, the search.

    Without ``has_centre`` the origin is the last point's station on the
    whole path (``kernels.nearest_segments`` and ``kernels.project_rows`` on
    that point); the window [origin - back, origin + ahead] applies when
    ``penalty > 0`` and a segment overlaps it (``kernels.window_overlaps``);
    then every point's search and projection.

    Args:
        points: (n, 2) [m], n >= 1, C-contiguous; the last is the origin's point.
        table, blocks, size, penalty, length, closed, half_max: as
            ``project_window``'s.
        back: the window starts this far behind the origin [m] ...
        ahead: ... and ends this far ahead [m].
        has_centre: whether ``centre`` is the origin's station.
        centre: the origin's station [m] (read when ``has_centre``).

    Returns:
        ``project_window``'s.
    """
    lo = 0.0
    hi = 0.0
    if penalty > 0.0:
        if not has_centre:
            last = points[-1:]
            seg, t, d2 = kernels.nearest_segments(
                last, table, blocks, size, False, 0.0, 0.0, 0.0, length, closed
            )
            centre = kernels.project_rows(last, seg, t, d2, table)[1][0]
        lo = centre - back
        hi = centre + ahead
    return project_window(
        points, table, blocks, size, penalty > 0.0, lo, hi, penalty, length, closed, half_max
    )


@_compiled
def project_window(  # noqa: PLR0917
    points, table, blocks, size, has_window, lo, hi, penalty, length, closed, half_max
):  # fmt: skip
    """``PathProjector.project`` in one call: the window's test, then the search.

    The window [lo, hi] applies when ``has_window``, ``penalty > 0`` and a
    segment overlaps it (``kernels.window_overlaps``); then every point's
    search (``kernels.nearest_segments``, segments outside the window
    ``penalty`` farther) and projection (``kernels.project_rows``).

    Args:
        points: (n, 2) [m], C-contiguous.
        table: the projector's (k, 9) segment table.
        blocks: its (b, 3) bounding circles of ``size`` segments each.
        has_window: whether [lo, hi] is a window to prefer.
        lo: the window's first station [m] ...
        hi: ... and its last [m] (wrapped on a closed path).
        penalty: added to segments outside the window [m]; <= 0: no window.
        length: the path's length [m].
        closed: whether stations wrap.
        half_max: half the longest segment [m].

    Returns:
        ``kernels.nearest_segments``' segments, then ``kernels.project_rows``'
        foot, station, offset, tangent and distance.
    """
    windowed = (
        has_window
        and penalty > 0.0
        and kernels.window_overlaps(lo, hi, table, length, closed, half_max)
    )
    middle = 0.5 * (lo + hi) if windowed else 0.0
    half = 0.5 * (hi - lo) if windowed else 0.0
    seg, t, d2 = kernels.nearest_segments(
        points, table, blocks, size, windowed, middle, half, penalty if windowed else 0.0,
        length, closed,
    )  # fmt: skip
    foot, station, offset, tangent, distance = kernels.project_rows(points, seg, t, d2, table)
    return seg, foot, station, offset, tangent, distance


@_compiled
def check_and_limit(path, boundary, profile, limits):
    """Step 6's numbers (arc length, start distance, crossing) and step 7's limits.

    Args:
        path: (p, 2) the fitted path [m], C-contiguous.
        boundary: (e, 2, 2) the boundary segments it may not cross [m].
        profile: whether to compute the speed profile's limits.
        limits: step 7's ``settings.LimitSettings``
            (``SpeedProfileConfig.limit_settings``).

    Returns:
        The arc length (max(p, 1),) [m] (``kernels.arc_length``) and its last
        value [m], the first point's distance from the origin [m]
        (``np.hypot``; NaN without points), whether the path crosses a
        boundary segment (``kernels.crosses_boundary``), and
        ``kernels.profile_limits``' (s, kappa, v, ratio) given that arc length
        (the arc length four times, unread, without ``profile`` or points).
    """
    s = kernels.arc_length(path)
    start = np.hypot(path[0, 0], path[0, 1]) if len(path) > 0 else math.nan
    crosses = kernels.crosses_boundary(path, boundary)
    if profile and len(path) > 0:
        return s, s[len(s) - 1], start, crosses, kernels.profile_limits(path, s, True, limits)
    return s, s[len(s) - 1], start, crosses, (s, s, s, s)
