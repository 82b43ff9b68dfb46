"""The gymnasium env, the closed loop and the command line.

``import envs`` registers ``conesim/ConeTrack-v0``::

    import gymnasium as gym
    import envs  # noqa: F401  (registers the env)

    env = gym.make("conesim/ConeTrack-v0", track="autocross", sensors="rtk")
"""

from __future__ import annotations

import gymnasium as gym

ENV_ID = "conesim/ConeTrack-v0"
# A backstop only: the env ends its episodes itself at its ``time_limit`` (with
# ``info["end_reason"] == "time_limit"``); 100,000 steps is 2,000 s at 50 Hz.
DEFAULT_MAX_EPISODE_STEPS = 100_000

if ENV_ID not in gym.registry:
    gym.register(
        id=ENV_ID,
        entry_point="envs.cone_track_env:ConeTrackEnv",
        max_episode_steps=DEFAULT_MAX_EPISODE_STEPS,
    )

__all__ = ["DEFAULT_MAX_EPISODE_STEPS", "ENV_ID"]
