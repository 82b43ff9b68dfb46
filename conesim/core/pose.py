"""Planar pose type and angle helpers shared by every layer.

A leaf module (numpy only), so that ``tracks`` and ``sim`` may use it without
pulling in the rest of ``localization``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray


def wrap_angle(angle: ArrayLike) -> NDArray[np.float64] | float:
    """Wrap angles into [-pi, pi).

    Args:
        angle: scalar or array [rad].

    Returns:
        The wrapped angle(s) [rad]; a float for a scalar input.

    >>> round(wrap_angle(3 * math.pi / 2), 12)
    -1.570796326795
    >>> wrap_angle(math.pi)
    -3.141592653589793
    >>> wrap_angle(np.array([0.0, 2 * math.pi + 0.5]))
    array([0. , 0.5])
    """
    if type(angle) is float:  # the same arithmetic on a float, without numpy's overhead
        return (angle + math.pi) % (2.0 * math.pi) - math.pi
    a = np.asarray(angle, dtype=float)
    wrapped = (a + math.pi) % (2.0 * math.pi) - math.pi
    if wrapped.ndim == 0:
        return float(wrapped)
    return wrapped


@dataclass(frozen=True, slots=True)
class Pose2D:
    """A pose in the plane.

    Attributes:
        x: position east (or forward in a vehicle frame) [m].
        y: position north (or left) [m].
        yaw: heading, counter-clockwise from +x [rad] (REP 103).
    """

    x: float
    y: float
    yaw: float

    def __post_init__(self) -> None:
        # One test on the fast path: poses are built every physics step.
        if math.isfinite(self.x) and math.isfinite(self.y) and math.isfinite(self.yaw):
            return
        for name in ("x", "y", "yaw"):
            value = getattr(self, name)
            if not math.isfinite(value):
                raise ValueError(f"Pose2D.{name} must be finite, got {value!r}")

    @property
    def xy(self) -> NDArray[np.float64]:
        """Position as a (2,) array [m]."""
        return np.array([self.x, self.y])

    def transform_points(self, points: ArrayLike) -> NDArray[np.float64]:
        """Map (n, 2) points (or one, (2,)) from this pose's frame into its parent frame [m]."""
        p = _points_2d(points, "transform_points")
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        rot = np.array([[c, -s], [s, c]])
        return p @ rot.T + self.xy

    def inverse_transform_points(self, points: ArrayLike) -> NDArray[np.float64]:
        """Map (n, 2) points (or one, (2,)) from the parent frame into this pose's frame [m]."""
        p = _points_2d(points, "inverse_transform_points") - self.xy
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        rot = np.array([[c, -s], [s, c]])
        return p @ rot


def _points_2d(points: ArrayLike, where: str) -> NDArray[np.float64]:
    """``points`` as (n, 2) floats: (n, 2) as given, (2,) as one row, none as
    (0, 2); else a ValueError."""
    p = np.asarray(points, dtype=float)
    if p.shape == (2,):
        return p.reshape(1, 2)
    if p.size == 0:  # no points, e.g. an empty list
        return p.reshape(0, 2)
    if p.ndim != 2 or p.shape[1] != 2:
        raise ValueError(f"Pose2D.{where}: points must be (n, 2) [m], got shape {p.shape}")
    return p
