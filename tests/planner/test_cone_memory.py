"""The planner's cone memory: missed cones recalled, ghosts not, labels voted."""

from __future__ import annotations

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose

from conesim.core.messages import FRAME_OS_SENSOR, FRAME_REFERENCE, ConeDetections, Header
from conesim.core.pose import Pose2D
from conesim.localization.frames import LATEST, Buffer, TransformStamped
from conesim.planner.cone_memory import ConeMemory
from conesim.planner.config import ConeMemoryConfig

CONES = np.array([[4.0, 1.5], [4.0, -1.5], [8.0, 1.5], [8.0, -1.5], [12.0, 1.5]])


def _buffer(poses: dict[float, Pose2D]) -> Buffer:
    buffer = Buffer()
    for t, pose in poses.items():
        buffer.set_transform(
            TransformStamped.from_pose2d(FRAME_REFERENCE, FRAME_OS_SENSOR, t, pose)
        )
    return buffer


def _scan(t: float, pose: Pose2D, rows: list[int], colours: list[str] | None = None):
    """The cones ``rows`` of CONES (in reference) as seen from ``pose`` at ``t``."""
    c, s = math.cos(pose.yaw), math.sin(pose.yaw)
    d = CONES[rows] - [pose.x, pose.y]
    local = np.column_stack([c * d[:, 0] + s * d[:, 1], -s * d[:, 0] + c * d[:, 1]])
    points = np.column_stack([local, np.zeros(len(rows))])
    return ConeDetections(
        Header(t, FRAME_OS_SENSOR), points, None if colours is None else tuple(colours)
    )


def test_a_cone_missed_in_one_scan_is_recalled_where_it_stands() -> None:
    # The car moves 1 m and turns 0.1 rad between scans; the second scan
    # misses cone 2, which comes back at its place seen from the new pose.
    # (Stamps from 1 s: a stamp of 0 is tf2's "latest".)
    p0, p1 = Pose2D(0.0, 0.0, 0.0), Pose2D(1.0, 0.2, 0.1)
    buffer = _buffer({1.0: p0, 1.1: p1})
    memory = ConeMemory()
    first = memory.recall(_scan(1.0, p0, [0, 1, 2, 3]), buffer, FRAME_REFERENCE, 1.0)
    assert len(first) == 4  # nothing remembered yet
    memory.recall(_scan(1.1, p1, [0, 1, 2, 3]), buffer, FRAME_REFERENCE, 1.1)
    assert_allclose(memory.points, CONES[:4], atol=1e-12)
    third = memory.recall(_scan(1.1, p1, [0, 1, 3]), buffer, FRAME_REFERENCE, 1.1)
    expected = _scan(1.1, p1, [0, 1, 2, 3]).points
    order = np.argsort(np.hypot(expected[:, 0], expected[:, 1]))
    assert_allclose(third.points, expected[order], atol=1e-12)
    assert memory.recalled_count == 1
    # Cone 2 is the third nearest: the one row marked as the memory's, not the scan's.
    assert memory.recalled.tolist() == [False, False, True, False]
    memory.recall(_scan(1.1, p1, [0, 1, 2, 3]), buffer, FRAME_REFERENCE, 1.1)
    assert not memory.recalled.any()


def test_a_ghost_seen_once_is_not_recalled() -> None:
    pose = Pose2D(0.0, 0.0, 0.0)
    buffer = _buffer({0.0: pose})
    memory = ConeMemory()
    memory.recall(_scan(0.0, pose, [0, 1, 4]), buffer, FRAME_REFERENCE, 0.0)  # 4: once
    for _ in range(2):
        out = memory.recall(_scan(0.0, pose, [0, 1]), buffer, FRAME_REFERENCE, 0.0)
        assert len(out) == 2


def test_a_cone_is_forgotten_after_keep_scans() -> None:
    pose = Pose2D(0.0, 0.0, 0.0)
    buffer = _buffer({0.0: pose})
    memory = ConeMemory(ConeMemoryConfig(keep_scans=3))
    for _ in range(2):
        memory.recall(_scan(0.0, pose, [0, 1]), buffer, FRAME_REFERENCE, 0.0)
    # cone 1 is last seen in scan 2: recalled in scans 3 and 4, gone in scan 5
    counts = [
        len(memory.recall(_scan(0.0, pose, [0]), buffer, FRAME_REFERENCE, 0.0)) for _ in range(3)
    ]
    assert counts == [2, 2, 1]


def test_position_is_the_mean_of_sightings() -> None:
    pose = Pose2D(0.0, 0.0, 0.0)
    buffer = _buffer({0.0: pose})
    memory = ConeMemory()
    for dx in (0.1, -0.1, 0.3):
        points = np.array([[4.0 + dx, 1.5, 0.0]])
        memory.recall(
            ConeDetections(Header(0.0, FRAME_OS_SENSOR), points), buffer, FRAME_REFERENCE, 0.0
        )
    assert_allclose(memory.points, [[4.1, 1.5]], atol=1e-12)
    assert memory.sightings.tolist() == [3]


def test_a_swapped_label_is_outvoted() -> None:
    pose = Pose2D(0.0, 0.0, 0.0)
    buffer = _buffer({0.0: pose})
    memory = ConeMemory()
    for _ in range(3):
        memory.recall(_scan(0.0, pose, [0, 1], ["blue", "yellow"]), buffer, FRAME_REFERENCE, 0.0)
    out = memory.recall(
        _scan(0.0, pose, [0, 1], ["yellow", "yellow"]), buffer, FRAME_REFERENCE, 0.0
    )
    assert out.colours == ("blue", "yellow")
    # a missed one comes back with its label
    out = memory.recall(_scan(0.0, pose, [1], ["yellow"]), buffer, FRAME_REFERENCE, 0.0)
    assert sorted(out.colours or ()) == ["blue", "yellow"]


def test_off_passes_the_scan_through() -> None:
    pose = Pose2D(0.0, 0.0, 0.0)
    buffer = _buffer({0.0: pose})
    memory = ConeMemory(ConeMemoryConfig(keep_scans=0))
    memory.recall(_scan(0.0, pose, [0, 1]), buffer, FRAME_REFERENCE, LATEST)
    scan = _scan(0.0, pose, [0])
    assert memory.recall(scan, buffer, FRAME_REFERENCE, LATEST) is scan
    assert len(memory.points) == 0


def test_bad_settings_are_refused() -> None:
    with pytest.raises(ValueError, match="match_radius"):
        ConeMemoryConfig(match_radius=0.0)
    with pytest.raises(ValueError, match="keep_scans"):
        ConeMemoryConfig(keep_scans=-1)
