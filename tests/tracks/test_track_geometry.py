"""Derived geometry against worked numbers: circle, lane, stadium, hairpin, skidpad."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from numpy.testing import assert_allclose

from conesim.core.pose import Pose2D
from conesim.tracks import ConeKind, Layout, Track, derive_start_pose, detect_layout
from conesim.tracks.geometry import build_geometry


def test_circle_centreline_radius_and_width(circle) -> None:
    """Inner 20 m, outer 24 m, cones every 3 m: centreline radius 22 m, width 4 m, within 2 cm."""
    track = circle()
    radius = np.hypot(*track.centreline.T)
    assert_allclose(radius, 22.0, atol=0.02)
    assert_allclose(track.widths, 4.0, atol=0.02)
    assert track.length_m == pytest.approx(2 * math.pi * 22.0, abs=0.05)


def test_circle_centreline_spacing_start_and_direction(circle) -> None:
    """~0.5 m spacing, no repeated closing point, starts at the start pose, heads its way."""
    track = circle()
    c = track.centreline
    steps = np.hypot(*np.diff(np.vstack([c, c[:1]]), axis=0).T)
    assert_allclose(steps, 0.5, atol=0.01)
    assert_allclose(c[0], [22.0, 0.0], atol=0.02)  # start pose (22, 0) facing north
    assert_allclose(track.direction, [0.0, 1.0], atol=1e-3)
    # no big orange cones: the start line is perpendicular at the start pose, spanning 20..24 m
    assert_allclose(track.start_finish, [[20.0, 0.0], [24.0, 0.0]], atol=0.02)


def test_clockwise_circle_runs_clockwise(circle) -> None:
    """Blue outside and the start pose facing south: the centreline turns right."""
    track = circle(clockwise=True)
    c = track.centreline
    x, y = c[:, 0], c[:, 1]
    assert 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y)) < 0
    assert_allclose(np.hypot(x, y), 22.0, atol=0.02)
    assert_allclose(track.direction, [0.0, -1.0], atol=1e-3)


def test_straight_lane_gives_the_straight(lane) -> None:
    """Cones at y = +-2 m from x = 0 to 50 m: centreline y = 0 from 0 to 50 m, width 4 m."""
    track = lane()
    c = track.centreline
    assert_allclose(c[:, 1], 0.0, atol=1e-3)
    assert_allclose(c[[0, -1], 0], [0.0, 50.0], atol=0.01)
    assert_allclose(np.diff(c[:, 0]), 0.5, atol=1e-3)
    assert_allclose(track.widths, 4.0, atol=1e-3)
    assert track.length_m == pytest.approx(50.0, abs=0.01)
    assert_allclose(track.direction, [1.0, 0.0], atol=1e-6)


def test_shuffled_cones_give_the_same_centreline(circle) -> None:
    """The file order of the cones does not matter."""
    track = circle()
    order = np.random.default_rng(0).permutation(len(track.cones))
    shuffled = Track(
        "shuffled", track.cones[order], tuple(track.kinds[i] for i in order), track.start_pose
    )
    assert_allclose(shuffled.centreline, track.centreline, atol=0.01)
    assert_allclose(shuffled.widths, track.widths, atol=0.01)


def test_hairpin_survives_shuffling(points) -> None:
    """A hairpin loop whose inner legs are 3 m apart (cones 3 m apart too), shuffled:
    the boundaries keep their true order and the centreline stays on the stadium."""
    inner = points(40.0, 1.5, 3.0)  # centreline radius 3 m, width 3 m: 9 m outside diameter
    outer = points(40.0, 4.5, 3.0)
    cones = np.vstack([inner, outer])
    kinds = (ConeKind.BLUE,) * len(inner) + (ConeKind.YELLOW,) * len(outer)
    order = np.random.default_rng(1).permutation(len(cones))
    track = Track("hairpin", cones[order], tuple(kinds[i] for i in order), Pose2D(20.0, -3.0, 0.0))
    left = track.left_boundary
    start = int(np.argmin(np.hypot(*(inner - left[0]).T)))
    assert_allclose(left, np.roll(inner, -start, axis=0), atol=1e-12)  # same order, same way
    x, y = track.centreline.T
    off = np.hypot(x - np.clip(x, 0.0, 40.0), y) - 3.0  # distance from the true centreline
    # The stadium's curvature jumps where straight meets arc; a spline through
    # the cones overshoots there by ~0.1 m. Elsewhere it is exact.
    assert np.abs(off).max() < 0.15
    assert np.median(np.abs(off)) < 0.01
    assert track.length_m == pytest.approx(80.0 + 2 * math.pi * 3.0, abs=0.5)


def test_start_finish_between_big_orange_cones(stadium) -> None:
    """The line joins the means of the big orange pairs; the centreline starts on it."""
    track = stadium()
    assert_allclose(track.start_finish, [[10.0, -13.0], [10.0, -17.0]], atol=1e-9)
    assert_allclose(track.centreline[0], [10.0, -15.0], atol=0.02)
    assert_allclose(track.direction, [1.0, 0.0], atol=1e-3)
    assert_allclose(track.finish_line, track.start_finish)
    # the big orange cones close the boundaries' gap at the line
    assert any(np.allclose(p, [9.7, -13.0]) for p in track.left_boundary)
    assert any(np.allclose(p, [10.3, -17.0]) for p in track.right_boundary)


def test_stadium_length(stadium) -> None:
    """Two 60 m straights and a 15 m radius: 120 + 2 pi 15 = 214.2 m within 0.5 m."""
    track = stadium()
    assert track.length_m == pytest.approx(120.0 + 2 * math.pi * 15.0, abs=0.5)
    assert_allclose(track.widths, 4.0, atol=0.1)


def test_open_lane_with_braking_zone_and_two_timing_lines() -> None:
    """fssim-style acceleration: orange braking zone joins the boundaries, 75 m timed."""
    cones, kinds = [], []
    for x in range(5, 71, 5):
        cones += [[x, 1.9], [x, -1.9]]
        kinds += [ConeKind.BLUE, ConeKind.YELLOW]
    for x in range(80, 176, 5):
        cones += [[x, 1.9], [x, -1.9]]
        kinds += [ConeKind.ORANGE] * 2
    cones.append([175.0, 0.0])  # fssim's end-of-lane cone on the centreline: no boundary
    kinds.append(ConeKind.ORANGE)
    for line_x in (-0.3, 0.3, 74.7, 75.3):
        cones += [[line_x, 1.9], [line_x, -1.9]]
        kinds += [ConeKind.BIG_ORANGE] * 2
    track = Track("acc", np.array(cones, float), tuple(kinds), Pose2D(-2.0, 0.0, 0.0), Layout.OPEN)
    assert_allclose(track.centreline[[0, -1]], [[-0.3, 0.0], [175.0, 0.0]], atol=0.01)
    assert track.length_m == pytest.approx(175.3, abs=0.01)
    assert_allclose(track.start_finish, [[0.0, 1.9], [0.0, -1.9]], atol=1e-9)
    assert_allclose(track.finish_line, [[75.0, 1.9], [75.0, -1.9]], atol=1e-9)
    assert len(track.left_boundary) == 14 + 20 + 4
    assert not any(np.allclose(p, [175.0, 0.0]) for p in track.right_boundary)


def test_open_lane_without_a_finish_line_finishes_at_its_end() -> None:
    """Only the start's big orange cones: the finish is 1 m before the
    lane's end (x = 99 m on a lane to 100 m), and the validator says so."""
    from conesim.tracks import check_report

    cones, kinds = [], []
    for x in range(5, 101, 5):
        cones += [[x, 1.9], [x, -1.9]]
        kinds += [ConeKind.BLUE, ConeKind.YELLOW]
    for line_x in (-0.3, 0.3):
        cones += [[line_x, 1.9], [line_x, -1.9]]
        kinds += [ConeKind.BIG_ORANGE] * 2
    track = Track("lane", np.array(cones, float), tuple(kinds), Pose2D(-2.0, 0.0, 0.0), Layout.OPEN)
    assert_allclose(track.start_finish, [[0.0, 1.9], [0.0, -1.9]], atol=1e-9)
    assert_allclose(track.finish_line, [[99.0, 1.9], [99.0, -1.9]], atol=1e-9)
    warnings = check_report(track)["warnings"]
    assert any("no second line of big orange cones" in w and "1 m before" in w for w in warnings)


def test_skidpad_circles_and_centreline(skidpad) -> None:
    """FS skidpad: circles r 9.125 m, 18.25 m apart; right circle first, clockwise."""
    track = skidpad()
    assert track.geometry.circles is not None
    right, left = track.geometry.circles
    assert_allclose(right.centre, [0.0, -9.125], atol=1e-6)
    assert_allclose(left.centre, [0.0, 9.125], atol=1e-6)
    assert right.radius == pytest.approx(9.125, abs=1e-6)
    assert right.width == pytest.approx(3.0, abs=1e-6)
    entry, loop, exit_ = 16.5, 2 * math.pi * 9.125, 21.0
    assert track.length_m == pytest.approx(entry + 2 * loop + exit_, abs=0.01)
    c = track.centreline
    s = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(c, axis=0).T))])

    def at(arc: float) -> list[float]:
        return [float(np.interp(arc, s, c[:, 0])), float(np.interp(arc, s, c[:, 1]))]

    assert_allclose(at(entry + loop / 4), [9.125, -9.125], atol=0.01)  # right circle, clockwise
    assert_allclose(at(entry + loop + loop / 4), [9.125, 9.125], atol=0.01)  # left, counter-cw
    assert_allclose(c[[0, -1]], [[-16.5, 0.0], [21.0, 0.0]], atol=0.01)
    assert_allclose(track.start_finish, [[0.0, 2.0], [0.0, -2.0]], atol=1e-9)
    lane = track.widths[: int(10 / 0.5)]
    assert_allclose(lane, 3.0, atol=1e-9)


def test_orientation_from_colours_without_start_pose(circle) -> None:
    """No start pose: the direction that puts blue on the left (counter-clockwise here)."""
    track = circle()
    geometry = build_geometry(track.cones, track.kinds, Layout.CLOSED, None)
    x, y = geometry.centreline.T
    assert 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y)) > 0


def test_derive_start_pose_from_big_orange(stadium) -> None:
    """At the middle of the start line, heading along the track."""
    track = stadium()
    pose = derive_start_pose(track.cones, track.kinds, Layout.CLOSED)
    assert (pose.x, pose.y) == pytest.approx((10.0, -15.0), abs=1e-9)
    assert pose.yaw == pytest.approx(0.0, abs=1e-3)


def test_detect_layout(circle, lane, skidpad) -> None:
    """Closed loop, open lane and skidpad are told apart from the cones alone."""
    for factory, expected in (
        (circle, Layout.CLOSED),
        (lane, Layout.OPEN),
        (skidpad, Layout.SKIDPAD),
    ):
        track = factory()
        assert detect_layout(track.cones, track.kinds) == expected


def test_counts_and_grouping(stadium) -> None:
    """counts() covers every kind; cones are stored grouped by kind in ConeKind order."""
    track = stadium()
    counts = track.counts()
    assert list(counts) == list(ConeKind)
    assert counts[ConeKind.BIG_ORANGE] == 4 and counts[ConeKind.UNKNOWN] == 0
    assert sum(counts.values()) == len(track.cones)
    rank = [list(ConeKind).index(k) for k in track.kinds]
    assert rank == sorted(rank)


def test_track_is_immutable(stadium) -> None:
    """Frozen fields, read-only cones and derived arrays."""
    track = stadium()
    with pytest.raises(dataclasses.FrozenInstanceError):
        track.name = "other"  # type: ignore[misc,unused-ignore]
    for array in (
        track.cones,
        track.centreline,
        track.widths,
        track.left_boundary,
        track.start_finish,
    ):
        with pytest.raises(ValueError, match="read-only"):
            array[0] = 0.0


def test_bad_track_arguments_raise_track_format_error() -> None:
    """Shape, NaN, kinds and layout are checked at construction."""
    from conesim.tracks import TrackFormatError

    pose = Pose2D(0.0, 0.0, 0.0)
    with pytest.raises(TrackFormatError, match=r"\(n, 2\)"):
        Track("t", np.zeros((3, 3)), (ConeKind.BLUE,) * 3, pose)
    with pytest.raises(TrackFormatError, match="finite"):
        Track("t", np.array([[np.nan, 0.0]]), (ConeKind.BLUE,), pose)
    with pytest.raises(TrackFormatError, match="kinds"):
        Track("t", np.zeros((2, 2)), (ConeKind.BLUE,), pose)
    with pytest.raises(TrackFormatError, match="purple"):
        Track("t", np.zeros((1, 2)), ("purple",), pose)  # type: ignore[arg-type]
    with pytest.raises(TrackFormatError, match="oval"):
        Track("t", np.zeros((1, 2)), (ConeKind.BLUE,), pose, "oval")  # type: ignore[arg-type]


def test_pickle_round_trip(skidpad) -> None:
    """A track (with its derived geometry) survives pickling, still read-only."""
    import pickle

    track = skidpad()
    _ = track.centreline
    back = pickle.loads(pickle.dumps(track))
    assert back == track
    assert "geometry" in back.__dict__  # not derived again
    np.testing.assert_array_equal(back.centreline, track.centreline)
    assert not back.cones.flags.writeable and not back.centreline.flags.writeable
    assert back.geometry.circles is not None
    assert not back.geometry.circles[0].centre.flags.writeable
