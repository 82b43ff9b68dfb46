"""The fusion EKF's state, its layout, and the motion model's settings and typed call.

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
10  map_bias_e    the cone map's offset east (optional, constant)        m
11  map_bias_n    the cone map's offset north (optional, constant)       m
==  ============  =====================================================  ========

(Indices of the optional states are those with every optional state
present; each one absent moves the later ones down.)

Why this state. The state lives at the antenna because the antenna *is* the
``gps_antenna`` frame the filter publishes (spec 000): GPS fixes observe it
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
The map's offset (``cones`` mode, ``localization.cones``) is the survey's
datum error, one constant for the whole map: in the state, a receiver that
is better than the map (RTK) estimates it, instead of the map's cones
pulling the pose off by it, and with a poorer one the map's small prior
keeps the pose on the map.

Motion model and observation models
-----------------------------------
The motion model (the IMU as the input, held over each interval) is the
compiled kernel :func:`localization.ekf.kernels.motion_terms`, whose
docstring derives x' = f(x, u, dt), the Jacobians F = df/dx and G = df/du and
the process noise Q; :class:`MotionStep` is its one typed Python call, and
:class:`ProcessModel` its settings. The observation models h(x) and their
Jacobians H are :mod:`localization.ekf.observation`.
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


@dataclass(frozen=True, slots=True)
class StateLayout:
    """Which optional states the filter carries, and where they are.

    Attributes:
        gps_bias: whether the Gauss-Markov receiver error (east, north) is in the state.
        heading_bias: whether the Gauss-Markov heading-sensor error is in the state.
        map_bias: whether the cone map's constant offset (east, north) is in the state.
    """

    gps_bias: bool = False
    heading_bias: bool = False
    map_bias: bool = False

    @property
    def n(self) -> int:
        """State dimension."""
        return N_CORE + 2 * self.gps_bias + self.heading_bias + 2 * self.map_bias

    @property
    def gps_bias_index(self) -> int | None:
        """Index of gps_bias_e (gps_bias_n follows), or None."""
        return N_CORE if self.gps_bias else None

    @property
    def heading_bias_index(self) -> int | None:
        """Index of heading_bias, or None."""
        return N_CORE + 2 * self.gps_bias if self.heading_bias else None

    @property
    def map_bias_index(self) -> int | None:
        """Index of map_bias_e (map_bias_n follows), or None."""
        return N_CORE + 2 * self.gps_bias + self.heading_bias if self.map_bias else None

    @property
    def names(self) -> tuple[str, ...]:
        """State names in index order."""
        extra = ("gps_bias_e", "gps_bias_n") * self.gps_bias + ("heading_bias",) * self.heading_bias
        extra += ("map_bias_e", "map_bias_n") * self.map_bias
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


class MotionStep:
    """The motion model over one interval: x' = f(x, u, dt), F = df/dx and Q, together.

    The one Python call of :func:`localization.ekf.kernels.motion_terms`
    (whose docstring has the equations): it packs the settings for the kernel
    once, checks the shapes the kernel does not, and adds Q's G Sigma G' with
    numpy's BLAS products. Together in one call because this is the filter's
    hot path (every IMU sample, every replay, every estimate ahead): x', F, G
    and Q's model terms share their trigonometry.

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
            (x' (n, 1), new, yaw unwrapped (the filter wraps); F (n, n), an
            array this object overwrites on its next call; Q (n, n), new).
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
