"""References the EKF's tests compare against: the numpy motion model, central differences.

The motion model exists once in the package, as the compiled kernel
``localization.ekf.kernels.motion_terms`` (its docstring derives x', F, G and
Q). :func:`motion_model`, :func:`jacob_f`, :func:`jacob_u` and
:func:`process_noise` are the readable numpy/Python formulation it was
checked against, kept here so that the tests keep comparing the kernel with
them exactly (bit for bit): the same IEEE operations in the same order.
:func:`numeric_jacobian` is the reference for any Jacobian, and
:func:`random_state` and ``LAYOUTS`` what they are evaluated on.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from conesim.localization.ekf.model import (
    GYRO_BIAS,
    N_CORE,
    VX,
    VY,
    WHEEL_SCALE,
    YAW,
    ProcessModel,
    StateLayout,
    X,
    Y,
)

FloatArray = NDArray[np.float64]

LAYOUTS = [
    StateLayout(),
    StateLayout(gps_bias=True),
    StateLayout(heading_bias=True),
    StateLayout(gps_bias=True, heading_bias=True),
]


def layout_id(layout: StateLayout) -> str:
    """A test id naming the optional states ("core" without any)."""
    return "-".join(layout.names[N_CORE:]) or "core"


def random_state(layout: StateLayout, rng: np.random.Generator) -> FloatArray:
    """A plausible state, (n, 1): yaw in [-3, 3) rad, vx 2-15 m/s, small bias, scale near 1."""
    x = rng.normal(size=(layout.n, 1))
    x[YAW, 0] = rng.uniform(-3.0, 3.0)
    x[VX, 0] = rng.uniform(2.0, 15.0)
    x[GYRO_BIAS, 0] *= 0.01
    x[WHEEL_SCALE, 0] = 1.0 + 0.01 * rng.normal()
    return x


def numeric_jacobian(f: Callable[[FloatArray], FloatArray], x: FloatArray) -> FloatArray:
    """Central differences, column by column."""
    x = np.asarray(x, dtype=float)
    flat = x.reshape(-1)
    cols = []
    for i in range(flat.size):
        h = 1e-6 * max(1.0, abs(flat[i]))
        up, down = flat.copy(), flat.copy()
        up[i] += h
        down[i] -= h
        cols.append((f(up.reshape(x.shape)) - f(down.reshape(x.shape))).reshape(-1) / (2.0 * h))
    return np.array(cols).T


def rot(angle: float) -> FloatArray:
    """The (2, 2) rotation by ``angle`` [rad], counter-clockwise."""
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s], [s, c]])


def _turn(angle: float, px: float, py: float) -> tuple[float, float]:
    """R(angle) (px, py), on floats."""
    c, s = math.cos(angle), math.sin(angle)
    return c * px - s * py, s * px + c * py


def _unpack(x: FloatArray, u: FloatArray) -> tuple[float, float, float, float, float, float]:
    """(yaw, w = w_m - gyro_bias, vx, vy, ax, ay) as floats."""
    return (
        float(x[YAW, 0]),
        float(u[0]) - float(x[GYRO_BIAS, 0]),
        float(x[VX, 0]),
        float(x[VY, 0]),
        float(u[1]),
        float(u[2]),
    )


def motion_model(x: FloatArray, u: FloatArray, dt: float, model: ProcessModel) -> FloatArray:
    """Propagate the state over ``dt`` with the IMU input held.

    Args:
        x: state, (n, 1).
        u: IMU input (w_m [rad/s], a_x [m/s^2], a_y [m/s^2]), (3,).
        dt: interval [s], >= 0.
        model: layout and noise settings.

    Returns:
        The propagated state, (n, 1); yaw is not wrapped here (the filter wraps).
    """
    yaw, w, vx, vy, ax, ay = _unpack(x, u)
    half = 0.5 * dt * dt
    vex, vey = _turn(yaw, vx, vy)
    aex, aey = _turn(yaw + 0.5 * w * dt, ax, ay)
    rvx, rvy = _turn(-w * dt, vx, vy)
    rax, ray = _turn(-0.5 * w * dt, ax, ay)
    out = x.copy()
    out[X, 0] += dt * vex + half * aex
    out[Y, 0] += dt * vey + half * aey
    out[YAW, 0] = yaw + w * dt
    out[VX, 0] = rvx + dt * rax
    out[VY, 0] = rvy + dt * ray
    layout = model.layout
    if layout.gps_bias:
        g = N_CORE
        out[g : g + 2, 0] *= math.exp(-dt / model.gps_bias_tau)
    h = layout.heading_bias_index
    if h is not None:
        out[h, 0] *= math.exp(-dt / model.heading_bias_tau)
    return out


def _dv_dgyro_bias(
    w: float, v: tuple[float, float], a: tuple[float, float], dt: float
) -> tuple[float, float]:
    """dv'/dgyro_bias = dt R(-w dt) S v + dt^2/2 R(-w dt/2) S a (S (px, py) = (-py, px))."""
    bx, by = _turn(-w * dt, -v[1], v[0])
    cx, cy = _turn(-0.5 * w * dt, -a[1], a[0])
    half = 0.5 * dt * dt
    return dt * bx + half * cx, dt * by + half * cy


def jacob_f(x: FloatArray, u: FloatArray, dt: float, model: ProcessModel) -> FloatArray:
    """F = d motion_model / dx, (n, n)."""
    yaw, w, vx, vy, ax, ay = _unpack(x, u)
    c, s = math.cos(yaw), math.sin(yaw)
    mid = yaw + 0.5 * w * dt
    sv = _turn(yaw, -vy, vx)  # R(yaw) S v
    sa = _turn(mid, -ay, ax)  # R(mid) S a
    half = 0.5 * dt * dt
    cw, sw = math.cos(w * dt), math.sin(w * dt)
    f = np.eye(model.layout.n)
    f[X, YAW] = dt * sv[0] + half * sa[0]
    f[Y, YAW] = dt * sv[1] + half * sa[1]
    f[X, VX], f[X, VY], f[Y, VX], f[Y, VY] = dt * c, -dt * s, dt * s, dt * c
    f[X, GYRO_BIAS] = -0.25 * dt**3 * sa[0]
    f[Y, GYRO_BIAS] = -0.25 * dt**3 * sa[1]
    f[YAW, GYRO_BIAS] = -dt
    f[VX, VX], f[VX, VY], f[VY, VX], f[VY, VY] = cw, sw, -sw, cw  # R(-w dt)
    f[VX, GYRO_BIAS], f[VY, GYRO_BIAS] = _dv_dgyro_bias(w, (vx, vy), (ax, ay), dt)
    layout = model.layout
    if layout.gps_bias:
        g = N_CORE
        phi = math.exp(-dt / model.gps_bias_tau)
        f[g, g] = f[g + 1, g + 1] = phi
    h = layout.heading_bias_index
    if h is not None:
        f[h, h] = math.exp(-dt / model.heading_bias_tau)
    return f


def jacob_u(x: FloatArray, u: FloatArray, dt: float, model: ProcessModel) -> FloatArray:
    """G = d motion_model / du, (n, 3)."""
    yaw, w, vx, vy, ax, ay = _unpack(x, u)
    mid = yaw + 0.5 * w * dt
    cm, sm = math.cos(mid), math.sin(mid)
    sa = _turn(mid, -ay, ax)  # R(mid) S a
    half = 0.5 * dt * dt
    ch, sh = math.cos(0.5 * w * dt), math.sin(0.5 * w * dt)
    dvx, dvy = _dv_dgyro_bias(w, (vx, vy), (ax, ay), dt)
    g = np.zeros((model.layout.n, 3))
    g[X, 0] = 0.25 * dt**3 * sa[0]
    g[Y, 0] = 0.25 * dt**3 * sa[1]
    g[X, 1], g[X, 2], g[Y, 1], g[Y, 2] = half * cm, -half * sm, half * sm, half * cm
    g[YAW, 0] = dt
    g[VX, 0], g[VY, 0] = -dvx, -dvy
    g[VX, 1], g[VX, 2], g[VY, 1], g[VY, 2] = dt * ch, dt * sh, -dt * sh, dt * ch  # dt R(-w dt/2)
    return g


def process_noise(
    x: FloatArray, u: FloatArray, u_cov: FloatArray, dt: float, model: ProcessModel
) -> FloatArray:
    """Q over ``dt``, (n, n): the IMU's noise through G plus the model terms.

    Args:
        x: state, (n, 1).
        u: IMU input, (3,).
        u_cov: the IMU's stated per-sample covariance of u, (3, 3).
        dt: interval [s], > 0.
        model: layout and noise settings.
    """
    g = jacob_u(x, u, dt, model)
    q = g @ (u_cov * (model.imu_period / dt)) @ g.T
    qa = model.accel_model_density**2
    if qa > 0.0:
        q[X : Y + 1, X : Y + 1] += qa * dt**3 / 3.0 * np.eye(2)
        pv = qa * dt * dt / 2.0 * rot(float(x[YAW, 0]))
        q[X : Y + 1, VX : VY + 1] += pv
        q[VX : VY + 1, X : Y + 1] += pv.T
        q[VX : VY + 1, VX : VY + 1] += qa * dt * np.eye(2)
    q[YAW, YAW] += model.yaw_model_density**2 * dt
    q[GYRO_BIAS, GYRO_BIAS] += model.gyro_bias_walk**2 * dt
    q[WHEEL_SCALE, WHEEL_SCALE] += model.wheel_scale_walk**2 * dt
    layout = model.layout
    if layout.gps_bias:
        k = N_CORE
        phi = math.exp(-dt / model.gps_bias_tau)
        q[k, k] += model.gps_bias_sigma**2 * (1.0 - phi * phi)
        q[k + 1, k + 1] += model.gps_bias_sigma**2 * (1.0 - phi * phi)
    h = layout.heading_bias_index
    if h is not None:
        phi = math.exp(-dt / model.heading_bias_tau)
        q[h, h] += model.heading_bias_sigma**2 * (1.0 - phi * phi)
    return q
