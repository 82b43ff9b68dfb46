"""The closed loop and its adapters: the gymnasium env, the command line, recording.

``import conesim`` registers ``conesim/ConeTrack-v0``::

    import gymnasium as gym

    env = gym.make("conesim:conesim/ConeTrack-v0", track="autocross", sensors="rtk")
"""

from __future__ import annotations

from conesim import DEFAULT_MAX_EPISODE_STEPS, ENV_ID

__all__ = ["DEFAULT_MAX_EPISODE_STEPS", "ENV_ID"]
