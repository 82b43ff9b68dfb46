"""Planar IMU: yaw rate and longitudinal/lateral specific force in ``gps_antenna``.

An integrating IMU, as MEMS parts with a decimation filter are: ``observe`` is
called at every physics step with that step's mean yaw rate and acceleration,
and a capture reports the mean since the previous capture, so the sample
stamped t describes the interval (t - 1/rate, t] (causal; the EKF integrates
each sample up to its own stamp).

Measurement at capture k, for each channel (gyro z, accel x, accel y)::

    m[k] = mean(true over the interval) + c + b[k] + s * sigma_d * v[k],
    sigma_d = N / sqrt(dt_s),  v ~ N(0, 1)
    b[k+1] = b[k] + K * sqrt(dt) * w[k],      b[0] = 0 (calibrated at start)

with N the white-noise density (gyro angle random walk, accelerometer velocity
random walk), dt_s = 1 / rate the sample period, K the bias random-walk
density (``noise.BiasRandomWalk``; dt = time between captures), c a constant
bias (``gyro_bias``, ``accel_bias``: a calibration left wrong) and s the
``noise_scale`` (a part noisier than its datasheet). The message states the
datasheet's white-noise variance sigma_d^2 (a driver knows its noise
density, not its current bias, nor that the part is worse than specified).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from conesim.core.messages import FRAME_GPS_ANTENNA, Header, Imu
from conesim.sim.sensors.noise import BiasRandomWalk, white_sigma
from conesim.sim.sensors.streams import stream
from conesim.sim.sensors.timing import SensorTiming
from conesim.sim.sensors.truth import TruthSample
from conesim.sim.sensors.validation import check_finite, check_non_negative, check_pair

STANDARD_GRAVITY = 9.80665  # [m/s^2]

# Datasheet figures (REFERENCES.md "Sensors"), converted to SI.
# ADIS16448: gyro 0.0135 deg/s/sqrt(Hz); accelerometer 0.23 mg/sqrt(Hz).
ADIS16448_GYRO_DENSITY = math.radians(0.0135)  # [rad/s/sqrt(Hz)]
ADIS16448_ACCEL_DENSITY = 0.23e-3 * STANDARD_GRAVITY  # [m/s^2/sqrt(Hz)]
# MPU-6000 as AirSim models it (ImuSimpleParams.hpp): gyro ARW 0.30 deg/sqrt(h),
# i.e. 0.30 / 60 deg/sqrt(s); accelerometer 0.24 mg/sqrt(Hz).
MPU6000_GYRO_DENSITY = math.radians(0.30 / 60.0)  # [rad/s/sqrt(Hz)] = [rad/sqrt(s)]
MPU6000_ACCEL_DENSITY = 0.24e-3 * STANDARD_GRAVITY  # [m/s^2/sqrt(Hz)]
# Bias random walk K = bias instability / sqrt(tau), as AirSim's ImuSimple.hpp:
# gyro 4.6 deg/h with tau 500 s; accelerometer 36 ug with tau 800 s.
MPU6000_GYRO_BIAS_WALK = math.radians(4.6 / 3600.0) / math.sqrt(500.0)  # [rad/s/sqrt(s)]
MPU6000_ACCEL_BIAS_WALK = 36e-6 * STANDARD_GRAVITY / math.sqrt(800.0)  # [m/s^2/sqrt(s)]


@dataclass(frozen=True)
class ImuConfig(SensorTiming):
    """IMU settings (defaults: ADIS16448 white noise, REFERENCES.md "Sensors").

    Attributes:
        gyro_noise_density: gyro white-noise density [rad/s/sqrt(Hz)].
        accel_noise_density: accelerometer white-noise density [m/s^2/sqrt(Hz)].
        gyro_bias_walk: gyro bias random-walk density [rad/s/sqrt(s)].
        accel_bias_walk: accelerometer bias random-walk density [m/s^2/sqrt(s)].
        gyro_bias: constant gyro bias [rad/s].
        accel_bias: constant accelerometer bias (x, y) [m/s^2].
        noise_scale: the white noise drawn is this times the densities' [-];
            the messages state the densities' variance.
    """

    rate: float = 100.0  # [Hz]
    latency: float = 0.0  # [s]
    gyro_noise_density: float = ADIS16448_GYRO_DENSITY  # [rad/s/sqrt(Hz)]
    accel_noise_density: float = ADIS16448_ACCEL_DENSITY  # [m/s^2/sqrt(Hz)]
    gyro_bias_walk: float = 0.0  # [rad/s/sqrt(s)]
    accel_bias_walk: float = 0.0  # [m/s^2/sqrt(s)]
    gyro_bias: float = 0.0  # [rad/s]
    accel_bias: tuple[float, float] = (0.0, 0.0)  # [m/s^2] (x, y)
    noise_scale: float = 1.0  # [-]

    def _validate(self) -> None:
        owner = "ImuConfig"
        check_non_negative(owner, "gyro_noise_density", self.gyro_noise_density, "[rad/s/sqrt(Hz)]")
        check_non_negative(
            owner, "accel_noise_density", self.accel_noise_density, "[m/s^2/sqrt(Hz)]"
        )
        check_non_negative(owner, "gyro_bias_walk", self.gyro_bias_walk, "[rad/s/sqrt(s)]")
        check_non_negative(owner, "accel_bias_walk", self.accel_bias_walk, "[m/s^2/sqrt(s)]")
        check_finite(owner, "gyro_bias", self.gyro_bias, "[rad/s]")
        bias = check_pair(owner, "accel_bias", self.accel_bias, "(x, y) [m/s^2]")
        object.__setattr__(self, "accel_bias", bias)
        check_non_negative(owner, "noise_scale", self.noise_scale, "[-]")

    @property
    def gyro_sigma(self) -> float:
        """Discrete gyro white-noise std at this rate [rad/s]."""
        return white_sigma(self.gyro_noise_density, self.period)

    @property
    def accel_sigma(self) -> float:
        """Discrete accelerometer white-noise std at this rate [m/s^2]."""
        return white_sigma(self.accel_noise_density, self.period)


class ImuSensor:
    """Simulated planar IMU publishing ``Imu`` in ``gps_antenna``.

    Args:
        config: the IMU's settings.
        seed: episode seed (streams "imu/gyro_white", "imu/accel_white",
            "imu/gyro_bias", "imu/accel_bias").
    """

    name = "imu"

    def __init__(self, config: ImuConfig, seed: int) -> None:
        self.config = config
        self._sigma_cache: tuple[ImuConfig, float, float, float, float] | None = None
        self.reset(seed)

    def reset(self, seed: int) -> None:
        """Restart the noise streams and zero the biases."""
        cfg = self.config
        self._gyro_white = stream(seed, self.name, "gyro_white")
        self._accel_white = stream(seed, self.name, "accel_white")
        self._gyro_bias = BiasRandomWalk(cfg.gyro_bias_walk, stream(seed, self.name, "gyro_bias"))
        self._accel_bias = BiasRandomWalk(
            cfg.accel_bias_walk, stream(seed, self.name, "accel_bias"), dim=2
        )
        self._last_t: float | None = None
        self._sum = [0.0, 0.0, 0.0]
        self._count = 0

    def observe(self, truth: TruthSample) -> None:
        """Integrate one physics step's motion (called at every step)."""
        acc = self._sum
        acc[0] += truth.yaw_rate
        acc[1] += truth.accel_x
        acc[2] += truth.accel_y
        self._count += 1

    def _sigmas(self) -> tuple[float, float, float, float]:
        """(gyro, accel) white-noise std stated, then drawn (times ``noise_scale``),
        of the current config, worked out once per config."""
        cfg = self.config
        cached = self._sigma_cache
        if cached is None or cached[0] is not cfg:
            sg, sa, scale = cfg.gyro_sigma, cfg.accel_sigma, cfg.noise_scale
            cached = self._sigma_cache = (cfg, sg, sa, scale * sg, scale * sa)
        return cached[1], cached[2], cached[3], cached[4]

    def capture(self, truth: TruthSample) -> Imu:
        """The IMU sample of a capture at ``truth.t``: the mean since the last one."""
        t = truth.t
        if self._count:
            n = self._count
            acc = self._sum
            yaw_rate, accel_x, accel_y = acc[0] / n, acc[1] / n, acc[2] / n
        else:  # captured without observing (a sensor used on its own)
            yaw_rate, accel_x, accel_y = truth.yaw_rate, truth.accel_x, truth.accel_y
        self._sum = [0.0, 0.0, 0.0]
        self._count = 0
        dt = 0.0 if self._last_t is None else t - self._last_t
        self._last_t = t
        (bg,) = self._gyro_bias.step(dt)
        ba0, ba1 = self._accel_bias.step(dt)
        sg, sa, dg, da = self._sigmas()
        gyro = yaw_rate + bg
        ax, ay = accel_x + ba0, accel_y + ba1
        # Without white noise (the ideal profile) nothing is drawn: sigma times
        # a draw is a signed zero, and adding one to these sums (never -0.0, as
        # b starts at +0) leaves them as they are, bit for bit; each stream is
        # its own, so no other draw moves.
        if dg != 0.0:
            gyro += dg * float(self._gyro_white.standard_normal())
        if da != 0.0:
            wa0, wa1 = self._accel_white.standard_normal(2).tolist()
            ax, ay = ax + da * wa0, ay + da * wa1
        cfg = self.config
        if cfg.gyro_bias != 0.0:  # without one, the sum itself (bit for bit)
            gyro += cfg.gyro_bias
        if cfg.accel_bias != (0.0, 0.0):
            ax, ay = ax + cfg.accel_bias[0], ay + cfg.accel_bias[1]
        return Imu(Header(t, FRAME_GPS_ANTENNA), gyro, ax, ay, sg * sg, sa * sa)
