"""A surveyed global path (tracks.survey): per-point noise and a whole-path bias."""

from __future__ import annotations

import numpy as np
import pytest
from numpy.testing import assert_allclose

from conesim.tracks.global_path import global_path_from_centreline
from conesim.tracks.survey import ConeSurvey, PathSurvey, surveyed, surveyed_cones


def test_noise_and_bias_have_the_stated_sizes() -> None:
    """4000 points: their errors' mean is the 0.3 m bias, their spread 0.2 m per axis."""
    x = np.linspace(0.0, 2000.0, 4000)
    exact = global_path_from_centreline(np.column_stack([x, np.zeros_like(x)]), closed=False)
    path = surveyed(exact, PathSurvey(noise=0.2, bias=0.3, seed=7))
    error = path.xy - exact.xy
    assert np.hypot(*error.mean(axis=0)) == pytest.approx(0.3, abs=0.01)
    assert_allclose(error.std(axis=0), 0.2, rtol=0.05)
    assert_allclose(surveyed(exact, PathSurvey(0.2, 0.3, 7)).xy, path.xy)  # per seed
    assert surveyed(exact, PathSurvey()) is exact
    with pytest.raises(ValueError, match=r"PathSurvey\.bias = -0\.1 is out of range"):
        PathSurvey(bias=-0.1)


def test_cone_map_survey_sizes_and_stream() -> None:
    """4000 cones at 5 cm noise and 10 cm bias: mean error 0.1 m, spread 0.05 m per axis;
    the same per seed, another stream than the path's; the default is 3 cm and 2 cm."""
    cones = np.column_stack([np.linspace(0.0, 2000.0, 4000), np.zeros(4000)])
    mapped = surveyed_cones(cones, ConeSurvey(noise=0.05, bias=0.1, seed=3))
    error = mapped - cones
    assert np.hypot(*error.mean(axis=0)) == pytest.approx(0.1, abs=0.005)
    assert_allclose(error.std(axis=0), 0.05, rtol=0.05)
    assert_allclose(surveyed_cones(cones, ConeSurvey(0.05, 0.1, 3)), mapped)
    assert (ConeSurvey().noise, ConeSurvey().bias) == (0.03, 0.02)
    assert_allclose(surveyed_cones(cones, ConeSurvey(0.0, 0.0)), cones)
    with pytest.raises(ValueError, match=r"ConeSurvey\.noise = -0\.1 is out of range"):
        ConeSurvey(noise=-0.1)
