"""Settings of the fusion EKF: one frozen dataclass, with per-profile defaults.

The sensor noise itself comes from the messages (each states its variance);
these settings say what the messages cannot: how the errors are correlated in
time, what else the model leaves out, how sure the first estimate is, and how
hard to gate. Per-profile defaults (``for_profile``) carry the receiver error
models of ``sim.sensors.profiles`` (u-blox M8 and ZED-F9P figures,
REFERENCES.md "Sensors"), as a team would characterise its own receiver.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from dataclasses import dataclass

from conesim.core.geodesy import DEFAULT_ORIGIN, ReferenceOrigin
from conesim.core.messages import FRAME_GPS_ANTENNA, FRAME_REFERENCE
from conesim.localization.ekf.model import ProcessModel, StateLayout


@dataclass(frozen=True, slots=True)
class EkfConfig:
    """Noise model, initialisation, gating and history of the fusion EKF.

    Attributes:
        imu_rate: rate at which the IMU states its per-sample variance [Hz].
        accel_model_density: white acceleration the IMU does not explain
            (accelerometer bias, the input held between samples) [m/s^2/sqrt(Hz)].
        yaw_model_density: white yaw rate the gyro does not explain [rad/s/sqrt(Hz)].
        gyro_bias_walk: gyro bias random walk [rad/s/sqrt(s)].
        wheel_scale_walk: wheel-speed scale random walk [1/sqrt(s)].
        gps_bias_sigma: stationary std of the receiver's correlated error per
            axis [m]; 0 leaves it out of the state (white GPS noise).
        gps_bias_tau: its correlation time [s].
        heading_bias_sigma: stationary std of the heading sensor's correlated
            error [rad]; 0 leaves it out of the state.
        heading_bias_tau: its correlation time [s].
        gps_sigma_floor: smallest GPS sigma per axis used in an update [m].
        heading_sigma_floor: smallest heading sigma used in an update [rad].
        speed_sigma_floor: smallest wheel-speed sigma used in an update [m/s].
        init_speed_sigma: sigma of the initial vx when no wheel speed is at hand [m/s].
        init_lateral_speed_sigma: sigma of the initial vy (set to 0) at rest [m/s].
        init_sideslip_sigma: sideslip sigma that adds ``init_sideslip_sigma * |vx|``
            to it: a car's antenna slides at a few degrees at most [rad].
        init_gyro_bias_sigma: sigma of the initial gyro bias (set to 0) [rad/s].
        init_wheel_scale_sigma: sigma of the initial wheel scale (set to 1) [-].
        init_sync_tolerance: largest stamp difference between the first fix
            and the heading (and wheel speed) used with it [s].
        init_yaw_rate_bound: yaw rate assumed at worst over that difference,
            to widen the initial yaw variance [rad/s].
        gate_probability: chi-square probability of the NIS gate [-], in (0, 1).
        history_window: how far back a late measurement is still applied [s].
        max_consecutive_gps_rejections: gated GPS fixes in a row after which
            the filter resets and initialises again [-].
        max_stamp_jump: a message stamped more than this after the newest one
            is rejected as too new (a clock glitch, e.g. a GPS-UTC leap-second
            offset) [s].
        clock_jump_messages: messages in a row rejected as too old or too new
            after which the clock itself is taken to have jumped: the filter
            resets and initialises again from the messages that follow [-].
        origin: geodetic origin of ``reference`` (fixes are projected about it).
        reference_frame: frame of positions and headings.
        antenna_frame: frame of the GPS, IMU and wheel-speed messages.
    """

    imu_rate: float = 100.0  # [Hz]
    # Tuned on sim.world (bench_ekf, 50 runs of autocross): see the README's
    # benchmark table for the NEES they give.
    # With the world's truth consistent to the step (sim.world), the model
    # leaves out little: 0.0015 / 1e-4 / 1e-4 gave rtk a mean NEES of 2.77 with
    # 85 % of time steps in band, these 2.89 and 91 %.
    accel_model_density: float = 0.001  # [m/s^2/sqrt(Hz)]
    yaw_model_density: float = 3e-5  # [rad/s/sqrt(Hz)]
    # 5x the gyro's own bias walk (REFERENCES.md: 4.6 deg/h over 500 s ->
    # 1.0e-6 rad/s/sqrt(s)); 1e-4 made the yaw variance 1.5x too large.
    gyro_bias_walk: float = 5e-6  # [rad/s/sqrt(s)]
    wheel_scale_walk: float = 1e-4  # [1/sqrt(s)]
    gps_bias_sigma: float = 0.0  # [m]
    gps_bias_tau: float = 60.0  # [s]
    heading_bias_sigma: float = 0.0  # [rad]
    heading_bias_tau: float = 60.0  # [s]
    gps_sigma_floor: float = 0.002  # [m]
    heading_sigma_floor: float = 1e-4  # [rad]
    speed_sigma_floor: float = 0.005  # [m/s]
    init_speed_sigma: float = 2.0  # [m/s]
    init_lateral_speed_sigma: float = 0.05  # [m/s]
    init_sideslip_sigma: float = 0.05  # [rad]
    init_gyro_bias_sigma: float = 0.005  # [rad/s]
    init_wheel_scale_sigma: float = 0.01  # [-]
    init_sync_tolerance: float = 0.1  # [s]
    init_yaw_rate_bound: float = 2.0  # [rad/s]
    gate_probability: float = 0.999  # [-]
    history_window: float = 1.0  # [s]
    max_consecutive_gps_rejections: int = 20  # [-]
    max_stamp_jump: float = 1.0  # [s]
    clock_jump_messages: int = 10  # [-]: 0.1 s of the 100 Hz IMU alone
    origin: ReferenceOrigin = DEFAULT_ORIGIN
    reference_frame: str = FRAME_REFERENCE
    antenna_frame: str = FRAME_GPS_ANTENNA

    def __post_init__(self) -> None:
        positive = (
            "imu_rate",
            "gps_bias_tau",
            "heading_bias_tau",
            "history_window",
            "max_stamp_jump",
        )
        for name in positive:
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0.0):
                raise ValueError(f"EkfConfig.{name} = {value!r} is out of range: allowed > 0")
        for f in dataclasses.fields(self):
            value = getattr(self, f.name)
            if isinstance(value, float) and not (math.isfinite(value) and value >= 0.0):
                raise ValueError(
                    f"EkfConfig.{f.name} = {value!r} is out of range: allowed finite and >= 0"
                )
        if not 0.0 < self.gate_probability < 1.0:
            raise ValueError(
                f"EkfConfig.gate_probability = {self.gate_probability!r} is out of range: "
                "allowed (0, 1)"
            )
        for name in ("max_consecutive_gps_rejections", "clock_jump_messages"):
            if getattr(self, name) < 1:
                raise ValueError(
                    f"EkfConfig.{name} = {getattr(self, name)!r} is out of range: allowed >= 1"
                )

    @property
    def layout(self) -> StateLayout:
        """The state layout these settings imply."""
        return StateLayout(
            gps_bias=self.gps_bias_sigma > 0.0, heading_bias=self.heading_bias_sigma > 0.0
        )

    def process_model(self, layout: StateLayout | None = None) -> ProcessModel:
        """The motion model's settings (on ``layout``, default :attr:`layout`)."""
        return ProcessModel(
            layout=layout or self.layout,
            imu_period=1.0 / self.imu_rate,
            accel_model_density=self.accel_model_density,
            yaw_model_density=self.yaw_model_density,
            gyro_bias_walk=self.gyro_bias_walk,
            wheel_scale_walk=self.wheel_scale_walk,
            gps_bias_sigma=self.gps_bias_sigma,
            gps_bias_tau=self.gps_bias_tau,
            heading_bias_sigma=self.heading_bias_sigma,
            heading_bias_tau=self.heading_bias_tau,
        )


# Receiver error models as sim.sensors.profiles states them (and why):
# rtk: ZED-F9P fixed RTK, 2.5 cm white per axis; heading white.
# consumer: u-blox M8, 2.12 m per axis of which 2.0 m correlated (tau 60 s);
#   heading 1 deg white + 2 deg correlated (tau 60 s).
# consumer_white: the same 2.12 m and 2.24 deg, all white.
PROFILES: Mapping[str, EkfConfig] = {
    "ideal": EkfConfig(),
    "rtk": EkfConfig(),
    "consumer": EkfConfig(
        gps_bias_sigma=2.0,
        gps_bias_tau=60.0,
        heading_bias_sigma=math.radians(2.0),
        heading_bias_tau=60.0,
        gyro_bias_walk=2e-4,
    ),
    "consumer_white": EkfConfig(gyro_bias_walk=2e-4),
}


def for_profile(name: str, **overrides: object) -> EkfConfig:
    """The EKF settings tuned for a sensor profile, with fields replaced.

    Args:
        name: ``ideal``, ``rtk``, ``consumer`` or ``consumer_white``.
        **overrides: EkfConfig fields to replace.

    Raises:
        ValueError: an unknown profile or field (the message lists the allowed ones).
    """
    if name not in PROFILES:
        raise ValueError(f"unknown EKF profile {name!r}; allowed: {', '.join(PROFILES)}")
    fields = [f.name for f in dataclasses.fields(EkfConfig)]
    unknown = sorted(set(overrides) - set(fields))
    if unknown:
        raise ValueError(f"unknown EkfConfig field(s) {unknown}; allowed: {', '.join(fields)}")
    return dataclasses.replace(PROFILES[name], **overrides)  # type: ignore[arg-type]
