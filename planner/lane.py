"""Step 5b of ``reference_path_planning``: the path kept inside the lane, with the car's body.

The midline runs through the bridges' midpoints, the middle of the lane.
Pure pursuit steers the rear axle along it, and the car's body reaches half
its width to each side, farther outside a tight turn, where the front end
sweeps out (``kernels.lane_room``): in a hairpin of 3 m lane-centre radius
at full lock (rear axle on 3.0 m), the front corner runs on
sqrt(3.7^2 + 2.28^2) = 4.35 m, 0.15 m inside the outer cones' 4.5 m. So the
path is moved along its normals, within the room the boundary edges leave
less the body's clearance, towards the smoothest path
(``kernels.lane_path``, an elastic band): it uses the lane's width in a
corner, and where the fitted spline ran closer to a cone than the body
allows, it is pushed back into the lane. Where a boundary edge is missing
(a knocked cone's gap, the end of the view), the room is measured to the
lane's half width from the path, as if the line ran on: the band does not
draw the path out through the gap.
"""

from __future__ import annotations

import numpy as np

from conesim.planner import kernels
from conesim.planner.bridges import TrackEstimate
from conesim.planner.config import MidlineConfig
from conesim.planner.geometry import FloatArray


def keep_in_lane(
    path: FloatArray, boundary: FloatArray, track: TrackEstimate, config: MidlineConfig
) -> FloatArray:
    """The (n, 2) path [m] moved into the lane less the car's body (module docstring).

    Args:
        path: the fitted path in ``os_sensor`` [m].
        boundary: (e, 2, 2) the boundary edges [m] (``bridges_and_midpoints``).
        track: the lane's width in view (its half is the room where no edge is met).
        config: the body, its clearance and the band's sweeps.
    """
    lane = config.lane_settings
    if not config.keep_in_lane or len(path) < 3:
        return path
    segments = np.ascontiguousarray(boundary, dtype=float).reshape(-1, 2, 2)
    left, right, normal = kernels.lane_room(path, segments, 0.5 * track.width, lane)
    moved: FloatArray = kernels.lane_path(path, left, right, normal, lane)
    return moved
