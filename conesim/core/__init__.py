"""The shared vocabulary at the bottom of conesim: what every package may import.

- ``messages``: what travels between the car and its software (the ROS pipeline's
  ROS messages, reduced to 2D), and the frame names.
- ``pose``: ``Pose2D`` and ``wrap_angle``.
- ``geodesy``: the reference origin and the ROS pipeline's GPS-to-local projection.
- ``polyline``: ``Polyline``, the one line type (stations, resampling,
  projection, curvature, crossings) of tracks, race control, the planner
  and the lap-time limit; ``projection``: ``Projection``, every projector's answer.
- ``compiled``: numba's ``njit`` with the on-disk cache the kernels share,
  keyed by ``kernel_digest``'s digest of the code they reach (``kernel_cache``),
  and cold compiles shared among helper processes (``kernel_workers``).

These modules import nothing else of conesim, as every ROS node shares
``geometry_msgs`` and ``sensor_msgs`` without depending on other nodes.
"""
