"""The planner's outputs as messages, one per ROS pipeline topic.

| ROS topic | type here | frame |
|---|---|---|
| ``/left_cone_marker``, ``/right_cone_marker`` | :class:`ConeMarker` | ``reference`` |
| ``/local_planned_path`` | :class:`LocalPath` | ``os_sensor`` |
| ``/final_waypoints``, ``/waypoint_speed_bars`` | :class:`Waypoints` | ``os_sensor`` |
| ``/delaunay_internal_lines`` | :class:`BridgeLines` | ``os_sensor`` |
| ``/delaunay_internal_midpoints`` | :class:`Midpoints` | ``os_sensor`` |

and the controller's output, :class:`ControlCommand`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from conesim.core.messages import Header
from conesim.planner.geometry import FloatArray


@dataclass(frozen=True, slots=True)
class ConeMarker:
    """Cones of one side (visualization_msgs/Marker SPHERE_LIST).

    Attributes:
        header: stamp and frame.
        points: (n, 2) [m].
        side: ``"left"`` or ``"right"``.
    """

    header: Header
    points: FloatArray
    side: str


@dataclass(frozen=True, slots=True)
class LocalPath:
    """nav_msgs/Path reduced to the plane.

    Attributes:
        header: planning stamp, frame ``os_sensor``.
        points: (n, 2) positions [m].
        yaw: (n,) heading of the path at each point [rad].
    """

    header: Header
    points: FloatArray
    yaw: FloatArray


@dataclass(frozen=True, slots=True)
class Waypoints:
    """Waypoints with target speeds (the ROS pipeline's ``Waypoint`` list and speed bars).

    Attributes:
        header: planning stamp, frame ``os_sensor``.
        points: (n, 2) [m].
        speeds: (n,) [m/s].
    """

    header: Header
    points: FloatArray
    speeds: FloatArray


@dataclass(frozen=True, slots=True)
class BridgeLines:
    """The Delaunay left-right edges (visualization_msgs/Marker LINE_LIST).

    Attributes:
        header: planning stamp, frame ``os_sensor``.
        lines: (m, 2, 2) [left end, right end] [m].
        used: (m,) whether each edge's midpoint feeds the path.
    """

    header: Header
    lines: FloatArray
    used: NDArray[np.bool_]


@dataclass(frozen=True, slots=True)
class Midpoints:
    """The ordered midpoints the path is fitted through.

    Attributes:
        header: planning stamp, frame ``os_sensor``.
        points: (k, 2) [m].
    """

    header: Header
    points: FloatArray


@dataclass(frozen=True, slots=True)
class ControlCommand:
    """What the autopilot sends to the car.

    Attributes:
        stamp: simulation time [s].
        steering: front wheel angle, + left [rad].
        acceleration: longitudinal acceleration demand, < 0 brakes [m/s^2].
    """

    stamp: float
    steering: float
    acceleration: float
