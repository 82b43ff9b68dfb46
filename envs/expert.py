"""The autopilot as an expert for ``ConeTrackEnv``: a baseline, or demonstrations to imitate.

The env wraps the closed loop without a driver; this drives it from the
outside, through the env's public interface only: the episode's frame tree,
global path and last step's record (``env.unwrapped.loop``:
``localizer.frames``, ``global_path``, ``control_rate``, ``record``, whose
``messages`` are the measurements the step delivered). It sees what a real
car's software sees, never the truth. Its command (steering [rad],
acceleration [m/s^2]) becomes an action through ``env.command_to_action``::

    env = gym.make("conesim:conesim/ConeTrack-v0", track="autocross")
    expert = AutopilotExpert(env)
    obs, info = env.reset(seed=0)
    action = expert.reset(info)
    while True:
        obs, reward, terminated, truncated, info = env.step(action)
        if terminated or truncated:
            break
        action = expert(info)     # the expert's action for the next step

The actions are the env's float32 actions. The autopilot plans its braking
within what an action can command (``env.brake_limit``: the centred
action's 3 m/s^2, the physical action's 10): at most ``BRAKE_SHARE`` of it,
the default's share of the car's 10 m/s^2 (so 2.4 m/s^2 with the centred
action). With the physical
action an episode driven this way is the autopilot's ``conesim run``
episode of the same seed up to the action space's float32 rounding of the
commands.
"""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np
from numpy.typing import NDArray

from conesim.envs.cone_track_env import ConeTrackEnv
from conesim.planner import Autopilot, AutopilotConfig
from conesim.planner.autopilot import AutopilotStep, default_config

BRAKE_SHARE = 0.8
"""The share of the action's braking limit the expert plans with at most: the
default autopilot's (8 of the car's 10 m/s^2)."""


class AutopilotExpert:
    """Drive a ``ConeTrackEnv`` with the ROS pipeline and pure pursuit.

    Call :meth:`reset` after every ``env.reset`` (the frame tree is new), then
    ``action = expert(info)`` after each step.

    Args:
        env: the env (a wrapped env is unwrapped).
        config: the autopilot's settings; by default the env's (its
            scenario's ``autopilot``), else the runner's for the episode's
            localization (``AutopilotConfig.cautious()`` with ``raw``); its
            braking plan is fitted to the action's limit either way.

    Attributes:
        output: the autopilot's last step (its command, plans and path), or None.
    """

    def __init__(self, env: Any, config: AutopilotConfig | None = None) -> None:
        base = env.unwrapped
        if not isinstance(base, ConeTrackEnv):
            raise TypeError(f"AutopilotExpert drives a ConeTrackEnv, got {type(base).__name__}")
        self.env = base
        self.config = config
        self.autopilot: Autopilot | None = None
        self.output: AutopilotStep | None = None

    def reset(self, info: dict[str, Any] | None = None) -> NDArray[np.float32]:
        """A fresh autopilot on the env's new episode; the first action."""
        loop = self.env.loop
        config = self.config or self.env.config.autopilot or default_config(loop.localization)
        self.autopilot = Autopilot(
            loop.localizer.frames,
            loop.global_path,
            self._within_action(config),
            control_rate=loop.control_rate,
        )
        return self(info)

    def __call__(self, info: dict[str, Any] | None = None) -> NDArray[np.float32]:
        """The action for the next control period, after the env's last step.

        ``info`` is not needed (the step's messages are read from the loop's
        record); it is taken so that ``expert(info)`` reads as a policy.
        """
        if self.autopilot is None:
            raise RuntimeError("AutopilotExpert: call reset(info) after env.reset()")
        record = self.env.loop.record
        assert record is not None, "AutopilotExpert: the env has not been reset"
        self.output = self.autopilot.step(record.t, record.messages)
        command = self.output.command
        return self.env.command_to_action(command.steering, command.acceleration)

    def _within_action(self, config: AutopilotConfig) -> AutopilotConfig:
        """``config`` with its braking plan at its share of the action's limit."""
        car = self.env.loop.world_config.vehicle.max_decel
        profile = config.speed_profile
        a_brake = min(profile.a_brake, BRAKE_SHARE * self.env.brake_limit)
        if self.env.brake_limit >= car or a_brake == profile.a_brake:
            return config
        fitted = dataclasses.replace(profile, a_brake=a_brake)
        return dataclasses.replace(config, speed_profile=fitted)
