"""The simulated world: the only place that knows the truth.

``World`` steps a pymunk car (``Vehicle``, a dynamic single-track model with
Pacejka tyres) among knockable cones (``ConeField``) on a track, with race
control (laps, off-track, stuck) and the sensor suite (``sim.sensors``).
Nothing outside ``sim`` imports pymunk.
"""

from __future__ import annotations

from conesim.sim.cones import ConeField, ConeParams
from conesim.sim.race_control import RaceControl, RaceRules, RaceState
from conesim.sim.sensors import SensorProfile, SensorSuite, TruthSample, get_profile
from conesim.sim.vehicle import Vehicle, VehicleState
from conesim.sim.vehicle_params import VehicleParams
from conesim.sim.world import World, WorldConfig

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
