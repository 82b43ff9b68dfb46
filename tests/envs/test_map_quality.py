"""The map's score against the true cones: worked numbers."""

from __future__ import annotations

import math

import numpy as np
from numpy.testing import assert_allclose

from conesim.envs.map_quality import map_quality

CONES = np.array([[0.0, 0.0], [4.0, 0.0], [8.0, 0.0], [0.0, 3.0], [4.0, 3.0], [8.0, 3.0]])
COV = np.tile(np.diag([0.01, 0.04]), (6, 1, 1))


def test_a_shifted_map_errs_by_its_shift_raw_and_by_nothing_aligned() -> None:
    """Every cone off by (0.3, 0.4): raw error 0.5 m, aligned 0, the offset 0.5 m, and the
    NEES per dof (0.09 / 0.01 + 0.16 / 0.04) / 2 = 6.5."""
    q = map_quality(CONES + np.array([0.3, 0.4]), COV, CONES)
    assert (q.landmarks, q.cones, q.missed, q.spurious) == (6, 6, 0, 0)
    assert_allclose([q.mean_error_m, q.max_error_m, q.offset_m], 0.5, atol=1e-12)
    assert_allclose([q.mean_error_aligned_m, q.max_error_aligned_m, q.rotation_deg], 0.0, atol=1e-9)
    assert_allclose(q.nees_per_dof, 6.5, atol=1e-9)


def test_a_rotated_map_is_its_shape_once_aligned() -> None:
    """The map turned 1 deg about the origin: raw errors up to 8.5 m x 1 deg, aligned 0."""
    a = math.radians(1.0)
    rot = np.array([[math.cos(a), -math.sin(a)], [math.sin(a), math.cos(a)]])
    q = map_quality(CONES @ rot.T, COV, CONES)
    assert_allclose(q.max_error_m, 2.0 * math.hypot(8.0, 3.0) * math.sin(a / 2), atol=1e-12)
    assert_allclose(q.rotation_deg, -1.0, atol=1e-9)
    assert q.mean_error_aligned_m < 1e-9


def test_missed_and_spurious_cones_are_counted() -> None:
    """One cone not mapped, one landmark 5 m from every cone: 1 missed, 1 spurious."""
    landmarks = np.vstack([CONES[1:], [[4.0, 8.0]]])
    q = map_quality(landmarks, COV, CONES)
    assert (q.landmarks, q.missed, q.spurious) == (6, 1, 1)
    assert q.mean_error_m == 0.0
