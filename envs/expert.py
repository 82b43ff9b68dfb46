"""The autopilot as an expert for ``ConeTrackEnv``: a baseline, or demonstrations to imitate.

The env wraps the closed loop without a driver; this drives it from the
outside, through the env's public interface only: the episode's frame tree
and global path (``env.unwrapped.loop``: ``localizer.frames``,
``global_path``, ``control_rate``) and the messages of each step
(``info["messages"]``). It sees what a real car's software sees, never the
truth. Its command (steering [rad], acceleration [m/s^2]) becomes an action
through ``env.command_to_action``::

    env = gym.make("conesim:conesim/ConeTrack-v0", track="autocross")
    expert = AutopilotExpert(env)
    obs, info = env.reset(seed=0)
    action = expert.reset(info)
    while True:
        obs, reward, terminated, truncated, info = env.step(action)
        if terminated or truncated:
            break
        action = expert(info)     # the expert's action for the next step

The actions are the env's float32 actions, so an episode driven this way is
the autopilot's ``conesim run`` episode of the same seed up to the action
space's float32 rounding of the commands.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from conesim.envs.cone_track_env import ConeTrackEnv
from conesim.planner import Autopilot, AutopilotConfig
from conesim.planner.autopilot import AutopilotStep, default_config


class AutopilotExpert:
    """Drive a ``ConeTrackEnv`` with the ROS pipeline and pure pursuit.

    Call :meth:`reset` after every ``env.reset`` (the frame tree is new), then
    ``action = expert(info)`` after each step.

    Args:
        env: the env (a wrapped env is unwrapped).
        config: the autopilot's settings; by default the env's (its
            scenario's ``autopilot``), else the runner's for the episode's
            localization (``AutopilotConfig.cautious()`` with ``raw``).

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

    def reset(self, info: dict[str, Any]) -> NDArray[np.float32]:
        """A fresh autopilot on the env's new episode; the first action."""
        loop = self.env.loop
        self.autopilot = Autopilot(
            loop.localizer.frames,
            loop.global_path,
            self.config or self.env.config.autopilot or default_config(loop.localization),
            control_rate=loop.control_rate,
        )
        return self(info)

    def __call__(self, info: dict[str, Any]) -> NDArray[np.float32]:
        """The action for the next control period, from the step's ``info``."""
        if self.autopilot is None:
            raise RuntimeError("AutopilotExpert: call reset(info) after env.reset()")
        self.output = self.autopilot.step(info["t"], info["messages"])
        command = self.output.command
        return self.env.command_to_action(command.steering, command.acceleration)
