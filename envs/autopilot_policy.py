"""The planner's autopilot as a policy for ``ConeTrackEnv``.

It sees only what the env gives a policy plus localization's frame tree: the
messages delivered in the last control period (``info["messages"]``), the
frame tree (``env.stack.buffer``, fed by the TF broadcaster) and the global
path the car carries. No ground truth. The autopilot's command (steering
[rad], acceleration [m/s^2]) is mapped back into the env's action space.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from conesim.envs.cone_track_env import ConeTrackEnv
from conesim.planner import Autopilot, AutopilotConfig


class AutopilotPolicy:
    """Drive a ``ConeTrackEnv`` with the seed's pipeline and pure pursuit.

    Call :meth:`reset` after every ``env.reset`` (the frame tree is new), then
    ``action = policy(info)`` after each step.

    Args:
        env: the env (a wrapped env is unwrapped).
        config: the autopilot's settings; by default ``AutopilotConfig()``,
            or ``AutopilotConfig.cautious()`` in an episode whose localization
            is ``raw`` (the seed's broadcaster: a pose up to 150 ms old).
    """

    def __init__(self, env: Any, config: AutopilotConfig | None = None) -> None:
        base = env.unwrapped
        if not isinstance(base, ConeTrackEnv):
            raise TypeError(f"AutopilotPolicy drives a ConeTrackEnv, got {type(base).__name__}")
        self.env = base
        self.config = config
        self.autopilot = Autopilot(base.stack.buffer, base.stack.global_path, self._settings())
        self._action = np.zeros(2, dtype=np.float32)

    def reset(self, info: dict[str, Any] | None = None) -> NDArray[np.float32]:
        """A fresh autopilot on the env's new frame tree; the first action."""
        stack = self.env.stack
        self.autopilot = Autopilot(stack.buffer, stack.global_path, self._settings())
        self.env.overlay = self.autopilot
        self._action = np.zeros(2, dtype=np.float32)
        return self(info or {"messages": stack.initial_messages})

    def _settings(self) -> AutopilotConfig | None:
        """The given settings, or the defaults for this episode's localization."""
        if self.config is None and self.env.stack.localization == "raw":
            return AutopilotConfig.cautious()
        return self.config

    def __call__(self, info: dict[str, Any]) -> NDArray[np.float32]:
        """The action for the next control period."""
        command = self.autopilot.step(self.env.stack.time, info.get("messages", ()))
        if command is not None:
            self._action = self.env.command_to_action(command.steering, command.acceleration)
        return self._action
