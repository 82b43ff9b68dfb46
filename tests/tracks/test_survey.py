"""A surveyed global path (tracks.survey): per-point noise and a whole-path bias."""

from __future__ import annotations

import numpy as np
import pytest
from numpy.testing import assert_allclose

from conesim.tracks.global_path import global_path_from_centreline
from conesim.tracks.survey import PathSurvey, surveyed


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
