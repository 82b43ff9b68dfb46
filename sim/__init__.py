"""The simulated world: the only place that knows the truth.

``World`` steps a pymunk car (``Vehicle``, a dynamic single-track model with
Pacejka tyres) among knockable cones (``ConeField``) on a track, with race
control (laps, off-track, stuck) and the sensor suite (``sim.sensors``).
Nothing outside ``sim`` imports pymunk.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from conesim.sim.cones import ConeField, ConeParams
    from conesim.sim.race_control import RaceControl, RaceRules, RaceState
    from conesim.sim.sensors import SensorProfile, SensorSuite, TruthSample, get_profile
    from conesim.sim.vehicle import Vehicle, VehicleState
    from conesim.sim.vehicle_params import VehicleParams
    from conesim.sim.world import World, WorldConfig

# Each name's module, imported when the name is first read: importing one
# module of ``sim`` (``sim.sensors`` for the command line's profiles) loads
# that module only, not the car model and its compiled kernels.
_MODULES = {
    "ConeField": "cones", "ConeParams": "cones",
    "RaceControl": "race_control", "RaceRules": "race_control", "RaceState": "race_control",
    "SensorProfile": "sensors", "SensorSuite": "sensors", "TruthSample": "sensors",
    "get_profile": "sensors",
    "Vehicle": "vehicle", "VehicleState": "vehicle",
    "VehicleParams": "vehicle_params",
    "World": "world", "WorldConfig": "world",
}  # fmt: skip


def __getattr__(name: str) -> Any:
    module = _MODULES.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    return getattr(importlib.import_module(f"{__name__}.{module}"), name)


__all__ = [
    "ConeField",
    "ConeParams",
    "RaceControl",
    "RaceRules",
    "RaceState",
    "SensorProfile",
    "SensorSuite",
    "TruthSample",
    "Vehicle",
    "VehicleParams",
    "VehicleState",
    "World",
    "WorldConfig",
    "get_profile",
]
