"""Track assets as a survey gives them: each point off by noise, the whole set by a bias.

The global path (``PathSurvey``, ``surveyed``) and the cone map the
``cones`` localization matches detections to (``ConeSurvey``,
``surveyed_cones``) use the same error model, each with its own stream.

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
from numpy.typing import NDArray

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
                    f"{type(self).__name__}.{name} = {value!r} is out of range: "
                    "allowed [0, inf) [m]"
                )
            object.__setattr__(self, name, float(value))
        if isinstance(self.seed, bool) or not (isinstance(self.seed, int) and self.seed >= 0):
            raise ValueError(
                f"{type(self).__name__}.seed = {self.seed!r} is out of range: "
                "allowed >= 0 (an integer)"
            )

    @property
    def exact(self) -> bool:
        """Whether the survey leaves the path as it is."""
        return self.noise == 0.0 and self.bias == 0.0


@dataclass(frozen=True)
class ConeSurvey(PathSurvey):
    """How far the surveyed cone map is off the cones as they stand (a few cm by default).

    Attributes:
        noise: each cone's error, per axis, one standard deviation [m].
        bias: the whole map's offset, in a direction drawn from ``seed`` [m].
        seed: the survey's random stream (a non-negative integer).
    """

    noise: float = 0.03  # [m] assumption: an RTK pole survey, a few cm per cone
    bias: float = 0.02  # [m] assumption: a base station's offset
    seed: int = 0


def _survey_error(xy: NDArray[np.float64], survey: PathSurvey, salt: int) -> NDArray[np.float64]:
    """``xy`` (n, 2) [m] as ``survey`` gives it, from the stream ``(seed, salt)``."""
    rng = np.random.default_rng([survey.seed, salt])
    theta = rng.uniform(0.0, 2.0 * math.pi)
    error = rng.normal(0.0, survey.noise, size=xy.shape) if survey.noise > 0.0 else 0.0
    return xy + survey.bias * np.array([math.cos(theta), math.sin(theta)]) + error


def surveyed_cones(cones: NDArray[np.float64], survey: ConeSurvey) -> NDArray[np.float64]:
    """The cone positions (n, 2) [m] as ``survey`` maps them (module docstring); a new array."""
    xy = np.array(cones, dtype=float)
    return xy if survey.exact else _survey_error(xy, survey, 0xC0E)


def surveyed(path: GlobalPath, survey: PathSurvey) -> GlobalPath:
    """``path`` as ``survey`` gives it (module docstring); the same path when exact."""
    if survey.exact:
        return path
    xy = _survey_error(path.xy, survey, 0x5E7)
    lat, lon = local_cartesian_to_gps(xy[:, 0], xy[:, 1], path.origin)
    return global_path_from_geodetic(lat, lon, path.cov, path.origin, closed=path.closed)
