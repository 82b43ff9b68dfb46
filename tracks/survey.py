"""A global path as a survey gives it: each point off by noise, the whole path by a bias.

The global path is the one track asset the planner reads. A team surveys it
(an RTK walk with a pole, or a lap driven with a good receiver), and no
survey is exact: each point has its own error, and the whole path may sit
off by a base station's or a datum's offset. ``PathSurvey`` says how much;
``surveyed`` applies it to the exact path, deterministically per seed:

    xy_i' = xy_i + bias * (cos theta, sin theta) + n_i,  n_i ~ N(0, noise^2 I)

with theta drawn once per path. The covariance the path states stays as it
was: the team does not know its survey's error.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from conesim.core.geodesy import local_cartesian_to_gps
from conesim.tracks.global_path import GlobalPath, global_path_from_geodetic


@dataclass(frozen=True)
class PathSurvey:
    """How far a surveyed global path is off the exact one.

    Attributes:
        noise: each point's error, per axis, one standard deviation [m].
        bias: the whole path's offset, in a direction drawn from ``seed`` [m].
        seed: the survey's random stream (a non-negative integer).
    """

    noise: float = 0.0  # [m]
    bias: float = 0.0  # [m]
    seed: int = 0

    def __post_init__(self) -> None:
        for name in ("noise", "bias"):
            value = getattr(self, name)
            if isinstance(value, bool) or not (
                isinstance(value, int | float) and 0.0 <= value < math.inf
            ):
                raise ValueError(
                    f"PathSurvey.{name} = {value!r} is out of range: allowed [0, inf) [m]"
                )
            object.__setattr__(self, name, float(value))
        if isinstance(self.seed, bool) or not (isinstance(self.seed, int) and self.seed >= 0):
            raise ValueError(
                f"PathSurvey.seed = {self.seed!r} is out of range: allowed >= 0 (an integer)"
            )

    @property
    def exact(self) -> bool:
        """Whether the survey leaves the path as it is."""
        return self.noise == 0.0 and self.bias == 0.0


def surveyed(path: GlobalPath, survey: PathSurvey) -> GlobalPath:
    """``path`` as ``survey`` gives it (module docstring); the same path when exact."""
    if survey.exact:
        return path
    rng = np.random.default_rng([survey.seed, 0x5E7])
    theta = rng.uniform(0.0, 2.0 * math.pi)
    error = rng.normal(0.0, survey.noise, size=path.xy.shape) if survey.noise > 0.0 else 0.0
    xy = path.xy + survey.bias * np.array([math.cos(theta), math.sin(theta)]) + error
    lat, lon = local_cartesian_to_gps(xy[:, 0], xy[:, 1], path.origin)
    return global_path_from_geodetic(lat, lon, path.cov, path.origin, closed=path.closed)
