"""A synthetic car and its sensors, for the filter's consistency tests and benchmark.

Filter consistency (Bar-Shalom: NEES, NIS) can only be judged against sensors
whose noise is exactly what the messages state. This module makes such data
without the simulator: a car on a winding loop with known truth, and white
sensor noise drawn from a caller's ``numpy.random.Generator``. It is test
support (as ``numpy.testing`` is for numpy) and nothing in the pipeline uses it.

The path: yaw rate w(t) = w0 + w1 sin(2 pi t / tw), forward speed
vx(t) = v0 + v1 sin(2 pi t / tv), a small sideslip vy = c w vx; the car turns
all the time, so its yaw crosses +-pi every few seconds. Positions are
integrated with tight tolerances (``scipy.integrate.solve_ivp``).

The IMU reports the *interval mean* of the yaw rate and specific force over
the sample period that ends at its stamp (an integrating IMU, as real MEMS
parts and the simulator's IMU are: causal). That is the input the filter's
hold assumes (each sample drives the prediction up to its own stamp), so a
test measures the filter's own consistency, not a sampling mismatch. Each
run draws a constant gyro bias and wheel-speed scale from the filter's priors.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.integrate import solve_ivp

from conesim.core.geodesy import local_cartesian_to_gps
from conesim.core.messages import (
    FRAME_GPS_ANTENNA,
    FRAME_REFERENCE,
    Header,
    HeadingStamped,
    Imu,
    Message,
    NavSatFix,
    WheelSpeed,
)
from conesim.core.pose import Pose2D, wrap_angle

FloatArray = NDArray[np.float64]
TWO_PI = 2.0 * math.pi
GRID_RATE = 200.0  # [Hz] truth grid; every sensor rate divides it


@dataclass(frozen=True, slots=True)
class Path:
    """The car's motion as closed-form functions of time.

    Attributes:
        w0: mean yaw rate [rad/s].
        w1: yaw-rate swing [rad/s].
        tw: its period [s].
        v0: mean forward speed [m/s].
        v1: speed swing [m/s].
        tv: its period [s].
        c: sideslip gain, vy = c w vx [s].
        yaw0: initial yaw [rad].
        start: initial antenna position (x, y) [m].
    """

    w0: float = 0.7  # [rad/s]
    w1: float = 0.4  # [rad/s]
    tw: float = 8.0  # [s]
    v0: float = 10.0  # [m/s]
    v1: float = 2.0  # [m/s]
    tv: float = 6.0  # [s]
    c: float = -0.02  # [s]
    yaw0: float = 2.5  # [rad]
    start: tuple[float, float] = (5.0, -3.0)  # [m]

    def yaw_rate(self, t: ArrayLike) -> FloatArray:
        """w(t) [rad/s]."""
        return np.asarray(self.w0 + self.w1 * np.sin(TWO_PI * np.asarray(t) / self.tw))

    def yaw(self, t: ArrayLike) -> FloatArray:
        """The integral of w from 0, unwrapped [rad]."""
        ta = np.asarray(t)
        swing = self.w1 * self.tw / TWO_PI * (1.0 - np.cos(TWO_PI * ta / self.tw))
        return np.asarray(self.yaw0 + self.w0 * ta + swing)

    def velocity(self, t: ArrayLike) -> FloatArray:
        """Body velocity (vx, vy) [m/s], shape (2, ...)."""
        vx = self.v0 + self.v1 * np.sin(TWO_PI * np.asarray(t) / self.tv)
        return np.array([vx, self.c * self.yaw_rate(t) * vx])

    def specific_force(self, t: ArrayLike) -> FloatArray:
        """Body-frame (ax, ay) = dv/dt + w x v [m/s^2], shape (2, ...)."""
        ta = np.asarray(t)
        w = self.yaw_rate(ta)
        dw = self.w1 * TWO_PI / self.tw * np.cos(TWO_PI * ta / self.tw)
        vx, vy = self.velocity(ta)
        dvx = self.v1 * TWO_PI / self.tv * np.cos(TWO_PI * ta / self.tv)
        dvy = self.c * (dw * vx + w * dvx)
        return np.array([dvx - w * vy, dvy + w * vx])


@dataclass(frozen=True, slots=True)
class Truth:
    """The path on a 200 Hz grid.

    Attributes:
        t: grid times [s], (n,).
        xy: antenna positions [m], (n, 2).
        yaw: yaw, unwrapped [rad], (n,).
        v: body velocity [m/s], (n, 2).
        imu: interval-mean (w [rad/s], ax, ay [m/s^2]) over [t - imu period, t], (n, 3).
    """

    t: FloatArray
    xy: FloatArray
    yaw: FloatArray
    v: FloatArray
    imu: FloatArray

    def index(self, stamp: float) -> int:
        """Grid index of a stamp."""
        return round(stamp * GRID_RATE)

    def pose(self, stamp: float) -> Pose2D:
        """The true antenna pose at a grid stamp."""
        k = self.index(stamp)
        return Pose2D(float(self.xy[k, 0]), float(self.xy[k, 1]), float(wrap_angle(self.yaw[k])))


def make_truth(path: Path, duration: float, imu_rate: float = 100.0) -> Truth:
    """Sample ``path`` on the 200 Hz grid for ``duration`` [s]."""
    t = np.arange(round(duration * GRID_RATE) + 1) / GRID_RATE

    def world_velocity(time: float, _p: FloatArray) -> FloatArray:
        yaw = float(path.yaw(time))
        vx, vy = path.velocity(time)
        c, s = math.cos(yaw), math.sin(yaw)
        return np.array([c * vx - s * vy, s * vx + c * vy])

    sol = solve_ivp(
        world_velocity, (0.0, float(t[-1])), list(path.start), t_eval=t, rtol=1e-11, atol=1e-11
    )
    period = 1.0 / imu_rate
    imu = np.zeros((len(t), 3))
    imu[:, 0] = (path.yaw(t) - path.yaw(t - period)) / period
    nodes, weights = np.polynomial.legendre.leggauss(4)
    for node, weight in zip(nodes, weights, strict=True):
        imu[:, 1:] += 0.5 * weight * path.specific_force(t - 0.5 * period * (1.0 - node)).T
    return Truth(t, sol.y.T, path.yaw(t), path.velocity(t).T, imu)


@dataclass(frozen=True, slots=True)
class SensorNoise:
    """White sensor noise (per sample), rates, latencies and per-run error draws.

    Attributes:
        gps: per-axis sigma [m].
        heading: sigma [rad].
        gyro: per-sample sigma [rad/s].
        accel: per-sample sigma [m/s^2].
        wheel: sigma [m/s].
        gyro_bias: std of the constant gyro bias drawn per run [rad/s].
        wheel_scale: std of the wheel-speed scale error drawn per run [-].
        gps_rate, heading_rate, imu_rate, wheel_rate: [Hz], dividing 200 Hz.
        gps_latency, heading_latency: delivery delay after the stamp [s].
    """

    gps: float = 0.03  # [m]
    heading: float = math.radians(0.25)  # [rad]
    gyro: float = 2.4e-3  # [rad/s] ADIS16448 density at 100 Hz
    accel: float = 0.023  # [m/s^2] ADIS16448 density at 100 Hz
    wheel: float = 0.05  # [m/s]
    gyro_bias: float = 0.005  # [rad/s]
    wheel_scale: float = 0.01  # [-]
    gps_rate: float = 10.0  # [Hz]
    heading_rate: float = 20.0  # [Hz]
    imu_rate: float = 100.0  # [Hz]
    wheel_rate: float = 50.0  # [Hz]
    gps_latency: float = 0.0  # [s]
    heading_latency: float = 0.0  # [s]


def fix_message(stamp: float, x: float, y: float, sigma: float) -> NavSatFix:
    """A fix at ``(x, y)`` in ``reference`` [m] stating per-axis ``sigma`` [m]."""
    lat, lon = local_cartesian_to_gps(x, y)
    cov = np.diag([sigma**2, sigma**2, (2.0 * sigma) ** 2])
    return NavSatFix(Header(stamp, FRAME_GPS_ANTENNA), float(lat), float(lon), 0.0, cov)


def messages(
    truth: Truth,
    noise: SensorNoise,
    rng: np.random.Generator,
    *,
    outliers: frozenset[float] = frozenset(),
    gps_gap: tuple[float, float] | None = None,
    outlier_size: float = 20.0,
) -> Iterator[tuple[float, Message]]:
    """The sensors' messages over the whole truth, in delivery order.

    Args:
        truth: the path.
        noise: noise settings.
        rng: the run's generator (one per run).
        outliers: fix stamps [s] displaced by ``outlier_size`` (multipath).
        gps_gap: (start, end) [s] without fixes (a silent dropout).
        outlier_size: multipath displacement [m].

    Yields:
        (delivery time [s], message); equal delivery times in the order
        IMU, wheel speed, heading, GPS.
    """
    bias = noise.gyro_bias * float(rng.standard_normal())
    scale = 1.0 + noise.wheel_scale * float(rng.standard_normal())
    every = {
        name: round(GRID_RATE / rate)
        for name, rate in (
            ("imu", noise.imu_rate),
            ("wheel", noise.wheel_rate),
            ("heading", noise.heading_rate),
            ("gps", noise.gps_rate),
        )
    }
    sigmas = np.array([noise.gyro, noise.accel, noise.accel])
    marked = {truth.index(stamp) for stamp in outliers}
    out: list[tuple[float, int, Message]] = []
    for k, t in enumerate(truth.t.tolist()):
        if k % every["imu"] == 0:
            w, ax, ay = (truth.imu[k] + sigmas * rng.standard_normal(3)).tolist()
            header = Header(t, FRAME_GPS_ANTENNA)
            out.append((t, 0, Imu(header, w + bias, ax, ay, noise.gyro**2, noise.accel**2)))
        if k % every["wheel"] == 0:
            speed = scale * float(truth.v[k, 0]) + noise.wheel * float(rng.standard_normal())
            out.append((t, 1, WheelSpeed(Header(t, FRAME_GPS_ANTENNA), speed, noise.wheel**2)))
        if k % every["heading"] == 0:
            yaw = float(wrap_angle(truth.yaw[k] + noise.heading * rng.standard_normal()))
            msg = HeadingStamped(Header(t, FRAME_REFERENCE), yaw, noise.heading**2)
            out.append((t + noise.heading_latency, 2, msg))
        if k % every["gps"] == 0:
            e = noise.gps * rng.standard_normal(2)
            if k in marked:
                e += outlier_size * np.array([math.cos(7.0 * t), math.sin(7.0 * t)])
            if gps_gap is None or not gps_gap[0] <= t < gps_gap[1]:
                fix = fix_message(t, truth.xy[k, 0] + e[0], truth.xy[k, 1] + e[1], noise.gps)
                out.append((t + noise.gps_latency, 3, fix))
    out.sort(key=lambda item: (item[0], item[1]))
    return ((d, msg) for d, _, msg in out)
