"""Settings of the ConeTrack env: one frozen dataclass, built from keyword
arguments (``gymnasium.make(..., track="autocross")``) or a mapping, with unknown
keys rejected and the allowed keys listed.

The settings of the episode itself are a scenario's (``envs.scenario``):
``scenario=`` (a ``Scenario`` or a scenario file) gives them all at once,
and the keywords given beside it change its parts; or the parts come one by
one (``sensors=`` a profile or its name, ``faults=``, ``ekf=``,
``vehicle=``, as objects or mappings). ``to_scenario()`` is the scenario
the env's episodes run, so the env and ``conesim run`` build their loops
alike. A scenario's ``seed`` is ``conesim run``'s: the env's episodes are
seeded by ``reset(seed=...)`` (``reset(seed=scenario.seed)`` drives the
run's episode)."""

from __future__ import annotations

import dataclasses
import math
import numbers
import os
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, Literal, get_args

import numpy as np

from conesim.envs.dataclass_io import build
from conesim.envs.ekf_tuning import tuning_name
from conesim.envs.loop import EpisodeRules
from conesim.envs.scenario import SEED_LIMIT, EkfTuning, Localization, Scenario
from conesim.envs.scenario_file import ekf_from_data, load_scenario, track_from_data
from conesim.localization.ekf import EkfConfig
from conesim.localization.modes import LOCALIZATION_MODES
from conesim.localization.slam import SlamConfig
from conesim.planner import AutopilotConfig
from conesim.sim.sensors import PROFILES as SENSOR_PROFILES
from conesim.sim.sensors import Faults, SensorProfile, get_profile
from conesim.sim.vehicle_params import VehicleParams
from conesim.tracks import DEFAULT_TRACK, GeneratedTrack, TrackSpec
from conesim.tracks.survey import ConeSurvey

OBSERVATION_MODES = ("vector", "dict")
RANDOM_TRACK = "random"
"""``track="random"``: a generated track per episode, its seed drawn from ``track_seeds``."""
ActionMode = Literal["centred", "physical"]
InfoMode = Literal["lean", "full"]
ACTION_MODES: tuple[str, ...] = get_args(ActionMode)
INFO_MODES: tuple[str, ...] = get_args(InfoMode)


@dataclass(frozen=True)
class RewardWeights:
    """Weights of the named reward terms (each term is also in ``info``).

    The default trades progress against time at 1 m per second and charges
    the Formula Student penalties at that rate: 2 s per cone down or out,
    10 s per off-course (REFERENCES.md), so a completed lap's return is its
    length minus its FS time, lap time plus penalties (the env's module
    docstring, "Rewards", works the numbers).

    Attributes:
        progress: per metre of net progress along the true centreline [1/m].
        time: per second of simulated time (negative: a cost) [1/s].
        cone_hit: per cone touched (counted once per cone); FS charges only
            cones down or out.
        cone_doo: per cone down or out.
        off_track: per excursion off the track.
        lap: per completed lap.
    """

    progress: float = 1.0  # [1/m]
    time: float = -1.0  # [1/s] the exchange rate: 1 s costs 1 m of progress
    cone_hit: float = 0.0
    cone_doo: float = -2.0  # FS: 2 s per DOO, at 1 m/s
    off_track: float = -10.0  # FS: 10 s per off-course, at 1 m/s
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
        track: shipped track name or a track file, or a generated track: a
            ``GeneratedTrack`` or ``{"generate": {"seed": S, ...}}``; or
            ``"random"``: a generated track per episode.
        track_seeds: the generator's seeds ``track="random"`` draws from,
            one per episode, uniformly with the episode's generator: a
            ``range`` or a pair ``(lo, hi)``, ``lo`` included and ``hi``
            not (train on ``(0, 1000)``, test on ``(1000, 1100)``).
        track_spec: the generated tracks' settings (``tracks.TrackSpec``, or
            a mapping of its fields).
        sensors: sensor profile, or a shipped one's name (``ideal``, ``rtk``,
            ``consumer``, ``consumer_white``).
        localization: ``fused`` (EKF), ``raw`` (the ROS pipeline's) or ``truth``.
        laps: laps to complete [-].
        control_rate: actions per simulated second [Hz].
        physics_rate: physics steps per second [Hz]; a multiple of control_rate.
        time_limit: truncation time [s]; None = 60 s per lap plus 30 s.
        max_cones: K, the detected cones in the observation [-].
        path_preview: N, the global path's points ahead in the observation
            (0: none; ``envs.observation``) [-].
        path_preview_step: their spacing along the path [m].
        observation: ``vector`` (normalised float32 Box) or ``dict`` (raw units).
        action: ``centred`` (``Box(-1, 1)``, zero is no steering and no
            acceleration, symmetric) or ``physical`` (steering [rad],
            acceleration [m/s^2]).
        info: ``lean`` (numbers only) or ``full`` (also the messages, lap
            times, truth and localization error).
        terminate_off_track: end the episode when the car leaves the track.
        terminate_stuck: end the episode when the car makes no progress.
        stuck_time: the stuck rule's window [s].
        stuck_progress: less net progress than this in ``stuck_time`` is
            stuck [m].
        stuck_grace: the stuck rule ends no episode before this time [s].
        rewards: reward weights.
        faults: what goes wrong with the sensors (``sim.sensors.faults``).
        ekf: the filter's settings; None: the tuning ``ekf_tuning`` names
            (``auto``: matched to the sensors, ``envs.ekf_tuning``). Also as a
            scenario file's ``ekf:``: a tuning's name, or ``{"tuning": name,
            field: value}`` (the fields over that tuning's).
        ekf_tuning: as ``Scenario.ekf_tuning``.
        vehicle: the car.
        cone_map: the cone map's survey error (``cones`` localization), as
            ``Scenario.cone_map``.
        slam: how ``slam`` localization builds its map, as ``Scenario.slam``.
        autopilot: the settings ``AutopilotExpert`` drives with by default
            (None: the localization's default); the env itself has no driver.
    """

    track: str | GeneratedTrack = DEFAULT_TRACK
    track_seeds: range | tuple[int, int] = range(1000)
    track_spec: TrackSpec = dataclasses.field(default_factory=TrackSpec)
    sensors: str = "rtk"
    localization: Localization = "fused"
    laps: int = 1
    control_rate: float = 50.0  # [Hz] ARCHITECTURE.md control rate
    physics_rate: float = 200.0  # [Hz]
    time_limit: float | None = None  # [s]
    max_cones: int = 32
    path_preview: int = 0
    path_preview_step: float = 2.0  # [m]
    observation: str = "vector"
    action: ActionMode = "centred"
    info: InfoMode = "lean"
    terminate_off_track: bool = True
    terminate_stuck: bool = True
    stuck_time: float = 10.0  # [s]
    stuck_progress: float = 1.0  # [m]
    stuck_grace: float = 15.0  # [s]
    rewards: RewardWeights = dataclasses.field(default_factory=RewardWeights)
    faults: Faults = dataclasses.field(default_factory=Faults)
    ekf: EkfConfig | None = None
    ekf_tuning: EkfTuning = "auto"
    vehicle: VehicleParams = dataclasses.field(default_factory=VehicleParams)
    cone_map: ConeSurvey = dataclasses.field(default_factory=ConeSurvey)
    slam: SlamConfig = dataclasses.field(default_factory=SlamConfig)
    autopilot: AutopilotConfig | None = None

    def __post_init__(self) -> None:
        if not isinstance(self.sensors, SensorProfile):
            _choice("sensors", self.sensors, tuple(SENSOR_PROFILES))
        object.__setattr__(self, "track_seeds", _seed_range(self.track_seeds))
        self._split_ekf_tuning()
        parts = (
            ("faults", Faults),
            ("vehicle", VehicleParams),
            ("cone_map", ConeSurvey),
            ("slam", SlamConfig),
            ("ekf", EkfConfig),
            ("track_spec", TrackSpec),
        )
        for name, cls in parts:
            if isinstance(getattr(self, name), Mapping):
                object.__setattr__(self, name, build(cls, getattr(self, name), path=(name,)))
        _choice("localization", self.localization, LOCALIZATION_MODES)
        _choice("observation", self.observation, OBSERVATION_MODES)
        _choice("action", self.action, ACTION_MODES)
        _choice("info", self.info, INFO_MODES)
        if isinstance(self.track, Mapping):  # {generate: {seed: S, ...}}, as in a scenario file
            object.__setattr__(self, "track", track_from_data(self.track, ("EnvConfig.track",)))
        if not isinstance(self.track, GeneratedTrack) and not (
            isinstance(self.track, str | os.PathLike) and os.fspath(self.track)
        ):
            raise ValueError(
                f"EnvConfig.track must be a track name or file, a GeneratedTrack or "
                f"{{generate: {{seed: S, ...}}}}, got {self.track!r}"
            )
        if not (_is_int(self.laps) and self.laps >= 1):
            raise ValueError(f"EnvConfig.laps must be an integer >= 1, got {self.laps!r}")
        if not (_is_int(self.max_cones) and 1 <= self.max_cones <= 512):
            raise ValueError(f"EnvConfig.max_cones must be in [1, 512], got {self.max_cones!r}")
        if not (_is_int(self.path_preview) and 0 <= self.path_preview <= 256):
            raise ValueError(
                f"EnvConfig.path_preview must be in [0, 256], got {self.path_preview!r}"
            )
        step = self.path_preview_step
        if not (_is_real(step) and math.isfinite(step) and 0.1 <= step <= 50.0):
            raise ValueError(f"EnvConfig.path_preview_step must be in [0.1, 50] [m], got {step!r}")
        if self.path_preview * step > 100.0:
            raise ValueError(
                f"EnvConfig.path_preview x path_preview_step must be <= 100 m (the "
                f"observation's bound), got {self.path_preview} x {step!r}"
            )
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
        stuck = (("stuck_time", False), ("stuck_progress", True), ("stuck_grace", True))
        for name, closed in stuck:
            value = getattr(self, name)
            if not (
                _is_real(value) and math.isfinite(value) and (value >= 0 if closed else value > 0)
            ):
                bound = ">= 0" if closed else "> 0"
                unit = "[m]" if name == "stuck_progress" else "[s]"
                raise ValueError(f"EnvConfig.{name} must be {bound} {unit}, got {value!r}")
        if self.time_limit is not None and not (
            _is_real(self.time_limit) and math.isfinite(self.time_limit) and self.time_limit > 0
        ):
            raise ValueError(
                f"EnvConfig.time_limit must be finite and > 0 [s], got {self.time_limit!r}"
            )
        # Plain Python values from here: a numpy float32 rate would make the
        # simulation clock float32 and the same seed give another run.
        track = self.track
        plain = {
            "track": track if isinstance(track, GeneratedTrack) else os.fspath(track),
            "laps": int(self.laps),
            "max_cones": int(self.max_cones),
            "path_preview": int(self.path_preview),
            "path_preview_step": float(self.path_preview_step),
            "control_rate": float(self.control_rate),
            "physics_rate": float(self.physics_rate),
            "time_limit": None if self.time_limit is None else float(self.time_limit),
            "terminate_off_track": bool(self.terminate_off_track),
            "terminate_stuck": bool(self.terminate_stuck),
            "stuck_time": float(self.stuck_time),
            "stuck_progress": float(self.stuck_progress),
            "stuck_grace": float(self.stuck_grace),
        }
        for name, value in plain.items():
            object.__setattr__(self, name, value)
        self.to_scenario()  # the episode's settings, checked as a scenario checks them

    @property
    def substeps(self) -> int:
        """Physics steps per action."""
        return round(self.physics_rate / self.control_rate)

    @property
    def episode_time_limit(self) -> float:
        """The truncation time [s]."""
        return self.time_limit if self.time_limit is not None else 60.0 * self.laps + 30.0

    @property
    def rules(self) -> EpisodeRules:
        """When the env's episodes end (the scenario's rules with the stuck rule's settings)."""
        return dataclasses.replace(
            self.to_scenario().rules,
            stuck_time=self.stuck_time,
            stuck_progress=self.stuck_progress,
            stuck_grace=self.stuck_grace,
        )

    def _split_ekf_tuning(self) -> None:
        """``ekf="consumer"`` or ``ekf={"tuning": "consumer", ...}`` as a scenario file
        reads it (``scenario_file.ekf_from_data``: the fields over the tuning's)."""
        ekf = self.ekf
        if isinstance(ekf, str):
            ekf = {"tuning": ekf}
        if not (isinstance(ekf, Mapping) and "tuning" in ekf):
            return
        if self.ekf_tuning != "auto":
            raise ValueError(
                f"EnvConfig: the tuning given twice, ekf={self.ekf!r} and "
                f"ekf_tuning={self.ekf_tuning!r}; give one"
            )
        if isinstance(self.sensors, SensorProfile):
            sensors, base = self.sensors, tuning_name(self.sensors)
        else:
            sensors, base = get_profile(self.sensors), self.sensors
        config, tuning = ekf_from_data(ekf, base, sensors)
        object.__setattr__(self, "ekf", config)
        object.__setattr__(self, "ekf_tuning", tuning)

    def to_scenario(self) -> Scenario:
        """The scenario the env's episodes run (its seed: ``reset``'s, not this)."""
        values = {field: getattr(self, key) for key, field in SCENARIO_FIELDS.items()}
        if isinstance(self.sensors, str):
            values["sensors"] = get_profile(self.sensors)
        return Scenario(**values)

    @classmethod
    def from_dict(cls, values: Mapping[str, Any]) -> EnvConfig:
        """Build from a mapping; unknown keys raise with the allowed keys listed.

        ``scenario`` (a ``Scenario`` or a scenario file) gives the episode's
        settings; the other keys change them.
        """
        values = dict(values)
        scenario = values.pop("scenario", None)
        allowed = [f.name for f in dataclasses.fields(cls)]
        unknown = sorted(set(values) - set(allowed))
        if unknown:
            raise ValueError(
                f"EnvConfig: unknown keys {unknown}; allowed keys: {[*allowed, 'scenario']}"
            )
        if scenario is not None:
            if not isinstance(scenario, Scenario):
                scenario = load_scenario(scenario)
            values = {**scenario_settings(scenario), **values}
        return cls(**values)


SCENARIO_FIELDS = {
    "track": "track",
    "laps": "laps",
    "time_limit": "time_limit",
    "terminate_off_track": "end_on_off_track",
    "terminate_stuck": "end_on_stuck",
    "control_rate": "control_rate",
    "physics_rate": "physics_rate",
    "localization": "localization",
    "sensors": "sensors",
    "faults": "faults",
    "ekf": "ekf",
    "ekf_tuning": "ekf_tuning",
    "autopilot": "autopilot",
    "vehicle": "vehicle",
    "cone_map": "cone_map",
    "slam": "slam",
}
"""``EnvConfig`` key -> the ``Scenario`` field it is (all but the scenario's seed)."""


def scenario_settings(scenario: Scenario) -> dict[str, Any]:
    """The ``EnvConfig`` keys a scenario sets (all but its seed)."""
    return {key: getattr(scenario, field) for key, field in SCENARIO_FIELDS.items()}


def _seed_range(value: Any) -> range:
    """``track_seeds`` as a range: a range or a pair (lo, hi) of seeds, lo < hi."""
    if isinstance(value, range):
        seeds = value
    elif isinstance(value, tuple | list) and len(value) == 2 and all(_is_int(v) for v in value):
        seeds = range(int(value[0]), int(value[1]))
    else:
        raise ValueError(
            f"EnvConfig.track_seeds must be a range or a pair (lo, hi) of integers, got {value!r}"
        )
    if not seeds or min(seeds[0], seeds[-1]) < 0 or max(seeds[0], seeds[-1]) >= SEED_LIMIT:
        raise ValueError(
            f"EnvConfig.track_seeds = {value!r} is out of range: allowed a non-empty range "
            "of seeds in [0, 2**63)"
        )
    return seeds


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
