"""The stamped transform type, its composition, and the 2D helpers.

:class:`TransformStamped` mirrors ROS's ``geometry_msgs/TransformStamped``: a
transform with ``frame_id = A`` and ``child_frame_id = B`` is B's pose in A and
maps points from B into A (``p_A = R(q) p_B + t``), the tf2 convention
(ros2/geometry2; REP 103 for axes and units). The rotation is a unit quaternion
in ROS order (x, y, z, w).

Unlike the ROS message, the value is checked when it is built: the stamp, the
translation and the quaternion must be finite, and the quaternion's norm must
be within :data:`QUATERNION_TOLERANCE` of 1 (it is then normalised exactly).
tf2's ``setTransform`` accepts ``| |q|^2 - 1 | < 1e-2``; this is stricter on
purpose, since a simulator computes its quaternions in float64 and a loosely
normalised one is a bug upstream. Frame names are not checked here: the
buffer strips a leading ``/`` and rejects empty names and self-transforms.

The 2D helpers cover the planar vehicle: :meth:`TransformStamped.from_pose2d`
builds a yaw-only transform at height ``z``, :meth:`TransformStamped.to_pose2d`
keeps x, y and the yaw (Z-Y-X decomposition), dropping z, roll and pitch.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Final

import numpy as np
from numpy.typing import ArrayLike, NDArray

from conesim.core.pose import Pose2D, wrap_angle
from conesim.localization.frames import rigid
from conesim.localization.frames.errors import InvalidArgumentError, InvalidTransformError
from conesim.localization.frames.rigid import Rigid

QUATERNION_TOLERANCE: Final[float] = 1e-6
"""Largest accepted deviation of ``|q|`` from 1 (dimensionless)."""


def strip_leading_slash(frame_id: str) -> str:
    """A frame name without its leading ``/``, as tf2's ``stripSlash`` does.

    >>> strip_leading_slash("/car1/gps_antenna")
    'car1/gps_antenna'
    """
    return frame_id[1:] if frame_id.startswith("/") else frame_id


def _frozen_array(values: ArrayLike) -> NDArray[np.float64]:
    array = np.array(values, dtype=float)
    array.flags.writeable = False
    return array


def _finite(value: float, what: str) -> None:
    if not math.isfinite(value):
        raise InvalidTransformError(f"{what} must be finite, got {value!r}")


def transform_points_rigid(a: Rigid, points: ArrayLike) -> NDArray[np.float64]:
    """Apply a rigid transform to many points at once.

    Args:
        a: the transform, as ``(tx, ty, tz, qx, qy, qz, qw)``.
        points: (n, 3) points [m], or (n, 2) points taken at z = 0.

    Returns:
        The mapped points [m], with the input's shape. For (n, 2) input the
        mapped z is dropped, so the result is the ground projection of the
        mapped points; for a yaw-only chain it does not depend on the z the
        input was taken at.

    Raises:
        InvalidArgumentError: if ``points`` is not (n, 2) or (n, 3).
    """
    p = np.asarray(points, dtype=float)
    if p.ndim != 2 or p.shape[1] not in (2, 3):
        raise InvalidArgumentError(f"points must have shape (n, 2) or (n, 3), got {p.shape}")
    rot = rigid.rotation_matrix(a)
    if p.shape[1] == 2:
        return p @ rot[:2, :2].T + np.array((a[0], a[1]))
    return p @ rot.T + np.array(a[:3])


@dataclass(frozen=True, slots=True, eq=False, init=False)
class TransformStamped:
    """The pose of ``child_frame_id`` in ``frame_id`` at time ``stamp``.

    Maps points from the child frame into the parent frame. Arrays are stored
    as read-only copies; equality is identity (compare with ``numpy.allclose``).
    scipy 1.17.1's ``Rotation.apply`` rejects read-only arrays (scipy#24751,
    fixed upstream): pass it ``np.array(t.translation)``.

    Attributes:
        frame_id: parent frame name.
        child_frame_id: child frame name.
        stamp: simulation time [s].
        translation: child origin in the parent frame, (3,) [m].
        rotation: unit quaternion (x, y, z, w), (4,).
        rigid: the same transform as a tuple ``(tx, ty, tz, qx, qy, qz, qw)``.
    """

    frame_id: str
    child_frame_id: str
    stamp: float
    translation: NDArray[np.float64]
    rotation: NDArray[np.float64]
    rigid: Rigid = field(init=False, repr=False)

    def __init__(
        self,
        frame_id: str,
        child_frame_id: str,
        stamp: float,
        translation: ArrayLike = (0.0, 0.0, 0.0),
        rotation: ArrayLike = (0.0, 0.0, 0.0, 1.0),
    ) -> None:
        """Check and store a transform.

        Args:
            frame_id: parent frame name.
            child_frame_id: child frame name.
            stamp: simulation time [s].
            translation: (3,) [m].
            rotation: (4,) quaternion (x, y, z, w), unit norm within
                :data:`QUATERNION_TOLERANCE`; stored normalised.

        Raises:
            InvalidTransformError: wrong shapes, NaN or inf anywhere, or a
                quaternion that is not unit-norm.
        """
        t = np.asarray(translation, dtype=float)
        q = np.asarray(rotation, dtype=float)
        if t.shape != (3,) or q.shape != (4,):
            raise InvalidTransformError(
                f"transform '{frame_id}' -> '{child_frame_id}': translation must be (3,) "
                f"and rotation (4,), got {t.shape} and {q.shape}"
            )
        what = f"transform '{frame_id}' -> '{child_frame_id}'"
        _finite(float(stamp), f"{what}: stamp")
        values = t.tolist() + q.tolist()
        for name, value in zip(("x", "y", "z", "qx", "qy", "qz", "qw"), values, strict=True):
            _finite(value, f"{what}: {name}")
        norm = math.sqrt(sum(v * v for v in values[3:]))
        if abs(norm - 1.0) > QUATERNION_TOLERANCE:
            raise InvalidTransformError(
                f"{what}: quaternion {tuple(values[3:])} has norm {norm!r}; it must be 1 "
                f"within {QUATERNION_TOLERANCE} (normalise it first)"
            )
        qx, qy, qz, qw = (v / norm for v in values[3:])
        a: Rigid = (values[0], values[1], values[2], qx, qy, qz, qw)
        self._store(frame_id, child_frame_id, float(stamp), a)

    def _store(self, frame_id: str, child_frame_id: str, stamp: float, a: Rigid) -> None:
        setattr_ = object.__setattr__
        setattr_(self, "frame_id", frame_id)
        setattr_(self, "child_frame_id", child_frame_id)
        setattr_(self, "stamp", stamp)
        setattr_(self, "translation", _frozen_array(a[:3]))
        setattr_(self, "rotation", _frozen_array(a[3:]))
        setattr_(self, "rigid", a)

    @classmethod
    def from_rigid(
        cls, frame_id: str, child_frame_id: str, stamp: float, a: Rigid
    ) -> TransformStamped:
        """Wrap a rigid tuple without checking it (for results of this package's maths)."""
        self = object.__new__(cls)
        self._store(frame_id, child_frame_id, stamp, a)
        return self

    @classmethod
    def from_pose2d(
        cls, frame_id: str, child_frame_id: str, stamp: float, pose: Pose2D, z: float = 0.0
    ) -> TransformStamped:
        """A yaw-only transform placing the child at ``pose`` in the parent.

        Args:
            frame_id: parent frame name.
            child_frame_id: child frame name.
            stamp: simulation time [s].
            pose: child origin (x, y) [m] and heading yaw [rad] in the parent.
            z: child origin height in the parent [m].
        """
        _finite(z, f"transform '{frame_id}' -> '{child_frame_id}': z")
        _finite(stamp, f"transform '{frame_id}' -> '{child_frame_id}': stamp")
        a: Rigid = (pose.x, pose.y, float(z), *rigid.quat_from_yaw(pose.yaw))
        return cls.from_rigid(frame_id, child_frame_id, float(stamp), a)

    def to_pose2d(self) -> Pose2D:
        """The child's planar pose in the parent: x, y [m] and yaw [rad] in [-pi, pi).

        Drops z, roll and pitch; the yaw is the Z-Y-X (yaw, pitch, roll) one.
        """
        yaw = float(wrap_angle(rigid.yaw_of(self.rigid)))
        return Pose2D(self.rigid[0], self.rigid[1], yaw)

    def inverse(self) -> TransformStamped:
        """The transform mapping points the other way (frame names swapped, same stamp)."""
        return self.from_rigid(
            self.child_frame_id, self.frame_id, self.stamp, rigid.invert(self.rigid)
        )

    def compose(self, other: TransformStamped) -> TransformStamped:
        """``self ∘ other``: from ``other.child_frame_id`` into ``self.frame_id``.

        ``self`` maps B into A and ``other`` maps C into B. The result carries
        ``self.stamp``, as tf2's ``doTransform`` stamps its output with the
        applied transform's stamp.

        Raises:
            InvalidArgumentError: if ``other.frame_id`` is not ``self.child_frame_id``.
        """
        if strip_leading_slash(other.frame_id) != strip_leading_slash(self.child_frame_id):
            raise InvalidArgumentError(
                f"cannot compose '{self.frame_id}' -> '{self.child_frame_id}' with "
                f"'{other.frame_id}' -> '{other.child_frame_id}': "
                f"'{other.frame_id}' is not '{self.child_frame_id}'"
            )
        return self.from_rigid(
            self.frame_id,
            other.child_frame_id,
            self.stamp,
            rigid.compose(self.rigid, other.rigid),
        )

    def as_matrix(self) -> NDArray[np.float64]:
        """The (4, 4) homogeneous matrix mapping child points into the parent."""
        matrix = np.eye(4)
        matrix[:3, :3] = rigid.rotation_matrix(self.rigid)
        matrix[:3, 3] = self.rigid[:3]
        return matrix

    def transform_points(self, points: ArrayLike) -> NDArray[np.float64]:
        """Map (n, 3) or (n, 2) child-frame points [m] into the parent frame.

        See :func:`transform_points_rigid` for the (n, 2) convention.
        """
        return transform_points_rigid(self.rigid, points)
