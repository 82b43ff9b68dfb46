"""``conesim/ConeTrack-v0``: drive a Formula Student cone track.

The env wraps the closed loop (``envs.loop.ClosedLoop``: the pymunk world,
its sensors, localization and the frame tree) without a driver: an action
becomes the car's steering and acceleration command for one control period
(``ClosedLoop.step``); the env observes, scores and passes on the loop's end
of the episode. To drive it with the autopilot (a baseline, or an expert for
imitation learning) use ``envs.expert.AutopilotExpert``.

## Action Space
``action="centred"`` (default): ``Box(-1, 1, (2,), float32)``,
``[steering, acceleration]``, both symmetric about zero: steering
``a0 * max_steer`` (0.47 rad), acceleration ``a1 * max_accel`` (+-3 m/s^2).
A zero action is no steering and no acceleration, and zero-mean random
actions accelerate the car by zero on average (so an untrained policy
moves: the car has no reverse gear, so its speed performs a random walk
held at zero from below). Braking is limited to ``max_accel`` in this mode: the
autopilot, planning its braking within it, loses about 2 % of lap time
(autocross 25.1 s -> 25.6 s, trackdrive 18.7 s -> 18.9 s).

``action="physical"``: ``Box([-max_steer, -max_decel], [max_steer,
max_accel])`` in [rad] and [m/s^2]: the car's whole range, full braking
(10 m/s^2) included; zero is still no command.

The command is held for one control period (``control_rate``, 50 Hz; 4
physics steps at 200 Hz). The steering actuator has a rate limit and a lag
(``sim.vehicle_params``). An action outside the space is clipped into it.

## Observation Space
``observation="vector"`` (default): float32, ``8 + 5 K`` entries (K =
``max_cones``, 32), every one scaled to order 1: speed / 20 m/s, yaw rate /
2 rad/s, the previous command, a pose-validity flag, the EKF's 1-sigma
position (/ 1 m) and heading (/ 0.1 rad) uncertainty, the cone detection's
age (/ 1 s), then the K nearest detected cones in ``os_sensor`` as (x / range,
y / range, mask, side: +1 blue / -1 yellow / 0, orange). ``observation="dict"``:
the same in raw units with the estimated pose and its covariance.
``path_preview=N`` (default 0) appends the global path's next N points
(``path_preview_step`` apart) in the localized ``gps_antenna`` frame. The
layouts and scales: ``envs.observation``.

## Rewards
A sum of named terms, each in ``info["reward_terms"]`` (weights:
``rewards={...}``, ``envs.config.RewardWeights``): ``progress`` (+1 per metre
of net progress along the true centreline; a cut across the infield never
pays), ``time`` (-1 per second), ``cone_doo`` (-2 per cone down or out),
``off_track`` (-10 per excursion), ``cone_hit`` (0 per cone touched) and
``lap`` (0 per lap).

The time weight is the exchange rate between time and progress, 1 m per
second, and the penalties are the Formula Student charges at that rate (2 s
per cone down or out, 10 s per off-course). So a completed lap of length L
returns ``L - (lap time + FS penalties)``: the return orders laps as FS
scores them, faster and cleaner always paying more. On trackdrive (270 m): a
clean lap at 5 m/s returns 270 - 54 = 216, at 10 m/s 243, at 10 m/s with a
cone down 241, the same as a clean lap 2 s slower. Progress dominates: every
second of driving faster than 1 m/s pays, so a crawl earns more than
standing still (-1 per second, -15 before the stuck rule ends it), and an
episode that ends early (off the track, stuck) forfeits the progress still
to come: leaving the track costs the 10 s penalty plus the rest of the lap.

## Starting State
The car stands still at the track's start pose (behind the start line), at
t = 0, sensors and filter freshly reset with the episode seed. With
``track="random"`` each episode's track is generated (``tracks.generate``,
``track_spec``: medium, 280-380 m, by default) from a seed drawn from
``track_seeds`` (default ``range(1000)``; a ``range`` or a pair ``(lo, hi)``)
with the episode's generator, so ``reset(seed=s)`` always gives the same
track; ``info["track_seed"]`` names it. Train on ``track_seeds=(0, 1000)``
and test on ``(1000, 1100)``: a policy then meets tracks it never saw.

## Episode End
Terminated when the requested laps are complete (an open lane such as
acceleration is one run, whatever ``laps`` says); when the car leaves the
track (``terminate_off_track``, default True; without it each excursion
costs its penalty and the episode goes on); when it is stuck
(``terminate_stuck``, default True): less than ``stuck_progress`` (1 m) of
net progress in the last ``stuck_time`` (10 s), and never before
``stuck_grace`` (15 s), so a car is never stuck before it had a chance to
move. Truncated at ``time_limit`` (default 60 s per lap + 30 s).
``info["end_reason"]`` says which, as an index into ``END_REASONS``. The
registered ``max_episode_steps`` is a backstop behind the env's own limit.

## Info
``info="lean"`` (default), numbers only so that vector envs stack them into
numeric arrays: ``t`` [s], ``progress_m``, ``speed`` (true, [m/s]),
``laps_completed``, ``lap_time`` (the last lap's [s], 0 before one),
``cones_hit``, ``cones_down_or_out``, ``off_track_events``, ``end_reason``
(0 while running, ``END_REASONS``), ``track_seed`` (the generated track's
seed, -1 for another track) and ``reward_terms``. ``info="full"``
adds ``lap_times``, ``truth`` (the antenna's pose, speed, steering),
``localization_error`` and ``messages`` (every measurement delivered in the
step).

## Arguments
``gymnasium.make("conesim:conesim/ConeTrack-v0", track="autocross" (or "random",
with track_seeds=(0, 1000) and track_spec={"size": "small"}), sensors="rtk",
localization="fused", laps=1, control_rate=50, observation="vector",
action="centred", info="lean", stuck_time=10, stuck_progress=1,
stuck_grace=15, terminate_off_track=True, time_limit=None,
render_mode="rgb_array", ...)``; every ``envs.config.EnvConfig`` field, or
``scenario=`` (a ``Scenario`` or a scenario file) with the keywords given
beside it changing its parts; ``sensors`` may be a ``SensorProfile``, and
``faults``, ``ekf`` and ``vehicle`` objects or mappings; ``track`` may be a
generated track (a ``GeneratedTrack``, or ``{"generate": {"seed": S, ...}}``
as in a scenario file). Unknown keys and values out of range raise, naming
them. ``reset(options=...)`` takes ``track``, ``sensors`` (a name or a
profile), ``localization`` and ``start_pose`` ((x, y, yaw) of the CG) for
that episode only.

## Version History
* v0: first release (conesim 0.1.0, unreleased: its dict observation grew
  ``pose_valid`` and ``cones_age``; then the centred action, the normalised
  vector observation, the lean info, the FS-rate reward and the stuck
  rule's grace, the random tracks and the path preview came, all before any release; a change
  after one gets a new version).
"""

from __future__ import annotations

import dataclasses
import math
import os
from typing import Any, SupportsFloat

import gymnasium as gym
import numpy as np
from numpy.typing import NDArray

from conesim.core.geodesy import GeodesyError, local_cartesian_to_gps
from conesim.core.pose import Pose2D
from conesim.envs.config import RANDOM_TRACK, EnvConfig
from conesim.envs.loop import Broadcast, ClosedLoop, EndReason, StepRecord, world_seed
from conesim.envs.observation import (
    PathPreview,
    SensorMemory,
    build_dict,
    build_vector,
    observation_space,
)
from conesim.envs.render import Renderer, Scene, SceneKeeper, window_problem
from conesim.envs.scenario import Localization
from conesim.planner.messages import ControlCommand
from conesim.sim.events import RaceStanding
from conesim.sim.sensors import SensorProfile, get_profile
from conesim.tracks import GeneratedTrack, Track, TrackGenerationError, TrackSource, load_track

ObsType = NDArray[np.float32] | dict[str, NDArray[np.float32]]
RESET_OPTIONS = ("track", "sensors", "localization", "start_pose")
REWARD_TERMS = ("progress", "time", "cone_hit", "cone_doo", "off_track", "lap")
END_REASONS = ("", *(str(r) for r in EndReason))
"""``info["end_reason"]`` indexes this: 0 while the episode runs, then its ``EndReason``."""
_END_CODES = {r: k for k, r in enumerate(EndReason, start=1)}
TRACK_CACHE_SIZE = 1024  # tracks kept (a generated one: 0.3-0.5 s to make, ~50 KB)
GENERATION_TRIES = 10  # seeds tried in turn when the generator gives one up


class ConeTrackEnv(gym.Env[ObsType, NDArray[np.float32]]):
    """A car on a cone track with noisy sensors and EKF localization (see the module docs).

    Attributes:
        loop: the closed loop of the current episode (public: its ``record``,
            ``localizer.frames`` and ``global_path`` serve a driver such as
            ``AutopilotExpert``).
        track_seed: the current episode's generated track's seed, -1 when
            the track is not generated.
    """

    metadata = {"render_modes": ["rgb_array", "human"], "render_fps": 20}  # noqa: RUF012

    def __init__(self, render_mode: str | None = None, **kwargs: Any) -> None:
        self.config = EnvConfig.from_dict(kwargs)
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(
                f"render_mode {render_mode!r}; allowed: {self.metadata['render_modes']}"
            )
        if render_mode == "human" and (problem := window_problem()) is not None:
            raise gym.error.DependencyNotInstalled(
                f'render_mode "human": {problem}; or "rgb_array"'
            )
        self.render_mode = render_mode
        # One frame per action: the recorded or shown video runs in real time.
        self.metadata = {**self.metadata, "render_fps": round(self.config.control_rate)}
        cfg = self.config
        self._track_cache: dict[TrackSource, Track] = {}
        first = self._generated(0) if cfg.track == RANDOM_TRACK else cfg.track
        self.track_seed = _generator_seed(first)
        self.loop = self._build_loop(first, cfg.sensors, cfg.localization)
        # What the loop was built for: an episode with the same track, sensors
        # and localization resets it (and its world) rather than building another.
        self._loop_key: tuple[object, ...] | None = (first, cfg.sensors, cfg.localization)
        p = self.loop.world_config.vehicle
        if cfg.action == "centred":
            self.action_space = gym.spaces.Box(-1.0, 1.0, (2,), dtype=np.float32)
            self._scale = (p.max_steer, p.max_accel)  # command per unit of action
        else:
            self.action_space = gym.spaces.Box(
                np.array([-p.max_steer, -p.max_decel], dtype=np.float32),
                np.array([p.max_steer, p.max_accel], dtype=np.float32),
                dtype=np.float32,
            )
            self._scale = (1.0, 1.0)
        # The observation's command: steering / max_steer, acceleration / the
        # action's acceleration scale (the centred action reads back as itself).
        self._obs_scale = (p.max_steer, p.max_accel if cfg.action == "centred" else p.max_decel)
        self._low = [float(v) for v in self.action_space.low]
        self._high = [float(v) for v in self.action_space.high]
        self.observation_space = observation_space(cfg.max_cones, cfg.observation, cfg.path_preview)
        self._record: StepRecord | None = None  # the last step's; None before reset
        self._renderer: Renderer | None = None
        self._scenes = self._scene_keeper()
        self._command = (0.0, 0.0)  # the last command over the observation's scales
        self._memory = SensorMemory()
        self._broadcast: Broadcast | None = None
        self._preview = self._path_preview()

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
        begun = False  # whether the current episode's loop began a reset (the episode is gone)
        try:
            track = chosen.track
            if track == RANDOM_TRACK:
                track = self._generated(int(self.np_random.integers(len(cfg.track_seeds))))
            key = (track, chosen.sensors, chosen.localization)
            if key == self._loop_key:
                loop = self.loop
            else:
                loop = self._build_loop(track, chosen.sensors, chosen.localization)
            # The loop's episode, if it has one, is gone once its reset begins:
            # a bad start is refused before.
            checked = False
            if loop.record is not None and start_pose is not None:
                origin = loop.world_config.origin
                local_cartesian_to_gps(start_pose.x, start_pose.y, origin)
                _refuse_off_track(loop, start_pose, options["start_pose"])
                checked = True
            begun = loop is self.loop and loop.record is not None
            record = loop.reset(world_seed(self.np_random), start_pose)
            if start_pose is not None and not checked:
                _refuse_off_track(loop, start_pose, options["start_pose"])
        except Exception as exc:
            self._np_random, self._np_random_seed = rng, rng_seed
            if rng is not None and rng_state is not None:
                rng.bit_generator.state = rng_state
            if begun:  # the last episode is gone: the next reset builds a loop
                self._record = None
                self._loop_key = None
            if isinstance(exc, GeodesyError) and start_pose is not None:
                pose = options["start_pose"]
                raise ValueError(f"reset option start_pose {pose!r}: {exc}") from None
            raise
        self.loop = loop
        self._loop_key = key
        self.track_seed = _generator_seed(track)
        self._command = (0.0, 0.0)
        self._memory = SensorMemory()
        self._broadcast = None
        self._preview = self._path_preview()
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
        steer, accel = self.action_to_command(action)
        os_, oa = self._obs_scale
        self._command = (steer / os_, accel / oa)
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

    def action_to_command(self, action: Any) -> tuple[float, float]:
        """(steering [rad], acceleration [m/s^2]) of an action, clipped into the action space.

        Raises:
            ValueError: the action is not two finite numbers.
        """
        values = np.asarray(action, dtype=np.float32)
        if values.shape != (2,):
            raise ValueError(
                f"action must have shape (2,) (steering, acceleration), got shape {values.shape}"
            )
        a0, a1 = values.tolist()
        if not (math.isfinite(a0) and math.isfinite(a1)):
            raise ValueError(f"action must be finite, got {action!r}")
        low, high = self._low, self._high
        a0 = min(max(a0, low[0]), high[0])
        a1 = min(max(a1, low[1]), high[1])
        return a0 * self._scale[0], a1 * self._scale[1]

    def command_to_action(self, steer: float, accel: float) -> NDArray[np.float32]:
        """Inverse of :meth:`action_to_command`, clipped to the action space."""
        action = np.array([steer / self._scale[0], accel / self._scale[1]], dtype=np.float32)
        return np.clip(action, self._low, self._high).astype(np.float32)

    @property
    def brake_limit(self) -> float:
        """The hardest braking an action can command [m/s^2] (positive)."""
        return -self._low[1] * self._scale[1]

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
        return scenario.closed_loop(self._track(track_name), rules=self.config.rules)

    def _track(self, name: TrackSource) -> Track:
        cache = self._track_cache
        if name not in cache:
            if len(cache) >= TRACK_CACHE_SIZE:  # the oldest goes (random tracks)
                del cache[next(iter(cache))]
            cache[name] = load_track(name)
        return cache[name]

    def _generated(self, index: int) -> GeneratedTrack:
        """The generated track of ``track_seeds[index]``, or of the next seed
        that makes one (a seed for which the generator gives up is skipped)."""
        seeds = self.config.track_seeds
        for k in range(min(len(seeds), GENERATION_TRIES)):
            seed = seeds[(index + k) % len(seeds)]
            source = GeneratedTrack(seed, self.config.track_spec)
            try:
                self._track(source)
            except TrackGenerationError:
                continue
            return source
        raise TrackGenerationError(
            f"track_seeds {seeds}: no track from {GENERATION_TRIES} seeds from index {index} on"
        )

    def _take(self, record: StepRecord) -> None:
        """Keep what the observation, the info and the picture need from a record."""
        self._record = record
        self._memory.update(record.messages)
        if record.broadcasts:
            self._broadcast = record.broadcasts[-1]
        self._scenes.update(record)

    def _path_preview(self) -> PathPreview | None:
        """The episode's path preview (its global path's), None without one."""
        n = self.config.path_preview
        if not n:
            return None
        return PathPreview(self.loop.global_path.polyline, n, self.config.path_preview_step)

    def _observe(self) -> ObsType:
        loop = self.loop
        estimate = loop.localizer.estimate(loop.time)
        cfg = self.config
        published = None  # the frame tree's pose, where there is no estimate and it is used
        if estimate is None and (cfg.observation == "dict" or self._preview is not None):
            published = loop.localizer.published_pose()
        preview = None  # (its points in gps_antenna, zeros without a pose; its length)
        if self._preview is not None:
            # A filter's own estimate (none after it resets, whatever was broadcast before),
            # else the frame tree's pose.
            unfiltered = loop.localization in ("raw", "truth")
            pose = estimate.pose if estimate is not None else published if unfiltered else None
            n = cfg.path_preview
            points = np.zeros((n, 2)) if pose is None else self._preview.points(pose)
            preview = (points, self._preview.length)
        if cfg.observation == "vector":
            valid = estimate is not None if loop.localization == "fused" else bool(self._broadcast)
            return build_vector(
                self._memory,
                estimate,
                self._command,
                cfg.max_cones,
                loop.world_config.sensor_profile.cones.max_range,
                pose_valid=valid,
                now=loop.time,
                preview=preview,
            )
        return build_dict(
            self._memory,
            estimate,
            self._command,
            cfg.max_cones,
            published=published,
            awaiting_estimate=estimate is None and loop.localization == "fused",
            now=loop.time,
            preview=None if preview is None else preview[0],
        )

    def _reward_terms(self, last: StepRecord, now: StepRecord) -> dict[str, float]:
        """Each weighted term of the step's reward, from the two records' standings."""
        w = self.config.rewards
        before, after = last.truth.race, now.truth.race
        # + 0.0: a term with nothing to count is 0.0, not -0.0 (a negative weight times 0)
        return {
            "progress": w.progress * (after.progress_m - before.progress_m) + 0.0,
            "time": w.time * (now.t - last.t) + 0.0,
            "cone_hit": w.cone_hit * (after.cones_hit - before.cones_hit) + 0.0,
            "cone_doo": w.cone_doo * (after.cones_down_or_out - before.cones_down_or_out) + 0.0,
            "off_track": w.off_track * (after.off_track_events - before.off_track_events) + 0.0,
            "lap": w.lap * (after.laps_completed - before.laps_completed) + 0.0,
        }

    @property
    def laps_to_drive(self) -> int:
        """Laps that end the episode: ``laps``, or 1 on an open lane (one run)."""
        return self.loop.laps_to_drive

    def _info(self, terms: dict[str, float]) -> dict[str, Any]:
        record = self._record
        assert record is not None
        race: RaceStanding = record.truth.race
        state = record.truth.state
        info: dict[str, Any] = {
            "t": record.t,
            "progress_m": race.progress_m,
            "speed": state.speed,
            "laps_completed": race.laps_completed,
            "lap_time": race.lap_times[-1] if race.lap_times else 0.0,
            "cones_hit": race.cones_hit,
            "cones_down_or_out": race.cones_down_or_out,
            "off_track_events": race.off_track_events,
            "end_reason": 0 if record.end is None else _END_CODES[record.end],
            "track_seed": self.track_seed,
            "reward_terms": terms,
        }
        if self.config.info == "lean":
            return info
        antenna = record.truth.antenna
        info["lap_times"] = list(race.lap_times)
        info["truth"] = {
            "x": antenna.x,
            "y": antenna.y,
            "yaw": antenna.yaw,
            "speed": state.speed,
            "steer": state.steer,
        }
        info["messages"] = record.messages
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


def _generator_seed(track: TrackSource) -> int:
    """A generated track's seed, -1 for any other track (``info["track_seed"]``)."""
    return track.seed if isinstance(track, GeneratedTrack) else -1


def _refuse_off_track(loop: ClosedLoop, start_pose: Pose2D, option: object) -> None:
    """Raise if ``start_pose`` (the ``start_pose`` option ``option``) is off the loop's track."""
    if loop.world.race.is_off_track_at(start_pose):
        raise ValueError(
            f"reset option start_pose {option!r} puts the car off the track {loop.track.name!r}"
        )


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
