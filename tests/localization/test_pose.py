"""Tests for localization.pose.Pose2D's point mapping."""

from __future__ import annotations

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose

from conesim.core.pose import Pose2D


def test_points_map_into_the_parent_frame_and_back() -> None:
    """A frame at (1, 2) turned 90 deg: its (1, 0) is the parent's (1, 3), its (0, 1) is (0, 2)."""
    pose = Pose2D(1.0, 2.0, math.pi / 2)
    parent = pose.transform_points([[1.0, 0.0], [0.0, 1.0]])
    assert_allclose(parent, [[1.0, 3.0], [0.0, 2.0]], atol=1e-12)
    assert_allclose(pose.inverse_transform_points(parent), [[1.0, 0.0], [0.0, 1.0]], atol=1e-12)
    assert_allclose(pose.transform_points([1.0, 0.0]), [[1.0, 3.0]], atol=1e-12)  # one point
    assert pose.transform_points([]).shape == (0, 2)  # none


@pytest.mark.parametrize("shape", [(2, 3), (4,), (2, 2, 2)])
def test_points_of_another_shape_rejected(shape: tuple[int, ...]) -> None:
    """(2, 3) x, y, z points are refused by shape, not read as three (x, y) pairs."""
    pose = Pose2D(0.0, 0.0, 0.0)
    for method in (pose.transform_points, pose.inverse_transform_points):
        with pytest.raises(ValueError, match=r"points must be \(n, 2\)"):
            method(np.zeros(shape))
