"""Compiled kernels (numba) for the planner's per-detection glue.

Why hand-written compiled code exists here: the planning step (classify +
plan + speed profile, issue 5: median <= 0.5 ms with 80 cones in view) runs
on a few dozen cones, where numpy's cost is per call, not per element. With
the numpy glue already tuned, the step measured 0.96-1.03 ms at 80 cones;
a perf profile gave the Python interpreter 34 %, numpy's per-call overhead
23 %, arithmetic 7.6 %, qhull 16 %, malloc 9 %, the k-d tree 3 %. Each
kernel replaces a chain of small numpy calls (masks, outer products,
gathers, argmins, a Python walk) with one loop over the elements, compiled
once (``cache=True``: later processes load the machine code from the cache
next to each module's file, in this package's ``__pycache__``, or from
``NUMBA_CACHE_DIR`` or the user's cache directory when the package directory
is not writable, e.g. a system install; with no writable cache directory at
all they compile in each process, with a warning per module). Compiling all
of them from a cold cache takes about 12 s on the 2-core development
machine (30-45 s on a slower one of the same kind), loading them from the
cache about 0.25 s.

Every kernel does the same IEEE operations per element, in the same order,
as the numpy code it replaces (no ``fastmath``, so no reassociation or
fused multiply-add): the results are bit for bit the same, including which
element wins a tie (first in the order numpy's ``argmin`` or stable
``argsort`` would see). ``tests/planner/test_speedups.py`` and the tests in
``tests/planner/kernels/`` keep the numpy formulations as references and
compare exactly.

The speed profile's kernels (``profile_limits``, ``profile_passes``) replace
its numpy steps and the Python loops of its friction-ellipse passes: 0.10 ms
per plan on 60 waypoints, 7.6 us compiled (``speed_profile``'s docstring).
Their one exception to "same operations": the jerk limit's cube root is left
to ``numpy.cbrt`` between them, as numpy's SIMD (SVML) cube root is not libm's.

The kernels are called through typed Python wrappers in ``geometry``,
``bridges``, ``midline`` and ``speed_profile``; they take plain
arrays and scalars (no dataclasses) and are untyped for mypy (``numba`` has no
stubs). Integer index arrays are ``intp``, sides ``int8``, flags ``bool``, all
C-contiguous, so each kernel compiles to one specialisation.

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
