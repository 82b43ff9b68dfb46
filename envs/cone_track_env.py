"""``conesim/ConeTrack-v0``: drive a Formula Student cone track.

The env wraps the closed loop (``envs.loop.ClosedLoop``: the pymunk world,
its sensors, localization and the frame tree) without a driver: an action
becomes the car's steering and acceleration command for one control period
(``ClosedLoop.step``); the env observes, scores and passes on the loop's end
of the episode. To drive it with the autopilot (a baseline, or an expert for
imitation learning) use ``envs.expert.AutopilotExpert``.

## Action Space
``Box(-1, 1, (2,), float32)``: ``[steering, acceleration]``. Steering maps
linearly to the front wheel angle within +-``max_steer`` (0.47 rad by
default); acceleration maps to ``a * max_accel`` for ``a >= 0`` (3 m/s^2) and
``a * max_decel`` below 0 (10 m/s^2). The steering actuator has a rate limit
and a lag (``sim.vehicle_params``).

## Observation Space
See ``envs.observation``: in ``vector`` mode a float32 Box of
``6 + 3 K`` values (estimated speed and yaw rate, the previous action, the
EKF's 1-sigma position and heading uncertainty, then the K nearest detected
cones in ``os_sensor`` as x, y, mask); ``dict`` mode adds colours, the
estimated pose and its covariance, ``pose_valid`` and ``cones_age`` (seconds
since the cone detection's stamp).

## Rewards
A sum of named terms, each also in ``info["reward_terms"]``: ``progress``
(metres of net progress along the true centreline), ``time`` (per second),
``cone_hit`` (per cone touched), ``cone_doo`` (per cone down or out; FS
charges 2 s), ``off_track`` (per excursion; FS charges 10 s), ``lap`` (per
lap). Weights: ``envs.config.RewardWeights``.

## Starting State
The car stands still at the track's start pose (behind the start line), at
t = 0, sensors and filter freshly reset with the episode seed.

## Episode End
Terminated when the requested laps are complete (an open lane such as
acceleration is one run, whatever ``laps`` says), when the car leaves the
track (``terminate_off_track``) or is stuck (``terminate_stuck``); truncated
at the time limit (``time_limit``; default 60 s per lap + 30 s).
``info["end_reason"]`` says which (``envs.loop.EndReason``). The registered
``max_episode_steps`` is a backstop behind the env's own limit.

## Arguments
``gymnasium.make("conesim:conesim/ConeTrack-v0", track="autocross", sensors="rtk",
localization="fused", laps=1, control_rate=50, observation="vector",
render_mode="rgb_array", ...)``; every ``envs.config.EnvConfig`` field, or
``scenario=`` (a ``Scenario`` or a scenario file) with the keywords given
beside it changing its parts; ``sensors`` may be a ``SensorProfile``, and
``faults``, ``ekf`` and ``vehicle`` objects or mappings; ``track`` may be a
generated track (a ``GeneratedTrack``, or ``{"generate": {"seed": S, ...}}``
as in a scenario file). Unknown keys raise,
listing the allowed ones. ``reset(options=...)`` takes ``track``,
``sensors`` (a name or a profile), ``localization`` and ``start_pose``
((x, y, yaw) of the CG) for that episode only.

## Version History
* v0: first release (conesim 0.1.0, unreleased: its dict observation grew
  ``pose_valid`` and ``cones_age`` before any release; a change after one
  gets a new version).
"""

from __future__ import annotations

import dataclasses
import math
import os
from typing import Any, SupportsFloat

import gymnasium as gym
import numpy as np
from numpy.typing import NDArray

from conesim.core.geodesy import GeodesyError
from conesim.core.pose import Pose2D
from conesim.envs.config import EnvConfig
from conesim.envs.loop import Broadcast, ClosedLoop, StepRecord, world_seed
from conesim.envs.observation import SensorMemory, build_observation, observation_space
from conesim.envs.render import Renderer, Scene, SceneKeeper
from conesim.envs.scenario import Localization
from conesim.planner.messages import ControlCommand
from conesim.sim.events import RaceStanding
from conesim.sim.sensors import SensorProfile, get_profile
from conesim.tracks import GeneratedTrack, Track, TrackSource, load_track

ObsType = NDArray[np.float32] | dict[str, NDArray[np.float32]]
RESET_OPTIONS = ("track", "sensors", "localization", "start_pose")
REWARD_TERMS = ("progress", "time", "cone_hit", "cone_doo", "off_track", "lap")


class ConeTrackEnv(gym.Env[ObsType, NDArray[np.float32]]):
    """A car on a cone track with noisy sensors and EKF localization (see the module docs).

    Attributes:
        loop: the closed loop of the current episode (public: its ``record``,
            ``localizer.frames`` and ``global_path`` serve a driver such as
            ``AutopilotExpert``).
    """

    metadata = {"render_modes": ["rgb_array", "human"], "render_fps": 20}  # noqa: RUF012

    def __init__(self, render_mode: str | None = None, **kwargs: Any) -> None:
        self.config = EnvConfig.from_dict(kwargs)
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(
                f"render_mode {render_mode!r}; allowed: {self.metadata['render_modes']}"
            )
        self.render_mode = render_mode
        # One frame per action: the recorded or shown video runs in real time.
        self.metadata = {**self.metadata, "render_fps": round(self.config.control_rate)}
        self.action_space = gym.spaces.Box(-1.0, 1.0, (2,), dtype=np.float32)
        self.observation_space = observation_space(self.config.max_cones, self.config.observation)
        self._track_cache: dict[TrackSource, Track] = {}
        cfg = self.config
        self.loop = self._build_loop(cfg.track, cfg.sensors, cfg.localization)
        self._record: StepRecord | None = None  # the last step's; None before reset
        self._renderer: Renderer | None = None
        self._scenes = self._scene_keeper()
        self._action = np.zeros(2, dtype=np.float32)
        self._memory = SensorMemory()
        self._broadcast: Broadcast | None = None

    # -- gymnasium API -----------------------------------------------------------------------

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[ObsType, dict[str, Any]]:
        """Start an episode; ``options`` may pick the track, sensors, localization, start.

        Options apply to this episode only: a later ``reset`` without them
        goes back to the env's configuration, so the same seed always gives
        the same episode.
        """
        options = dict(options or {})
        unknown = sorted(set(options) - set(RESET_OPTIONS))
        if unknown:
            raise ValueError(f"reset options {unknown} unknown; allowed: {list(RESET_OPTIONS)}")
        cfg = self.config
        chosen = EnvConfig(  # validates and normalises the options
            track=options.get("track", cfg.track),
            sensors=options.get("sensors", cfg.sensors),
            localization=options.get("localization", cfg.localization),
        )
        start_pose = _start_pose_option(options.get("start_pose"))
        # A refused reset leaves the env as it was, its random generator included.
        rng, rng_seed = self._np_random, self._np_random_seed
        rng_state = None if rng is None else rng.bit_generator.state
        super().reset(seed=seed)
        try:
            loop = self._build_loop(chosen.track, chosen.sensors, chosen.localization)
            record = loop.reset(world_seed(self.np_random), start_pose)
            if start_pose is not None and loop.world.race.is_off_track_at(start_pose):
                raise ValueError(
                    f"reset option start_pose {options['start_pose']!r} puts the car off the "
                    f"track {loop.track.name!r}"
                )
        except Exception as exc:
            self._np_random, self._np_random_seed = rng, rng_seed
            if rng is not None and rng_state is not None:
                rng.bit_generator.state = rng_state
            if isinstance(exc, GeodesyError) and start_pose is not None:
                pose = options["start_pose"]
                raise ValueError(f"reset option start_pose {pose!r}: {exc}") from None
            raise
        self.loop = loop
        self._action = np.zeros(2, dtype=np.float32)
        self._memory = SensorMemory()
        self._broadcast = None
        self._scenes = self._scene_keeper()
        if self._renderer is not None:
            self._renderer.global_path = loop.global_path
        self._take(record)
        if self.render_mode == "human":
            self.render()
        return self._observe(), self._info(dict.fromkeys(REWARD_TERMS, 0.0))

    def step(
        self, action: NDArray[np.float32]
    ) -> tuple[ObsType, SupportsFloat, bool, bool, dict[str, Any]]:
        """Apply an action for one control period (``physics_rate / control_rate`` steps)."""
        # 1. act
        last = self._record
        if last is None:
            raise gym.error.ResetNeeded("call reset() before step()")
        act = np.asarray(action, dtype=np.float32)
        if act.shape != (2,):
            raise ValueError(
                f"action must have shape (2,) (steering, acceleration), got shape {act.shape}"
            )
        a0, a1 = act.tolist()
        if not (math.isfinite(a0) and math.isfinite(a1)):
            raise ValueError(f"action must be finite, got {action!r}")
        self._action = np.minimum(np.maximum(act, -1.0), 1.0)  # np.clip without its wrapper
        steer, accel = self.action_to_command(self._action)
        # 2. simulate: the closed loop, with the action as its command
        record = self.loop.step(ControlCommand(last.t, steer, accel))
        self._take(record)
        # 3. observe
        obs = self._observe()
        # 4. reward terms
        terms = self._reward_terms(last, record)
        reward = float(sum(terms.values()))
        # 5. terminated / truncated
        end = record.end
        terminated = end is not None and not end.truncated
        truncated = end is not None and end.truncated
        info = self._info(terms)
        if self.render_mode == "human":
            self.render()
        return obs, reward, terminated, truncated, info

    def render(self) -> NDArray[np.uint8] | None:
        """``rgb_array``: the frame; ``human``: show it in a window."""
        if self.render_mode is None:
            gym.logger.warn("render() called without a render_mode; pass render_mode to make()")
            return None
        if self._renderer is None:
            self._renderer = Renderer(self.loop.global_path)
        frame = self._renderer.rgb_array(self.scene())
        if self.render_mode == "human":
            self._renderer.show(frame, self.metadata["render_fps"])
            return None
        return frame

    def close(self) -> None:
        """Close the render window, if any."""
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None

    # -- pieces ------------------------------------------------------------------------------

    def action_to_command(self, action: NDArray[np.float32]) -> tuple[float, float]:
        """Map an action in [-1, 1]^2 to (steering [rad], acceleration [m/s^2])."""
        p = self.loop.world_config.vehicle
        a = float(action[1])
        return float(action[0]) * p.max_steer, a * (p.max_accel if a >= 0 else p.max_decel)

    def command_to_action(self, steer: float, accel: float) -> NDArray[np.float32]:
        """Inverse of :meth:`action_to_command`, clipped to the action space."""
        p = self.loop.world_config.vehicle
        a = accel / p.max_accel if accel >= 0 else accel / p.max_decel
        return np.clip(np.array([steer / p.max_steer, a], dtype=np.float32), -1.0, 1.0)

    def _build_loop(
        self, track_name: TrackSource, sensors: SensorProfile | str, localization: Localization
    ) -> ClosedLoop:
        """A loop for one episode: the env's scenario with this track, sensors, localization."""
        scenario = dataclasses.replace(
            self.config.to_scenario(),
            track=track_name if isinstance(track_name, GeneratedTrack) else os.fspath(track_name),
            sensors=sensors if isinstance(sensors, SensorProfile) else get_profile(sensors),
            localization=localization,
        )
        return scenario.closed_loop(self._track(track_name))

    def _track(self, name: TrackSource) -> Track:
        if name not in self._track_cache:
            self._track_cache[name] = load_track(name)
        return self._track_cache[name]

    def _take(self, record: StepRecord) -> None:
        """Keep what the observation, the info and the picture need from a record."""
        self._record = record
        self._memory.update(record.messages)
        if record.broadcasts:
            self._broadcast = record.broadcasts[-1]
        self._scenes.update(record)

    def _observe(self) -> ObsType:
        loop = self.loop
        estimate = loop.localizer.estimate(loop.time)
        dict_pose = self.config.observation == "dict" and estimate is None
        return build_observation(
            self._memory,
            estimate,
            self._action,
            self.config.max_cones,
            self.config.observation,
            published=loop.localizer.published_pose() if dict_pose else None,
            awaiting_estimate=estimate is None and loop.localization == "fused",
            now=loop.time,
        )

    def _reward_terms(self, last: StepRecord, now: StepRecord) -> dict[str, float]:
        """Each weighted term of the step's reward, from the two records' standings."""
        w = self.config.rewards
        weights = {
            "progress": w.progress,
            "time": w.time,
            "cone_hit": w.cone_hit,
            "cone_doo": w.cone_doo,
            "off_track": w.off_track,
            "lap": w.lap,
        }
        before, after = _counts(last), _counts(now)
        # + 0.0: a term with nothing to count is 0.0, not -0.0 (a negative weight times 0)
        return {k: weights[k] * (after[k] - before[k]) + 0.0 for k in REWARD_TERMS}

    @property
    def laps_to_drive(self) -> int:
        """Laps that end the episode: ``laps``, or 1 on an open lane (one run)."""
        return self.loop.laps_to_drive

    def _info(self, terms: dict[str, float]) -> dict[str, Any]:
        record = self._record
        assert record is not None
        race = record.truth.race
        state = record.truth.state
        antenna = record.truth.antenna
        info: dict[str, Any] = {
            "t": record.t,
            "reward_terms": terms,
            "end_reason": "" if record.end is None else str(record.end),
            "laps_completed": race.laps_completed,
            "lap_times": list(race.lap_times),
            "progress_m": race.progress_m,
            "cones_hit": race.cones_hit,
            "cones_down_or_out": race.cones_down_or_out,
            "off_track_events": race.off_track_events,
            "truth": {
                "x": antenna.x,
                "y": antenna.y,
                "yaw": antenna.yaw,
                "speed": state.speed,
                "steer": state.steer,
            },
            "messages": record.messages,
        }
        last = self._broadcast
        # Always a dict, inf (no pose yet) before the first broadcast: gymnasium's
        # vector envs stack each info key across sub-envs and need one type per
        # key, and its checker compares infos with == (NaN != NaN).
        info["localization_error"] = (
            {"position_m": last.position_error, "yaw_rad": last.yaw_error}
            if last is not None
            else {"position_m": math.inf, "yaw_rad": math.inf}
        )
        return info

    def _scene_keeper(self) -> SceneKeeper:
        p = self.loop.world_config.vehicle
        return SceneKeeper(tuple(str(k) for k in self.loop.track.kinds), p.length, p.width)

    def scene(self) -> Scene:
        """What a frame shows now (truth, estimate, detections)."""
        if self._record is None:
            raise gym.error.ResetNeeded("call reset() before render()")
        loop = self.loop
        return self._scenes.scene(loop.localizer.frames, loop.localizer.estimate(loop.time))


def _counts(record: StepRecord) -> dict[str, float]:
    """What the reward terms count, after a step."""
    race: RaceStanding = record.truth.race
    return {
        "progress": race.progress_m,
        "time": record.t,
        "cone_hit": float(race.cones_hit),
        "cone_doo": float(race.cones_down_or_out),
        "off_track": float(race.off_track_events),
        "lap": float(race.laps_completed),
    }


def _start_pose_option(value: Any) -> Pose2D | None:
    """The ``start_pose`` reset option, (x [m], y [m], yaw [rad]) of the CG, or None."""
    if value is None:
        return None
    try:
        if isinstance(value, str | bytes):
            raise TypeError
        x, y, yaw = (float(v) for v in value)
    except (TypeError, ValueError):
        raise ValueError(
            f"reset option start_pose must be (x [m], y [m], yaw [rad]) numbers, got {value!r}"
        ) from None
    if not all(math.isfinite(v) for v in (x, y, yaw)):
        raise ValueError(f"reset option start_pose must be finite, got {value!r}")
    return Pose2D(x, y, yaw)
