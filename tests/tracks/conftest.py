"""Synthetic tracks with known geometry, shared by the tracks tests."""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
import pytest
from numpy.typing import NDArray

from conesim.core.pose import Pose2D
from conesim.tracks import ConeKind, Layout, Track

FloatArray = NDArray[np.float64]


def ring_points(radius: float, spacing: float, phase: float = 0.0) -> FloatArray:
    """Points every ~``spacing`` [m] round a circle of ``radius`` [m] at the origin."""
    count = round(2 * math.pi * radius / spacing)
    angle = phase + np.arange(count) * 2 * math.pi / count
    return radius * np.column_stack([np.cos(angle), np.sin(angle)])


def stadium_points(straight: float, radius: float, spacing: float) -> FloatArray:
    """A stadium loop, counter-clockwise from (0, -radius): straights along y = +-radius
    from x = 0 to ``straight``, semicircles at both ends; points about ``spacing`` apart."""
    pts = []
    n_straight = max(1, math.ceil(straight / spacing))
    n_arc = max(2, math.ceil(math.pi * radius / spacing))
    for x in np.linspace(0.0, straight, n_straight, endpoint=False):
        pts.append((x, -radius))
    for a in np.linspace(-math.pi / 2, math.pi / 2, n_arc, endpoint=False):
        pts.append((straight + radius * math.cos(a), radius * math.sin(a)))
    for x in np.linspace(straight, 0.0, n_straight, endpoint=False):
        pts.append((x, radius))
    for a in np.linspace(math.pi / 2, 3 * math.pi / 2, n_arc, endpoint=False):
        pts.append((radius * math.cos(a), radius * math.sin(a)))
    return np.array(pts)


def make_stadium(
    straight: float = 60.0,
    *,
    radius: float = 15.0,
    width: float = 4.0,
    spacing: float = 4.0,
    big_orange: bool = True,
    start: Pose2D | None = None,
) -> Track:
    """A counter-clockwise stadium track (blue inside), start line at x = 10 on the
    bottom straight: FS-clean with the defaults (214 m, 4 m wide, R 15 m turns)."""
    left = stadium_points(straight, radius - width / 2, spacing)
    right = stadium_points(straight, radius + width / 2, spacing)
    keep_l = np.hypot(left[:, 0] - 10.0, left[:, 1] + radius) > 1.0
    keep_r = np.hypot(right[:, 0] - 10.0, right[:, 1] + radius) > 1.0
    cones = [left[keep_l], right[keep_r]]
    kinds = [ConeKind.BLUE] * int(keep_l.sum()) + [ConeKind.YELLOW] * int(keep_r.sum())
    if big_orange:
        y_l, y_r = -radius + width / 2, -radius - width / 2
        cones.append(np.array([[9.7, y_l], [10.3, y_l], [9.7, y_r], [10.3, y_r]]))
        kinds += [ConeKind.BIG_ORANGE] * 4
    pose = start if start is not None else Pose2D(6.0, -radius, 0.0)
    return Track("stadium", np.vstack(cones), tuple(kinds), pose, Layout.CLOSED)


def make_circle(
    r_inner: float = 20.0, r_outer: float = 24.0, spacing: float = 3.0, clockwise: bool = False
) -> Track:
    """A circular track; counter-clockwise puts blue inside, clockwise outside."""
    inner, outer = ring_points(r_inner, spacing), ring_points(r_outer, spacing, phase=0.05)
    blue, yellow = (outer, inner) if clockwise else (inner, outer)
    mid = 0.5 * (r_inner + r_outer)
    yaw = -math.pi / 2 if clockwise else math.pi / 2
    kinds = (ConeKind.BLUE,) * len(blue) + (ConeKind.YELLOW,) * len(yellow)
    return Track("circle", np.vstack([blue, yellow]), kinds, Pose2D(mid, 0.0, yaw))


def make_lane(length: float = 50.0, half_width: float = 2.0, spacing: float = 5.0) -> Track:
    """A straight open lane along +x from x = 0 to ``length``."""
    x = np.arange(0.0, length + 1e-9, spacing)
    cones = np.vstack(
        [
            np.column_stack([x, np.full_like(x, half_width)]),
            np.column_stack([x, np.full_like(x, -half_width)]),
        ]
    )
    kinds = (ConeKind.BLUE,) * len(x) + (ConeKind.YELLOW,) * len(x)
    return Track("lane", cones, kinds, Pose2D(1.0, 0.0, 0.0), Layout.OPEN)


def make_skidpad(
    centre_distance: float = 18.25, d_inner: float = 15.25, d_outer: float = 21.25
) -> Track:
    """The FS skidpad with cone centres on the FS circles (REFERENCES.md), entry along +x."""
    half, r_in, r_out = centre_distance / 2, d_inner / 2, d_outer / 2
    cones, kinds = [], []
    for cy, inner, outer in (
        (-half, ConeKind.YELLOW, ConeKind.BLUE),
        (half, ConeKind.BLUE, ConeKind.YELLOW),
    ):
        for r, kind in ((r_in, inner), (r_out, outer)):
            for a in np.arange(16) * 2 * math.pi / 16 + math.pi / 2:
                p = np.array([r * math.cos(a), cy + r * math.sin(a)])
                if kind == outer and math.hypot(p[0], p[1] + cy) < r_out + 0.5:
                    continue
                cones.append(p)
                kinds.append(kind)
    for x in (-15.0, -11.25, 11.0, 16.0, 21.0):
        cones += [np.array([x, 1.5]), np.array([x, -1.5])]
        kinds += [ConeKind.ORANGE, ConeKind.ORANGE]
    for x in (-1.3, 1.3):
        cones += [np.array([x, 2.0]), np.array([x, -2.0])]
        kinds += [ConeKind.BIG_ORANGE, ConeKind.BIG_ORANGE]
    return Track("skidpad", np.array(cones), tuple(kinds), Pose2D(-16.5, 0.0, 0.0), Layout.SKIDPAD)


@pytest.fixture
def stadium() -> Callable[..., Track]:
    """Factory of stadium tracks (see ``make_stadium``)."""
    return make_stadium


@pytest.fixture
def circle() -> Callable[..., Track]:
    """Factory of circular tracks (see ``make_circle``)."""
    return make_circle


@pytest.fixture
def lane() -> Callable[..., Track]:
    """Factory of straight open lanes (see ``make_lane``)."""
    return make_lane


@pytest.fixture
def skidpad() -> Callable[..., Track]:
    """Factory of skidpads (see ``make_skidpad``)."""
    return make_skidpad


@pytest.fixture
def points() -> Callable[..., FloatArray]:
    """Factory of stadium-shaped point loops (see ``stadium_points``)."""
    return stadium_points
