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
# ``info["end_reason"] == "time_limit"``). 10 million steps is 2.3 simulated
# days at 50 Hz: far behind the time limit of any lap count a user would set
# (60 s per lap + 30 s), so the env's own end, with its reason, comes first.
DEFAULT_MAX_EPISODE_STEPS = 10_000_000

if ENV_ID not in gym.registry:
    gym.register(
        id=ENV_ID,
        entry_point="envs.cone_track_env:ConeTrackEnv",
        max_episode_steps=DEFAULT_MAX_EPISODE_STEPS,
    )

__all__ = ["DEFAULT_MAX_EPISODE_STEPS", "ENV_ID"]
