"""Tests for sim.sensors.noise and sim.sensors.streams: the noise recursions and streams."""

from __future__ import annotations

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose

from conesim.sim.sensors.noise import BiasRandomWalk, GaussMarkov, white_sigma
from conesim.sim.sensors.streams import stable_key, stream


def test_white_sigma_is_density_over_sqrt_dt() -> None:
    """0.0135 deg/s/sqrt(Hz) sampled at 100 Hz is 0.135 deg/s."""
    assert_allclose(white_sigma(0.0135, 0.01), 0.135, rtol=1e-12)
    assert_allclose(white_sigma(math.radians(0.30 / 60.0), 0.01), math.radians(0.05), rtol=1e-12)


def test_gauss_markov_is_stationary_with_lag_one_correlation() -> None:
    """20,000 chains, sigma 0.7, tau 1 s, dt 0.1 s: std 0.7 and Corr(b_k, b_k+1) = e^-0.1."""
    gm = GaussMarkov(0.7, 1.0, np.random.default_rng(0), dim=20_000)
    start = gm.value.copy()
    for _ in range(30):
        previous = gm.value.copy()
        gm.step(0.1)
    assert_allclose(np.std(start), 0.7, rtol=0.05)  # SE 0.5 %
    assert_allclose(np.std(gm.value), 0.7, rtol=0.05)
    corr = np.corrcoef(previous, gm.value)[0, 1]
    assert abs(corr - math.exp(-0.1)) < 0.01  # SE (1 - 0.819) / sqrt(N) = 0.0013


def test_gauss_markov_exact_for_any_step() -> None:
    """A 2.5 s step with tau 5 s correlates by e^-0.5 = 0.6065 and keeps the std."""
    gm = GaussMarkov(2.0, 5.0, np.random.default_rng(1), dim=20_000)
    before = gm.value.copy()
    after = gm.step(2.5)
    assert abs(np.corrcoef(before, after)[0, 1] - math.exp(-0.5)) < 0.02
    assert_allclose(np.std(after), 2.0, rtol=0.05)


def test_bias_random_walk_variance_grows_linearly() -> None:
    """K = 0.02 /sqrt(s): after 100 steps of 0.01 s, std = K sqrt(1 s) = 0.02."""
    walk = BiasRandomWalk(0.02, np.random.default_rng(2), dim=20_000)
    assert np.all(walk.value == 0.0)
    for _ in range(100):
        walk.step(0.01)
    assert_allclose(np.std(walk.value), 0.02, rtol=0.05)


def test_zero_sigma_processes_stay_exactly_zero() -> None:
    """sigma = 0 and K = 0 give exact zeros (the ideal profile)."""
    gm = GaussMarkov(0.0, 1.0, np.random.default_rng(3), dim=2)
    walk = BiasRandomWalk(0.0, np.random.default_rng(3), dim=2)
    for _ in range(5):
        assert gm.step(0.1) == (0.0, 0.0)
        assert walk.step(0.1) == (0.0, 0.0)


def test_stream_keys_are_stable_and_streams_differ() -> None:
    """CRC-32 keys are fixed numbers; (seed, names) picks a reproducible, distinct stream."""
    assert stable_key("gps") == 1424645575
    a = stream(7, "gps", "white").standard_normal(4)
    assert np.array_equal(a, stream(7, "gps", "white").standard_normal(4))
    assert not np.array_equal(a, stream(7, "gps", "bias").standard_normal(4))
    assert not np.array_equal(a, stream(8, "gps", "white").standard_normal(4))


@pytest.mark.parametrize("seed", [-1, 1.5, True])
def test_stream_rejects_bad_seed(seed: object) -> None:
    """A seed must be a non-negative integer."""
    with pytest.raises(ValueError, match="seed"):
        stream(seed, "gps")  # type: ignore[arg-type]
