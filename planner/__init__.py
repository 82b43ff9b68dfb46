"""Planner: cone side classification, Delaunay midline, speed profile, pure pursuit.

The ROS pipeline's nodes as plain functions, and one class wiring them at their rates:

- :func:`classify_cones_by_side` (``classify``): detections -> left/right cones
  in ``reference``.
- :func:`reference_path_planning` (``midline``): left/right cones -> the local
  path in ``os_sensor`` with waypoint speeds, bridge lines and midpoints.
- :func:`speed_profile` (``speed_profile``): curvature, drive and brake limits.
- :func:`pure_pursuit` (``pure_pursuit``) and :class:`SpeedController`
  (``speed_control``): steering and acceleration commands.
- :class:`Autopilot` (``autopilot``): all of it, from messages and the frame tree.

The per-detection loops of classification and planning are compiled with
numba (``kernels``; compiled on first use, then loaded from numba's cache).

The planner sees only what a real car's software sees: messages, the frame
tree and the global path. It never imports ``sim``.
"""

from __future__ import annotations

from conesim.core.projection import Projection
from conesim.planner.autopilot import Autopilot
from conesim.planner.classify import LEFT, RIGHT, ClassifiedCones, classify_cones_by_side
from conesim.planner.config import (
    AutopilotConfig,
    ClassifierConfig,
    MidlineConfig,
    PurePursuitConfig,
    SpeedControlConfig,
    SpeedProfileConfig,
)
from conesim.planner.geometry import PathProjector
from conesim.planner.messages import (
    BridgeLines,
    ConeMarker,
    ControlCommand,
    LocalPath,
    Midpoints,
    Waypoints,
)
from conesim.planner.midline import (
    LocalPlan,
    PlanStatus,
    carry_path_forward,
    reference_path_planning,
)
from conesim.planner.pure_pursuit import SteeringResult, lookahead_distance, pure_pursuit
from conesim.planner.speed_control import SpeedController, target_on_path
from conesim.planner.speed_profile import speed_profile

__all__ = [
    "LEFT",
    "RIGHT",
    "Autopilot",
    "AutopilotConfig",
    "BridgeLines",
    "ClassifiedCones",
    "ClassifierConfig",
    "ConeMarker",
    "ControlCommand",
    "LocalPath",
    "LocalPlan",
    "MidlineConfig",
    "Midpoints",
    "PathProjector",
    "PlanStatus",
    "Projection",
    "PurePursuitConfig",
    "SpeedControlConfig",
    "SpeedController",
    "SpeedProfileConfig",
    "SteeringResult",
    "Waypoints",
    "carry_path_forward",
    "classify_cones_by_side",
    "lookahead_distance",
    "pure_pursuit",
    "reference_path_planning",
    "speed_profile",
    "target_on_path",
]
