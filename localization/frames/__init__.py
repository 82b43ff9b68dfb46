"""The frame tree with tf2 semantics (ros2/geometry2), in Python.

The vehicle's tree (spec 000, ``shared/ARCHITECTURE.md``)::

    reference --(dynamic, 20 Hz)--> gps_antenna --(static: z = -0.1 m)--> os_sensor

Usage::

    buffer = Buffer()
    buffer.set_transform(
        TransformStamped.from_pose2d("reference", "gps_antenna", t, Pose2D(x, y, yaw))
    )
    buffer.set_transform_static(
        TransformStamped("gps_antenna", "os_sensor", 0.0, translation=(0.0, 0.0, -0.1))
    )
    cones_ref = buffer.transform_points("reference", "os_sensor", cones_sensor, LATEST)
    # Time travel through the fixed frame: a path planned in os_sensor at t_old,
    # in os_sensor at t_now.
    path_now = buffer.transform_points_full(
        "os_sensor", t_now, "os_sensor", path_old, t_old, "reference"
    )

Modules: :mod:`.transform` (the stamped transform, composition, 2D helpers),
:mod:`.rigid` (the float maths of the hot path), :mod:`.cache` (one link's
history, interpolation and pruning), :mod:`.buffer` (the tree and lookups),
:mod:`.errors`.
"""

from __future__ import annotations

from conesim.localization.frames.buffer import DEFAULT_AUTHORITY, LATEST, Buffer, FrameInfo
from conesim.localization.frames.cache import DEFAULT_CACHE_TIME, StaticCache, TimeCache
from conesim.localization.frames.errors import (
    ConnectivityError,
    ExtrapolationError,
    FrameNotFoundError,
    FrameTreeError,
    InvalidArgumentError,
    InvalidTransformError,
    TransformError,
)
from conesim.localization.frames.transform import (
    QUATERNION_TOLERANCE,
    TransformStamped,
    strip_leading_slash,
    transform_points_rigid,
)

__all__ = [
    "DEFAULT_AUTHORITY",
    "DEFAULT_CACHE_TIME",
    "LATEST",
    "QUATERNION_TOLERANCE",
    "Buffer",
    "ConnectivityError",
    "ExtrapolationError",
    "FrameInfo",
    "FrameNotFoundError",
    "FrameTreeError",
    "InvalidArgumentError",
    "InvalidTransformError",
    "StaticCache",
    "TimeCache",
    "TransformError",
    "TransformStamped",
    "strip_leading_slash",
    "transform_points_rigid",
]
