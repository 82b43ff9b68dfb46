"""Settings of the cone map built while driving (``localization.slam``)."""

from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass(frozen=True, slots=True)
class SlamConfig:
    """How landmarks enter, leave and stop entering the map.

    Attributes:
        confirm_scans: scans a candidate must be seen in before it becomes a
            landmark (false positives, drawn anew each scan, never are) [-].
        candidate_radius: a detection this close to a candidate is that candidate [m].
        candidate_timeout: a candidate not seen again for this long is dropped [s].
        prune_misses: a landmark in view but not matched this many scans more
            than it was matched is removed from the map (marginalised) [-].
        max_landmarks: the map's size limit; candidates wait beyond it [-].
        start_sigma: how well the car stands on the track's start pose, per axis [m].
        start_yaw_sigma: and its heading there [rad].
        loop_radius: the pose this close to the start, after ``min_loop_distance``
            of driving, closes the loop: no landmark enters or leaves after it [m].
        min_loop_distance: driving before the loop may close [m].
    """

    confirm_scans: int = 3  # [-]
    candidate_radius: float = 0.5  # [m]
    candidate_timeout: float = 0.5  # [s]
    prune_misses: int = 5  # [-]
    max_landmarks: int = 600  # [-]
    start_sigma: float = 0.05  # [m] assumption: the car placed on its marks
    start_yaw_sigma: float = math.radians(0.5)  # [rad]
    loop_radius: float = 3.0  # [m]
    min_loop_distance: float = 50.0  # [m]

    def __post_init__(self) -> None:
        for name in ("confirm_scans", "prune_misses", "max_landmarks"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or value < 1:
                raise ValueError(f"SlamConfig.{name} = {value!r} is out of range: allowed >= 1")
        for name in (
            "candidate_radius",
            "candidate_timeout",
            "start_sigma",
            "start_yaw_sigma",
            "loop_radius",
            "min_loop_distance",
        ):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0.0):
                raise ValueError(f"SlamConfig.{name} = {value!r} is out of range: allowed > 0")
