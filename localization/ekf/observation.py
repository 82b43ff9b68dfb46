"""The fusion EKF's observation models: z = h(x) + noise, H = dh/dx, and the residual.

Each sensor's h(x) and Jacobian H exist here once; the filter evaluates them
through :data:`OBSERVATIONS` (and builds the constant H's once, with the
same functions). State indices: :mod:`.model`.

* GPS position (the antenna; no lever arm): h = p (+ gps_bias),
  H = [I2 0 .. (I2)], constant.
* Heading (dual antenna, ``/global_yaw``): h = yaw (+ heading_bias),
  H = e_yaw (+ e_heading_bias), constant; its residual z - h is wrapped into
  [-pi, pi), h itself is not.
* Wheel speed: h = wheel_scale * vx, H[vx] = wheel_scale, H[wheel_scale] = vx.

Written on floats (``x.item``) rather than array slices: they run on every
update; the sums and products are the same IEEE operations either way.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Final

import numpy as np
from numpy.typing import NDArray

from conesim.localization.ekf.health import Sensor
from conesim.localization.ekf.model import VX, WHEEL_SCALE, YAW, StateLayout, X, Y, wrap_yaw

FloatArray = NDArray[np.float64]


def h_position(x: FloatArray, layout: StateLayout) -> FloatArray:
    """Expected GPS position of the antenna in ``reference`` [m], (2, 1).

    Args:
        x: state, (n, 1).
        layout: where the receiver error (if any) sits in ``x``.
    """
    east, north = x.item(X), x.item(Y)
    g = layout.gps_bias_index
    if g is not None:
        east, north = east + x.item(g), north + x.item(g + 1)
    return np.array([[east], [north]])


def jacob_h_position(x: FloatArray, layout: StateLayout) -> FloatArray:
    """H of :func:`h_position`, (2, n); the same for every ``x``."""
    h = np.zeros((2, layout.n))
    h[0, X] = h[1, Y] = 1.0
    g = layout.gps_bias_index
    if g is not None:
        h[0, g] = h[1, g + 1] = 1.0
    return h


def h_heading(x: FloatArray, layout: StateLayout) -> FloatArray:
    """Expected heading [rad], (1, 1), not wrapped (the residual is).

    Args:
        x: state, (n, 1).
        layout: where the heading-sensor error (if any) sits in ``x``.
    """
    yaw = x.item(YAW)
    k = layout.heading_bias_index
    if k is not None:
        yaw += x.item(k)
    return np.array([[yaw]])


def jacob_h_heading(x: FloatArray, layout: StateLayout) -> FloatArray:
    """H of :func:`h_heading`, (1, n); the same for every ``x``."""
    h = np.zeros((1, layout.n))
    h[0, YAW] = 1.0
    k = layout.heading_bias_index
    if k is not None:
        h[0, k] = 1.0
    return h


def h_wheel_speed(x: FloatArray, layout: StateLayout) -> FloatArray:
    """Expected wheel speed wheel_scale * vx [m/s], (1, 1).

    Args:
        x: state, (n, 1).
        layout: unused (the scale is a core state); the signature every h shares.
    """
    return np.array([[x.item(WHEEL_SCALE) * x.item(VX)]])


def jacob_h_wheel_speed(x: FloatArray, layout: StateLayout) -> FloatArray:
    """H of :func:`h_wheel_speed`, (1, n): vx's entry is wheel_scale, wheel_scale's is vx."""
    h = np.zeros((1, layout.n))
    h[0, VX] = x.item(WHEEL_SCALE)
    h[0, WHEEL_SCALE] = x.item(VX)
    return h


def difference(z: FloatArray, hx: FloatArray) -> FloatArray:
    """The residual z - h(x), (m, 1), in the measurement's unit."""
    return z - hx


def heading_residual(z: FloatArray, hx: FloatArray) -> FloatArray:
    """The residual z - h(x) of a heading, wrapped into [-pi, pi) [rad], (1, 1)."""
    return np.array([[wrap_yaw(z.item(0) - hx.item(0))]])


StateFunction = Callable[[FloatArray, StateLayout], FloatArray]


@dataclass(frozen=True, slots=True)
class Observation:
    """One sensor's observation model.

    Attributes:
        h: expected measurement h(x, layout), (m, 1).
        jacobian: H = dh/dx at (x, layout), (m, n).
        residual: z - h(x) from (z, h(x)), (m, 1) (wrapped for an angle).
        constant: whether H is the same for every x (then the filter builds it once).
    """

    h: StateFunction
    jacobian: StateFunction
    residual: Callable[[FloatArray, FloatArray], FloatArray]
    constant: bool


OBSERVATIONS: Final[Mapping[Sensor, Observation]] = {
    Sensor.GPS: Observation(h_position, jacob_h_position, difference, constant=True),
    Sensor.HEADING: Observation(h_heading, jacob_h_heading, heading_residual, constant=True),
    Sensor.WHEEL_SPEED: Observation(h_wheel_speed, jacob_h_wheel_speed, difference, constant=False),
}
"""The observation model of each measured sensor (the IMU is the input, not observed)."""
