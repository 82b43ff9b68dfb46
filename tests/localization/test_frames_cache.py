"""Tests for localization.frames.cache, modelled on tf2's cache_unittest.cpp (ros2/geometry2)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose
from scipy.spatial.transform import Rotation, Slerp

from conesim.localization.frames import ExtrapolationError, StaticCache, TimeCache, rigid
from conesim.localization.frames.rigid import Rigid


def item(x: float, yaw: float = 0.0) -> Rigid:
    """A transform at (x, 0, 0) with the given yaw [rad]."""
    return (x, 0.0, 0.0, *rigid.quat_from_yaw(yaw))


def test_repeatability() -> None:
    """Each of 99 in-order samples is returned exactly at its own stamp."""
    cache = TimeCache("child", "parent")
    for i in range(1, 100):
        assert cache.insert(i * 0.01, item(float(i)))
    assert len(cache) == 99
    for i in range(1, 100):
        assert cache.sample(i * 0.01) == item(float(i))


def test_repeatability_reverse_insert_order() -> None:
    """Samples inserted newest first are sorted and returned exactly at their stamps."""
    cache = TimeCache("child", "parent")
    for i in reversed(range(100)):
        assert cache.insert(i * 0.01, item(float(i)))
    assert cache.stamps == tuple(i * 0.01 for i in range(100))
    for i in range(100):
        assert cache.sample(i * 0.01) == item(float(i))


def test_cartesian_interpolation() -> None:
    """Translation is linear in time between two samples, e.g. exact at the midpoint."""
    rng = np.random.default_rng(0)
    for _ in range(20):
        cache = TimeCache("child", "parent")
        a, b = rng.uniform(-10.0, 10.0, (2, 3))
        cache.insert(2.0, (*a, 0.0, 0.0, 0.0, 1.0))
        cache.insert(3.0, (*b, 0.0, 0.0, 0.0, 1.0))
        for pos in range(100):
            out = cache.sample(2.0 + pos / 100.0)
            assert_allclose(out[:3], a + (b - a) * pos / 100.0, atol=1e-12)
        assert_allclose(cache.sample(2.5)[:3], (a + b) / 2.0, atol=1e-12)


def test_angular_interpolation_matches_slerp() -> None:
    """Rotation between two samples is scipy's Slerp, e.g. half the yaw at the midpoint."""
    rng = np.random.default_rng(0)
    for _ in range(20):
        cache = TimeCache("child", "parent")
        rotations = Rotation.random(2, random_state=rng)
        q0, q1 = rotations.as_quat()
        cache.insert(2.0, (0.0, 0.0, 0.0, *q0))
        cache.insert(3.0, (0.0, 0.0, 0.0, *q1))
        slerp = Slerp([2.0, 3.0], rotations)
        for pos in range(100):
            time = 2.0 + pos / 100.0
            expected = slerp([time])[0]
            got = Rotation.from_quat(cache.sample(time)[3:])
            assert (got * expected.inv()).magnitude() < 1e-9
    cache = TimeCache("child", "parent")
    cache.insert(0.0, item(0.0, yaw=0.2))
    cache.insert(1.0, item(0.0, yaw=1.2))
    assert_allclose(rigid.yaw_of(cache.sample(0.5)), 0.7, atol=1e-12)


@pytest.mark.parametrize(
    ("time", "direction", "shown"),
    [
        (0.5, "past", "earliest data is at time 1.0 s"),
        (2.5, "future", "latest data is at time 2.0"),
    ],
)
def test_extrapolation_both_ways(time: float, direction: str, shown: str) -> None:
    """Before the oldest or after the newest stamp raises, saying past or future and the range."""
    cache = TimeCache("child", "parent")
    cache.insert(1.0, item(0.0))
    cache.insert(2.0, item(1.0))
    with pytest.raises(ExtrapolationError) as info:
        cache.sample(time)
    err = info.value
    assert (err.direction, err.time, err.earliest, err.latest) == (direction, time, 1.0, 2.0)
    assert f"extrapolation into the {direction}" in str(err)
    assert f"requested time {time!r} s" in str(err)
    assert shown in str(err)
    assert "[1.0, 2.0] s" in str(err)
    assert "'parent' -> 'child'" in str(err)


def test_single_sample_at_another_time_is_extrapolation() -> None:
    """One sample answers only at its own stamp, as in tf2."""
    cache = TimeCache("child", "parent")
    cache.insert(1.0, item(3.0))
    assert cache.sample(1.0) == item(3.0)
    with pytest.raises(ExtrapolationError, match=r"into the past.*only time 1\.0 s"):
        cache.sample(0.9)
    with pytest.raises(ExtrapolationError, match=r"into the future.*only time 1\.0 s"):
        cache.sample(1.1)


def test_pruning_relative_to_newest_stamp() -> None:
    """As tf2's GetAllItems test: keep stamps >= newest - cache_time, drop data older than that."""
    cache = TimeCache("child", "parent", cache_time=10.0)
    for stamp in (0.0, 10.0, 5.0, 3.0, 8.0):
        assert cache.insert(stamp, item(stamp))
    # The oldest is exactly cache_time behind the newest: kept.
    assert cache.stamps == (0.0, 3.0, 5.0, 8.0, 10.0)
    assert cache.insert(15.0, item(15.0))
    assert cache.stamps == (5.0, 8.0, 10.0, 15.0)
    # Data older than the newest minus cache_time is dropped on arrival.
    assert not cache.insert(0.0, item(0.0))
    assert cache.stamps == (5.0, 8.0, 10.0, 15.0)
    with pytest.raises(ExtrapolationError, match="into the past"):
        cache.sample(4.0)


def test_memory_stays_flat_over_a_long_run() -> None:
    """Ten minutes at 20 Hz with a 10 s cache holds 201 samples and still interpolates."""
    cache = TimeCache("child", "parent", cache_time=10.0)
    for k in range(12_000):
        cache.insert(k * 0.05, item(k * 0.05, yaw=0.01 * k))
    assert len(cache) == 201
    assert (cache.oldest, cache.latest) == (pytest.approx(589.95), pytest.approx(599.95))
    assert_allclose(cache.sample(595.0 + 0.025)[0], 595.025, atol=1e-9)


def test_same_stamp_replaces_sample() -> None:
    """A second sample at a stamp already held replaces the first; the length stays."""
    cache = TimeCache("child", "parent")
    cache.insert(1.0, item(0.0))
    cache.insert(2.0, item(2.0))
    cache.insert(2.0, item(4.0, yaw=1.0))
    assert len(cache) == 2
    assert cache.sample(2.0) == item(4.0, yaw=1.0)
    assert_allclose(cache.sample(1.5)[0], 2.0, atol=1e-12)
    assert_allclose(rigid.yaw_of(cache.sample(1.5)), 0.5, atol=1e-12)


def test_out_of_order_insert_refreshes_interpolation() -> None:
    """A sample inserted between two others splits their interval for translation and slerp."""
    cache = TimeCache("child", "parent")
    cache.insert(0.0, item(0.0, yaw=0.0))
    cache.insert(2.0, item(2.0, yaw=0.4))
    cache.insert(1.0, item(5.0, yaw=-1.0))
    assert_allclose(cache.sample(0.5)[0], 2.5, atol=1e-12)
    assert_allclose(rigid.yaw_of(cache.sample(0.5)), -0.5, atol=1e-12)
    assert_allclose(cache.sample(1.5)[0], 3.5, atol=1e-12)
    assert_allclose(rigid.yaw_of(cache.sample(1.5)), -0.3, atol=1e-12)


def test_static_cache_holds_at_any_time() -> None:
    """A static link answers at every time, and a new transform replaces the old."""
    cache = StaticCache("os_sensor", "gps_antenna")
    cache.insert(0.0, (0.0, 0.0, -0.1, 0.0, 0.0, 0.0, 1.0))
    for time in (-5.0, 0.0, 1e-9, 3.0, 1e6):
        assert cache.sample(time) == (0.0, 0.0, -0.1, 0.0, 0.0, 0.0, 1.0)
    cache.insert(4.0, item(1.0, yaw=math.pi))
    assert cache.sample(0.0) == item(1.0, yaw=math.pi)
    assert len(cache) == 1
