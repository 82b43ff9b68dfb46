"""Compiled kernels (numba) for the planner's per-detection steps.

Why compiled: the planning step runs per detection on a few dozen cones,
where numpy's cost is per call, not per element; each kernel is one loop
over the elements in place of a chain of small numpy calls. They are
compiled on first use with numba's on-disk cache (``cache=True``, through
``conesim.core.compiled.cached_njit``: beside each module's file, or under
``NUMBA_CACHE_DIR`` or the user's cache directory when the package
directory is not writable; with no writable cache directory at all they
compile in each process, with a warning per module).

Every kernel does the same IEEE operations per element, in the same order,
as the numpy code it was written from (no ``fastmath``, so no reassociation
or fused multiply-add): the results are bit for bit the same, including
which element wins a tie (first in the order numpy's ``argmin`` or stable
``argsort`` would see). That numpy code is kept as the reference in
``tests/planner/`` (``test_speedups.py`` and ``kernels/``), which compares
exactly. The one exception: the jerk limit's cube root is left to
``numpy.cbrt`` between ``profile_limits`` and ``profile_passes``, as numpy's
SIMD (SVML) cube root is not libm's.

The kernels are called through typed Python wrappers (in ``geometry``,
``classify``, ``bridges``, ``midline``, ``spline`` and ``speed_profile``),
chained with their neighbours in ``planner.kernel_chains``, or by other
kernels (``sub_table``, ``median``, ``boundary_offset``, ``polyline_crosses``,
``start_index``, ``chain_nearest``). Kernels take arrays, scalars and the
settings groups of ``planner.settings`` (named tuples, read by field), and
are untyped for mypy (``numba`` has no stubs). Integer index arrays are
``intp``, sides ``int8``, flags ``bool``, all C-contiguous, so each kernel
compiles to one specialisation.

One module per concept, each compiled with its own cache (numba caches per
source file); every kernel is re-exported here, so callers write
``kernels.<name>``:

- ``projection``: projection onto the global path (``nearest_segments``,
  ``project_rows``, ``window_overlaps``).
- ``cone_points``: ground points, sides of the path, tangent tips
  (``ground_points``, ``side_of_path``, ``with_tips``).
- ``track``: step 2, the cones in view, the pair table and the track
  estimate (``in_view``, ``pair_table``, ``sub_table``, ``median``,
  ``estimate_track``, ``boundary_offset``, ``boundary_cones``).
- ``partners``: step 3a, virtual partners (``partners_needed``,
  ``partner_points``).
- ``bridges``: step 3, Delaunay edges, bridges and boundary edges
  (``delaunay_edges``, ``find_bridges``, ``boundary_edges``).
- ``ordering``: step 4, the midpoints in driving order (``start_index``,
  ``chain_nearest``, ``ordered_midpoints``).
- ``spline``: step 5, the B-spline sampled along its length (``spline_path``).
- ``polyline``: step 6, arc length and crossing tests (``arc_length``,
  ``polyline_crosses``, ``crosses_boundary``).
- ``speed_profile``: step 7, the profile's limits and passes
  (``profile_limits``, ``profile_passes``).
- ``_common`` (private): the station wrap and a mask's rows, shared by the
  modules above.
"""

from __future__ import annotations

from conesim.planner.kernels.bridges import boundary_edges, delaunay_edges, find_bridges
from conesim.planner.kernels.cone_points import ground_points, side_of_path, with_tips
from conesim.planner.kernels.lane import lane_path, lane_room
from conesim.planner.kernels.ordering import chain_nearest, ordered_midpoints, start_index
from conesim.planner.kernels.partners import partner_points, partners_needed
from conesim.planner.kernels.polyline import arc_length, crosses_boundary, polyline_crosses
from conesim.planner.kernels.projection import nearest_segments, project_rows, window_overlaps
from conesim.planner.kernels.speed_profile import profile_limits, profile_passes
from conesim.planner.kernels.spline import spline_path
from conesim.planner.kernels.track import (
    boundary_cones,
    boundary_offset,
    estimate_track,
    in_view,
    median,
    pair_table,
    sub_table,
)

__all__ = [
    "arc_length",
    "boundary_cones",
    "boundary_edges",
    "boundary_offset",
    "chain_nearest",
    "crosses_boundary",
    "delaunay_edges",
    "estimate_track",
    "find_bridges",
    "ground_points",
    "in_view",
    "lane_path",
    "lane_room",
    "median",
    "nearest_segments",
    "ordered_midpoints",
    "pair_table",
    "partner_points",
    "partners_needed",
    "polyline_crosses",
    "profile_limits",
    "profile_passes",
    "project_rows",
    "side_of_path",
    "spline_path",
    "start_index",
    "sub_table",
    "window_overlaps",
    "with_tips",
]
