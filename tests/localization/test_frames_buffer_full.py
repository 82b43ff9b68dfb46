"""Tests for the buffer's time-travel lookup (tf2's "advanced" lookupTransform).

``lookup_transform_full(target, target_time, source, source_time, fixed)`` is
``(target <- fixed at target_time) ∘ (fixed <- source at source_time)``; the
expected numbers below are worked out by hand.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose

from conesim.core.pose import Pose2D
from conesim.localization.frames import (
    LATEST,
    Buffer,
    ConnectivityError,
    ExtrapolationError,
    FrameNotFoundError,
    InvalidArgumentError,
    TransformStamped,
)

SQRT2 = math.sqrt(2.0)


def driving_tree(poses: dict[float, Pose2D]) -> Buffer:
    """Spec 000's tree with the antenna at ``poses`` (stamp -> pose), os_sensor 0.1 m below."""
    buffer = Buffer()
    for stamp, pose in poses.items():
        buffer.set_transform(TransformStamped.from_pose2d("reference", "gps_antenna", stamp, pose))
    buffer.set_transform_static(
        TransformStamped("gps_antenna", "os_sensor", 0.0, translation=(0.0, 0.0, -0.1))
    )
    return buffer


def straight_tree() -> Buffer:
    """The car driving along x at 1 m/s with yaw 0: x = t at t = 1, ..., 5 s."""
    return driving_tree({float(t): Pose2D(float(t), 0.0, 0.0) for t in range(1, 6)})


def turning_tree() -> Buffer:
    """A quarter circle of radius 10 m: (0, 0) heading east at 1 s, (10, 10) north at 2 s."""
    return driving_tree({1.0: Pose2D(0.0, 0.0, 0.0), 2.0: Pose2D(10.0, 10.0, math.pi / 2)})


def assert_yaw_only(t: TransformStamped, x: float, y: float, z: float, yaw: float) -> None:
    """``t`` translates by (x, y, z) and turns by ``yaw`` about z."""
    assert_allclose(t.translation, [x, y, z], atol=1e-12)
    assert_allclose(t.rotation, [0.0, 0.0, math.sin(yaw / 2), math.cos(yaw / 2)], atol=1e-12)


# -- worked examples ---------------------------------------------------------------------------


def test_straight_drive_moves_old_points_back_by_the_distance_driven() -> None:
    """At 1 m/s for 3 s: os_sensor at 1 s is 3 m behind os_sensor at 4 s.

    Target leg: os_sensor <- reference at 4 s is the inverse of (4, 0, -0.1),
    i.e. (-4, 0, 0.1); source leg: reference <- os_sensor at 1 s is
    (1, 0, -0.1). Composed: (-3, 0, 0), no rotation. A cone 5 m ahead at 1 s
    is 2 m ahead at 4 s.
    """
    buffer = straight_tree()
    t = buffer.lookup_transform_full("os_sensor", 4.0, "os_sensor", 1.0, "reference")
    assert (t.frame_id, t.child_frame_id, t.stamp) == ("os_sensor", "os_sensor", 4.0)
    assert_yaw_only(t, -3.0, 0.0, 0.0, 0.0)
    out = buffer.transform_points_full(
        "os_sensor", 4.0, "os_sensor", [[5.0, 0.0, 0.0], [5.0, 1.0, 0.2]], 1.0, "reference"
    )
    assert_allclose(out, [[2.0, 0.0, 0.0], [2.0, 1.0, 0.2]], atol=1e-12)
    # Interpolated times: 2.5 s -> 3.75 s is 1.25 m.
    t = buffer.lookup_transform_full("os_sensor", 3.75, "os_sensor", 2.5, "reference")
    assert t.stamp == 3.75
    assert_yaw_only(t, -1.25, 0.0, 0.0, 0.0)


def test_turning_case_worked_by_hand() -> None:
    """gps_antenna at 2 s, (10, 10) heading north, sees the antenna of 1 s, (0, 0) heading east.

    inverse(P2) turns by -90 deg, (x, y) -> (y, -x), and translates by
    -(10, -10) = (-10, 10); composed with P1 = identity: (-10, 10, 0), yaw
    -90 deg. The point 1 m ahead at 1 s, (1, 0) in reference, is 10 m behind
    and 9 m left of the car at 2 s: (-10, 9).
    """
    buffer = turning_tree()
    t = buffer.lookup_transform_full("gps_antenna", 2.0, "gps_antenna", 1.0, "reference")
    assert (t.frame_id, t.child_frame_id, t.stamp) == ("gps_antenna", "gps_antenna", 2.0)
    assert_yaw_only(t, -10.0, 10.0, 0.0, -math.pi / 2)
    out = buffer.transform_points_full(
        "gps_antenna", 2.0, "gps_antenna", [[1.0, 0.0]], 1.0, "reference"
    )
    assert_allclose(out, [[-10.0, 9.0]], atol=1e-12)
    pose = t.to_pose2d()
    assert_allclose([pose.x, pose.y, pose.yaw], [-10.0, 10.0, -math.pi / 2], atol=1e-12)


def test_turning_case_at_an_interpolated_time_through_the_static_link() -> None:
    """Half-way, 1.5 s: (5, 5) heading 45 deg (linear translation, slerp yaw).

    os_sensor <- reference at 1.5 s is the inverse of (5, 5, -0.1) turned
    45 deg: (-5 sqrt 2, 0, 0.1) turned -45 deg; composed with reference <-
    os_sensor at 1 s, (0, 0, -0.1), the heights cancel: (-5 sqrt 2, 0, 0),
    yaw -45 deg. A point (5 sqrt 2, 0) ahead at 1 s maps to
    R(-45 deg) (5 sqrt 2, 0) + (-5 sqrt 2, 0) = (5 - 5 sqrt 2, -5).
    """
    buffer = turning_tree()
    t = buffer.lookup_transform_full("os_sensor", 1.5, "os_sensor", 1.0, "reference")
    assert t.stamp == 1.5
    assert_yaw_only(t, -5.0 * SQRT2, 0.0, 0.0, -math.pi / 4)
    out = buffer.transform_points_full(
        "os_sensor", 1.5, "os_sensor", [[5.0 * SQRT2, 0.0, 0.0]], 1.0, "reference"
    )
    assert_allclose(out, [[5.0 - 5.0 * SQRT2, -5.0, 0.0]], atol=1e-12)


def test_backwards_in_time_is_the_inverse() -> None:
    """Carrying from 2 s back to 1 s undoes carrying from 1 s to 2 s; stamps follow the target."""
    buffer = turning_tree()
    forward = buffer.lookup_transform_full("os_sensor", 2.0, "gps_antenna", 1.0, "reference")
    back = buffer.lookup_transform_full("gps_antenna", 1.0, "os_sensor", 2.0, "reference")
    assert (back.frame_id, back.child_frame_id, back.stamp) == ("gps_antenna", "os_sensor", 1.0)
    assert_allclose(back.as_matrix() @ forward.as_matrix(), np.eye(4), atol=1e-12)
    assert_allclose(back.as_matrix(), forward.inverse().as_matrix(), atol=1e-12)


def test_matches_the_two_legs_looked_up_and_composed() -> None:
    """The result is lookup(target, fixed, target_time) ∘ lookup(fixed, source, source_time)."""
    buffer = turning_tree()
    for target_time, source_time in [(2.0, 1.0), (1.25, 1.75), (1.5, 1.5)]:
        full = buffer.lookup_transform_full(
            "os_sensor", target_time, "gps_antenna", source_time, "reference"
        )
        legs = buffer.lookup_transform("os_sensor", "reference", target_time).compose(
            buffer.lookup_transform("reference", "gps_antenna", source_time)
        )
        assert full.rigid == legs.rigid
        assert full.stamp == target_time


# -- identity case -----------------------------------------------------------------------------


def test_same_time_on_both_legs_is_the_plain_lookup() -> None:
    """One time on both legs: the fixed frame drops out, whatever frame it is."""
    buffer = turning_tree()
    buffer.set_transform_static(TransformStamped("reference", "cone_map", 0.0, (3.0, -2.0, 0.0)))
    fixed_frames = ("reference", "cone_map", "gps_antenna", "os_sensor")
    for time in (1.0, 1.3, 2.0):
        plain = buffer.lookup_transform("os_sensor", "reference", time)
        for fixed in fixed_frames:
            full = buffer.lookup_transform_full("os_sensor", time, "reference", time, fixed)
            assert (full.frame_id, full.child_frame_id, full.stamp) == (
                "os_sensor",
                "reference",
                time,
            )
            assert_allclose(full.as_matrix(), plain.as_matrix(), atol=1e-12)
        # Through the common ancestor it is the same arithmetic: bit for bit.
        full = buffer.lookup_transform_full("os_sensor", time, "reference", time, "reference")
        assert full.rigid == plain.rigid
    # LATEST on both legs: each leg takes its own chain's latest time, here both 2 s.
    # The stamp is the target leg's: 2 s where that leg holds the dynamic link,
    # 0 where it is static only (os_sensor <- gps_antenna) or the identity.
    plain = buffer.lookup_transform("os_sensor", "reference", LATEST)
    assert plain.stamp == 2.0
    for fixed, stamp in zip(fixed_frames, (2.0, 2.0, LATEST, LATEST), strict=True):
        full = buffer.lookup_transform_full("os_sensor", LATEST, "reference", LATEST, fixed)
        assert full.stamp == stamp
        assert_allclose(full.as_matrix(), plain.as_matrix(), atol=1e-12)


def test_same_frame_same_time_is_the_identity() -> None:
    """A frame at one time in itself: the identity, also at LATEST (stamped the latest time)."""
    buffer = straight_tree()
    for time in (2.5, LATEST):
        t = buffer.lookup_transform_full("os_sensor", time, "os_sensor", time, "reference")
        assert_allclose(t.as_matrix(), np.eye(4), atol=1e-12)
        assert t.stamp == (5.0 if time == LATEST else time)


# -- LATEST ------------------------------------------------------------------------------------


def test_latest_is_resolved_per_leg() -> None:
    """Time 0 on a leg is the latest common time of that leg's chain alone.

    gps_antenna has data up to 5 s and car2 up to 3 s. A plain LATEST lookup
    between them uses 3 s for both; the full lookup through reference takes
    gps_antenna at 5 s (x = 5) and car2 at 3 s ((20, 1) heading north):
    inverse(car2) maps (5, 0) to R(-90 deg) (5 - 20, 0 - 1) = (-1, 15).
    """
    buffer = straight_tree()
    for stamp in (2.0, 3.0):
        buffer.set_transform(
            TransformStamped.from_pose2d(
                "reference", "car2", stamp, Pose2D(20.0, stamp - 2.0, math.pi / 2)
            )
        )
    t = buffer.lookup_transform_full("car2", LATEST, "gps_antenna", LATEST, "reference")
    assert t.stamp == 3.0  # the target leg's latest time
    assert_yaw_only(t, -1.0, 15.0, 0.0, -math.pi / 2)
    plain = buffer.lookup_transform("car2", "gps_antenna", LATEST)
    assert plain.stamp == 3.0
    assert_yaw_only(plain, -1.0, 17.0, 0.0, -math.pi / 2)  # gps_antenna at 3 s: x = 3
    # Mixed: a given source time, LATEST target, and the other way round.
    t = buffer.lookup_transform_full("car2", LATEST, "gps_antenna", 1.0, "reference")
    assert t.stamp == 3.0
    assert_yaw_only(t, -1.0, 19.0, 0.0, -math.pi / 2)
    t = buffer.lookup_transform_full("car2", 2.0, "gps_antenna", LATEST, "reference")
    assert t.stamp == 2.0
    assert_yaw_only(t, 0.0, 15.0, 0.0, -math.pi / 2)  # car2 at 2 s: (20, 0)


def test_latest_follows_new_data() -> None:
    """A LATEST target leg moves on as data arrives; the result's stamp says which time it used."""
    buffer = straight_tree()
    first = buffer.lookup_transform_full("os_sensor", LATEST, "os_sensor", 1.0, "reference")
    assert first.stamp == 5.0
    assert_yaw_only(first, -4.0, 0.0, 0.0, 0.0)
    buffer.set_transform(
        TransformStamped.from_pose2d("reference", "gps_antenna", 6.0, Pose2D(6.0, 0.0, 0.0))
    )
    later = buffer.lookup_transform_full("os_sensor", LATEST, "os_sensor", 1.0, "reference")
    assert later.stamp == 6.0
    assert_yaw_only(later, -5.0, 0.0, 0.0, 0.0)


# -- static-only chains ------------------------------------------------------------------------


def test_static_only_chain_holds_at_any_times() -> None:
    """Only static links: any two times give the plain static lookup; LATEST is stamped 0."""
    buffer = Buffer()
    buffer.set_transform_static(TransformStamped("base_link", "laser", 0.0, (1.0, 0.0, 0.5)))
    buffer.set_transform_static(
        TransformStamped(
            "base_link", "camera", 0.0, (0.0, 0.5, 1.0), (0.0, 0.0, math.sin(0.25), math.cos(0.25))
        )
    )
    plain = buffer.lookup_transform("camera", "laser", LATEST)
    for target_time, source_time in [(3.0, 100.0), (100.0, 3.0), (LATEST, 7.0), (7.0, LATEST)]:
        t = buffer.lookup_transform_full("camera", target_time, "laser", source_time, "base_link")
        assert t.stamp == target_time
        assert_allclose(t.as_matrix(), plain.as_matrix(), atol=1e-12)
    # The laser's origin in the camera: R(-0.5 rad) ((1, 0) - (0, 0.5)), height 0.5 - 1.
    c, s = math.cos(0.5), math.sin(0.5)
    assert_allclose(plain.translation, [c * 1.0 + s * -0.5, -s * 1.0 + c * -0.5, -0.5], atol=1e-12)


def test_fixed_frame_may_move_when_both_legs_are_static() -> None:
    """Legs of static links (or a frame in itself) hold at any time, whatever the fixed frame."""
    buffer = straight_tree()
    # Source leg os_sensor <- gps_antenna is static; target leg os_sensor in itself.
    t = buffer.lookup_transform_full("os_sensor", 99.0, "gps_antenna", 4.0, "os_sensor")
    assert t.stamp == 99.0
    assert_yaw_only(t, 0.0, 0.0, 0.1, 0.0)


# -- errors ------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("leg", "target_time", "source_time", "names"),
    [
        (
            "source",
            4.0,
            0.5,
            "in the source leg, frame 'os_sensor' at source_time 0.5 s into fixed frame "
            "'reference'",
        ),
        (
            "target",
            7.5,
            1.0,
            "in the target leg, fixed frame 'reference' into frame 'os_sensor' at "
            "target_time 7.5 s",
        ),
    ],
)
def test_extrapolation_names_the_leg(
    leg: str, target_time: float, source_time: float, names: str
) -> None:
    """A source time before the oldest data or a target time after the newest: the error
    is the link's (reference -> gps_antenna, data 1-5 s) and names the leg and its time."""
    buffer = straight_tree()
    call = ("os_sensor", target_time, "os_sensor", source_time, "reference")
    with pytest.raises(ExtrapolationError) as info:
        buffer.lookup_transform_full(*call)
    err = info.value
    time, direction = (source_time, "past") if leg == "source" else (target_time, "future")
    assert (err.frame, err.parent, err.time, err.direction) == (
        "gps_antenna",
        "reference",
        time,
        direction,
    )
    assert (err.earliest, err.latest) == (1.0, 5.0)
    assert names in str(err)
    other = "target" if leg == "source" else "source"
    assert f"{other} leg" not in str(err)
    assert not buffer.can_transform_full(*call)


def test_source_leg_is_looked_up_first() -> None:
    """Both legs out of range: the source leg's error, as tf2 looks it up first."""
    buffer = straight_tree()
    with pytest.raises(ExtrapolationError, match="in the source leg") as info:
        buffer.lookup_transform_full("os_sensor", 9.0, "os_sensor", 0.5, "reference")
    assert info.value.time == 0.5


def test_latest_leg_error_shows_latest() -> None:
    """A LATEST leg that still extrapolates says it was the latest common time."""
    buffer = straight_tree()
    buffer.set_transform(
        TransformStamped.from_pose2d("gps_antenna", "wheel", 8.0, Pose2D(1.0, 0.0, 0.0))
    )
    # wheel's chain: latest common time min(5, 8) = 5, before wheel's only stamp 8.
    with pytest.raises(ExtrapolationError, match=r"source_time 0\.0 s \(latest\)") as info:
        buffer.lookup_transform_full("os_sensor", 4.0, "wheel", LATEST, "reference")
    assert info.value.time == 5.0


def test_fixed_frame_not_connected() -> None:
    """A fixed frame in another tree: ConnectivityError naming the leg that could not connect."""
    buffer = straight_tree()
    buffer.set_transform_static(TransformStamped("map", "landmark", 0.0, (1.0, 0.0, 0.0)))
    with pytest.raises(ConnectivityError, match="in the source leg") as info:
        buffer.lookup_transform_full("os_sensor", 4.0, "os_sensor", 1.0, "map")
    assert "fixed frame 'map'" in str(info.value)
    assert not buffer.can_transform_full("os_sensor", 4.0, "os_sensor", 1.0, "map")
    # Source and fixed connected, target in the other tree: the target leg.
    with pytest.raises(ConnectivityError, match="in the target leg"):
        buffer.lookup_transform_full("landmark", 4.0, "os_sensor", 1.0, "reference")


@pytest.mark.parametrize("argument", ["target_frame", "source_frame", "fixed_frame"])
def test_unknown_frames_are_named(argument: str) -> None:
    """Each unknown frame raises FrameNotFoundError naming the argument."""
    buffer = straight_tree()
    frames = {"target_frame": "os_sensor", "source_frame": "os_sensor", "fixed_frame": "reference"}
    frames[argument] = "base_link"
    call = (frames["target_frame"], 4.0, frames["source_frame"], 1.0, frames["fixed_frame"])
    with pytest.raises(FrameNotFoundError, match=f"lookup_transform_full argument {argument}"):
        buffer.lookup_transform_full(*call)
    assert not buffer.can_transform_full(*call)
    frames[argument] = ""
    call = (frames["target_frame"], 4.0, frames["source_frame"], 1.0, frames["fixed_frame"])
    with pytest.raises(InvalidArgumentError, match=f"{argument} must be a non-empty"):
        buffer.lookup_transform_full(*call)
    assert not buffer.can_transform_full(*call)


@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf])
def test_non_finite_times_are_named(bad: float) -> None:
    """A NaN or infinite time raises InvalidArgumentError naming target_time or source_time."""
    buffer = straight_tree()
    with pytest.raises(InvalidArgumentError, match="target_time must be finite"):
        buffer.lookup_transform_full("os_sensor", bad, "os_sensor", 1.0, "reference")
    with pytest.raises(InvalidArgumentError, match="source_time must be finite"):
        buffer.lookup_transform_full("os_sensor", 4.0, "os_sensor", bad, "reference")
    assert not buffer.can_transform_full("os_sensor", 4.0, "os_sensor", bad, "reference")


def test_arguments_are_checked_before_any_leg() -> None:
    """An unknown fixed frame is reported even when a leg would also fail."""
    buffer = straight_tree()
    with pytest.raises(FrameNotFoundError, match="fixed_frame"):
        buffer.lookup_transform_full("os_sensor", 9.0, "os_sensor", 0.5, "nowhere")
    with pytest.raises(InvalidArgumentError, match="target_time"):
        buffer.lookup_transform_full("os_sensor", math.nan, "os_sensor", 0.5, "reference")


def test_can_transform_full_when_it_can() -> None:
    """True exactly where the lookup succeeds; frame names may carry a leading slash."""
    buffer = straight_tree()
    assert buffer.can_transform_full("os_sensor", 4.0, "os_sensor", 1.0, "reference")
    assert buffer.can_transform_full("/os_sensor", LATEST, "os_sensor", 1.0, "/reference")
    t = buffer.lookup_transform_full("/os_sensor", 4.0, "/gps_antenna", 1.0, "/reference")
    assert (t.frame_id, t.child_frame_id) == ("os_sensor", "gps_antenna")


def test_transform_points_full_matches_the_lookup() -> None:
    """(n, 3) and (n, 2) points as transform_points takes them; other shapes are refused."""
    buffer = turning_tree()
    points = np.random.default_rng(3).uniform(-20.0, 20.0, (40, 3))
    t = buffer.lookup_transform_full("os_sensor", 1.8, "gps_antenna", 1.1, "reference")
    out = buffer.transform_points_full("os_sensor", 1.8, "gps_antenna", points, 1.1, "reference")
    assert_allclose(out, t.transform_points(points), atol=1e-12)
    out_2d = buffer.transform_points_full(
        "os_sensor", 1.8, "gps_antenna", points[:, :2], 1.1, "reference"
    )
    assert out_2d.shape == (40, 2)
    assert_allclose(out_2d, t.transform_points(points[:, :2]), atol=1e-12)
    with pytest.raises(InvalidArgumentError, match="shape"):
        buffer.transform_points_full("os_sensor", 1.8, "gps_antenna", [1.0, 2.0], 1.1, "reference")
