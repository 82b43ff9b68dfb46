"""Settings of the ConeTrack env: one frozen dataclass, built from keyword
arguments (``gymnasium.make(..., track="autocross")``) or a mapping, with unknown
keys rejected and the allowed keys listed."""

from __future__ import annotations

import dataclasses
import math
import numbers
import os
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from conesim.localization.modes import LOCALIZATION_MODES
from conesim.sim.sensors import PROFILES as SENSOR_PROFILES
from conesim.tracks import DEFAULT_TRACK

OBSERVATION_MODES = ("vector", "dict")


@dataclass(frozen=True)
class RewardWeights:
    """Weights of the named reward terms (each term is also in ``info``).

    The default penalties follow the Formula Student scoring: 2 s per cone
    down or out, 10 s per off-course (REFERENCES.md), as metres of progress
    at 10 m/s (-20 and -100).

    Attributes:
        progress: per metre of net progress along the true centreline [1/m].
        time: per second of simulated time (negative: a cost) [1/s].
        cone_hit: per cone touched (counted once per cone).
        cone_doo: per cone down or out.
        off_track: per excursion off the track.
        lap: per completed lap.
    """

    progress: float = 1.0  # [1/m]
    time: float = -1.0  # [1/s]
    cone_hit: float = -5.0
    cone_doo: float = -20.0  # FS: 2 s per DOO x 10 m/s
    off_track: float = -100.0  # FS: 10 s per off-course x 10 m/s
    lap: float = 0.0

    def __post_init__(self) -> None:
        for f in dataclasses.fields(self):
            value = getattr(self, f.name)
            if not _is_real(value) or not math.isfinite(value):
                raise ValueError(f"RewardWeights.{f.name} must be finite, got {value!r}")


@dataclass(frozen=True)
class EnvConfig:
    """Settings of ``conesim/ConeTrack-v0``.

    Attributes:
        track: shipped track name or a track file.
        sensors: sensor profile (``ideal``, ``rtk``, ``consumer``, ``consumer_white``).
        localization: ``fused`` (EKF), ``raw`` (the ROS pipeline's) or ``truth``.
        laps: laps to complete [-].
        control_rate: actions per simulated second [Hz].
        physics_rate: physics steps per second [Hz]; a multiple of control_rate.
        time_limit: truncation time [s]; None = 60 s per lap plus 30 s.
        max_cones: K, the detected cones in the observation [-].
        observation: ``vector`` (flat float32 Box) or ``dict``.
        terminate_off_track: end the episode when the car leaves the track.
        terminate_stuck: end the episode when the car makes no progress.
        rewards: reward weights.
    """

    track: str = DEFAULT_TRACK
    sensors: str = "rtk"
    localization: str = "fused"
    laps: int = 1
    control_rate: float = 50.0  # [Hz] ARCHITECTURE.md control rate
    physics_rate: float = 200.0  # [Hz]
    time_limit: float | None = None  # [s]
    max_cones: int = 32
    observation: str = "vector"
    terminate_off_track: bool = True
    terminate_stuck: bool = True
    rewards: RewardWeights = dataclasses.field(default_factory=RewardWeights)

    def __post_init__(self) -> None:
        _choice("sensors", self.sensors, tuple(SENSOR_PROFILES))
        _choice("localization", self.localization, LOCALIZATION_MODES)
        _choice("observation", self.observation, OBSERVATION_MODES)
        if not (isinstance(self.track, str | os.PathLike) and os.fspath(self.track)):
            raise ValueError(f"EnvConfig.track must be a track name or file, got {self.track!r}")
        if not (_is_int(self.laps) and self.laps >= 1):
            raise ValueError(f"EnvConfig.laps must be an integer >= 1, got {self.laps!r}")
        if not (_is_int(self.max_cones) and 1 <= self.max_cones <= 512):
            raise ValueError(f"EnvConfig.max_cones must be in [1, 512], got {self.max_cones!r}")
        for name in ("terminate_off_track", "terminate_stuck"):
            flag = getattr(self, name)
            if not isinstance(flag, bool | np.bool_):
                raise ValueError(f"EnvConfig.{name} must be True or False, got {flag!r}")
        if isinstance(self.rewards, Mapping):
            object.__setattr__(self, "rewards", _weights(self.rewards))
        if not isinstance(self.rewards, RewardWeights):
            raise ValueError(
                f"EnvConfig.rewards must be a mapping of reward weights, got {self.rewards!r}"
            )
        for name in ("control_rate", "physics_rate"):
            value = getattr(self, name)
            if not (_is_real(value) and math.isfinite(value) and value > 0):
                raise ValueError(f"EnvConfig.{name} must be > 0 [Hz], got {value!r}")
        ratio = self.physics_rate / self.control_rate
        if abs(ratio - round(ratio)) > 1e-9 or round(ratio) < 1:
            raise ValueError(
                f"EnvConfig.physics_rate ({self.physics_rate} Hz) must be a whole multiple "
                f"of control_rate ({self.control_rate} Hz)"
            )
        if self.time_limit is not None and not (
            _is_real(self.time_limit) and math.isfinite(self.time_limit) and self.time_limit > 0
        ):
            raise ValueError(f"EnvConfig.time_limit must be > 0 [s], got {self.time_limit!r}")
        # Plain Python values from here: a numpy float32 rate would make the
        # simulation clock float32 and the same seed give another run.
        plain = {
            "track": os.fspath(self.track),
            "laps": int(self.laps),
            "max_cones": int(self.max_cones),
            "control_rate": float(self.control_rate),
            "physics_rate": float(self.physics_rate),
            "time_limit": None if self.time_limit is None else float(self.time_limit),
            "terminate_off_track": bool(self.terminate_off_track),
            "terminate_stuck": bool(self.terminate_stuck),
        }
        for name, value in plain.items():
            object.__setattr__(self, name, value)

    @property
    def substeps(self) -> int:
        """Physics steps per action."""
        return round(self.physics_rate / self.control_rate)

    @property
    def episode_time_limit(self) -> float:
        """The truncation time [s]."""
        return self.time_limit if self.time_limit is not None else 60.0 * self.laps + 30.0

    @classmethod
    def from_dict(cls, values: Mapping[str, Any]) -> EnvConfig:
        """Build from a mapping; unknown keys raise with the allowed keys listed."""
        allowed = [f.name for f in dataclasses.fields(cls)]
        unknown = sorted(set(values) - set(allowed))
        if unknown:
            raise ValueError(f"EnvConfig: unknown keys {unknown}; allowed keys: {allowed}")
        return cls(**dict(values))


def _weights(weights: Mapping[str, Any]) -> RewardWeights:
    """Reward weights from a mapping; unknown keys raise with the allowed keys listed."""
    names = [f.name for f in dataclasses.fields(RewardWeights)]
    bad = sorted(set(weights) - set(names))
    if bad:
        raise ValueError(f"RewardWeights: unknown keys {bad}; allowed keys: {names}")
    return RewardWeights(**weights)


def _is_int(value: Any) -> bool:
    """An integer (Python's or numpy's), not a bool."""
    return isinstance(value, numbers.Integral) and not isinstance(value, bool | np.bool_)


def _is_real(value: Any) -> bool:
    """A real number (Python's or numpy's), not a bool."""
    return isinstance(value, numbers.Real) and not isinstance(value, bool | np.bool_)


def _choice(name: str, value: str, allowed: tuple[str, ...]) -> None:
    if not isinstance(value, str) or value not in allowed:
        raise ValueError(f"EnvConfig.{name}: unknown value {value!r}; allowed: {list(allowed)}")
