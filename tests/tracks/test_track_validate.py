"""The validator: a worked case for every rule, and the report's exact shape."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from conesim.core.polyline import Polyline
from conesim.core.pose import Pose2D
from conesim.tracks import ConeKind, Layout, Track, check_report, validate_track


def only(messages: list[str], fragment: str) -> str:
    """The one message containing ``fragment``."""
    found = [m for m in messages if fragment in m]
    assert len(found) == 1, messages
    return found[0]


def test_clean_track_has_no_findings(stadium) -> None:
    """214 m, 4 m wide, 15 m radius turns, 60 m straights, cones <= 4 m apart, 4 big orange."""
    report = validate_track(stadium())
    assert report.warnings == [] and report.errors == [] and report.ok


def test_width_below_3_m(stadium) -> None:
    """FS: width >= 3 m."""
    message = only(validate_track(stadium(width=2.8)).warnings, "track width")
    assert "2.8" in message and "below the FS minimum of 3 m" in message


def test_cone_spacing_above_5_m(stadium) -> None:
    """FS: cone spacing <= 5 m along a boundary."""
    report = validate_track(stadium(spacing=6.0))
    assert "exceed the FS maximum of 5 m" in only(report.warnings, "left boundary")
    assert "exceed the FS maximum of 5 m" in only(report.warnings, "right boundary")


def test_no_big_orange_cones(stadium) -> None:
    """FS: big orange cones at the start/finish line."""
    assert "no big orange cones" in only(
        validate_track(stadium(big_orange=False)).warnings, "big orange"
    )


def test_lap_length_outside_200_500_m(stadium) -> None:
    """FS: lap 200-500 m. 2 x 20 m + 2 pi 15 m = 134 m."""
    assert "lap length 134" in only(validate_track(stadium(straight=20.0)).warnings, "lap length")


def test_straight_longer_than_80_m(stadium) -> None:
    """FS: straights <= 80 m."""
    message = only(validate_track(stadium(straight=90.0)).warnings, "straight of")
    assert "longer than the FS maximum of 80 m" in message


def test_constant_turn_wider_than_50_m(stadium) -> None:
    """FS: constant turns <= 50 m diameter; each 30 m radius half circle is 60 m."""
    warnings = validate_track(stadium(straight=20.0, radius=30.0)).warnings
    turns = [m for m in warnings if m.startswith("constant turn")]
    assert len(turns) == 2
    for message in turns:
        assert "of 180 deg" in message and "above the FS maximum of 50 m" in message
        diameter = float(message.split("has a ")[1].split(" m")[0])
        assert diameter == pytest.approx(
            60.0, abs=3.0
        )  # the corner's entry and exit ramps add a little


def test_hairpin_tighter_than_9_m(stadium) -> None:
    """FS: hairpins >= 9 m outside diameter; radius 2.5 m + 3 m width gives 8 m."""
    track = stadium(radius=2.5, width=3.0, spacing=2.0)
    message = only(validate_track(track).warnings, "outside diameter")
    assert "below the FS hairpin minimum of 9 m" in message
    diameter = float(message.split("has a ")[1].split(" m")[0])
    assert diameter == pytest.approx(8.0, abs=0.6)


def test_unknown_cones(stadium) -> None:
    """Cones of unknown colour are reported."""
    base = stadium()
    track = Track(
        "t",
        np.vstack([base.cones, [[30.0, 0.0]]]),
        (*base.kinds, ConeKind.UNKNOWN),
        base.start_pose,
    )
    assert only(validate_track(track).warnings, "unknown") == "1 cones of unknown colour"


def test_no_left_boundary() -> None:
    """Two blue cones are no boundary: an error, not a crash."""
    cones = np.array([[0.0, 2.0], [5.0, 2.0], [0.0, -2.0], [5.0, -2.0], [10.0, -2.0]])
    kinds = (ConeKind.BLUE, ConeKind.BLUE, ConeKind.YELLOW, ConeKind.YELLOW, ConeKind.YELLOW)
    report = validate_track(Track("t", cones, kinds, Pose2D(1.0, 0.0, 0.0), Layout.OPEN))
    assert report.errors == ["no left boundary: 2 blue cones (at least 3 needed)"]
    assert check_report(Track("t", cones, kinds, Pose2D(1.0, 0.0, 0.0)))["errors"]


def test_crossing_boundaries(stadium) -> None:
    """A yellow cone put beyond the blue line makes the boundaries cross."""
    base = stadium()
    cones = base.cones.copy()
    yellow = [i for i, k in enumerate(base.kinds) if k == ConeKind.YELLOW]
    i = min(yellow, key=lambda j: np.hypot(*(cones[j] - [30.0, -17.0])))
    cones[i] = [30.0, -12.0]  # 1 m beyond the blue line at y = -13
    message = only(validate_track(Track("t", cones, base.kinds, base.start_pose)).errors, "cross")
    assert message.startswith("left and right boundaries cross")


def test_self_crossing_polyline() -> None:
    """A bow tie crosses itself once; a square does not."""
    bow = np.array([[0.0, 0.0], [1.0, 1.0], [1.0, 0.0], [0.0, 1.0]])
    square = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    assert Polyline(bow, True).crossings() == [(0, 2)]
    assert Polyline(square, True).crossings() == []
    shifted = Polyline(square + np.array([0.5, 0.5]), True)
    assert Polyline(square, True).crossings(shifted) == [(1, 0), (2, 3)]


def test_start_pose_outside_the_track(stadium) -> None:
    """10 m into the infield is not on a 4 m wide track."""
    message = only(validate_track(stadium(start=Pose2D(30.0, -5.0, 0.0))).errors, "start pose")
    assert message == (
        "start pose (30.00, -5.00) is outside the track: 10.00 m from the centreline "
        "where the track is 4.00 m wide"
    )


def test_start_pose_facing_backwards(stadium) -> None:
    """Driving clockwise puts the blue (inner) cones on the right: an error."""
    report = validate_track(stadium(start=Pose2D(6.0, -15.0, math.pi)))
    assert "blue cones lie on the right" in only(report.errors, "blue")


def test_geometry_that_cannot_be_derived(stadium) -> None:
    """A loop declared a skidpad: no rings, so no geometry: an error, NaN figures."""
    base = stadium()
    track = Track("t", base.cones, base.kinds, base.start_pose, Layout.SKIDPAD)
    report = check_report(track)
    assert report["errors"] == [
        "cannot derive the track geometry: skidpad: the blue and yellow cones do not form "
        "two pairs of concentric circles"
    ]
    assert math.isnan(report["length_m"])


def test_fs_skidpad_is_clean_and_a_wrong_one_warns(skidpad) -> None:
    """FS dimensions pass; centres 20 m apart and a 14 m inner circle do not."""
    assert validate_track(skidpad()).warnings == []
    warnings = validate_track(skidpad(centre_distance=20.0, d_inner=14.0)).warnings
    assert "skidpad centre distance is 20.00 m, FS: 18.25 m" in only(warnings, "centre distance")
    assert "14.00 m" in only(warnings, "right inner circle diameter")


def test_acceleration_finish_must_be_75_m_after_the_start() -> None:
    """Open track: a finish line 70 m after the start is not FS acceleration."""
    cones, kinds = [], []
    for x in range(5, 101, 5):
        cones += [[x, 1.9], [x, -1.9]]
        kinds += [ConeKind.BLUE, ConeKind.YELLOW]
    for line_x in (-0.3, 0.3, 69.7, 70.3):
        cones += [[line_x, 1.9], [line_x, -1.9]]
        kinds += [ConeKind.BIG_ORANGE] * 2
    track = Track("acc", np.array(cones, float), tuple(kinds), Pose2D(-1.0, 0.0, 0.0), Layout.OPEN)
    message = only(validate_track(track).warnings, "open track")
    assert "70.0 m apart" in message and "75 m" in message


def test_check_report_shape(stadium) -> None:
    """Exactly the documented keys, JSON-able, with the worked numbers."""
    report = check_report(stadium())
    assert list(report) == ["cones", "length_m", "width_min_m", "width_max_m", "warnings", "errors"]
    # blue: 2 straights x ceil(60 / 4) + 2 arcs x ceil(pi 13 / 4) = 30 + 22; yellow: 30 + 2 x 14
    assert report["cones"] == {"blue": 52, "yellow": 58, "orange": 0, "big_orange": 4, "unknown": 0}
    assert report["length_m"] == pytest.approx(214.2, abs=0.5)
    assert report["width_min_m"] == pytest.approx(4.0, abs=0.1)
    assert report["width_max_m"] == pytest.approx(4.0, abs=0.1)
    assert json.loads(json.dumps(report)) == report
