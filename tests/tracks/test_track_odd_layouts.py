"""Derived geometry where layouts are odd: a gate wider than the lane, a repeated
first cone, a missing cone (issue 15, part 2)."""

from __future__ import annotations

import numpy as np
import pytest
from numpy.testing import assert_allclose

from conesim.core.pose import Pose2D
from conesim.tracks import ConeKind, Layout, Track, check_report
from conesim.tracks.global_path import global_path_for_track
from tests.tracks.conftest import stadium_points

RADIUS = 15.0  # [m] the stadium's centre radius
HALF = 1.5  # [m] half of its 3 m lane
GATE_X = 10.0  # [m] the start/finish line crosses the bottom straight here


def gate_stadium(gate_half: float, keep_line_cones: bool = True, half: float = HALF) -> Track:
    """A ``2 half`` (3 m) wide counter-clockwise stadium (60 m straights, R 15 m),
    blue inside, cones 3 m apart, and four big orange cones at x = 10 +- 0.3
    standing ``gate_half`` [m] either side of the centreline (1.5: on the edges)."""
    left = stadium_points(60.0, RADIUS - half, 3.0)
    right = stadium_points(60.0, RADIUS + half, 3.0)
    if not keep_line_cones:  # the edge cones at the line give way to the gate
        left = left[np.abs(left[:, 0] - GATE_X) > 1.0]
        right = right[np.abs(right[:, 0] - GATE_X) > 1.0]
    y_l, y_r = -RADIUS + gate_half, -RADIUS - gate_half
    gate = np.array([[9.7, y_l], [10.3, y_l], [9.7, y_r], [10.3, y_r]])
    kinds = [ConeKind.BLUE] * len(left) + [ConeKind.YELLOW] * len(right)
    return Track(
        "gate",
        np.vstack([left, right, gate]),
        (*kinds, *[ConeKind.BIG_ORANGE] * 4),
        Pose2D(6.0, -RADIUS, 0.0),
        Layout.CLOSED,
    )


def near_gate(track: Track, within: float = 5.0) -> np.ndarray:
    """Mask of the centreline points within ``within`` [m] of the line's middle."""
    return np.hypot(*(track.centreline - [GATE_X, -RADIUS]).T) < within


@pytest.mark.parametrize("gate_half", [1.5, 1.9, 2.2, 2.5])
@pytest.mark.parametrize("keep_line_cones", [True, False])
def test_gate_wider_than_the_lane_leaves_it_straight(gate_half: float, keep_line_cones) -> None:
    """A 3 m lane with gate cones at +-1.5 to +-2.5 m: the lane stays 3 m wide
    (>= 2.9 m) and straight (|curvature| < 0.01 1/m, y = -15 m within 1 cm) at the gate."""
    track = gate_stadium(gate_half, keep_line_cones)
    near = near_gate(track)
    assert near.sum() > 10
    assert track.widths.min() >= 2.9
    assert_allclose(track.widths[near], 3.0, atol=0.05)
    assert np.abs(track.geometry.curvature[near]).max() < 0.01
    assert_allclose(track.centreline[near, 1], -RADIUS, atol=0.01)
    # the start/finish line runs between the gate's cones, at x = 10
    assert_allclose(track.start_finish, [[10.0, -RADIUS + gate_half], [10.0, -RADIUS - gate_half]])


@pytest.mark.parametrize("gate_half", [2.0, 2.3, 2.6])
def test_gate_wider_than_the_lane_gives_no_findings(gate_half: float) -> None:
    """``track check`` finds nothing at a wide gate of a 3.2 m lane (a 3 m one is
    measured 2 mm narrow in its bends): no narrow place, no tight turn."""
    report = check_report(gate_stadium(gate_half, half=1.6))
    assert report["warnings"] == [] and report["errors"] == []
    assert report["width_min_m"] == pytest.approx(3.2, abs=0.05)


def test_global_path_is_smooth_through_a_wide_gate() -> None:
    """The path derived for the car runs straight through the gate: within 1 cm of
    y = -15 m for 5 m either side of the line."""
    track = gate_stadium(2.5)
    xy = global_path_for_track(track).xy
    near = np.hypot(*(xy - [GATE_X, -RADIUS]).T) < 5.0
    assert_allclose(xy[near, 1], -RADIUS, atol=0.01)


@pytest.mark.parametrize("offset", [0.0, 0.02])
def test_repeated_first_cone_is_one_cone(offset: float) -> None:
    """A layout that lists its first blue and yellow cones again at the end (or 2 cm
    off) derives the same centreline as without the repeats, to 1 mm."""
    base = gate_stadium(2.3, half=1.6)
    blue, yellow = base.cones_of(ConeKind.BLUE), base.cones_of(ConeKind.YELLOW)
    gate = base.cones_of(ConeKind.BIG_ORANGE)
    repeated = Track(
        "repeated",
        np.vstack([blue, blue[:1] + offset, yellow, yellow[:1] - offset, gate]),
        (*[ConeKind.BLUE] * (len(blue) + 1), *[ConeKind.YELLOW] * (len(yellow) + 1),
         *[ConeKind.BIG_ORANGE] * 4),
        base.start_pose,
        Layout.CLOSED,
    )  # fmt: skip
    assert len(repeated.left_boundary) == len(base.left_boundary)
    assert repeated.length_m == pytest.approx(base.length_m, abs=1e-3)
    assert_allclose(repeated.centreline, base.centreline, atol=1e-3)
    assert check_report(repeated)["warnings"] == []


@pytest.mark.parametrize("where", ["straight", "bend"])
def test_missing_cone_is_interpolated(where: str) -> None:
    """One blue cone taken out of a straight or the middle of a bend: the centreline
    moves less than 5 cm and its curvature stays that of the stadium (within
    0.01 1/m of 0 or 1/15) where it was; the validator names the gap, nothing else."""
    base = gate_stadium(2.3, half=1.6)
    blue = base.cones_of(ConeKind.BLUE)
    target = [30.0, -RADIUS + 1.6] if where == "straight" else [60.0 + RADIUS - 1.6, 0.0]
    gone = int(np.argmin(np.hypot(*(blue - target).T)))
    others = [base.cones_of(k) for k in (ConeKind.YELLOW, ConeKind.BIG_ORANGE)]
    track = Track(
        "missing",
        np.vstack([np.delete(blue, gone, axis=0), *others]),
        (*[ConeKind.BLUE] * (len(blue) - 1), *[ConeKind.YELLOW] * len(others[0]),
         *[ConeKind.BIG_ORANGE] * 4),
        base.start_pose,
        Layout.CLOSED,
    )  # fmt: skip
    moved = np.hypot(*(track.centreline[:, None] - base.centreline[None]).T).min(axis=0)
    assert moved.max() < 0.05
    kappa = np.abs(track.geometry.curvature)
    near = np.hypot(*(track.centreline - target).T) < 5.0
    expected = 0.0 if where == "straight" else 1.0 / RADIUS
    assert_allclose(kappa[near], expected, atol=0.01)
    assert kappa.max() < 1 / RADIUS + 0.01
    warnings = check_report(track)["warnings"]
    assert len(warnings) == 1 and "gaps between cones exceed" in warnings[0]
