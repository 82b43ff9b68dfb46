"""Tests for frame-tree errors: each raised where it should be; bad input changes nothing."""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
import pytest
from numpy.testing import assert_allclose

from conesim.core.pose import Pose2D
from conesim.localization import frames as tf2

YAW_30 = (0.0, 0.0, math.sin(math.pi / 12), math.cos(math.pi / 12))


def seed_tree() -> tf2.Buffer:
    """Spec 000's tree with dynamic data at 1.0 s and 2.0 s."""
    buffer = tf2.Buffer()
    for stamp, x in [(1.0, 100.0), (2.0, 102.0)]:
        buffer.set_transform(
            tf2.TransformStamped.from_pose2d(
                "reference", "gps_antenna", stamp, Pose2D(x, 50.0, math.pi / 2)
            )
        )
    buffer.set_transform_static(
        tf2.TransformStamped("gps_antenna", "os_sensor", 0.0, translation=(0.0, 0.0, -0.1))
    )
    return buffer


def snapshot(buffer: tf2.Buffer) -> tuple[object, ...]:
    """Everything observable about a buffer built by seed_tree."""
    lookups = [
        buffer.lookup_transform("reference", "os_sensor", time).as_matrix()
        for time in (tf2.LATEST, 1.0, 1.5, 2.0)
    ]
    return (buffer.all_frame_names(), buffer.frames(), np.array(lookups))


def test_hierarchy() -> None:
    """Every error is a TransformError; the natural builtin bases are there too."""
    for error in (
        tf2.FrameNotFoundError,
        tf2.ConnectivityError,
        tf2.ExtrapolationError,
        tf2.InvalidArgumentError,
        tf2.InvalidTransformError,
        tf2.FrameTreeError,
    ):
        assert issubclass(error, tf2.TransformError)
    assert issubclass(tf2.TransformError, Exception)
    assert issubclass(tf2.FrameNotFoundError, LookupError)
    assert issubclass(tf2.InvalidTransformError, ValueError)
    assert issubclass(tf2.InvalidArgumentError, ValueError)
    assert issubclass(tf2.FrameTreeError, tf2.InvalidTransformError)


@pytest.mark.parametrize(
    ("target", "source", "missing", "argument"),
    [("reference", "os_senor", "os_senor", "source_frame"), ("map", "os_sensor", "map", "target")],
)
def test_unknown_frame(target: str, source: str, missing: str, argument: str) -> None:
    """An unknown frame raises FrameNotFoundError naming it and listing the known frames."""
    buffer = seed_tree()
    with pytest.raises(tf2.FrameNotFoundError, match=f"'{missing}' passed to .*{argument}") as info:
        buffer.lookup_transform(target, source, tf2.LATEST)
    assert "['gps_antenna', 'os_sensor', 'reference']" in str(info.value)
    with pytest.raises(tf2.FrameNotFoundError):
        buffer.lookup_transform(missing, missing, tf2.LATEST)


def test_unconnected_trees() -> None:
    """Frames in two separate trees raise ConnectivityError naming both and their roots."""
    buffer = seed_tree()
    buffer.set_transform_static(tf2.TransformStamped("map", "odom", 0.0))
    with pytest.raises(tf2.ConnectivityError) as info:
        buffer.lookup_transform("odom", "os_sensor", tf2.LATEST)
    message = str(info.value)
    assert "'odom' and 'os_sensor'" in message
    assert "root 'map'" in message
    assert "root 'reference'" in message


@pytest.mark.parametrize(("time", "direction"), [(0.5, "past"), (2.5, "future")])
def test_extrapolation_in_lookup(time: float, direction: str) -> None:
    """A lookup outside the data raises ExtrapolationError with direction, time, range, frames."""
    buffer = seed_tree()
    with pytest.raises(tf2.ExtrapolationError) as info:
        buffer.lookup_transform("os_sensor", "reference", time)
    err = info.value
    assert (err.direction, err.time, err.earliest, err.latest) == (direction, time, 1.0, 2.0)
    assert (err.frame, err.parent) == ("gps_antenna", "reference")
    message = str(err)
    assert f"into the {direction}" in message
    assert f"requested time {time!r} s" in message
    assert "available [1.0, 2.0] s" in message
    assert "from frame 'reference' to frame 'os_sensor'" in message


def test_latest_common_time_before_a_links_data_is_extrapolation() -> None:
    """LATEST can still fail if one link's newest stamp predates another's oldest, as in"""
    buffer = tf2.Buffer()
    buffer.set_transform(tf2.TransformStamped("a", "b", 1.0))
    buffer.set_transform(tf2.TransformStamped("b", "c", 5.0))
    buffer.set_transform(tf2.TransformStamped("b", "c", 6.0))
    with pytest.raises(tf2.ExtrapolationError, match=r"past.*requested time 1\.0 s.*'b' -> 'c'"):
        buffer.lookup_transform("a", "c", tf2.LATEST)


def make_transform(**changes: object) -> Callable[[], tf2.TransformStamped]:
    """A constructor call for gps_antenna -> os_sensor with some arguments changed."""
    arguments: dict[str, object] = {
        "frame_id": "gps_antenna",
        "child_frame_id": "os_sensor",
        "stamp": 3.0,
        "translation": (0.0, 0.0, -0.2),
        "rotation": YAW_30,
    }
    arguments.update(changes)
    return lambda: tf2.TransformStamped(**arguments)


@pytest.mark.parametrize(
    ("build", "match"),
    [
        (make_transform(translation=(0.0, math.nan, 0.0)), "y must be finite"),
        (make_transform(translation=(math.inf, 0.0, 0.0)), "x must be finite"),
        (make_transform(rotation=(0.0, 0.0, math.nan, 1.0)), "qz must be finite"),
        (make_transform(stamp=math.nan), "stamp must be finite"),
        (make_transform(stamp=math.inf), "stamp must be finite"),
        (make_transform(rotation=(0.0, 0.0, 0.0, 1.0 + 1e-5)), "norm 1.00001"),
        (make_transform(rotation=(0.0, 0.0, 0.0, 0.0)), "norm 0.0"),
        (make_transform(rotation=(0.0, 0.0, 1.0)), r"rotation \(4,\)"),
        (make_transform(translation=[[0.0, 0.0, 0.0]]), r"translation must be \(3,\)"),
        (
            lambda: tf2.TransformStamped.from_pose2d("a", "b", 0.0, Pose2D(0, 0, 0), z=math.nan),
            "z must be finite",
        ),
    ],
)
def test_invalid_values_rejected(build: Callable[[], tf2.TransformStamped], match: str) -> None:
    """NaN, inf, a quaternion off unit norm or a wrong shape raise InvalidTransformError."""
    with pytest.raises(tf2.InvalidTransformError, match=match) as info:
        build()
    assert "'gps_antenna' -> 'os_sensor'" in str(info.value) or "'a' -> 'b'" in str(info.value)


STAMPED = tf2.TransformStamped
REJECTED = [
    (STAMPED("os_sensor", "os_sensor", 3.0), tf2.InvalidTransformError, "self-transform"),
    (STAMPED("/os_sensor", "os_sensor", 3.0), tf2.InvalidTransformError, "self-transform"),
    (STAMPED("", "os_sensor", 3.0), tf2.InvalidTransformError, "non-empty"),
    (STAMPED("reference", "/", 3.0), tf2.InvalidTransformError, "non-empty"),
    (STAMPED("reference", "os_sensor", 3.0), tf2.FrameTreeError, "second parent"),
    (STAMPED("map", "gps_antenna", 3.0), tf2.FrameTreeError, "second parent"),
    (STAMPED("os_sensor", "reference", 3.0), tf2.FrameTreeError, "cycle"),
    (STAMPED("gps_antenna", "reference", 3.0), tf2.FrameTreeError, "cycle"),
]


@pytest.mark.parametrize(("transform", "error", "match"), REJECTED)
@pytest.mark.parametrize("static", [False, True])
def test_rejected_transform_leaves_buffer_unchanged(
    transform: tf2.TransformStamped, error: type[Exception], match: str, static: bool
) -> None:
    """Self-transforms, empty names, second parents and cycles raise and change nothing."""
    buffer = seed_tree()
    before = snapshot(buffer)
    with pytest.raises(error, match=match):
        buffer.set_transform(transform, authority="test", static=static)
    after = snapshot(buffer)
    assert after[:2] == before[:2]
    assert_allclose(after[2], before[2], atol=0)


def test_messages_name_the_frames() -> None:
    """Tree errors name the child, its existing parent and the authority."""
    buffer = seed_tree()
    with pytest.raises(tf2.FrameTreeError) as info:
        buffer.set_transform(tf2.TransformStamped("map", "gps_antenna", 3.0), authority="ekf")
    message = str(info.value)
    assert "'gps_antenna' already has parent 'reference'" in message
    assert "'map' -> 'gps_antenna'" in message
    assert "authority 'ekf'" in message


@pytest.mark.parametrize("time", [math.nan, math.inf, -math.inf])
def test_non_finite_lookup_time(time: float) -> None:
    """A non-finite lookup time raises InvalidArgumentError."""
    with pytest.raises(tf2.InvalidArgumentError, match="finite"):
        seed_tree().lookup_transform("reference", "os_sensor", time)


@pytest.mark.parametrize("points", [np.zeros(3), np.zeros((4, 4)), np.zeros((2, 3, 1))])
def test_bad_points_shape(points: np.ndarray) -> None:
    """Points that are not (n, 2) or (n, 3) raise InvalidArgumentError."""
    with pytest.raises(tf2.InvalidArgumentError, match=r"\(n, 2\) or \(n, 3\)"):
        seed_tree().transform_points("reference", "os_sensor", points, tf2.LATEST)


def test_other_invalid_arguments() -> None:
    """A bad cache time, an empty lookup name or mismatched compose frames are rejected."""
    for cache_time in (0.0, -1.0, math.nan):
        with pytest.raises(tf2.InvalidArgumentError, match="cache_time"):
            tf2.Buffer(cache_time=cache_time)
    with pytest.raises(tf2.InvalidArgumentError, match="target_frame"):
        seed_tree().lookup_transform("", "os_sensor", tf2.LATEST)
    a = tf2.TransformStamped("A", "B", 0.0)
    with pytest.raises(tf2.InvalidArgumentError, match="'C' is not 'B'"):
        a.compose(tf2.TransformStamped("C", "D", 0.0))
