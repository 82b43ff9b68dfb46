"""classify_cones_by_side: known sides on a straight and circles, stamps, colour mode."""

from __future__ import annotations

import math
from types import ModuleType

import numpy as np
import pytest
from numpy.testing import assert_allclose

from conesim.core.messages import ConeDetections, Header
from conesim.core.pose import Pose2D
from conesim.planner import LEFT, RIGHT, ClassifierConfig, PathProjector, classify_cones_by_side
from conesim.tracks.global_path import global_path_from_centreline


def nearest(points: np.ndarray, reference: np.ndarray) -> np.ndarray:
    """Distance of each point to the nearest reference point [m]."""
    return np.min(np.hypot(*(points[:, None, :] - reference[None]).transpose(2, 0, 1)), axis=1)


def test_straight_known_sides_offsets_and_stations(synth: ModuleType, straight) -> None:
    """On a straight along +x: left cones y = +1.5 are left with offset 1.5, station x + 10."""
    pose = Pose2D(5.0, 0.3, 0.1)
    scene = synth.make_scene(straight, pose)
    cones = classify_cones_by_side(scene.detections, scene.buffer, straight.global_path)
    assert len(cones) == len(scene.detections) == 14
    assert np.all(nearest(cones.left, straight.left) < 1e-9)
    assert np.all(nearest(cones.right, straight.right) < 1e-9)
    assert_allclose(cones.offset, cones.points[:, 1], atol=1e-8)
    assert_allclose(np.abs(cones.offset), 1.5, atol=1e-8)
    assert_allclose(cones.station, cones.points[:, 0] + 10.0, atol=1e-8)
    assert_allclose(cones.sensor_station, 15.0, atol=1e-8)
    assert cones.header.frame_id == "reference"
    assert cones.header.stamp == scene.stamp


@pytest.mark.parametrize("clockwise", [False, True])
def test_circle_known_sides(synth: ModuleType, clockwise: bool) -> None:
    """On a circle of R = 15 m, left is the inside when driving counter-clockwise, else outside."""
    track = synth.circle_track(clockwise=clockwise)
    scene = synth.make_scene(track, synth.pose_on(track, 100, lateral=0.4, dyaw=-0.1))
    cones = classify_cones_by_side(scene.detections, scene.buffer, track.global_path)
    inner, outer = (16.5, 13.5) if clockwise else (13.5, 16.5)
    assert len(cones.left) > 3 and len(cones.right) > 3
    # Cones are laid out from a 720-gon, whose chords lie up to
    # 15 (1 - cos(pi / 720)) = 1.4e-4 m inside the circle.
    assert_allclose(np.hypot(*cones.left.T), inner, atol=2e-4)
    assert_allclose(np.hypot(*cones.right.T), outer, atol=2e-4)
    # Offsets of the cones ahead; a cone beyond the preferred stretch behind the
    # car (window_back = 20 m) projects onto its end: side right, offset not exact.
    ahead = scene.detections.points[cones.index, 0] > -10.0
    assert_allclose(cones.offset[ahead], cones.side[ahead] * 1.5, atol=2e-4)


def test_transform_is_taken_at_the_detection_stamp(synth: ModuleType, straight) -> None:
    """Cones seen at t = 1 s map with the pose of t = 1 s, not the latest one (t = 2 s)."""
    pose_1, pose_2 = Pose2D(0.0, 0.0, 0.0), Pose2D(10.0, 0.0, 0.2)
    scene = synth.make_scene(straight, pose_1, stamp=1.0)
    synth.set_pose(scene.buffer, pose_2, 2.0)
    path = straight.global_path
    at_stamp = classify_cones_by_side(scene.detections, scene.buffer, path)
    latest = classify_cones_by_side(scene.detections, scene.buffer, path, time=0.0)
    local = scene.detections.points[:, :2]
    assert at_stamp.header.stamp == 1.0
    assert_allclose(at_stamp.points, pose_1.transform_points(local), atol=1e-12)
    assert latest.header.stamp == 2.0
    assert_allclose(latest.points, pose_2.transform_points(local), atol=1e-12)


def test_colour_mode_trusts_blue_and_yellow_only(synth: ModuleType, straight) -> None:
    """With the colour always deciding (``geometry_overrules`` inf): blue left, yellow
    right even against the geometry; orange is geometric."""
    pose = Pose2D(0.0, 0.0, 0.0)
    scene = synth.make_scene(straight, pose, colours=True, extra=np.array([[6.0, -0.9]]))
    labels = list(scene.detections.colours)
    flipped = next(i for i, c in enumerate(labels) if c == "blue")
    labels[flipped] = "yellow"
    det = ConeDetections(scene.detections.header, scene.detections.points, tuple(labels))
    path = straight.global_path
    geometric = classify_cones_by_side(det, scene.buffer, path, ClassifierConfig(mode="geometric"))
    always = ClassifierConfig(mode="colour", geometry_overrules=math.inf)
    colour = classify_cones_by_side(det, scene.buffer, path, always)
    row = {int(i): k for k, i in enumerate(colour.index)}
    assert geometric.side[row[flipped]] == LEFT
    assert colour.side[row[flipped]] == RIGHT
    assert colour.colour_disagreements == 1
    orange = labels.index("orange")
    assert not colour.by_colour[row[orange]]
    assert colour.side[row[orange]] == RIGHT  # y = -0.9: right of the path
    assert np.count_nonzero(colour.side != geometric.side) == 1


def test_geometry_overrules_a_swapped_colour(synth: ModuleType, straight) -> None:
    """The default colour mode: 5 % of the cones (1 in 20) with blue and yellow swapped.

    A boundary cone of the 3 m lane stands 1.5 m from the global path, twice
    the 0.75 m beyond which the geometry decides: every swapped cone keeps its
    side. A yellow cone 0.5 m left of the path (within 0.75 m, where the map
    is unsure) keeps its colour's side, right.
    """
    pose = Pose2D(0.0, 0.0, 0.0)
    scene = synth.make_scene(straight, pose, colours=True, extra=np.array([[8.0, 0.5]]))
    labels = list(scene.detections.colours)
    named = [i for i, c in enumerate(labels) if c in ("blue", "yellow")]
    swapped = named[::20]
    for i in swapped:
        labels[i] = "yellow" if labels[i] == "blue" else "blue"
    extra = labels.index("orange")
    labels[extra] = "yellow"
    det = ConeDetections(scene.detections.header, scene.detections.points, tuple(labels))
    path = straight.global_path
    geometric = classify_cones_by_side(det, scene.buffer, path, ClassifierConfig(mode="geometric"))
    colour = classify_cones_by_side(det, scene.buffer, path)
    assert ClassifierConfig().mode == "colour"
    row = {int(i): k for k, i in enumerate(colour.index)}
    assert colour.colour_disagreements == len(swapped) + 1
    for i in swapped:
        assert abs(colour.offset[row[i]]) == pytest.approx(1.5, abs=0.01)
        assert colour.side[row[i]] == geometric.side[row[i]]
        assert not colour.by_colour[row[i]]
    assert geometric.side[row[extra]] == LEFT
    assert colour.side[row[extra]] == RIGHT and colour.by_colour[row[extra]]


def test_colour_mode_without_colours_is_the_seed_rule(synth: ModuleType, circle) -> None:
    """A colour-blind detection in colour mode classifies exactly as the ROS pipeline does."""
    scene = synth.make_scene(circle, synth.pose_on(circle, 0))
    config = ClassifierConfig(mode="colour")
    a = classify_cones_by_side(scene.detections, scene.buffer, circle.global_path, config)
    b = classify_cones_by_side(scene.detections, scene.buffer, circle.global_path)
    assert np.array_equal(a.side, b.side)
    assert not a.by_colour.any()


def test_non_finite_detections_are_dropped_and_counted(synth: ModuleType, straight) -> None:
    """A NaN row is dropped, counted, and the index maps kept cones to their rows."""
    scene = synth.make_scene(straight, Pose2D(0.0, 0.0, 0.0))
    points = scene.detections.points.copy()
    points[2, 0] = np.nan
    det = ConeDetections(scene.detections.header, points)
    cones = classify_cones_by_side(det, scene.buffer, straight.global_path)
    assert cones.rejected == 1
    assert len(cones) == len(det) - 1
    assert 2 not in cones.index
    assert_allclose(cones.points[:, :2], points[cones.index, :2], atol=1e-12)


def test_station_hint_picks_the_current_pass(synth: ModuleType) -> None:
    """On a path that passes a straight twice (lasso), the hint selects the second pass."""
    first = np.column_stack([np.arange(0.0, 20.0, 0.5), np.zeros(40)])
    a = np.arange(-math.pi / 2, 1.5 * math.pi, 0.05)
    loop = np.column_stack([20.0 + 10.0 * np.cos(a), 10.0 + 10.0 * np.sin(a)])
    loop = loop[np.hypot(loop[:, 0] - 20.0, loop[:, 1]) > 0.3]  # leave out the joint
    second = np.column_stack([np.arange(20.0, 40.0, 0.5), np.zeros(40)])
    path = global_path_from_centreline(np.vstack([first, loop, second]), closed=False)
    projector = PathProjector(path.polyline)
    cones = np.array([[25.0, 1.5], [25.0, -1.5], [30.0, 1.5], [30.0, -1.5]])
    pose = Pose2D(22.0, 0.0, 0.0)
    scene = synth.make_scene(
        synth.straight_track(), pose, left=cones[::2], right=cones[1::2], max_range=30.0
    )
    joined = np.vstack([first[-1:], loop, second[:1]])
    second_pass = 19.5 + float(np.sum(np.hypot(*np.diff(joined, axis=0).T)))  # station of (20, 0)
    hinted = classify_cones_by_side(
        scene.detections, scene.buffer, projector, station_hint=second_pass
    )
    assert_allclose(hinted.sensor_station, second_pass + 2.0, atol=1e-6)
    assert_allclose(hinted.station - hinted.sensor_station, [3.0, 3.0, 8.0, 8.0], atol=1e-6)
    assert np.array_equal(hinted.side, [LEFT, RIGHT, LEFT, RIGHT])


def test_empty_detection(synth: ModuleType, straight) -> None:
    """No cones: empty arrays, the sensor's station still known."""
    scene = synth.make_scene(straight, Pose2D(0.0, 0.0, 0.0))
    det = ConeDetections(Header(scene.stamp, "os_sensor"), np.zeros((0, 3)))
    cones = classify_cones_by_side(det, scene.buffer, straight.global_path)
    assert len(cones) == 0 and cones.left.shape == (0, 2)
    assert_allclose(cones.sensor_station, 10.0, atol=1e-8)
