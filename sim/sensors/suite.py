"""The sensor scheduler: every sensor of the car, captured and delivered on time.

``SensorSuite.step(truth)`` is called once per physics step with the current
truth. For each sensor, in the fixed order ``SENSOR_ORDER``, it asks the
sensor's ``CaptureClock`` whether a capture is due (quantisation: see
``timing.py``), captures, and queues the message for delivery at
stamp + latency. It returns every queued message whose delivery time has come
(t >= stamp + latency, within ``TIME_EPS``), sorted by stamp and, at equal
stamps, by ``DELIVERY_RANK``: the IMU and wheel speed (the motion up to the
stamp) before the heading, the fix and the cones, the order in which an
estimator applies them. Delivered the other way round, a zero-latency heading
reaches the filter before the IMU sample that ends at its stamp, is gated
against a prediction with the previous sample's rate, and is replayed when the
sample comes.

A disabled sensor captures nothing, but its clock keeps running so that it
resumes on its grid, and messages already in flight are still delivered.
``reset(seed)`` restarts streams, biases, clocks and queues; the settings
(including faults and enable flags set on the suite) are kept. Only the enable
flags and the GPS faults change on a running suite; any other setting (a rate,
a noise figure) takes a new suite, built from a profile changed with
``override``.
"""

from __future__ import annotations

import dataclasses
import math
from collections import deque
from typing import Protocol

from conesim.core.geodesy import DEFAULT_ORIGIN, ReferenceOrigin
from conesim.core.messages import Message
from conesim.sim.sensors.cone_detector import ConeDetector
from conesim.sim.sensors.gps import GpsReceiver
from conesim.sim.sensors.heading import HeadingSensor
from conesim.sim.sensors.imu import ImuSensor
from conesim.sim.sensors.profiles import DEFAULT_PROFILE, SECTIONS, SensorProfile, get_profile
from conesim.sim.sensors.timing import TIME_EPS, CaptureClock, SensorTiming
from conesim.sim.sensors.truth import TruthSample
from conesim.sim.sensors.validation import check_non_negative, check_positive, check_probability
from conesim.sim.sensors.wheel_speed import WheelSpeedSensor

SENSOR_ORDER = SECTIONS  # ("gps", "heading", "imu", "wheel_speed", "cones")
DELIVERY_RANK = {"imu": 0, "wheel_speed": 1, "heading": 2, "gps": 3, "cones": 4}


class Sensor(Protocol):
    """What the suite needs of a sensor model."""

    name: str

    @property
    def config(self) -> SensorTiming: ...

    def reset(self, seed: int) -> None: ...

    def capture(self, truth: TruthSample) -> Message | None: ...


def _delivery_order(item: tuple[float, int, Message]) -> tuple[float, int]:
    """(stamp, delivery rank) of a queued delivery."""
    return item[0], item[1]


# One sensor's clock, queue of pending deliveries and delivery rank.
_Slot = tuple[Sensor, CaptureClock, deque[tuple[float, float, Message]], int]


class SensorSuite:
    """All sensors of one car, with their clocks and delivery queues.

    Args:
        profile: a ``SensorProfile`` or the name of one (default "rtk").
        seed: episode seed, a non-negative integer.
        origin: geodetic origin of ``reference`` (for the GPS fixes).

    Attributes:
        gps, heading, imu, wheel_speed, cones: the sensor models.
    """

    def __init__(
        self,
        profile: SensorProfile | str = DEFAULT_PROFILE,
        seed: int = 0,
        origin: ReferenceOrigin = DEFAULT_ORIGIN,
    ) -> None:
        p = get_profile(profile) if isinstance(profile, str) else profile
        self.gps = GpsReceiver(p.gps, seed, origin)
        self.heading = HeadingSensor(p.heading, seed)
        self.imu = ImuSensor(p.imu, seed)
        self.wheel_speed = WheelSpeedSensor(p.wheel_speed, seed)
        self.cones = ConeDetector(p.cones, seed)
        self._name = p.name
        self._sensors: tuple[Sensor, ...] = (
            self.gps,
            self.heading,
            self.imu,
            self.wheel_speed,
            self.cones,
        )
        self._clocks = [CaptureClock(s.config.rate, s.config.phase) for s in self._sensors]
        self._queues: list[deque[tuple[float, float, Message]]] = [deque() for _ in self._sensors]
        self._ranks = [DELIVERY_RANK[s.name] for s in self._sensors]
        # What ``step`` walks at every step that captures or delivers, zipped once.
        self._slots: tuple[_Slot, ...] = tuple(
            zip(self._sensors, self._clocks, self._queues, self._ranks, strict=True)
        )
        self._last_t: float | None = None
        self._plan()
        self.seed = seed

    def _plan(self) -> None:
        """Note the earliest capture threshold and delivery time of all sensors.

        A step before both captures and delivers nothing (``CaptureClock.due``
        is False below its threshold), so ``step`` returns at once.
        """
        self._next_capture = min(clock.threshold for clock in self._clocks)
        self._next_delivery = min(
            (queue[0][0] for queue in self._queues if queue), default=math.inf
        )

    @property
    def profile(self) -> SensorProfile:
        """The current settings, including faults and enable flags set since."""
        return SensorProfile(
            self._name,
            self.gps.config,
            self.heading.config,
            self.imu.config,
            self.wheel_speed.config,
            self.cones.config,
        )

    def reset(self, seed: int) -> None:
        """Start a new episode: fresh streams from ``seed``, clocks and queues emptied."""
        for sensor, clock, queue in zip(self._sensors, self._clocks, self._queues, strict=True):
            sensor.reset(seed)
            clock.reset()
            queue.clear()
        self._last_t = None
        self._plan()
        self.seed = seed

    def step(self, truth: TruthSample) -> list[Message]:
        """Capture what is due at ``truth.t``; return what is delivered now.

        Args:
            truth: the state at this physics step; ``truth.t`` must increase.

        Returns:
            Messages with stamp + latency <= truth.t, sorted by (stamp, delivery rank).
        """
        t = truth.t
        if self._last_t is not None and not t > self._last_t:
            raise ValueError(f"SensorSuite.step: time must increase, got {t} after {self._last_t}")
        self._last_t = t
        self.imu.observe(truth)  # the integrating IMU sees every step
        deliver_by = t + TIME_EPS
        if t < self._next_capture and self._next_delivery > deliver_by:
            return []  # no clock is due and no queued message is
        next_capture = next_delivery = math.inf
        out: list[tuple[float, int, Message]] = []
        # Each sensor captures, then its due deliveries are taken: a queue only
        # ever holds its own sensor's messages, so the order of ``out`` is that
        # of two passes (all captures, then all deliveries) before the sort.
        for sensor, clock, queue, rank in self._slots:
            # ``due`` is False, with no side effect, below the threshold.
            if t >= clock.threshold and clock.due(t) and sensor.config.enabled:
                message = sensor.capture(truth)
                if message is not None:
                    queue.append((t + sensor.config.latency, t, message))
            next_capture = min(next_capture, clock.threshold)
            if queue:
                while queue and queue[0][0] <= deliver_by:
                    _, stamp, message = queue.popleft()
                    out.append((stamp, rank, message))
                if queue and queue[0][0] < next_delivery:
                    next_delivery = queue[0][0]
        self._next_capture, self._next_delivery = next_capture, next_delivery
        if not out:
            return []
        if len(out) > 1:
            out.sort(key=_delivery_order)
        return [message for _, _, message in out]

    def set_enabled(self, name: str, enabled: bool) -> None:
        """Switch one sensor on or off by name ("gps", "heading", "imu", ...)."""
        if name not in SENSOR_ORDER:
            raise ValueError(f"unknown sensor {name!r}; allowed: {', '.join(SENSOR_ORDER)}")
        sensor = getattr(self, name)
        sensor.config = dataclasses.replace(sensor.config, enabled=enabled)

    def inject_gps_dropout(self, start: float, duration: float) -> None:
        """Add a GPS dropout window [start, start + duration) [s] of capture time."""
        check_non_negative("inject_gps_dropout", "start", start, "[s]")
        check_positive("inject_gps_dropout", "duration", duration, "[s]")
        cfg = self.gps.config
        self.gps.config = dataclasses.replace(cfg, dropouts=(*cfg.dropouts, (start, duration)))

    def set_gps_multipath(self, probability: float, magnitude: float) -> None:
        """Replace a fraction ``probability`` of fixes by jumps of ``magnitude`` [m]."""
        check_probability("set_gps_multipath", "probability", probability)
        check_non_negative("set_gps_multipath", "magnitude", magnitude, "[m]")
        self.gps.config = dataclasses.replace(
            self.gps.config, multipath_probability=probability, multipath_magnitude=magnitude
        )

    @property
    def skipped_captures(self) -> dict[str, int]:
        """Nominal captures that fell between physics steps, per sensor."""
        return {s.name: c.skipped for s, c in zip(self._sensors, self._clocks, strict=True)}
