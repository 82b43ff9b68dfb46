"""Rigid-transform algebra on plain floats, for the frame tree's hot path.

A rigid transform is held as a flat tuple ``(tx, ty, tz, qx, qy, qz, qw)``:
a translation [m] and a unit quaternion in ROS order (x, y, z, w). A transform
``a`` that maps points from frame B into frame A does ``p_A = R(q) p_B + t``.

A lookup composes two or three such transforms. For 3-vectors and
quaternions, Python float arithmetic is several times faster than numpy
(whose per-call overhead is about a microsecond) and than constructing scipy
``Rotation`` objects (about ten), so composition, inversion and the per-lookup
half of slerp are written out here. :func:`slerp_step` takes the relative
rotation vector of two samples as ``scipy.spatial.transform.Slerp``
precomputes it, ``Rotation.from_quat(...).as_rotvec()``, written out on
floats with scipy's operations (:func:`rotvec_of`; scipy's object costs ten
microseconds per stored sample), and :func:`interpolate` then evaluates
``r0 * Rotation.from_rotvec(ratio * rotvec)``, which is what
``Slerp.__call__`` does. The tests check both against scipy.
"""

from __future__ import annotations

import math
from typing import Final, TypeAlias

import numpy as np
from numpy.typing import NDArray
from scipy.spatial.transform import Rotation

Rigid: TypeAlias = tuple[float, float, float, float, float, float, float]
"""(tx, ty, tz, qx, qy, qz, qw): translation [m] and unit quaternion."""

Quaternion: TypeAlias = tuple[float, float, float, float]
"""(qx, qy, qz, qw), ROS order."""

SlerpStep: TypeAlias = tuple[float, float, float, float]
"""(ax, ay, az, angle): unit axis and angle [rad] from one sample to the next."""

IDENTITY: Final[Rigid] = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0)
NO_ROTATION: Final[SlerpStep] = (0.0, 0.0, 0.0, 0.0)


def quat_multiply(q: Quaternion, r: Quaternion) -> Quaternion:
    """Hamilton product ``q * r`` (apply ``r`` first, then ``q``)."""
    qx, qy, qz, qw = q
    rx, ry, rz, rw = r
    return (
        qw * rx + qx * rw + qy * rz - qz * ry,
        qw * ry - qx * rz + qy * rw + qz * rx,
        qw * rz + qx * ry - qy * rx + qz * rw,
        qw * rw - qx * rx - qy * ry - qz * rz,
    )


def compose(a: Rigid, b: Rigid) -> Rigid:
    """``a ∘ b``: if ``b`` maps C into B and ``a`` maps B into A, the result maps C into A.

    Rotation: ``q = qa * qb``. Translation: ``t = R(qa) tb + ta``, with the
    vector rotated as ``v' = v + w u' + u x u'`` where ``u' = 2 u x v``
    (``u`` the vector part of ``qa``, ``w`` its scalar part).
    """
    ax, ay, az, qx, qy, qz, qw = a
    bx, by, bz, rx, ry, rz, rw = b
    cx = 2.0 * (qy * bz - qz * by)
    cy = 2.0 * (qz * bx - qx * bz)
    cz = 2.0 * (qx * by - qy * bx)
    return (
        bx + qw * cx + (qy * cz - qz * cy) + ax,
        by + qw * cy + (qz * cx - qx * cz) + ay,
        bz + qw * cz + (qx * cy - qy * cx) + az,
        qw * rx + qx * rw + qy * rz - qz * ry,
        qw * ry - qx * rz + qy * rw + qz * rx,
        qw * rz + qx * ry - qy * rx + qz * rw,
        qw * rw - qx * rx - qy * ry - qz * rz,
    )


def invert(a: Rigid) -> Rigid:
    """The inverse transform: ``q' = conj(q)``, ``t' = -R(q') t``."""
    tx, ty, tz, qx, qy, qz, qw = a
    # Rotate t by the conjugate (vector part negated), then negate.
    cx = 2.0 * (qz * ty - qy * tz)
    cy = 2.0 * (qx * tz - qz * tx)
    cz = 2.0 * (qy * tx - qx * ty)
    return (
        -(tx + qw * cx + (qz * cy - qy * cz)),
        -(ty + qw * cy + (qx * cz - qz * cx)),
        -(tz + qw * cz + (qy * cx - qx * cy)),
        -qx,
        -qy,
        -qz,
        qw,
    )


def rotation_matrix(a: Rigid) -> NDArray[np.float64]:
    """The (3, 3) rotation matrix of a transform's unit quaternion."""
    _, _, _, x, y, z, w = a
    return np.array(
        [
            [1.0 - 2.0 * (y * y + z * z), 2.0 * (x * y - z * w), 2.0 * (x * z + y * w)],
            [2.0 * (x * y + z * w), 1.0 - 2.0 * (x * x + z * z), 2.0 * (y * z - x * w)],
            [2.0 * (x * z - y * w), 2.0 * (y * z + x * w), 1.0 - 2.0 * (x * x + y * y)],
        ]
    )


def yaw_of(a: Rigid) -> float:
    """Yaw [rad] of a transform's rotation, in (-pi, pi].

    The first angle of the intrinsic Z-Y'-X'' (yaw, pitch, roll) decomposition,
    as tf2's ``getYaw`` and scipy's ``as_euler("ZYX")[0]`` give it:
    ``atan2(2 (w z + x y), 1 - 2 (y^2 + z^2))``.
    """
    _, _, _, x, y, z, w = a
    return math.atan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))


def quat_from_yaw(yaw: float) -> Quaternion:
    """Unit quaternion of a rotation by ``yaw`` [rad] about +z."""
    half = 0.5 * yaw
    return (0.0, 0.0, math.sin(half), math.cos(half))


def rotvec_of(q: Quaternion) -> tuple[float, float, float]:
    """``Rotation.from_quat(q).as_rotvec()`` on floats, the same operations in the same order.

    scipy's single-rotation path (its Cython backend) normalises ``q`` by
    ``sqrt((x^2 + y^2 + z^2) + w^2)``, flips it onto ``w >= 0`` (at ``w == 0``
    onto a positive first non-zero component), takes ``angle = 2 atan2(|v|,
    w)`` and scales the vector part by ``angle / sin(angle / 2)``, or by
    its Taylor series ``2 + a^2 / 12 + 7 a^4 / 2880`` for ``angle <= 1e-3``.
    Written out, it costs about a microsecond instead of ten;
    ``tests/localization/test_frames_transform.py`` compares the two exactly,
    so a scipy that computes it differently is noticed.

    Raises:
        ValueError: a zero quaternion (as scipy).
    """
    x, y, z, w = q
    norm = math.sqrt(x * x + y * y + z * z + w * w)
    if not 0.0 < norm < math.inf:
        return _scipy_rotvec(q)  # scipy raises (zero norm) or gives its NaNs
    x, y, z, w = x / norm, y / norm, z / norm, w / norm
    if w < 0.0 or (w == 0.0 and (x < 0.0 or (x == 0.0 and (y < 0.0 or (y == 0.0 and z < 0.0))))):
        x, y, z, w = -x, -y, -z, -w
    angle = 2.0 * math.atan2(math.sqrt(x * x + y * y + z * z), w)
    if angle <= 1e-3:
        angle2 = angle * angle
        scale = 2.0 + angle2 / 12.0 + 7.0 * angle2 * angle2 / 2880.0
    else:
        scale = angle / math.sin(angle / 2.0)
    return scale * x, scale * y, scale * z


def _scipy_rotvec(q: Quaternion) -> tuple[float, float, float]:
    """``Rotation.from_quat(q).as_rotvec()`` by scipy itself."""
    rotvec = Rotation.from_quat(q).as_rotvec()
    return float(rotvec[0]), float(rotvec[1]), float(rotvec[2])


def slerp_step(a: Rigid, b: Rigid) -> SlerpStep:
    """Axis and angle of the rotation from ``a``'s orientation to ``b``'s.

    This is scipy ``Slerp``'s precomputation, ``(r0.inv() * r1).as_rotvec()``,
    split into a unit axis and an angle in [0, pi] (the shorter way round, as
    tf2's ``slerp`` also takes). Done once per stored pair of samples.
    """
    delta = quat_multiply((-a[3], -a[4], -a[5], a[6]), (b[3], b[4], b[5], b[6]))
    rx, ry, rz = rotvec_of(delta)
    angle = math.sqrt(rx * rx + ry * ry + rz * rz)
    if angle == 0.0:
        return NO_ROTATION
    return (rx / angle, ry / angle, rz / angle, angle)


def interpolate(a: Rigid, b: Rigid, step: SlerpStep, ratio: float) -> Rigid:
    """The transform a fraction ``ratio`` in [0, 1] of the way from ``a`` to ``b``.

    Translation: ``ta + ratio (tb - ta)`` (linear). Rotation: slerp,
    ``qa * exp(ratio * angle * axis / 2)`` with ``step = slerp_step(a, b)``,
    which equals scipy's ``Slerp`` (and tf2's ``slerp``) at ``ratio``.
    """
    ax, ay, az, qx, qy, qz, qw = a
    ux, uy, uz, angle = step
    half = 0.5 * ratio * angle
    s = math.sin(half)
    dx, dy, dz, dw = ux * s, uy * s, uz * s, math.cos(half)
    return (
        ax + ratio * (b[0] - ax),
        ay + ratio * (b[1] - ay),
        az + ratio * (b[2] - az),
        qw * dx + qx * dw + qy * dz - qz * dy,
        qw * dy - qx * dz + qy * dw + qz * dx,
        qw * dz + qx * dy - qy * dx + qz * dw,
        qw * dw - qx * dx - qy * dy - qz * dz,
    )
