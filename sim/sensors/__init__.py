"""Sensor models of the simulated car, their profiles and the scheduler.

``SensorSuite(profile, seed, origin).step(truth)`` is the entry point: called
once per physics step with a ``TruthSample``, it returns the messages
(``localization.messages``) delivered at that step. Profiles ("ideal", "rtk"
(default), "consumer", "consumer_white") are frozen dataclass trees in
``profiles.py``; each sensor's noise model is in its own module's docstring.
Faults (``faults.py``) are named changes to a profile's fields.
"""

from __future__ import annotations

from conesim.sim.sensors.cone_detector import ConeDetector, ConeDetectorConfig
from conesim.sim.sensors.cone_map import ConeMap
from conesim.sim.sensors.faults import (
    ConeFaults,
    Faults,
    GpsFaults,
    HeadingFaults,
    ImuFaults,
    WheelSpeedFaults,
    apply_faults,
)
from conesim.sim.sensors.gps import GpsConfig, GpsReceiver
from conesim.sim.sensors.heading import HeadingConfig, HeadingSensor
from conesim.sim.sensors.imu import ImuConfig, ImuSensor
from conesim.sim.sensors.profiles import (
    DEFAULT_PROFILE,
    PROFILES,
    SensorProfile,
    get_profile,
    override,
)
from conesim.sim.sensors.suite import SENSOR_ORDER, SensorSuite
from conesim.sim.sensors.timing import CaptureClock, SensorTiming
from conesim.sim.sensors.truth import TruthSample
from conesim.sim.sensors.wheel_speed import WheelSpeedConfig, WheelSpeedSensor

__all__ = [
    "DEFAULT_PROFILE",
    "PROFILES",
    "SENSOR_ORDER",
    "CaptureClock",
    "ConeDetector",
    "ConeDetectorConfig",
    "ConeFaults",
    "ConeMap",
    "Faults",
    "GpsConfig",
    "GpsFaults",
    "GpsReceiver",
    "HeadingConfig",
    "HeadingFaults",
    "HeadingSensor",
    "ImuConfig",
    "ImuFaults",
    "ImuSensor",
    "SensorProfile",
    "SensorSuite",
    "SensorTiming",
    "TruthSample",
    "WheelSpeedConfig",
    "WheelSpeedFaults",
    "WheelSpeedSensor",
    "apply_faults",
    "get_profile",
    "override",
]
