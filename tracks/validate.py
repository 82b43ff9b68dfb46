"""Checking a track against the Formula Student rules and for drivability.

Formula Student figures (REFERENCES.md, "Formula Student tracks") are
WARNINGS: organisers bend them and a simulator can still run the track.
Geometry that cannot be driven is an ERROR: too few cones for a boundary,
boundaries or centreline that cross, a start pose off the track, blue cones
on the right of the driving direction, or cones from which no geometry can be
derived. (A track always has a start pose: readers derive one from the big
orange cones or refuse the file with "no start pose".)

Warnings (closed = loop; open = lane; skidpad):

* width >= 3 m (all), to ``WIDTH_TOLERANCE_M`` (3 cm) of the derivation;
* cone spacing along a boundary <= 5 m (closed, open);
* big orange cones at the start/finish line (all); open: a second line
  75 m after the start (acceleration);
* lap length 200-500 m (closed);
* straights <= 80 m (closed);
* constant turns <= 50 m diameter (closed);
* hairpins >= 9 m outside diameter, checked as the tightest point of any turn
  (closed, open);
* skidpad: inner/outer circle diameters 15.25 / 21.25 m and centres 18.25 m
  apart, within 0.5 m (cone centres stand ~0.15 m off the lines, as in fssim);
* cones of unknown colour present (all).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray
from scipy.ndimage import uniform_filter1d

from conesim.core.polyline import Polyline
from conesim.tracks.derived import TrackGeometry
from conesim.tracks.errors import TrackFormatError
from conesim.tracks.global_path import global_path_findings, global_path_for_track
from conesim.tracks.kinds import ConeKind, Layout
from conesim.tracks.lanes import LANE_END_FINISH_M, MIN_SIDE_CONES
from conesim.tracks.model import Track

FloatArray = NDArray[np.float64]

# FS figures, REFERENCES.md "Formula Student tracks".
MIN_WIDTH_M = 3.0
MAX_CONE_SPACING_M = 5.0
MIN_LAP_M, MAX_LAP_M = 200.0, 500.0
MAX_STRAIGHT_M = 80.0
MAX_CONSTANT_TURN_DIAMETER_M = 50.0
MIN_HAIRPIN_OUTSIDE_DIAMETER_M = 9.0
SKIDPAD_INNER_DIAMETER_M = 15.25
SKIDPAD_OUTER_DIAMETER_M = 21.25
SKIDPAD_CENTRE_DISTANCE_M = 18.25
ACCELERATION_LENGTH_M = 75.0  # REFERENCES.md: "Acceleration: 75 m timed"
# Our tolerances and definitions.
SKIDPAD_TOLERANCE_M = 0.5
ACCELERATION_TOLERANCE_M = 1.0
STRAIGHT_CURVATURE = 1.0 / 150.0  # [1/m] gentler than a 150 m radius counts as straight
CONSTANT_TURN_MIN_ANGLE = math.pi / 2  # [rad] a turn this long is a "constant turn"
CURVATURE_WINDOW_M = 2.0  # [m] curvature is averaged over this much centreline
# The width is measured between splines through the cones, which run up to 2-3 cm
# inside the lane where its curvature changes fast (an S-bend's change of
# direction): a lane laid out 3.00 m wide is not narrow for that.
WIDTH_TOLERANCE_M = 0.03


@dataclass
class ValidationReport:
    """Findings of `validate_track`.

    Attributes:
        warnings: Formula Student rules the track bends.
        errors: problems that make the track undrivable.
    """

    warnings: list[str] = field(default_factory=list)
    errors: list[str] = field(default_factory=list)

    @property
    def ok(self) -> bool:
        """True when there are no errors."""
        return not self.errors


def validate_track(track: Track) -> ValidationReport:
    """Check ``track`` against the FS rules (warnings) and for drivability (errors)."""
    report = ValidationReport()
    counts = track.counts()
    for kind, side in ((ConeKind.BLUE, "left"), (ConeKind.YELLOW, "right")):
        if counts[kind] < MIN_SIDE_CONES:
            report.errors.append(
                f"no {side} boundary: {counts[kind]} {kind} cones "
                f"(at least {MIN_SIDE_CONES} needed)"
            )
    if report.errors:
        return report
    try:
        geometry = track.geometry
    except TrackFormatError as exc:
        report.errors.append(f"cannot derive the track geometry: {exc.reason}")
        return report
    if counts[ConeKind.UNKNOWN]:
        report.warnings.append(f"{counts[ConeKind.UNKNOWN]} cones of unknown colour")
    _check_width(geometry, report)
    _check_timing_cones(track, geometry, report)
    if track.layout == Layout.SKIDPAD:
        _check_skidpad(geometry, report)
    else:
        _check_spacing(geometry, report)
        _check_tightest_turn(geometry, report)
        _check_crossings(geometry, report)
        _check_colours(track, geometry, report)
    if track.layout == Layout.CLOSED:
        _check_lap_length(geometry, report)
        _check_straights(geometry, report)
        _check_constant_turns(geometry, report)
    _check_start_pose(track, geometry, report)
    return report


def check_report(track: Track) -> dict[str, Any]:
    """The validator's findings as one JSON-able dict, the global path's included.

    The track's global path (``global_path_for_track``) is checked against
    the track too (``global_path_findings``); a track whose geometry cannot
    be derived has no path to check (its errors say why).

    Raises:
        GlobalPathError: the track's global path file is malformed.

    Returns:
        ``{"cones": {"blue": n, "yellow": n, "orange": n, "big_orange": n,
        "unknown": n}, "length_m": x, "width_min_m": x, "width_max_m": x,
        "warnings": [...], "errors": [...]}``; lengths in metres, rounded to
        1 mm (NaN when no geometry can be derived: see ``errors``).
    """
    report = validate_track(track)
    warnings, errors = list(report.warnings), list(report.errors)
    try:
        path = global_path_for_track(track)
    except TrackFormatError:
        pass
    else:
        path_warnings, path_errors = global_path_findings(track, path)
        warnings += path_warnings
        errors += path_errors
    try:
        geometry = track.geometry
        length, w_min, w_max = geometry.length_m, geometry.widths.min(), geometry.widths.max()
    except TrackFormatError:
        length = w_min = w_max = math.nan
    return {
        "cones": {str(kind): n for kind, n in track.counts().items()},
        "length_m": round(float(length), 3),
        "width_min_m": round(float(w_min), 3),
        "width_max_m": round(float(w_max), 3),
        "warnings": warnings,
        "errors": errors,
    }


def _at(geometry: TrackGeometry, index: int) -> str:
    """Where centreline point ``index`` is, for messages."""
    x, y = geometry.centreline[index]
    along = index * geometry.length_m / max(len(geometry.centreline), 1)
    return f"{along:.0f} m along the track ({x:.1f}, {y:.1f})"


def _check_width(geometry: TrackGeometry, report: ValidationReport) -> None:
    i = int(np.argmin(geometry.widths))
    if geometry.widths[i] < MIN_WIDTH_M - WIDTH_TOLERANCE_M:
        report.warnings.append(
            f"track width {geometry.widths[i]:.2f} m at {_at(geometry, i)} is below the FS "
            f"minimum of {MIN_WIDTH_M:g} m"
        )


def _check_spacing(geometry: TrackGeometry, report: ValidationReport) -> None:
    for side, cones in (("left", geometry.left_boundary), ("right", geometry.right_boundary)):
        pts = Polyline(cones, geometry.closed).ring
        gaps = np.hypot(*np.diff(pts, axis=0).T)
        wide = gaps > MAX_CONE_SPACING_M + 1e-6
        if wide.any():
            i = int(np.argmax(gaps))
            x, y = 0.5 * (pts[i] + pts[i + 1])
            report.warnings.append(
                f"{side} boundary: {int(wide.sum())} gaps between cones exceed the FS maximum "
                f"of {MAX_CONE_SPACING_M:g} m (largest {gaps[i]:.2f} m near ({x:.1f}, {y:.1f}))"
            )


def _check_timing_cones(track: Track, geometry: TrackGeometry, report: ValidationReport) -> None:
    if track.counts()[ConeKind.BIG_ORANGE] == 0:
        report.warnings.append(
            "no big orange cones: FS marks the start/finish line with 4 (some layouts 2)"
        )
        return
    if track.layout != Layout.OPEN:
        return
    big = track.cones_of(ConeKind.BIG_ORANGE)
    finish = geometry.finish_line
    if len(geometry.timing_lines) < 2 or _near_line(big, finish) < 2:
        report.warnings.append(
            f"open track: no second line of big orange cones (acceleration: the finish "
            f"{ACCELERATION_LENGTH_M:g} m after the start); the run finishes "
            f"{LANE_END_FINISH_M:g} m before the lane's end"
        )
        return
    start, finish = (line.mean(axis=0) for line in (geometry.start_finish, geometry.finish_line))
    s = Polyline(geometry.centreline).project(np.vstack([start, finish])).station
    timed = float(s[1] - s[0])
    if abs(timed - ACCELERATION_LENGTH_M) > ACCELERATION_TOLERANCE_M:
        report.warnings.append(
            f"open track: start and finish lines are {timed:.1f} m apart, FS acceleration "
            f"is timed over {ACCELERATION_LENGTH_M:g} m"
        )


def _near_line(points: FloatArray, line: FloatArray, within: float = 1.0) -> int:
    """How many points lie within ``within`` [m] of the segment ``line`` (2, 2)."""
    foot = Polyline(line).project(points).foot
    return int(np.count_nonzero(np.hypot(*(points - foot).T) <= within))


def _check_lap_length(geometry: TrackGeometry, report: ValidationReport) -> None:
    if not MIN_LAP_M <= geometry.length_m <= MAX_LAP_M:
        report.warnings.append(
            f"lap length {geometry.length_m:.1f} m is outside the FS range "
            f"{MIN_LAP_M:g}-{MAX_LAP_M:g} m"
        )


def _smoothed_curvature(geometry: TrackGeometry) -> FloatArray:
    step = geometry.length_m / max(len(geometry.centreline), 1)
    size = max(1, round(CURVATURE_WINDOW_M / step))
    mode = "wrap" if geometry.closed else "nearest"
    return np.asarray(uniform_filter1d(geometry.curvature, size, mode=mode), dtype=float)


def _runs(mask: NDArray[np.bool_], closed: bool) -> list[NDArray[np.intp]]:
    """Index runs where ``mask`` holds (a loop joins a run across its start)."""
    if mask.all():
        return [np.arange(len(mask))]
    shift = int(np.argmin(mask)) if closed else 0
    rolled = np.roll(mask, -shift)
    index = np.roll(np.arange(len(mask)), -shift)
    edges = np.flatnonzero(np.diff(np.concatenate([[0], rolled.astype(int), [0]])))
    return [index[a:b] for a, b in zip(edges[::2], edges[1::2], strict=True)]


def _check_straights(geometry: TrackGeometry, report: ValidationReport) -> None:
    kappa = _smoothed_curvature(geometry)
    step = geometry.length_m / len(kappa)
    runs = _runs(np.abs(kappa) < STRAIGHT_CURVATURE, geometry.closed)
    longest = max(runs, key=len, default=np.zeros(0, dtype=np.intp))
    if len(longest) * step > MAX_STRAIGHT_M:
        report.warnings.append(
            f"straight of {len(longest) * step:.0f} m from {_at(geometry, int(longest[0]))} "
            f"is longer than the FS maximum of {MAX_STRAIGHT_M:g} m"
        )


def _check_constant_turns(geometry: TrackGeometry, report: ValidationReport) -> None:
    kappa = _smoothed_curvature(geometry)
    step = geometry.length_m / len(kappa)
    for sign in (1.0, -1.0):
        for run in _runs(sign * kappa >= STRAIGHT_CURVATURE, geometry.closed):
            angle = float(np.abs(kappa[run]).sum() * step)
            if angle < CONSTANT_TURN_MIN_ANGLE:
                continue
            diameter = 2.0 * len(run) * step / angle
            if diameter > MAX_CONSTANT_TURN_DIAMETER_M:
                report.warnings.append(
                    f"constant turn of {math.degrees(angle):.0f} deg at "
                    f"{_at(geometry, int(run[0]))} has a {diameter:.0f} m diameter, "
                    f"above the FS maximum of {MAX_CONSTANT_TURN_DIAMETER_M:g} m"
                )


def _check_tightest_turn(geometry: TrackGeometry, report: ValidationReport) -> None:
    kappa = np.abs(_smoothed_curvature(geometry))
    outside = 2.0 * (1.0 / np.maximum(kappa, 1e-9) + 0.5 * geometry.widths)
    i = int(np.argmin(outside))
    if outside[i] < MIN_HAIRPIN_OUTSIDE_DIAMETER_M:
        report.warnings.append(
            f"turn at {_at(geometry, i)} has a {outside[i]:.1f} m outside diameter, below the FS "
            f"hairpin minimum of {MIN_HAIRPIN_OUTSIDE_DIAMETER_M:g} m"
        )


def _check_skidpad(geometry: TrackGeometry, report: ValidationReport) -> None:
    assert geometry.circles is not None
    right, left = geometry.circles
    checks = [
        (
            "centre distance",
            float(np.hypot(*(right.centre - left.centre))),
            SKIDPAD_CENTRE_DISTANCE_M,
        ),
    ]
    for name, circle in (("right", right), ("left", left)):
        checks.append(
            (f"{name} inner circle diameter", 2 * circle.r_inner, SKIDPAD_INNER_DIAMETER_M)
        )
        checks.append(
            (f"{name} outer circle diameter", 2 * circle.r_outer, SKIDPAD_OUTER_DIAMETER_M)
        )
    for what, value, expected in checks:
        if abs(value - expected) > SKIDPAD_TOLERANCE_M:
            report.warnings.append(
                f"skidpad {what} is {value:.2f} m, FS: {expected:g} m (+-{SKIDPAD_TOLERANCE_M:g} m)"
            )


def _check_crossings(geometry: TrackGeometry, report: ValidationReport) -> None:
    closed = geometry.closed
    left, right, centre = (
        Polyline(points, closed)
        for points in (geometry.left_boundary, geometry.right_boundary, geometry.centreline)
    )
    for what, found, where in (
        ("left boundary crosses itself", left.crossings(), left),
        ("right boundary crosses itself", right.crossings(), right),
        ("left and right boundaries cross", left.crossings(right), left),
        ("centreline crosses itself", centre.crossings(), centre),
    ):
        if found:
            x, y = where.points[found[0][0]]
            report.errors.append(f"{what} ({len(found)} crossings, first near ({x:.1f}, {y:.1f}))")


def _check_colours(track: Track, geometry: TrackGeometry, report: ValidationReport) -> None:
    centre = Polyline(geometry.centreline, geometry.closed)
    lateral = centre.project(track.cones_of(ConeKind.BLUE)).lateral
    if np.mean(lateral < 0) > 0.5:
        report.errors.append(
            "most blue cones lie on the right of the driving direction: the start pose faces "
            "the wrong way round the track, or blue and yellow are swapped"
        )


def _check_start_pose(track: Track, geometry: TrackGeometry, report: ValidationReport) -> None:
    pose = track.start_pose
    foot = Polyline(geometry.centreline, geometry.closed).project(pose.xy).foot
    i = int(np.argmin(np.hypot(*(geometry.centreline - foot[0]).T)))
    off = float(np.hypot(*(pose.xy - foot[0])))
    if off > 0.5 * geometry.widths[i]:
        report.errors.append(
            f"start pose ({pose.x:.2f}, {pose.y:.2f}) is outside the track: {off:.2f} m from "
            f"the centreline where the track is {geometry.widths[i]:.2f} m wide"
        )
