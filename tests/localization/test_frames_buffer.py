"""Tests for localization.frames.buffer: lookups through the tree, tf2 semantics."""

from __future__ import annotations

import logging
import math

import numpy as np
import pytest
from numpy.testing import assert_allclose
from scipy.spatial.transform import Rotation

from conesim.core.pose import Pose2D
from conesim.localization.frames import LATEST, Buffer, ExtrapolationError, TransformStamped

IDENTITY_MATRIX = np.eye(4)


def seed_tree(stamp: float = 1.0) -> Buffer:
    """Spec 000's tree: vehicle at (100, 50) with yaw 90 deg, os_sensor 0.1 m below."""
    buffer = Buffer()
    buffer.set_transform(
        TransformStamped.from_pose2d(
            "reference", "gps_antenna", stamp, Pose2D(100.0, 50.0, math.pi / 2)
        ),
        authority="vehicle_tf_broadcaster",
    )
    buffer.set_transform_static(
        TransformStamped("gps_antenna", "os_sensor", 0.0, translation=(0.0, 0.0, -0.1))
    )
    return buffer


def random_transform(
    rng: np.random.Generator, parent: str, child: str, stamp: float
) -> TransformStamped:
    """A transform with a uniformly random rotation and a translation within 10 m."""
    q = Rotation.random(random_state=rng).as_quat()
    return TransformStamped(parent, child, stamp, rng.uniform(-10.0, 10.0, 3), q)


def random_tree(rng: np.random.Generator) -> tuple[Buffer, dict[str, np.ndarray]]:
    """Two branches under "root" (a1 <- a2, b1 <- b2 <- b3); each frame's matrix into root."""
    buffer = Buffer()
    to_root = {"root": np.eye(4)}
    for parent, child in [("root", "a1"), ("a1", "a2"), ("root", "b1"), ("b1", "b2"), ("b2", "b3")]:
        t = random_transform(rng, parent, child, 1.0)
        buffer.set_transform(t)
        to_root[child] = to_root[parent] @ t.as_matrix()
    return buffer, to_root


def test_seed_example_point_ahead_of_os_sensor() -> None:
    """Spec 000: (1, 0, 0) in os_sensor is (100, 51, -0.1) in reference."""
    buffer = seed_tree()
    for time in (1.0, LATEST):
        out = buffer.transform_points("reference", "os_sensor", [[1.0, 0.0, 0.0]], time)
        assert_allclose(out, [[100.0, 51.0, -0.1]], atol=1e-9)
    t = buffer.lookup_transform("reference", "os_sensor", LATEST)
    assert (t.frame_id, t.child_frame_id, t.stamp) == ("reference", "os_sensor", 1.0)
    assert_allclose(t.transform_points([[1.0, 0.0, 0.0]]), [[100.0, 51.0, -0.1]], atol=1e-9)
    assert_allclose(t.translation, [100.0, 50.0, -0.1], atol=1e-9)


def test_seed_example_reference_into_os_sensor() -> None:
    """The inverse lookup brings (100, 51, -0.1) in reference back to (1, 0, 0) in os_sensor."""
    buffer = seed_tree()
    out = buffer.transform_points("os_sensor", "reference", [[100.0, 51.0, -0.1]], LATEST)
    assert_allclose(out, [[1.0, 0.0, 0.0]], atol=1e-9)
    pose = buffer.lookup_pose2d("reference", "os_sensor", LATEST)
    assert_allclose([pose.x, pose.y, pose.yaw], [100.0, 50.0, math.pi / 2], atol=1e-12)


def test_transform_points_2d_gives_ground_projection() -> None:
    """(n, 2) points are taken at z = 0 and come back as (n, 2), z dropped."""
    buffer = seed_tree()
    points = np.array([[1.0, 0.0], [0.0, -2.0], [3.0, 4.0]])
    out = buffer.transform_points("reference", "os_sensor", points, LATEST)
    assert out.shape == (3, 2)
    assert_allclose(out, [[100.0, 51.0], [102.0, 50.0], [96.0, 53.0]], atol=1e-9)
    full = buffer.transform_points("reference", "os_sensor", np.c_[points, np.zeros(3)], LATEST)
    assert_allclose(out, full[:, :2], atol=1e-12)


def test_transform_points_matches_lookup_per_point() -> None:
    """The vectorised mapping equals the looked-up matrix applied to each point."""
    rng = np.random.default_rng(0)
    buffer, _ = random_tree(rng)
    points = rng.uniform(-20.0, 20.0, (50, 3))
    matrix = buffer.lookup_transform("a2", "b3", 1.0).as_matrix()
    expected = np.array([matrix @ np.append(p, 1.0) for p in points])[:, :3]
    assert_allclose(buffer.transform_points("a2", "b3", points, 1.0), expected, atol=1e-9)


def test_chain_through_common_ancestor() -> None:
    """Two children of one parent: B's points reach A via the parent."""
    buffer = Buffer()
    buffer.set_transform(TransformStamped.from_pose2d("P", "A", 0.0, Pose2D(1.0, 0.0, 0.0)))
    buffer.set_transform(TransformStamped.from_pose2d("P", "B", 0.0, Pose2D(0.0, 2.0, math.pi / 2)))
    out = buffer.transform_points("A", "B", [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]], 0.0)
    assert_allclose(out, [[-1.0, 2.0, 0.0], [-1.0, 3.0, 0.0]], atol=1e-12)
    pose = buffer.lookup_pose2d("A", "B", 0.0)
    assert_allclose([pose.x, pose.y, pose.yaw], [-1.0, 2.0, math.pi / 2], atol=1e-12)


def test_chain_matches_matrix_products() -> None:
    """Every lookup in a 6-frame tree equals inv(target -> root) @ (source -> root)."""
    rng = np.random.default_rng(0)
    buffer, to_root = random_tree(rng)
    for target in to_root:
        for source in to_root:
            expected = np.linalg.inv(to_root[target]) @ to_root[source]
            got = buffer.lookup_transform(target, source, 1.0)
            assert (got.frame_id, got.child_frame_id) == (target, source)
            assert_allclose(got.as_matrix(), expected, atol=1e-9)


def test_lookup_is_inverse_of_reverse_lookup() -> None:
    """lookup(A, B) equals lookup(B, A).inverse(), and their composition is the identity."""
    rng = np.random.default_rng(0)
    buffer, _ = random_tree(rng)
    for target, source in [("a2", "b3"), ("root", "b2"), ("b3", "b1"), ("a1", "a1")]:
        forward = buffer.lookup_transform(target, source, 1.0)
        backward = buffer.lookup_transform(source, target, 1.0)
        assert_allclose(forward.as_matrix(), backward.inverse().as_matrix(), atol=1e-9)
        assert_allclose(forward.compose(backward).as_matrix(), IDENTITY_MATRIX, atol=1e-9)
        assert_allclose(backward.compose(forward).as_matrix(), IDENTITY_MATRIX, atol=1e-9)


def test_interpolated_lookup_through_static_link() -> None:
    """Half-way between two poses the vehicle is at the mean position and half the yaw."""
    buffer = seed_tree(stamp=1.0)
    buffer.set_transform(
        TransformStamped.from_pose2d("reference", "gps_antenna", 2.0, Pose2D(102.0, 54.0, 2.0))
    )
    t = buffer.lookup_transform("reference", "os_sensor", 1.5)
    assert t.stamp == 1.5
    assert_allclose(t.translation, [101.0, 52.0, -0.1], atol=1e-12)
    assert_allclose(t.to_pose2d().yaw, (math.pi / 2 + 2.0) / 2, atol=1e-12)


def test_time_zero_is_latest_common_time() -> None:
    """LATEST uses the smallest newest stamp over the chain's dynamic links."""
    buffer = Buffer()
    for k in range(11):
        stamp = 0.1 * k
        buffer.set_transform(
            TransformStamped.from_pose2d("reference", "car", stamp, Pose2D(stamp, 0.0, 0.0))
        )
        if k <= 5:
            buffer.set_transform(
                TransformStamped.from_pose2d("car", "wheel", stamp, Pose2D(0.0, stamp, 0.0))
            )
    buffer.set_transform_static(TransformStamped("wheel", "hub", 0.0, translation=(0, 0, 1)))
    assert buffer.latest_common_time("reference", "hub") == 0.5
    latest = buffer.lookup_transform("reference", "hub", LATEST)
    assert latest.stamp == 0.5
    assert_allclose(latest.translation, [0.5, 0.5, 1.0], atol=1e-12)
    assert_allclose(
        latest.as_matrix(), buffer.lookup_transform("reference", "hub", 0.5).as_matrix(), atol=0
    )
    assert buffer.lookup_transform("reference", "car", LATEST).stamp == 1.0
    assert buffer.lookup_transform("hub", "wheel", LATEST).stamp == 0.0


def test_static_links_hold_at_any_time() -> None:
    """A chain of static links answers at any time; LATEST gives stamp 0."""
    buffer = Buffer()
    buffer.set_transform_static(TransformStamped("base", "gps", 5.0, translation=(0.5, 0, 1)))
    buffer.set_transform_static(TransformStamped("gps", "lidar", 5.0, translation=(0, 0, -0.1)))
    for time in (LATEST, -3.0, 1e-6, 4.0, 1e9):
        t = buffer.lookup_transform("base", "lidar", time)
        assert_allclose(t.translation, [0.5, 0.0, 0.9], atol=1e-12)
        assert t.stamp == time


def test_leading_slash_is_stripped() -> None:
    """'/reference' and 'reference' name the same frame, in inserts and lookups."""
    buffer = Buffer()
    buffer.set_transform(
        TransformStamped.from_pose2d("/reference", "/gps_antenna", 1.0, Pose2D(1.0, 2.0, 0.0))
    )
    assert buffer.all_frame_names() == ["gps_antenna", "reference"]
    t = buffer.lookup_transform("/reference", "gps_antenna", LATEST)
    assert (t.frame_id, t.child_frame_id) == ("reference", "gps_antenna")
    assert_allclose(t.translation, [1.0, 2.0, 0.0], atol=0)
    assert buffer.can_transform("reference", "/gps_antenna", 1.0)
    assert buffer.frame_exists("/reference")


def test_two_vehicles_under_one_reference() -> None:
    """Prefixed frames are plain names: car1's sensor sees car2's antenna through reference."""
    buffer = Buffer()
    for car, pose in [("car1", Pose2D(10.0, 0.0, 0.0)), ("car2", Pose2D(10.0, 5.0, math.pi))]:
        buffer.set_transform(
            TransformStamped.from_pose2d("reference", f"{car}/gps_antenna", 1.0, pose)
        )
        buffer.set_transform_static(
            TransformStamped(
                f"{car}/gps_antenna", f"{car}/os_sensor", 0.0, translation=(0, 0, -0.1)
            )
        )
    out = buffer.transform_points("car1/os_sensor", "car2/gps_antenna", [[0.0, 0.0, 0.0]], LATEST)
    assert_allclose(out, [[0.0, 5.0, 0.1]], atol=1e-12)
    pose = buffer.lookup_pose2d("car1/os_sensor", "car2/os_sensor", LATEST)
    assert_allclose([pose.x, pose.y, abs(pose.yaw)], [0.0, 5.0, math.pi], atol=1e-12)


def test_can_transform() -> None:
    """can_transform is True where lookup works and False for each lookup failure."""
    buffer = seed_tree(stamp=1.0)
    buffer.set_transform_static(TransformStamped("elsewhere", "island", 0.0))
    assert buffer.can_transform("reference", "os_sensor", 1.0)
    assert buffer.can_transform("reference", "os_sensor", LATEST)
    assert not buffer.can_transform("reference", "os_sensor", 2.0)
    assert not buffer.can_transform("reference", "missing", 1.0)
    assert not buffer.can_transform("reference", "island", 1.0)
    # Invalid arguments answer False too, as tf2's canTransform does.
    assert not buffer.can_transform("", "os_sensor", 1.0)
    assert not buffer.can_transform("reference", "os_sensor", math.nan)


def test_same_frame_is_identity() -> None:
    """A known frame looked up in itself is the identity at the requested time."""
    buffer = seed_tree()
    t = buffer.lookup_transform("gps_antenna", "gps_antenna", 7.0)
    assert_allclose(t.as_matrix(), IDENTITY_MATRIX, atol=0)
    assert t.stamp == 7.0


def test_cache_time_is_configurable() -> None:
    """With a 1 s cache only the last second of a link is held."""
    buffer = Buffer(cache_time=1.0)
    for k in range(51):
        buffer.set_transform(
            TransformStamped.from_pose2d("reference", "car", k * 0.1, Pose2D(k * 0.1, 0, 0))
        )
    info = buffer.frames()["car"]
    assert (info.oldest, info.latest, info.length) == (pytest.approx(4.0), 5.0, 11)
    with pytest.raises(ExtrapolationError, match="past"):
        buffer.lookup_transform("reference", "car", 3.5)


def test_old_data_is_dropped_with_a_warning(caplog: pytest.LogCaptureFixture) -> None:
    """Data older than newest - cache_time is not stored: False and a TF_OLD_DATA warning."""
    buffer = Buffer(cache_time=1.0)
    buffer.set_transform(TransformStamped.from_pose2d("reference", "car", 5.0, Pose2D(0, 0, 0)))
    with caplog.at_level(logging.WARNING, logger="conesim.localization.frames.buffer"):
        stored = buffer.set_transform(
            TransformStamped.from_pose2d("reference", "car", 3.0, Pose2D(1, 0, 0))
        )
    assert not stored
    assert "TF_OLD_DATA" in caplog.text
    assert buffer.frames()["car"].length == 1


def test_switching_static_and_dynamic_replaces_the_link() -> None:
    """As in tf2, a static transform for a dynamic link (or back) replaces its cache."""
    buffer = seed_tree(stamp=1.0)
    buffer.set_transform_static(
        TransformStamped.from_pose2d("reference", "gps_antenna", 3.0, Pose2D(7.0, 8.0, 0.0))
    )
    info = buffer.frames()["gps_antenna"]
    assert (info.static, info.length, info.authority) == (True, 1, "default_authority")
    assert_allclose(
        buffer.lookup_transform("reference", "os_sensor", 123.0).translation, [7, 8, -0.1]
    )
    buffer.set_transform(TransformStamped("gps_antenna", "os_sensor", 4.0, translation=(1, 0, 0)))
    with pytest.raises(ExtrapolationError):
        buffer.lookup_transform("reference", "os_sensor", 3.0)


def test_root_may_gain_a_parent_later() -> None:
    """Linking a root under a new frame extends the tree; earlier chains still hold."""
    buffer = seed_tree()
    before = buffer.lookup_transform("reference", "os_sensor", LATEST).as_matrix()
    buffer.set_transform_static(TransformStamped("world", "reference", 0.0, translation=(1, 1, 0)))
    assert_allclose(buffer.lookup_transform("reference", "os_sensor", LATEST).as_matrix(), before)
    out = buffer.transform_points("world", "os_sensor", [[1.0, 0.0, 0.0]], LATEST)
    assert_allclose(out, [[101.0, 52.0, -0.1]], atol=1e-9)


def test_frames_reports_links() -> None:
    """frames() lists each child's parent, kind, authority, stamps and length."""
    buffer = seed_tree(stamp=1.0)
    info = buffer.frames()
    assert list(info) == ["gps_antenna", "os_sensor"]
    assert info["gps_antenna"].parent == "reference"
    assert info["gps_antenna"].authority == "vehicle_tf_broadcaster"
    assert not info["gps_antenna"].static
    assert info["os_sensor"].static
