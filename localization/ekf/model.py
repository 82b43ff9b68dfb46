"""The fusion EKF's state, motion model and observation models, with Jacobians.

State: the pose of ``gps_antenna`` in ``reference``, plus what the sensors need
----------------------------------------------------------------------------------

==  ============  =====================================================  ========
 i  name          meaning                                                unit
==  ============  =====================================================  ========
 0  x             antenna east in ``reference``                          m
 1  y             antenna north in ``reference``                         m
 2  yaw           heading of ``gps_antenna``, CCW from east, [-pi, pi)    rad
 3  vx            antenna velocity along the car's x axis (forward)      m/s
 4  vy            antenna velocity along the car's y axis (left)         m/s
 5  gyro_bias     gyro z bias (yaw_rate_measured = yaw_rate + bias)      rad/s
 6  wheel_scale   wheel-speed scale (speed_measured = scale * vx)        -
 7  gps_bias_e    receiver error east (optional, Gauss-Markov)           m
 8  gps_bias_n    receiver error north (optional, Gauss-Markov)          m
 9  heading_bias  heading-sensor error (optional, Gauss-Markov)          rad
==  ============  =====================================================  ========

Why this state. The state lives at the antenna because the antenna *is* the
``gps_antenna`` frame the filter publishes (seed 000): GPS fixes observe it
without a lever arm, the IMU sits there (its specific force is the antenna's,
``sim.world`` moves it to the lever arm), and the broadcaster needs no
CG-to-antenna offset. The IMU is the *input* (a strapdown 2D INS), not a
measurement: at 100 Hz it is the fastest sensor, it measures exactly the
derivatives the kinematics need, and its stated white noise becomes the process
noise, so Q comes from a datasheet instead of a guessed vehicle model (no tyre
parameters in the estimator). A planar car slides: its antenna moves at a
sideslip angle to its heading (``sim.vehicle`` is a tyre model, not a
unicycle), so the body velocity has both components ``vx, vy``; dropping ``vy``
would bend the heading towards the course by the sideslip (degrees in a
corner, against a 0.1 deg heading target). The gyro bias and the wheel-speed
scale are the two sensor errors that grow a dead-reckoning error through a GPS
dropout (a 0.5 % scale error is 0.25 m after 50 m); both are observable while
GPS is there (heading against integrated yaw rate, GPS velocity against wheel
speed). Accelerometer biases are left out: tens of micro-g, they are covered by
``accel_model_density``. The optional Gauss-Markov states model the
time-correlated receiver and heading errors (a u-blox M8 is mostly a slowly
wandering bias): a filter that takes a correlated error for white noise
averages it as if it were white and reports a covariance far too small (mean
NEES near 55; REFERENCES.md, "Filter consistency"). With the bias in the state
the covariance stays honest; the bias itself is not observable from GPS alone,
so it still limits the absolute position error (only a map would remove it).

Motion model (IMU as input u = (w_m, a_x, a_y), held over each interval dt)
----------------------------------------------------------------------------
With w = w_m - gyro_bias, R(a) the 2D rotation and S = [[0, -1], [1, 0]]
(so dR(a)/da = R(a) S), the body velocity rotates with the car and is pushed
by the specific force a = (a_x, a_y); in ``reference`` the velocity is
V = R(yaw) v and dV/dt = R(yaw) a. Integrated with yaw at the interval's
midpoint for the acceleration (second order)::

    p'   = p + dt R(yaw) v + dt^2/2 R(yaw + w dt/2) a
    yaw' = yaw + w dt
    v'   = R(-w dt) v + dt R(-w dt/2) a
    gyro_bias', wheel_scale' = gyro_bias, wheel_scale       (random walks)
    gps_bias' = phi_g gps_bias,  heading_bias' = phi_h heading_bias,  phi = exp(-dt/tau)

Jacobian F = df/dx (identity except)::

    dp'/dyaw        = dt R(yaw) S v + dt^2/2 R(yaw + w dt/2) S a
    dp'/dv          = dt R(yaw)
    dp'/dgyro_bias  = -dt^3/4 R(yaw + w dt/2) S a
    dyaw'/dgyro_bias = -dt
    dv'/dv          = R(-w dt)
    dv'/dgyro_bias  = dt R(-w dt) S v + dt^2/2 R(-w dt/2) S a
    dgps_bias'/dgps_bias = phi_g I,  dheading_bias'/dheading_bias = phi_h

Input Jacobian G = df/du (w_m enters as -gyro_bias, so dG/dw_m = -dF/dgyro_bias)::

    dp'/dw_m = dt^3/4 R(yaw + w dt/2) S a     dp'/da = dt^2/2 R(yaw + w dt/2)
    dyaw'/dw_m = dt
    dv'/dw_m = -dv'/dgyro_bias                dv'/da = dt R(-w dt/2)

Process noise: Q = G (Sigma_u T / dt) G^T + Q_model, where Sigma_u is the
IMU's stated per-sample variance at its period T (a white density of
sigma^2 T, so splitting an IMU interval at a measurement keeps the total),
and Q_model adds white acceleration (density q_a: Q_pp = q_a dt^3/3 I,
Q_pv = q_a dt^2/2 R(yaw), Q_vv = q_a dt I), white yaw-rate (q_w dt), the
bias random walks (K^2 dt) and the exact Gauss-Markov terms sigma^2 (1 - phi^2).

Observation models (z = h(x) + noise), with H = dh/dx
-----------------------------------------------------
* GPS position (the antenna; no lever arm): h = p (+ gps_bias), H = [I2 0 .. (I2)].
* Heading (dual antenna, ``/global_yaw``): h = yaw (+ heading_bias),
  H = e_yaw (+ e_heading_bias); its residual is wrapped into [-pi, pi).
* Wheel speed: h = wheel_scale * vx, H[vx] = wheel_scale, H[wheel_scale] = vx.

Written for speed: :class:`MotionStep` is the filter's hot path (every IMU
sample, every replay, every estimate ahead). It evaluates :func:`motion_model`,
:func:`jacob_f` and :func:`process_noise` in one compiled pass over floats
(:func:`localization.ekf.kernels.motion_terms`, numba), with the same
expressions in the same order (so the same numbers, bit for bit), sharing the
trigonometry and writing F, G and Q's model terms into arrays it owns; only
Q's G Sigma G' is left to numpy (its BLAS products). The functions above stay
the readable reference (the tests check the two agree).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Final

import numpy as np
from numpy.typing import NDArray

from conesim.localization.ekf import kernels

FloatArray = NDArray[np.float64]

X: Final = 0
Y: Final = 1
YAW: Final = 2
VX: Final = 3
VY: Final = 4
GYRO_BIAS: Final = 5
WHEEL_SCALE: Final = 6
N_CORE: Final = 7
"""Number of states every layout has (indices 0-6 above)."""

CORE_NAMES: Final = ("x", "y", "yaw", "vx", "vy", "gyro_bias", "wheel_scale")
_TWO_PI: Final = 2.0 * math.pi


def wrap_yaw(angle: float) -> float:
    """:func:`localization.pose.wrap_angle` on a float, without numpy: the same arithmetic, bits."""
    return (angle + math.pi) % _TWO_PI - math.pi


def rot(angle: float) -> FloatArray:
    """The (2, 2) rotation by ``angle`` [rad], counter-clockwise."""
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s], [s, c]])


def _turn(angle: float, px: float, py: float) -> tuple[float, float]:
    """R(angle) (px, py), on floats (the hot path avoids small numpy arrays)."""
    c, s = math.cos(angle), math.sin(angle)
    return c * px - s * py, s * px + c * py


@dataclass(frozen=True, slots=True)
class StateLayout:
    """Which optional states the filter carries, and where they are.

    Attributes:
        gps_bias: whether the Gauss-Markov receiver error (east, north) is in the state.
        heading_bias: whether the Gauss-Markov heading-sensor error is in the state.
    """

    gps_bias: bool = False
    heading_bias: bool = False

    @property
    def n(self) -> int:
        """State dimension."""
        return N_CORE + 2 * self.gps_bias + self.heading_bias

    @property
    def gps_bias_index(self) -> int | None:
        """Index of gps_bias_e (gps_bias_n follows), or None."""
        return N_CORE if self.gps_bias else None

    @property
    def heading_bias_index(self) -> int | None:
        """Index of heading_bias, or None."""
        return N_CORE + 2 * self.gps_bias if self.heading_bias else None

    @property
    def names(self) -> tuple[str, ...]:
        """State names in index order."""
        extra = ("gps_bias_e", "gps_bias_n") * self.gps_bias + ("heading_bias",) * self.heading_bias
        return CORE_NAMES + extra


@dataclass(frozen=True, slots=True)
class ProcessModel:
    """Everything the motion model needs besides the state and the input.

    Attributes:
        layout: the state layout.
        imu_period: period T at which the IMU states its per-sample variance [s].
        accel_model_density: white acceleration beyond the IMU's noise [m/s^2/sqrt(Hz)].
        yaw_model_density: white yaw rate beyond the gyro's noise [rad/s/sqrt(Hz)].
        gyro_bias_walk: gyro bias random walk [rad/s/sqrt(s)].
        wheel_scale_walk: wheel-speed scale random walk [1/sqrt(s)].
        gps_bias_sigma: stationary std of the receiver error per axis [m].
        gps_bias_tau: its correlation time [s].
        heading_bias_sigma: stationary std of the heading-sensor error [rad].
        heading_bias_tau: its correlation time [s].
    """

    layout: StateLayout
    imu_period: float  # [s]
    accel_model_density: float  # [m/s^2/sqrt(Hz)]
    yaw_model_density: float  # [rad/s/sqrt(Hz)]
    gyro_bias_walk: float  # [rad/s/sqrt(s)]
    wheel_scale_walk: float  # [1/sqrt(s)]
    gps_bias_sigma: float = 0.0  # [m]
    gps_bias_tau: float = math.inf  # [s]
    heading_bias_sigma: float = 0.0  # [rad]
    heading_bias_tau: float = math.inf  # [s]


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
    """Propagate the state over ``dt`` with the IMU input held (module docstring).

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
    """F = d motion_model / dx, (n, n) (formulas in the module docstring)."""
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
    """G = d motion_model / du, (n, 3) (formulas in the module docstring)."""
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


def h_position(x: FloatArray, layout: StateLayout) -> FloatArray:
    """Expected GPS position of the antenna in ``reference`` [m], (2, 1)."""
    z = x[X : Y + 1].copy()
    if layout.gps_bias:
        z += x[N_CORE : N_CORE + 2]
    return z


def jacob_h_position(x: FloatArray, layout: StateLayout) -> FloatArray:
    """H of :func:`h_position`, (2, n)."""
    h = np.zeros((2, layout.n))
    h[0, X] = h[1, Y] = 1.0
    if layout.gps_bias:
        h[0, N_CORE] = h[1, N_CORE + 1] = 1.0
    return h


def h_heading(x: FloatArray, layout: StateLayout) -> FloatArray:
    """Expected heading [rad], (1, 1), not wrapped (the residual is)."""
    z = x[YAW : YAW + 1].copy()
    k = layout.heading_bias_index
    if k is not None:
        z += x[k : k + 1]
    return z


def jacob_h_heading(x: FloatArray, layout: StateLayout) -> FloatArray:
    """H of :func:`h_heading`, (1, n)."""
    h = np.zeros((1, layout.n))
    h[0, YAW] = 1.0
    k = layout.heading_bias_index
    if k is not None:
        h[0, k] = 1.0
    return h


def h_wheel_speed(x: FloatArray, layout: StateLayout) -> FloatArray:
    """Expected wheel speed wheel_scale * vx [m/s], (1, 1)."""
    return np.array([[x[WHEEL_SCALE, 0] * x[VX, 0]]])


def jacob_h_wheel_speed(x: FloatArray, layout: StateLayout) -> FloatArray:
    """H of :func:`h_wheel_speed`, (1, n)."""
    h = np.zeros((1, layout.n))
    h[0, VX] = x[WHEEL_SCALE, 0]
    h[0, WHEEL_SCALE] = x[VX, 0]
    return h


class MotionStep:
    """f(x, u, dt), F and Q of one interval, together (module docstring: written for speed).

    Args:
        model: layout and noise settings.

    Attributes:
        model: the settings.
    """

    def __init__(self, model: ProcessModel) -> None:
        self.model = model
        layout = model.layout
        n = layout.n
        self._f = np.eye(n)  # F; the same entries are overwritten by every call
        self._g = np.zeros((n, 3))  # G; rows x..vy overwritten by every call, the rest stay 0
        self._qm = np.zeros((n, n))  # Q's model terms; likewise
        g, h = layout.gps_bias_index, layout.heading_bias_index
        self._g_index = -1 if g is None else g
        self._h_index = -1 if h is None else h
        self._imu_period = model.imu_period
        params = np.zeros(kernels.N_PARAMS)
        params[kernels.GPS_TAU] = model.gps_bias_tau
        params[kernels.HEADING_TAU] = model.heading_bias_tau
        params[kernels.QA] = model.accel_model_density**2
        params[kernels.QW] = model.yaw_model_density**2
        params[kernels.QB] = model.gyro_bias_walk**2
        params[kernels.QS] = model.wheel_scale_walk**2
        params[kernels.GPS_VAR] = model.gps_bias_sigma**2
        params[kernels.HEADING_VAR] = model.heading_bias_sigma**2
        params.flags.writeable = False
        self._params = params

    def __call__(
        self, x: FloatArray, u: FloatArray, u_cov: FloatArray, dt: float
    ) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Propagate over ``dt`` > 0 with the input held.

        Args:
            x: state, (n, 1).
            u: IMU input (w_m, a_x, a_y), (3,).
            u_cov: its per-sample covariance, (3, 3).
            dt: interval [s], > 0.

        Returns:
            (x' (n, 1), new and unwrapped as from :func:`motion_model`; F (n, n),
            an array this object overwrites on its next call; Q (n, n), new).
        """
        n = self._f.shape[0]
        if x.shape != (n, 1) or u.shape != (3,):  # the kernel does not check bounds
            raise ValueError(f"MotionStep: x {x.shape}, u {u.shape}; expected ({n}, 1) and (3,)")
        out = np.empty_like(x)
        f, gu, qm = self._f, self._g, self._qm
        kernels.motion_terms(x, u, dt, self._g_index, self._h_index, self._params, out, f, gu, qm)
        q = np.dot(np.dot(gu, u_cov * (self._imu_period / dt)), gu.T)  # less overhead than @
        q += qm
        return out, f, q
