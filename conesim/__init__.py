"""conesim: a closed-loop 2D vehicle simulator for Formula Student cone tracks.

The packages, one namespace however they are installed:

- ``conesim.core``: the shared vocabulary every package imports (messages,
  ``Pose2D``, frame names, the reference origin and geodesy, the polyline).
- ``conesim.tracks``: track data, formats, validation, the global path.
- ``conesim.sim``: the world: pymunk car and cones, race control, sensors.
- ``conesim.localization``: the frame tree, the EKF, the TF broadcaster.
- ``conesim.planner``: cone side classification, Delaunay midline, speed
  profile, pure pursuit, and the autopilot that wires them.
- ``conesim.envs``: the closed loop, the gymnasium env, the command line.

``import conesim`` registers the env (``gymnasium.make("conesim/ConeTrack-v0")``);
``gymnasium.make("conesim:conesim/ConeTrack-v0")`` imports it by itself.
"""

from __future__ import annotations

import logging

import gymnasium as gym

__version__ = "0.1.0"

ENV_ID = "conesim/ConeTrack-v0"
# A backstop only: the env ends its episodes itself at its ``time_limit`` (with
# ``info["end_reason"]`` naming ``time_limit``). 10 million steps is 2.3 simulated
# days at 50 Hz: far behind the time limit of any lap count a user would set.
DEFAULT_MAX_EPISODE_STEPS = 10_000_000

if ENV_ID not in gym.registry:
    gym.register(
        id=ENV_ID,
        entry_point="conesim.envs.cone_track_env:ConeTrackEnv",
        max_episode_steps=DEFAULT_MAX_EPISODE_STEPS,
    )

# A library logs, the application decides what is shown (the logging HOWTO's
# advice for libraries); the ``conesim`` command configures logging (``-v``).
logging.getLogger(__name__).addHandler(logging.NullHandler())

__all__ = ["DEFAULT_MAX_EPISODE_STEPS", "ENV_ID", "__version__"]
