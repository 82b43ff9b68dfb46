"""The cone observation model: a map cone's position in the sensor frame, h(x) and H.

A map cone at ``m`` in ``reference``, the map offset by ``b`` (the state's
``map_bias``, when it has one), seen from the antenna pose (p, yaw) with the
sensor at ``o`` in the antenna frame::

    h(x) = R(yaw)^T (m + b - p) - o                   (2, 1) [m]
    dh/dp   = -R(yaw)^T,   dh/db = R(yaw)^T           (2, 2) each
    dh/dyaw = dR(yaw)^T/dyaw (m + b - p)
            = [[-sin yaw, cos yaw], [-cos yaw, -sin yaw]] (m + b - p)   (2, 1)

and zero for every other state (the GPS and heading errors do not enter).
With the cones in the state (SLAM, ``localization.slam``) each cone's own
columns get dh/dm = R(yaw)^T, as the offset's do.
The detection's covariance comes from the detector's range and bearing noise
at the measured point (r, b), plus the map's survey error::

    R_i = sigma_r^2 u u' + (r sigma_b)^2 v v' + sigma_map^2 I,
    u = (cos b, sin b), v = (-sin b, cos b)

(the range/bearing noise linearised into the Cartesian point, as
``sim.sensors.cone_detector`` draws it). A scan's detections stack into one
(2a, 1) measurement with a block-diagonal R: one filterpy update per scan.
Written with numpy over all the detections at once: no per-cone Python loop.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from conesim.localization.cones.config import ConeUpdateConfig
from conesim.localization.ekf.model import YAW, X, Y

FloatArray = NDArray[np.float64]


def _relative(x: FloatArray, landmarks: FloatArray, bias: int | None) -> tuple[FloatArray, ...]:
    """(m + b - p) per landmark, east and north, (a,) each."""
    ox, oy = (0.0, 0.0) if bias is None else (x.item(bias), x.item(bias + 1))
    return landmarks[:, 0] + (ox - x.item(X)), landmarks[:, 1] + (oy - x.item(Y))


def h_cones(
    x: FloatArray, landmarks: FloatArray, offset: tuple[float, float], bias: int | None = None
) -> FloatArray:
    """Expected detections of ``landmarks`` (a, 2) [m] in the sensor frame, stacked (2a, 1).

    Args:
        x: state, (n, 1).
        landmarks: the map cones, (a, 2) [m].
        offset: the sensor's planar origin in the antenna frame [m].
        bias: the index of ``map_bias_e`` in ``x``, or None.
    """
    yaw = x.item(YAW)
    c, s = math.cos(yaw), math.sin(yaw)
    dx, dy = _relative(x, landmarks, bias)
    out = np.empty((len(landmarks), 2))
    out[:, 0] = c * dx + s * dy - offset[0]
    out[:, 1] = -s * dx + c * dy - offset[1]
    return out.reshape(-1, 1)


def jacob_h_cones(
    x: FloatArray,
    landmarks: FloatArray,
    n: int,
    bias: int | None = None,
    columns: NDArray[np.intp] | None = None,
) -> FloatArray:
    """H of :func:`h_cones`, (2a, n): only the x, y, yaw (and map_bias) columns are non-zero,
    and, with ``columns`` (a,) (each cone's east index in a SLAM state), each cone's own two."""
    yaw = x.item(YAW)
    c, s = math.cos(yaw), math.sin(yaw)
    dx, dy = _relative(x, landmarks, bias)
    h = np.zeros((len(landmarks), 2, n))
    h[:, 0, X], h[:, 0, Y] = -c, -s
    h[:, 1, X], h[:, 1, Y] = s, -c
    h[:, 0, YAW] = -s * dx + c * dy
    h[:, 1, YAW] = -c * dx - s * dy
    if bias is not None:
        h[:, 0, bias], h[:, 0, bias + 1] = c, s
        h[:, 1, bias], h[:, 1, bias + 1] = -s, c
    if columns is not None:
        rows = np.arange(len(landmarks))
        h[rows, 0, columns], h[rows, 0, columns + 1] = c, s
        h[rows, 1, columns], h[rows, 1, columns + 1] = -s, c
    return h.reshape(-1, n)


def detection_covariance(points: FloatArray, config: ConeUpdateConfig) -> FloatArray:
    """Each detection's covariance in the sensor frame (module docstring), (k, 2, 2) [m^2]."""
    r = np.hypot(points[:, 0], points[:, 1])
    b = np.arctan2(points[:, 1], points[:, 0])
    c, s = np.cos(b), np.sin(b)
    var_r = config.range_sigma**2
    var_t = (r * config.bearing_sigma) ** 2
    cov = np.empty((len(points), 2, 2))
    cov[:, 0, 0] = var_r * c * c + var_t * s * s
    cov[:, 1, 1] = var_r * s * s + var_t * c * c
    cov[:, 0, 1] = cov[:, 1, 0] = (var_r - var_t) * c * s
    cov[:, 0, 0] += config.map_sigma**2
    cov[:, 1, 1] += config.map_sigma**2
    return cov


def block_diagonal(blocks: FloatArray) -> FloatArray:
    """(a, 2, 2) blocks as one (2a, 2a) block-diagonal matrix."""
    a = len(blocks)
    out = np.zeros((a, 2, a, 2))
    idx = np.arange(a)
    out[idx, :, idx, :] = blocks
    return out.reshape(2 * a, 2 * a)
