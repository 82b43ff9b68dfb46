"""The scenario: everything one run takes, as one frozen, typed object.

A ``Scenario`` holds the track, laps and seed, the sensors (a
``SensorProfile``) and their ``Faults``, the localization mode and the EKF's
settings, the autopilot's, the vehicle's parameters, the rates and the
episode's limits: each part is the existing frozen config of its package,
which checks itself. ``conesim run SCENARIO.yaml``, ``run_scenario`` and
``gymnasium.make(..., scenario=...)`` all take one; the YAML form and its
loader are ``envs.scenario_file``.

Two parts may be left to follow the others, and are None until then:

* ``ekf``: the tuning ``ekf_tuning`` names; ``auto`` matches the sensors
  (``envs.ekf_tuning``: the profile's shipped tuning, else rtk's, with the
  receiver's error model taken from the profile, before the faults);
* ``autopilot``: ``planner.autopilot.default_config(localization)`` (the
  cautious limits with the raw pose).

They are kept None, not filled in when the object is made, so that
``dataclasses.replace(scenario, sensors=...)`` (one point of a sweep) gets
the tuning of the new sensors. ``resolved()`` fills them in and names the
tuning it took; that is what ``conesim scenario show`` prints and what
``result.json`` embeds.

Faults are applied to the profile when the world is built
(``world_config``), after the EKF is matched: the filter is told what the
sensors are, never what goes wrong with them.
"""

from __future__ import annotations

import dataclasses
import math
import os
from dataclasses import dataclass, field
from typing import Literal, get_args

from conesim.envs.ekf_tuning import matched_cone_update, matched_ekf, tuning_name
from conesim.envs.loop import ClosedLoop, DriverFactory, EpisodeRules
from conesim.localization.ekf import EkfConfig, for_profile
from conesim.localization.modes import LOCALIZATION_MODES
from conesim.localization.slam import SlamConfig
from conesim.planner import AutopilotConfig
from conesim.planner.autopilot import CONTROL_RATE, default_config
from conesim.sim.sensors import DEFAULT_PROFILE, Faults, SensorProfile, apply_faults, get_profile
from conesim.sim.vehicle_params import VehicleParams
from conesim.sim.world import WorldConfig
from conesim.tracks import DEFAULT_TRACK, GeneratedTrack, Track, track_label
from conesim.tracks.generate.spec import SEED_LIMIT  # a seed is an integer in [0, it)
from conesim.tracks.survey import ConeSurvey, PathSurvey

Localization = Literal["fused", "raw", "truth", "cones", "slam"]
"""The localization modes (``localization.modes``)."""
EkfTuning = Literal["auto", "ideal", "rtk", "consumer", "consumer_white", "custom"]
"""``auto`` (matched to the sensors), a shipped tuning, or ``custom`` (EkfConfig's defaults)."""
AutopilotPreset = Literal["auto", "default", "cautious"]
"""The autopilot settings a scenario's start from: ``auto`` follows the localization."""

MAX_LAPS = 100  # [-] at a minute a lap, over an hour and a half of simulated driving
RATE_LIMITS = {"control_rate": (1.0, 1000.0), "physics_rate": (1.0, 10_000.0)}  # [Hz]
"""The loop's and the physics' rates allowed: below 1 Hz a step outlasts a corner;
above 10 kHz a lap costs hours of wall time and pymunk gains nothing."""


@dataclass(frozen=True)
class Scenario:
    """One run, completely (see the module docstring).

    Attributes:
        track: a shipped track's name, a track file, or a generated track
            (``GeneratedTrack(seed, TrackSpec(...))``).
        laps: laps to drive, 1 to ``MAX_LAPS`` [-] (an open lane is one run).
        seed: the episode seed, as ``conesim run --seed`` and ``env.reset(seed=)``.
        time_limit: truncation time [s]; None: 60 s per lap plus 30 s.
        end_on_off_track: the run ends when the car leaves the track.
        end_on_stuck: the run ends when race control finds the car stuck.
        control_rate: the loop's clock: the autopilot's (or action's) rate [Hz]
            (``RATE_LIMITS``).
        physics_rate: physics steps per second [Hz], a multiple of control_rate.
        localization: ``fused`` (EKF), ``raw`` (the ROS pipeline's), ``truth``,
            ``cones`` (the EKF with the cone scans against the cone map), or
            ``slam`` (the EKF building the cone map as it drives).
        sensors: the sensors, as the team knows them (before the faults).
        faults: what goes wrong with them.
        ekf: the filter's settings; None: the tuning ``ekf_tuning`` names.
        ekf_tuning: ``auto``, a shipped tuning or ``custom`` (with ``ekf``
            given: the tuning its fields started from, for reports).
        autopilot: the autopilot's settings; None: the localization's default.
        vehicle: the car.
        global_path: how far the global path given to the car is off the
            track's (``tracks.survey.PathSurvey``: per-point noise, a bias).
        cone_map: how far the cone map of ``cones`` localization is off the
            cones (``tracks.survey.ConeSurvey``: per-cone noise, a bias).
        slam: how ``slam`` localization builds its map
            (``localization.slam.SlamConfig``).
    """

    track: str | GeneratedTrack = DEFAULT_TRACK
    laps: int = 1
    seed: int = 0
    time_limit: float | None = None  # [s]
    end_on_off_track: bool = True
    end_on_stuck: bool = True
    control_rate: float = CONTROL_RATE  # [Hz]
    physics_rate: float = 200.0  # [Hz]
    localization: Localization = "fused"
    sensors: SensorProfile = field(default_factory=lambda: get_profile(DEFAULT_PROFILE))
    faults: Faults = field(default_factory=Faults)
    ekf: EkfConfig | None = None
    ekf_tuning: EkfTuning = "auto"
    autopilot: AutopilotConfig | None = None
    vehicle: VehicleParams = field(default_factory=VehicleParams)
    global_path: PathSurvey = field(default_factory=PathSurvey)
    cone_map: ConeSurvey = field(default_factory=ConeSurvey)
    slam: SlamConfig = field(default_factory=SlamConfig)

    def __post_init__(self) -> None:
        track = self.track
        if not isinstance(track, GeneratedTrack):
            if not (isinstance(track, str | os.PathLike) and os.fspath(track).strip()):
                raise ValueError(
                    f"Scenario.track = {track!r}: give a shipped track name or a file "
                    "(or a GeneratedTrack)"
                )
            object.__setattr__(self, "track", os.fspath(track))
        if isinstance(self.laps, bool) or not (
            isinstance(self.laps, int) and 1 <= self.laps <= MAX_LAPS
        ):
            raise ValueError(
                f"Scenario.laps = {self.laps!r} is out of range: allowed [1, {MAX_LAPS}]"
            )
        if isinstance(self.seed, bool) or not (
            isinstance(self.seed, int) and 0 <= self.seed < SEED_LIMIT
        ):
            raise ValueError(
                f"Scenario.seed = {self.seed!r} is out of range: allowed [0, 2**63) (an integer)"
            )
        for name, (low, high) in RATE_LIMITS.items():
            rate = getattr(self, name)
            if not (math.isfinite(rate) and low <= rate <= high):
                raise ValueError(
                    f"Scenario.{name} = {rate!r} is out of range: allowed [{low:g}, {high:g}] [Hz]"
                )
            # plain floats: an int or numpy rate would give the clock another type
            object.__setattr__(self, name, float(rate))
        ratio = self.physics_rate / self.control_rate
        if abs(ratio - round(ratio)) > 1e-9 or round(ratio) < 1:
            raise ValueError(
                f"Scenario: physics_rate ({self.physics_rate} Hz) must be a "
                f"whole multiple of control_rate ({self.control_rate} Hz)"
            )
        if self.localization not in LOCALIZATION_MODES:
            raise ValueError(
                f"Scenario.localization = {self.localization!r}: allowed "
                f"{', '.join(LOCALIZATION_MODES)}"
            )
        if self.ekf_tuning not in get_args(EkfTuning):
            raise ValueError(
                f"Scenario.ekf_tuning = {self.ekf_tuning!r}: allowed "
                f"{', '.join(get_args(EkfTuning))}"
            )
        self._check_types()
        if self.time_limit is not None:
            object.__setattr__(self, "time_limit", float(self.time_limit))
        self.rules  # noqa: B018 (EpisodeRules checks the time limit)
        try:  # each part is valid alone; together they must be too
            apply_faults(self.sensors, self.faults)
        except ValueError as exc:
            raise ValueError(f"Scenario: the sensors with their faults: {exc}") from None

    def _check_types(self) -> None:
        """Each part is its package's config (a mapping belongs in ``scenario_file``)."""
        parts: tuple[tuple[str, type | tuple[type, ...]], ...] = (
            ("sensors", SensorProfile),
            ("faults", Faults),
            ("ekf", (EkfConfig, type(None))),
            ("autopilot", (AutopilotConfig, type(None))),
            ("vehicle", VehicleParams),
            ("global_path", PathSurvey),
            ("cone_map", ConeSurvey),
            ("slam", SlamConfig),
        )
        for name, kind in parts:
            value = getattr(self, name)
            if not isinstance(value, kind):
                expected = kind.__name__ if isinstance(kind, type) else kind[0].__name__
                raise TypeError(
                    f"Scenario.{name} must be a {expected}, got {type(value).__name__} "
                    "(envs.scenario_file builds one from a mapping)"
                )

    @property
    def track_name(self) -> str:
        """The track as messages name it (a generated one by its name)."""
        return track_label(self.track)

    @property
    def rules(self) -> EpisodeRules:
        """When the episode ends."""
        return EpisodeRules(
            laps=self.laps,
            time_limit=self.time_limit,
            end_on_off_track=self.end_on_off_track,
            end_on_stuck=self.end_on_stuck,
        )

    @property
    def ekf_tuning_name(self) -> str:
        """The tuning the filter's settings are, or start from (``auto`` resolved)."""
        if self.ekf_tuning != "auto":
            return self.ekf_tuning
        return "custom" if self.ekf is not None else tuning_name(self.sensors)

    def ekf_config(self) -> EkfConfig:
        """The filter's settings (``ekf``, or the tuning ``ekf_tuning`` names)."""
        if self.ekf is not None:
            return self.ekf
        if self.ekf_tuning == "auto":
            return matched_ekf(self.sensors)
        if self.ekf_tuning == "custom":
            return EkfConfig()
        return for_profile(self.ekf_tuning)

    def autopilot_config(self) -> AutopilotConfig:
        """The autopilot's settings (``autopilot``, or the localization's default)."""
        return self.autopilot or default_config(self.localization)

    def world_config(self) -> WorldConfig:
        """The world's settings: the rates, the vehicle, the sensors with their faults."""
        return WorldConfig(
            physics_rate=self.physics_rate,
            sensors=apply_faults(self.sensors, self.faults),
            vehicle=self.vehicle,
        )

    def resolved(self) -> Scenario:
        """The same run with the EKF and autopilot settings filled in, the tuning named."""
        return dataclasses.replace(
            self,
            ekf=self.ekf_config(),
            ekf_tuning=self.ekf_tuning_name,  # type: ignore[arg-type]
            autopilot=self.autopilot_config(),
        )

    def closed_loop(
        self,
        track: Track,
        driver: DriverFactory | None = None,
        rules: EpisodeRules | None = None,
    ) -> ClosedLoop:
        """The closed loop of this scenario on ``track`` (loaded from ``self.track``);
        ``rules`` replace the scenario's (the env's stuck rule and its grace)."""
        return ClosedLoop(
            track,
            self.world_config(),
            localization=self.localization,
            control_rate=self.control_rate,
            rules=rules or self.rules,
            driver=driver,
            ekf=self.ekf_config(),
            survey=self.global_path,
            cone_map=self.cone_map,
            cones=matched_cone_update(self.sensors),
            slam=self.slam,
        )
