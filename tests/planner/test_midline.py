"""reference_path_planning: the midline of known tracks, poor detections, fallback, outputs.

"Within the true boundaries" is checked as: every path point, mapped to
``reference``, lies within ``width / 2`` of the true centreline. The measured
worst deviations are noted next to each bound.
"""

from __future__ import annotations

import dataclasses
from types import ModuleType

import numpy as np
import pytest
from numpy.testing import assert_allclose
from scipy.interpolate import splev, splprep

from conesim.core.messages import ConeDetections, Header
from conesim.core.polyline import Polyline
from conesim.core.pose import Pose2D
from conesim.localization.frames import Buffer
from conesim.planner import (
    LEFT,
    RIGHT,
    ClassifiedCones,
    ClassifierConfig,
    LocalPlan,
    MidlineConfig,
    PlanStatus,
    classify_cones_by_side,
    reference_path_planning,
)
from conesim.planner.spline import fit_path

# The Delaunay midline itself: the body's room in the lane (``planner.lane``)
# moves the path on purpose and is tested in test_lane.py.
MIDLINE = MidlineConfig(keep_in_lane=False)


def plan_scene(
    scene, classifier: ClassifierConfig | None = None, **kw
) -> tuple[LocalPlan, np.ndarray, ClassifiedCones]:
    """Classify and plan a scene; also the path in ``reference``."""
    cones = classify_cones_by_side(
        scene.detections, scene.buffer, scene.track.global_path, classifier
    )
    kw.setdefault("config", MIDLINE)
    plan = reference_path_planning(cones, scene.buffer, **kw)
    in_ref = scene.buffer.transform_points("reference", "os_sensor", plan.path, plan.header.stamp)
    return plan, in_ref, cones


def worst(track, in_ref: np.ndarray) -> float:
    """Largest distance of the path from the true centreline [m]."""
    return float(track.distance_to_centre(in_ref).max())


def followed(scene) -> tuple[LocalPlan, float]:
    """Plan ``scene``, which must plan OK: the plan, and its largest distance from the
    scene's true centreline [m]."""
    plan, in_ref, _ = plan_scene(scene)
    assert plan.status is PlanStatus.OK
    return plan, worst(scene.track, in_ref)


def ahead_of(pose: Pose2D, cones: np.ndarray, count: int, skip: int = 0) -> np.ndarray:
    """Indices of the ``count`` cones nearest in front of ``pose``, after ``skip``."""
    local = pose.inverse_transform_points(cones)
    dist = np.where(local[:, 0] > 0.0, np.hypot(*local.T), np.inf)
    return np.argsort(dist)[skip : skip + count]


# -- symmetric tracks: the midline is the centreline -------------------------------------------


def test_straight_midline_is_the_centreline(synth: ModuleType, straight) -> None:
    """On a straight the path is y = 0 exactly, every 0.5 m from the first rung ahead."""
    scene = synth.make_scene(straight, Pose2D(0.0, 0.0, 0.0))
    plan, in_ref, _ = plan_scene(scene)
    assert plan.status is PlanStatus.OK and plan.reason == ""
    assert_allclose(in_ref[:, 1], 0.0, atol=1e-9)
    assert_allclose(plan.midpoints, [[5.0, 0.0], [10.0, 0.0], [15.0, 0.0]], atol=1e-9)
    assert_allclose(np.hypot(*np.diff(plan.path, axis=0).T), 0.5, atol=1e-9)
    assert plan.header.frame_id == "os_sensor" and plan.header.stamp == scene.stamp


def test_speeds_hook_replaces_the_profile(synth: ModuleType, straight) -> None:
    """``speeds(path, s)`` gets the path and its arc length (0, 0.5, ..., 10 m on the
    straight) and its result becomes the waypoints' speeds; without it, the profile."""
    scene = synth.make_scene(straight, Pose2D(0.0, 0.0, 0.0))
    seen: list[tuple[np.ndarray, np.ndarray | None]] = []

    def speeds(path: np.ndarray, s: np.ndarray | None) -> np.ndarray:
        seen.append((path, s))
        return np.full(len(path), 7.0)

    plan, _, _ = plan_scene(scene, speeds=speeds)
    ((path, s),) = seen
    assert path is plan.path and s is not None
    assert_allclose(s, 0.5 * np.arange(len(path)), atol=1e-9)
    assert_allclose(s[-1], 10.0, atol=1e-9)
    assert_allclose(plan.speeds, 7.0)
    default, _, _ = plan_scene(scene, v_start=0.0)
    assert default.speeds[0] == 0.0 and default.speeds.max() > 0.0


@pytest.mark.parametrize("clockwise", [False, True])
@pytest.mark.parametrize(("lateral", "dyaw"), [(0.0, 0.0), (0.6, -0.15), (-0.4, 0.2)])
def test_circle_midline_within_2_cm(
    synth: ModuleType, clockwise: bool, lateral: float, dyaw: float
) -> None:
    """On a circle of R = 15 m the path stays within 2 cm of the centreline (measured 7 mm)."""
    track = synth.circle_track(clockwise=clockwise)
    scene = synth.make_scene(track, synth.pose_on(track, 37, lateral, dyaw))
    plan, off = followed(scene)
    assert plan.path[-1, 0] > 10.0  # the path reaches well ahead
    assert off < 0.02
    spacing = np.hypot(*np.diff(plan.path, axis=0).T)
    assert_allclose(spacing[:-1], 0.5, rtol=2e-3)


# -- poor detections: the path stays on the track ----------------------------------------------


@pytest.mark.parametrize("missing", [2, 3])
@pytest.mark.parametrize("side", ["left", "right"])
def test_gap_of_missing_cones(synth: ModuleType, circle, missing: int, side: str) -> None:
    """2-3 cones missing on one side: virtual partners fill the gap (measured 7 mm)."""
    pose = synth.pose_on(circle, 0)
    row = getattr(circle, side)
    kept = np.delete(row, ahead_of(pose, row, missing, skip=1), axis=0)
    scene = synth.make_scene(circle, pose, **{side: kept})
    plan, off = followed(scene)
    assert len(plan.virtual) >= missing - 1
    assert off < 0.03


@pytest.mark.parametrize("where", [(7.5, 0.0), (7.5, 0.8), (12.0, -0.6), (6.0, 0.2)])
def test_false_positive_inside_the_track(synth: ModuleType, straight, circle, where) -> None:
    """A ghost cone inside the track does not bend the path (measured 0-7 mm)."""
    for track, pose in ((straight, Pose2D(0.0, 0.0, 0.0)), (circle, synth.pose_on(circle, 0))):
        ghost = pose.transform_points(np.array([where]))
        # On the circle the track bends left: put the ghost at the same offset from
        # the centreline as on the straight.
        if track is circle:
            radial = ghost[0] / np.hypot(*ghost[0])
            ghost = radial[None, :] * (15.0 - where[1])
        scene = synth.make_scene(track, pose, extra=ghost)
        _, off = followed(scene)
        assert off < 0.05


def test_false_positive_just_outside_the_track(synth: ModuleType, circle) -> None:
    """A ghost 0.5 m outside the boundary pulls the path by at most a quarter of a metre."""
    pose = synth.pose_on(circle, 0)
    ghost = np.array([[17.0 * np.cos(0.4), 17.0 * np.sin(0.4)]])
    scene = synth.make_scene(circle, pose, extra=ghost)
    _, off = followed(scene)
    assert off < 0.25


def test_misclassified_cone_by_colour(synth: ModuleType, circle) -> None:
    """A blue cone reported yellow: its bridges span nothing and are rejected (measured 7 mm)."""
    pose = synth.pose_on(circle, 0)
    scene = synth.make_scene(circle, pose, colours=True)
    labels = list(scene.detections.colours)
    points = scene.detections.points
    first_blue = next(i for i, c in enumerate(labels) if c == "blue" and points[i, 0] > 3.0)
    labels[first_blue] = "yellow"
    det = ConeDetections(scene.detections.header, points, tuple(labels))
    scene = dataclasses.replace(scene, detections=det)
    plan, in_ref, cones = plan_scene(scene, ClassifierConfig(mode="colour"))
    assert cones.colour_disagreements == 1
    assert plan.status is PlanStatus.OK
    assert worst(circle, in_ref) < 0.03


def test_misclassified_cone_in_the_marker(synth: ModuleType, straight) -> None:
    """A left cone handed over as a right cone (wrong side label): the path stays centred."""
    scene = synth.make_scene(straight, Pose2D(0.0, 0.0, 0.0))
    cones = classify_cones_by_side(scene.detections, scene.buffer, straight.global_path)
    wrong = int(np.flatnonzero((cones.side == LEFT) & (cones.points[:, 0] == 10.0))[0])
    side = cones.side.copy()
    side[wrong] = RIGHT
    swapped = dataclasses.replace(cones, side=side)
    plan = reference_path_planning(swapped, scene.buffer, config=MIDLINE)
    assert plan.status is PlanStatus.OK
    assert_allclose(plan.path[:, 1], 0.0, atol=0.05)


@pytest.mark.parametrize("visible", ["left", "right"])
def test_only_one_side_in_view(synth: ModuleType, circle, visible: str) -> None:
    """One side only: the path runs half the nominal 3 m inside it (measured 7 mm off centre)."""
    pose = synth.pose_on(circle, 0)
    hidden = "right" if visible == "left" else "left"
    scene = synth.make_scene(circle, pose, **{hidden: np.zeros((0, 2))})
    plan, off = followed(scene)
    assert plan.track.width == 3.0 and not plan.track.measured  # the nominal width
    assert off < 0.03


def test_one_side_of_a_wider_track_offsets_by_the_nominal_half_width(synth: ModuleType) -> None:
    """On a 4 m track with only the inner (left) row: the path is 1.5 m inside it, r = 14.5 m."""
    track = synth.circle_track(width=4.0)
    scene = synth.make_scene(track, synth.pose_on(track, 0), right=np.zeros((0, 2)))
    plan, in_ref, _ = plan_scene(scene)
    assert plan.status is PlanStatus.OK
    assert_allclose(np.hypot(*in_ref.T), 13.0 + 1.5, atol=0.02)


@pytest.mark.parametrize("index", [60, 90, 110, 120, 130, 140])
@pytest.mark.parametrize("hide_inner_exit", [False, True])
def test_hairpin_far_side_through_the_infield(
    synth: ModuleType, hairpin, index: int, hide_inner_exit: bool
) -> None:
    """In a hairpin the exit leg shows through the infield; the path never crosses it.

    With ``hide_inner_exit`` the exit leg's inner row is out of sight, so its
    outer row faces the entry leg across an open 4 m infield. Measured worst
    deviation 0.31 m (a chord across the apex at the edge of the 20 m view).
    """
    left = hairpin.left
    if hide_inner_exit:
        left = left[~((left[:, 1] > 3.5) & (left[:, 0] < -0.5))]
    scene = synth.make_scene(hairpin, synth.pose_on(hairpin, index), left=left)
    plan, off = followed(scene)
    assert off < 0.5
    used = plan.bridge_lines[plan.bridges.used]
    assert np.all(np.hypot(*(used[:, 0] - used[:, 1]).T) < 4.5)  # no bridge across the infield


def test_stray_cone_far_outside_gets_no_partner(synth: ModuleType, straight) -> None:
    """A ghost 4.4 m right of the path is no boundary cone: no virtual partner, path centred."""
    pose = Pose2D(0.0, 0.0, 0.0)
    scene = synth.make_scene(straight, pose, extra=np.array([[3.0, -4.4]]))
    plan, _, _ = plan_scene(scene)
    assert plan.status is PlanStatus.OK
    assert len(plan.virtual) == 0
    assert plan.dropped == 1 + 4  # the ghost, and the cones at x = -5 and -10 m (min_x = -3 m)
    assert_allclose(plan.path[:, 1], 0.0, atol=1e-9)


# -- fallback ----------------------------------------------------------------------------------


def test_fallback_carries_the_previous_path_into_the_current_frame(
    synth: ModuleType, straight
) -> None:
    """No sound path: the last one, moved through the frame tree, 1 m closer and shifted 0.2 m."""
    first = synth.make_scene(straight, Pose2D(0.0, 0.0, 0.0), stamp=1.0)
    good, _, _ = plan_scene(first)
    buffer: Buffer = first.buffer
    pose_2 = Pose2D(1.0, 0.2, 0.0)
    synth.set_pose(buffer, pose_2, 1.1)
    lone = synth.detect(straight.left[3:4], pose_2, 1.1)  # one cone and its virtual partner
    cones = classify_cones_by_side(lone, buffer, straight.global_path)
    plan = reference_path_planning(cones, buffer, previous=good, config=MIDLINE)
    assert plan.status is PlanStatus.FALLBACK and plan.fallback
    assert plan.reason == "1 ordered midpoints (need 2)"
    assert_allclose(plan.path, good.path - [1.0, 0.2], atol=1e-12)
    assert len(plan.speeds) == len(plan.path)
    # And again from the fallback plan, a further 1 m on.
    synth.set_pose(buffer, Pose2D(2.0, 0.2, 0.0), 1.2)
    again = reference_path_planning(
        classify_cones_by_side(
            synth.detect(straight.left[3:4], pose_2, 1.2), buffer, straight.global_path
        ),
        buffer,
        previous=plan,
    )
    assert again.status is PlanStatus.FALLBACK
    assert_allclose(again.path, good.path - [2.0, 0.2], atol=1e-12)


def test_without_a_previous_path_the_plan_fails(synth: ModuleType, straight) -> None:
    """No sound path and nothing to carry: failed, with an empty path."""
    scene = synth.make_scene(straight, Pose2D(0.0, 0.0, 0.0))
    empty = ConeDetections(Header(scene.stamp, "os_sensor"), np.zeros((0, 3)))
    cones = classify_cones_by_side(empty, scene.buffer, straight.global_path)
    plan = reference_path_planning(cones, scene.buffer, config=MIDLINE)
    assert plan.status is PlanStatus.FAILED
    assert plan.path.shape == (0, 2) and plan.speeds.shape == (0,)


def test_fallback_drops_what_lies_behind(synth: ModuleType, straight) -> None:
    """Carried 6 m forward, the points behind the car are dropped: it starts at the nearest."""
    first = synth.make_scene(straight, Pose2D(0.0, 0.0, 0.0), stamp=1.0)
    good, _, _ = plan_scene(first)
    synth.set_pose(first.buffer, Pose2D(6.0, 0.0, 0.0), 1.1)
    cones = classify_cones_by_side(
        ConeDetections(Header(1.1, "os_sensor"), np.zeros((0, 3))),
        first.buffer,
        straight.global_path,
    )
    plan = reference_path_planning(cones, first.buffer, previous=good, config=MIDLINE)
    assert plan.status is PlanStatus.FALLBACK
    assert_allclose(plan.path[0], [0.0, 0.0], atol=1e-12)  # old x = 6 m, now beside the car
    assert_allclose(plan.path[-1], good.path[-1] - [6.0, 0.0], atol=1e-12)


# -- pieces and outputs ------------------------------------------------------------------------


def test_few_midpoints_are_joined_by_straight_lines() -> None:
    """Three midpoints (fewer than min_spline_points = 4): a polyline every 0.5 m."""
    mids = np.array([[0.0, 0.0], [2.0, 0.0], [2.0, 1.5]])
    path = fit_path(mids, MidlineConfig())
    assert len(path) == 8  # 3.5 m: 0, 0.5, ..., 3.5
    assert_allclose(path[4], [2.0, 0.0])
    assert_allclose(path[-1], [2.0, 1.5])
    assert np.all((path[:5, 1] == 0.0) & (path[4:, 0] == 2.0)[: len(path[4:])].all())


def test_spline_path_lies_on_the_fitted_spline() -> None:
    """Four or more midpoints: points on splprep's interpolating spline, 0.5 m apart."""
    x = np.linspace(0.0, 12.0, 7)
    mids = np.column_stack([x, 2.0 * np.sin(x / 4.0)])
    path = fit_path(mids, MidlineConfig())
    tck, _ = splprep(mids.T, s=0.0, k=3)
    u = np.linspace(0.0, 1.0, 20001)
    dense = np.column_stack(splev(u, tck))
    gap = np.hypot(*(path[:, None, :] - dense[None]).transpose(2, 0, 1)).min(axis=1)
    assert gap.max() < 4e-4  # on the spline: within half the dense samples' 7e-4 m spacing
    assert_allclose(path[0], mids[0], atol=1e-12)
    assert_allclose(path[-1], mids[-1], atol=1e-12)
    step = np.hypot(*np.diff(path, axis=0).T)
    assert_allclose(step[:-1], 0.5, rtol=2e-3)  # chord error of the 0.25 m sampling
    assert not np.allclose(path[4:6, 1], np.interp(path[4:6, 0], x, mids[:, 1]), atol=1e-3)


def test_fitpack_flag_falls_back_to_straight_lines(monkeypatch: pytest.MonkeyPatch) -> None:
    """splprep reporting ier > 0 (a FITPACK warning) gives the polyline, as the ROS pipeline."""
    import conesim.planner.spline

    real = conesim.planner.spline.splprep

    def flagged(*args, **kwargs):  # type: ignore[no-untyped-def]
        tcku, fp, _, message = real(*args, **kwargs)
        return tcku, fp, 1, message

    monkeypatch.setattr(conesim.planner.spline, "splprep", flagged)
    x = np.linspace(0.0, 12.0, 7)
    mids = np.column_stack([x, 2.0 * np.sin(x / 4.0)])
    assert_allclose(fit_path(mids, MidlineConfig()), Polyline(mids).sample_every(0.5).points)


def test_outputs_match_the_seed_topics(synth: ModuleType, circle) -> None:
    """Path with yaw, waypoints with speeds, bridge lines left-to-right, midpoints."""
    scene = synth.make_scene(circle, synth.pose_on(circle, 0))
    plan, _, _ = plan_scene(scene)
    path = plan.local_path()
    d = np.diff(plan.path, axis=0)
    assert_allclose(path.yaw[:-1], np.arctan2(d[:, 1], d[:, 0]))
    waypoints = plan.waypoints()
    assert waypoints.speeds.shape == (len(plan.path),) and waypoints.speeds[-1] == 0.0
    lines = plan.bridge_message()
    assert lines.lines.shape == (len(plan.bridges.left), 2, 2)
    assert np.array_equal(lines.lines[:, 0], plan.cones.points[plan.bridges.left])
    assert np.all(plan.cones.side[plan.bridges.left] == LEFT)
    assert np.all(plan.cones.side[plan.bridges.right] == RIGHT)
    assert_allclose(plan.midpoint_message().points, plan.midpoints)
    for message in (path, waypoints, lines, plan.midpoint_message()):
        assert message.header.frame_id == "os_sensor"


def test_planning_is_deterministic(synth: ModuleType, hairpin) -> None:
    """The same input gives the same plan, bit for bit."""
    scene = synth.make_scene(hairpin, synth.pose_on(hairpin, 90))
    a, _, _ = plan_scene(scene)
    b, _, _ = plan_scene(scene)
    for name in ("path", "speeds", "midpoints"):
        assert np.array_equal(getattr(a, name), getattr(b, name))
    assert np.array_equal(a.bridge_lines, b.bridge_lines)


@pytest.mark.parametrize("shift", [-0.8, 0.8])
def test_global_path_off_the_middle(synth: ModuleType, straight, shift: float) -> None:
    """A global path 0.8 m off the track's middle: sides right, path on the true middle."""
    scene = synth.make_scene(straight, Pose2D(0.0, 0.0, 0.0))
    shifted = dataclasses.replace(straight, centre=straight.centre + np.array([0.0, shift]))
    cones = classify_cones_by_side(scene.detections, scene.buffer, shifted.global_path)
    assert_allclose(np.abs(cones.offset - cones.side * 1.5), abs(shift), atol=1e-8)
    plan = reference_path_planning(cones, scene.buffer, config=MIDLINE)
    assert plan.status is PlanStatus.OK
    assert plan.track.centre == pytest.approx(-shift) and plan.track.width == pytest.approx(3.0)
    assert plan.dropped == 4  # only the cones behind min_x
    assert_allclose(plan.path[:, 1], 0.0, atol=1e-9)


def test_fallback_fails_when_the_old_stamp_left_the_cache(synth: ModuleType, straight) -> None:
    """The previous path cannot be moved once its stamp is older than the cache: failed."""
    buffer = Buffer(cache_time=1.0)
    synth.set_pose(buffer, Pose2D(0.0, 0.0, 0.0), 1.0)
    scene = dataclasses.replace(
        synth.make_scene(straight, Pose2D(0.0, 0.0, 0.0), stamp=1.0), buffer=buffer
    )
    good, _, _ = plan_scene(scene)
    synth.set_pose(buffer, Pose2D(1.0, 0.0, 0.0), 2.5)  # drops the sample at 1.0 s
    empty = ConeDetections(Header(2.5, "os_sensor"), np.zeros((0, 3)))
    cones = classify_cones_by_side(empty, buffer, straight.global_path)
    plan = reference_path_planning(cones, buffer, previous=good, config=MIDLINE)
    assert plan.status is PlanStatus.FAILED and len(plan.path) == 0
