"""``conesim/ConeTrack-v0``: drive a Formula Student cone track.

The env hosts the closed loop (``envs.stack.VehicleStack``: the pymunk world,
its sensors, the EKF and the frame tree). An action sets the car's steering
and acceleration for one control period; the world runs its physics substeps
and sensors; localization takes every message; the env observes, scores and
decides whether the episode is over.

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
``info["end_reason"]`` says which. The registered ``max_episode_steps`` is a
backstop behind the env's own limit.

## Arguments
``gymnasium.make("conesim/ConeTrack-v0", track="autocross", sensors="rtk",
localization="fused", laps=1, control_rate=50, observation="vector",
render_mode="rgb_array", ...)``; every ``envs.config.EnvConfig`` field. Unknown
keys raise, listing the allowed ones. ``reset(options=...)`` takes ``track``,
``sensors``, ``localization`` and ``start_pose`` ((x, y, yaw) of the CG) for
that episode only.

## Version History
* v0: first release (conesim 0.1.0, unreleased: its dict observation grew
  ``pose_valid`` and ``cones_age`` before any release; a change after one
  gets a new version).
"""

from __future__ import annotations

import contextlib
import math
from typing import Any, SupportsFloat

import gymnasium as gym
import numpy as np
from numpy.typing import NDArray

from conesim.core.geodesy import GeodesyError
from conesim.core.messages import Message
from conesim.core.pose import Pose2D
from conesim.envs.config import EnvConfig
from conesim.envs.observation import SensorMemory, build_observation, observation_space
from conesim.envs.render import Renderer, Scene
from conesim.envs.stack import VehicleStack
from conesim.localization.frames import LATEST, TransformError
from conesim.sim.world import WorldConfig
from conesim.tracks import Track, load_track

ObsType = NDArray[np.float32] | dict[str, NDArray[np.float32]]
RESET_OPTIONS = ("track", "sensors", "localization", "start_pose")


class ConeTrackEnv(gym.Env[ObsType, NDArray[np.float32]]):
    """A car on a cone track with noisy sensors and EKF localization (see the module docs)."""

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
        self._track_cache: dict[str, Track] = {}
        self.stack = self._build_stack(
            0, self.config.track, self.config.sensors, self.config.localization
        )
        self.overlay: Any = None  # an object with planner intermediates, for drawing
        self._renderer: Renderer | None = None
        self._action = np.zeros(2, dtype=np.float32)
        self._memory = SensorMemory()
        self.last_messages: list[Message] = []
        self._counts: dict[str, float] | None = None  # score at the last step; None before reset

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
        track, sensors, localization = chosen.track, chosen.sensors, chosen.localization
        start_pose = _start_pose_option(options.get("start_pose"))
        # A refused reset leaves the env as it was, its random generator included.
        rng, rng_seed = self._np_random, self._np_random_seed
        rng_state = None if rng is None else rng.bit_generator.state
        super().reset(seed=seed)
        try:
            episode_seed = int(self.np_random.integers(0, 2**31 - 1))
            stack = self._build_stack(episode_seed, track, sensors, localization, start_pose)
            if start_pose is not None and stack.world.race.is_off_track_at(start_pose):
                raise ValueError(
                    f"reset option start_pose {options['start_pose']!r} puts the car off the "
                    f"track {stack.track.name!r}"
                )
        except Exception as exc:
            self._np_random, self._np_random_seed = rng, rng_seed
            if rng is not None and rng_state is not None:
                rng.bit_generator.state = rng_state
            if isinstance(exc, GeodesyError) and start_pose is not None:
                pose = options["start_pose"]
                raise ValueError(f"reset option start_pose {pose!r}: {exc}") from None
            raise
        self.stack = stack
        self.overlay = None  # a policy attaches its own after reset
        if self._renderer is not None:
            self._renderer.global_path = self.stack.global_path
        self._action = np.zeros(2, dtype=np.float32)
        self._memory = SensorMemory()
        self._memory.update(self.stack.initial_messages)
        self.last_messages = list(self.stack.initial_messages)
        self._counts = self._score_counts()
        if self.render_mode == "human":
            self.render()
        return self._observe(), self._info(dict.fromkeys(self._reward_weights(), 0.0), "")

    def step(
        self, action: NDArray[np.float32]
    ) -> tuple[ObsType, SupportsFloat, bool, bool, dict[str, Any]]:
        """Apply an action for one control period (``physics_rate / control_rate`` steps)."""
        # 1. act
        if self._counts is None:
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
        self.stack.world.set_command(steer, accel)
        # 2. simulate
        self.last_messages = self.stack.run_physics_steps(self.config.substeps)
        self._memory.update(self.last_messages)
        # 3. observe
        obs = self._observe()
        # 4. reward terms
        terms = self._reward_terms()
        reward = float(sum(terms.values()))
        # 5. terminated / truncated
        terminated, truncated, reason = self._episode_end()
        info = self._info(terms, reason)
        if self.render_mode == "human":
            self.render()
        return obs, reward, terminated, truncated, info

    def render(self) -> NDArray[np.uint8] | None:
        """``rgb_array``: the frame; ``human``: show it in a window."""
        if self.render_mode is None:
            gym.logger.warn("render() called without a render_mode; pass render_mode to make()")
            return None
        if self._renderer is None:
            self._renderer = Renderer(self.stack.global_path)
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
        p = self.stack.world_config.vehicle
        a = float(action[1])
        return float(action[0]) * p.max_steer, a * (p.max_accel if a >= 0 else p.max_decel)

    def command_to_action(self, steer: float, accel: float) -> NDArray[np.float32]:
        """Inverse of :meth:`action_to_command`, clipped to the action space."""
        p = self.stack.world_config.vehicle
        a = accel / p.max_accel if accel >= 0 else accel / p.max_decel
        return np.clip(np.array([steer / p.max_steer, a], dtype=np.float32), -1.0, 1.0)

    def _build_stack(
        self,
        seed: int,
        track_name: str,
        sensors: str,
        localization: str,
        start_pose: Pose2D | None = None,
    ) -> VehicleStack:
        if track_name not in self._track_cache:
            self._track_cache[track_name] = load_track(track_name)
        world_config = WorldConfig(physics_rate=self.config.physics_rate, sensors=sensors)
        return VehicleStack(
            self._track_cache[track_name], world_config, localization, seed, start_pose
        )

    def _observe(self) -> ObsType:
        estimate = self.stack.estimate()
        dict_pose = self.config.observation == "dict" and estimate is None
        return build_observation(
            self._memory,
            estimate,
            self._action,
            self.config.max_cones,
            self.config.observation,
            published=self.stack.published_pose() if dict_pose else None,
            awaiting_estimate=estimate is None and self.stack.localization == "fused",
            now=self.stack.world.time,
        )

    def _score_counts(self) -> dict[str, float]:
        world = self.stack.world
        race = world.race_state
        return {
            "progress": race.progress_m,
            "time": world.time,
            "cone_hit": float(len(world.cones.hit_ids)),
            "cone_doo": float(len(world.cones.doo_ids)),
            "off_track": float(len(race.off_track)),
            "lap": float(race.laps_completed),
        }

    def _reward_weights(self) -> dict[str, float]:
        """Each reward term's weight, by name (the keys of ``info["reward_terms"]``)."""
        w = self.config.rewards
        return {
            "progress": w.progress,
            "time": w.time,
            "cone_hit": w.cone_hit,
            "cone_doo": w.cone_doo,
            "off_track": w.off_track,
            "lap": w.lap,
        }

    def _reward_terms(self) -> dict[str, float]:
        counts = self._score_counts()
        weights = self._reward_weights()
        last = self._counts
        assert last is not None  # step() checks that reset() came first
        # + 0.0: a term with nothing to count is 0.0, not -0.0 (a negative weight times 0)
        terms = {k: weights[k] * (counts[k] - last[k]) + 0.0 for k in weights}
        self._counts = counts
        return terms

    def _episode_end(self) -> tuple[bool, bool, str]:
        world = self.stack.world
        race = world.race_state
        cfg = self.config
        if race.laps_completed >= self.laps_to_drive:
            return True, False, "laps_completed"
        if cfg.terminate_off_track and race.off_track:
            return True, False, "off_track"
        if cfg.terminate_stuck and race.stuck:
            return True, False, "stuck"
        if world.time >= cfg.episode_time_limit - 1e-9:
            return False, True, "time_limit"
        return False, False, ""

    @property
    def laps_to_drive(self) -> int:
        """Laps that end the episode: ``laps``, or 1 on an open lane (one run)."""
        return 1 if self.stack.track.layout == "open" else self.config.laps

    def _info(self, terms: dict[str, float], reason: str) -> dict[str, Any]:
        world = self.stack.world
        race = world.race_state
        state = world.state
        antenna = state.antenna_pose()
        info: dict[str, Any] = {
            "t": world.time,
            "reward_terms": terms,
            "end_reason": reason,
            "laps_completed": race.laps_completed,
            "lap_times": list(race.lap_times),
            "progress_m": race.progress_m,
            "cones_hit": len(world.cones.hit_ids),
            "cones_down_or_out": len(world.cones.doo_ids),
            "off_track_events": len(race.off_track),
            "truth": {
                "x": antenna.x,
                "y": antenna.y,
                "yaw": antenna.yaw,
                "speed": state.speed,
                "steer": state.steer,
            },
            "messages": self.last_messages,
        }
        samples = self.stack.localization_samples
        # Always a dict, inf (no pose yet) before the first broadcast: gymnasium's
        # vector envs stack each info key across sub-envs and need one type per
        # key, and its checker compares infos with == (NaN != NaN).
        info["localization_error"] = (
            {"position_m": samples[-1].position_error, "yaw_rad": samples[-1].yaw_error}
            if samples
            else {"position_m": math.inf, "yaw_rad": math.inf}
        )
        return info

    def scene(self) -> Scene:
        """What a frame shows now (truth, estimate, detections, planner overlay)."""
        world = self.stack.world
        p = world.config.vehicle
        est = self.stack.estimate()
        scene = Scene(
            cones=np.asarray(world.cones.positions),
            kinds=world.cones.kinds,
            car=world.state.pose,
            car_length=p.length,
            car_width=p.width,
            t=world.time,
            speed=world.state.speed,
            laps=world.race_state.laps_completed,
        )
        if est is not None:
            scene.estimate = est.pose
            scene.covariance = np.asarray(est.pose_covariance)[:2, :2]
        det = self._memory.detections
        buffer = self.stack.buffer
        if det is not None and len(det):
            with contextlib.suppress(TransformError):  # placed with the pose at capture
                scene.detections = buffer.transform_points(
                    "reference", "os_sensor", np.asarray(det.points[:, :2]), det.header.stamp
                )
        ap = self.overlay
        if ap is not None:
            scene.left = np.asarray(ap.left_cones)
            scene.right = np.asarray(ap.right_cones)
            path_ref = np.asarray(getattr(ap, "path_reference", np.zeros((0, 2))))
            scene.path = path_ref
            plan = getattr(ap, "plan", None)
            if plan is not None and len(plan.speeds) == len(path_ref):
                scene.speeds = np.asarray(plan.speeds)
            look = ap.lookahead_point
            if look is not None:
                with contextlib.suppress(TransformError):
                    scene.lookahead = buffer.transform_points(
                        "reference", "os_sensor", np.asarray(look).reshape(1, 2), LATEST
                    )[0]
        return scene


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
