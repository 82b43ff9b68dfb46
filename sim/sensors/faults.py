"""Sensor faults: named changes to a sensor profile that combine predictably.

A fault says what goes wrong with a sensor in the terms a test plan uses
("30 % of the cones missed", "no fix from 10 s to 12 s"); applied to a
``SensorProfile`` (``apply_faults``) it sets fields of the sensor configs, so
the sensor models need no fault logic of their own and a fault is visible
in the profile it makes. Each sensor has one frozen dataclass; a field at
its default is no fault::

    fault                              sets (in the sensor's config)
    cones.detection_probability  q     detection_probability_at_zero and _slope
                                       times q: p(r) -> q p(r), a miss of 1 - q
                                       on top of the detector's own
    cones.false_positives_per_scan n   false_positive_rate + n [1/scan]
    cones.colour_swap_probability  p   confusion -> confusion @ S(p): a blue
                                       label becomes yellow, and yellow blue,
                                       with probability p
    cones.noise_scale  s               range_sigma and bearing_sigma times s
    cones.extra_latency  L             latency + L [s]
    gps.dropouts  ((start, end), ...)  dropouts + (start, end - start) [s]
    gps.multipath_rate, _size          multipath_probability, _magnitude [m]
    gps.bias_drift, _start             drift_rate (east, north) [m/s], drift_start [s]
    imu.gyro_bias, accel_bias          gyro_bias + b [rad/s], accel_bias + b [m/s^2]
    imu.noise_scale  s                 noise_scale times s
    heading.dropouts  ((start, end),)  dropouts + (start, end - start) [s]
    wheel_speed.slip_sigma  s          slip_sigma -> hypot(slip_sigma, s)

Composable: every rule is a product, a sum, an appended window, a product
with a swap matrix or a sum in quadrature, and no two faults touch the same
field, so several faults give the same profile in any order (of sensors and
of keys). The two-parameter GPS faults (multipath, bias drift) set their
fields, replacing what an override of the profile set there. A fault never
changes what a message states about its noise: the EKF is not told.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from typing import Any, Protocol, TypeVar

from conesim.sim.sensors.cone_detector import MAX_FALSE_POSITIVES, ConeDetectorConfig
from conesim.sim.sensors.gps import GpsConfig
from conesim.sim.sensors.heading import HeadingConfig
from conesim.sim.sensors.imu import ImuConfig
from conesim.sim.sensors.profiles import SECTIONS, SensorProfile
from conesim.sim.sensors.validation import (
    check_closed,
    check_finite,
    check_non_negative,
    check_pair,
    check_probability,
)
from conesim.sim.sensors.wheel_speed import WheelSpeedConfig
from conesim.sim.sensors.windows import Windows

C = TypeVar("C")

Spans = tuple[tuple[float, float], ...]
"""((start [s], end [s]), ...): windows of capture time, as a test plan names them."""


class Fault(Protocol[C]):
    """What ``apply_faults`` needs of a sensor's faults."""

    def apply(self, config: C, /) -> C:
        """The sensor's config with the faults in it."""
        ...


def _check_spans(owner: str, name: str, spans: Spans) -> Spans:
    """The spans as tuples of floats, each with 0 <= start < end [s]."""
    out = []
    for i, span in enumerate(spans):
        pair = tuple(span)
        if not (
            len(pair) == 2
            and all(isinstance(v, int | float) and math.isfinite(v) for v in pair)
            and 0.0 <= pair[0] < pair[1]
        ):
            raise ValueError(
                f"{owner}.{name}[{i}] = {span!r} is out of range: "
                "allowed [start, end] [s] with 0 <= start < end"
            )
        out.append((float(pair[0]), float(pair[1])))
    return tuple(out)


def _windows(spans: Spans) -> Windows:
    """(start, end) spans as the sensors' (start, duration) windows."""
    return tuple((start, end - start) for start, end in spans)


@dataclass(frozen=True)
class ConeFaults:
    """Faults of the cone detector (see the module docstring for what each sets).

    Attributes:
        detection_probability: each cone the detector would report is
            reported with this probability (misses: 1 - q) [-].
        false_positives_per_scan: mean ghost cones added to every scan, at most
            ``MAX_FALSE_POSITIVES`` [1/scan].
        colour_swap_probability: chance that a blue label is reported yellow,
            and a yellow one blue [-].
        noise_scale: range and bearing noise times this [-].
        extra_latency: added delay from capture to delivery [s].
    """

    detection_probability: float = 1.0  # [-]
    false_positives_per_scan: float = 0.0  # [1/scan]
    colour_swap_probability: float = 0.0  # [-]
    noise_scale: float = 1.0  # [-]
    extra_latency: float = 0.0  # [s]

    def __post_init__(self) -> None:
        owner = "ConeFaults"
        check_probability(owner, "detection_probability", self.detection_probability)
        check_closed(
            owner, "false_positives_per_scan", self.false_positives_per_scan,
            low=0.0, high=MAX_FALSE_POSITIVES, unit="[1/scan]",
        )  # fmt: skip
        check_probability(owner, "colour_swap_probability", self.colour_swap_probability)
        check_non_negative(owner, "noise_scale", self.noise_scale, "[-]")
        check_non_negative(owner, "extra_latency", self.extra_latency, "[s]")

    def apply(self, config: ConeDetectorConfig) -> ConeDetectorConfig:
        """The detector's config with these faults in it."""
        changes: dict[str, Any] = {}
        q = self.detection_probability
        if q != 1.0:
            changes["detection_probability_at_zero"] = q * config.detection_probability_at_zero
            changes["detection_probability_slope"] = q * config.detection_probability_slope
        if self.false_positives_per_scan:
            changes["false_positive_rate"] = (
                config.false_positive_rate + self.false_positives_per_scan
            )
        p = self.colour_swap_probability
        if p:
            # (C @ S)[i] for S swapping blue and yellow with probability p
            changes["confusion"] = tuple(
                (b * (1.0 - p) + y * p, b * p + y * (1.0 - p), *rest)
                for b, y, *rest in config.confusion
            )
        s = self.noise_scale
        if s != 1.0:
            changes["range_sigma"] = s * config.range_sigma
            changes["bearing_sigma"] = s * config.bearing_sigma
        if self.extra_latency:
            changes["latency"] = config.latency + self.extra_latency
        return dataclasses.replace(config, **changes) if changes else config


@dataclass(frozen=True)
class GpsFaults:
    """Faults of the GNSS receiver (see the module docstring for what each sets).

    Attributes:
        dropouts: windows [start, end] of capture time without a fix [s]
            (the receiver's ``dropout_mode`` says whether it publishes NO_FIX
            or nothing).
        multipath_rate: share of fixes that are outliers [-].
        multipath_size: how far an outlier is displaced [m].
        bias_drift: (east, north) rate at which the fix walks off [m/s].
        bias_drift_start: capture time the drift starts [s].
    """

    dropouts: Spans = ()  # ((start [s], end [s]), ...)
    multipath_rate: float = 0.0  # [-]
    multipath_size: float = 10.0  # [m] assumption: a reflection off a building or truck
    bias_drift: tuple[float, float] = (0.0, 0.0)  # [m/s] (east, north)
    bias_drift_start: float = 0.0  # [s]

    def __post_init__(self) -> None:
        owner = "GpsFaults"
        object.__setattr__(self, "dropouts", _check_spans(owner, "dropouts", self.dropouts))
        check_probability(owner, "multipath_rate", self.multipath_rate)
        check_non_negative(owner, "multipath_size", self.multipath_size, "[m]")
        drift = check_pair(owner, "bias_drift", self.bias_drift, "(east, north) [m/s]")
        object.__setattr__(self, "bias_drift", drift)
        check_non_negative(owner, "bias_drift_start", self.bias_drift_start, "[s]")

    def apply(self, config: GpsConfig) -> GpsConfig:
        """The receiver's config with these faults in it."""
        changes: dict[str, Any] = {}
        if self.dropouts:
            changes["dropouts"] = (*config.dropouts, *_windows(self.dropouts))
        if self.multipath_rate:
            changes["multipath_probability"] = self.multipath_rate
            changes["multipath_magnitude"] = self.multipath_size
        if self.bias_drift != (0.0, 0.0):
            changes["drift_rate"] = self.bias_drift
            changes["drift_start"] = self.bias_drift_start
        return dataclasses.replace(config, **changes) if changes else config


@dataclass(frozen=True)
class ImuFaults:
    """Faults of the IMU (see the module docstring for what each sets).

    Attributes:
        gyro_bias: constant gyro bias added [rad/s].
        accel_bias: constant accelerometer bias added (x, y) [m/s^2].
        noise_scale: white noise times this; the stated variance stays [-].
    """

    gyro_bias: float = 0.0  # [rad/s]
    accel_bias: tuple[float, float] = (0.0, 0.0)  # [m/s^2] (x, y)
    noise_scale: float = 1.0  # [-]

    def __post_init__(self) -> None:
        owner = "ImuFaults"
        check_finite(owner, "gyro_bias", self.gyro_bias, "[rad/s]")
        bias = check_pair(owner, "accel_bias", self.accel_bias, "(x, y) [m/s^2]")
        object.__setattr__(self, "accel_bias", bias)
        check_non_negative(owner, "noise_scale", self.noise_scale, "[-]")

    def apply(self, config: ImuConfig) -> ImuConfig:
        """The IMU's config with these faults in it."""
        changes: dict[str, Any] = {}
        if self.gyro_bias:
            changes["gyro_bias"] = config.gyro_bias + self.gyro_bias
        if self.accel_bias != (0.0, 0.0):
            bx, by = config.accel_bias
            changes["accel_bias"] = (bx + self.accel_bias[0], by + self.accel_bias[1])
        if self.noise_scale != 1.0:
            changes["noise_scale"] = config.noise_scale * self.noise_scale
        return dataclasses.replace(config, **changes) if changes else config


@dataclass(frozen=True)
class HeadingFaults:
    """Faults of the dual-antenna heading.

    Attributes:
        dropouts: windows [start, end] of capture time without a heading [s].
    """

    dropouts: Spans = ()  # ((start [s], end [s]), ...)

    def __post_init__(self) -> None:
        object.__setattr__(
            self, "dropouts", _check_spans("HeadingFaults", "dropouts", self.dropouts)
        )

    def apply(self, config: HeadingConfig) -> HeadingConfig:
        """The heading sensor's config with these faults in it."""
        if not self.dropouts:
            return config
        return dataclasses.replace(config, dropouts=(*config.dropouts, *_windows(self.dropouts)))


@dataclass(frozen=True)
class WheelSpeedFaults:
    """Faults of the wheel-speed sensor.

    Attributes:
        slip_sigma: std of wheel slip noise, a share of the speed [-]
            (in quadrature with the sensor's own).
    """

    slip_sigma: float = 0.0  # [-]

    def __post_init__(self) -> None:
        check_non_negative("WheelSpeedFaults", "slip_sigma", self.slip_sigma, "[-]")

    def apply(self, config: WheelSpeedConfig) -> WheelSpeedConfig:
        """The wheel-speed sensor's config with these faults in it."""
        if not self.slip_sigma:
            return config
        return dataclasses.replace(
            config, slip_sigma=math.hypot(config.slip_sigma, self.slip_sigma)
        )


@dataclass(frozen=True)
class Faults:
    """Every sensor's faults (each section at its default: no fault).

    Attributes:
        gps: the GNSS receiver's.
        heading: the heading sensor's.
        imu: the IMU's.
        wheel_speed: the wheel-speed sensor's.
        cones: the cone detector's.
    """

    gps: GpsFaults = field(default_factory=GpsFaults)
    heading: HeadingFaults = field(default_factory=HeadingFaults)
    imu: ImuFaults = field(default_factory=ImuFaults)
    wheel_speed: WheelSpeedFaults = field(default_factory=WheelSpeedFaults)
    cones: ConeFaults = field(default_factory=ConeFaults)

    @property
    def active(self) -> tuple[str, ...]:
        """The faults set, as "section.field" names, in section order."""
        names = []
        for section in SECTIONS:
            fault = getattr(self, section)
            default = type(fault)()
            names += [
                f"{section}.{f.name}"
                for f in dataclasses.fields(fault)
                if getattr(fault, f.name) != getattr(default, f.name)
            ]
        return tuple(names)


def apply_faults(profile: SensorProfile, faults: Faults) -> SensorProfile:
    """``profile`` with ``faults`` in its sensor configs (the profile itself without any).

    The name stays the profile's: the faults are a run's, not a new profile.
    """
    changes = {}
    for section in SECTIONS:
        fault: Fault[Any] = getattr(faults, section)
        config = getattr(profile, section)
        faulty = fault.apply(config)
        if faulty is not config:
            changes[section] = faulty
    return dataclasses.replace(profile, **changes) if changes else profile
