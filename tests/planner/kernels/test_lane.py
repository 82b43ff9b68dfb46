"""The lane kernels (``planner.kernels.lane``) against numpy's formulation, to 1e-12 m."""

from __future__ import annotations

import math

import numpy as np
from numpy.testing import assert_allclose

from conesim.planner import MidlineConfig, kernels

LANE = MidlineConfig().lane_settings


def ref_lane_room(
    path: np.ndarray, segments: np.ndarray, default: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``lane_room`` with numpy: rays along the normals against every segment at once."""
    tangent = np.gradient(path, axis=0) * 2.0
    tangent[0], tangent[-1] = path[1] - path[0], path[-1] - path[-2]
    normal = np.column_stack([-tangent[:, 1], tangent[:, 0]]) / np.hypot(*tangent.T)[:, None]
    a, e = segments[:, 0], segments[:, 1] - segments[:, 0]

    def hit(d: np.ndarray) -> np.ndarray:
        det = e[None, :, 0] * d[:, None, 1] - e[None, :, 1] * d[:, None, 0]
        r = a[None] - path[:, None]
        with np.errstate(divide="ignore", invalid="ignore"):
            t = (e[None, :, 0] * r[..., 1] - e[None, :, 1] * r[..., 0]) / det
            u = (d[:, None, 0] * r[..., 1] - d[:, None, 1] * r[..., 0]) / det
        ok = (det != 0.0) & (u >= 0.0) & (u <= 1.0) & (t > 0.0) & (t < default)
        return np.where(ok, t, default).min(axis=1)

    to_left, to_right = hit(normal), hit(-normal)
    ab, bc = path[1:-1] - path[:-2], path[2:] - path[1:-1]
    cross = ab[:, 0] * bc[:, 1] - ab[:, 1] * bc[:, 0]
    denom = np.hypot(*ab.T) * np.hypot(*bc.T) * np.hypot(*(path[2:] - path[:-2]).T)
    kappa = np.concatenate([[0.0], 2.0 * cross / denom, [0.0]])
    h = LANE.body_half_width
    radius = 1.0 / np.maximum(np.abs(kappa), 1e-6)
    sweep = np.where(np.abs(kappa) > 1e-6, np.hypot(radius + h, LANE.body_front) - radius - h, 0.0)
    base = h + LANE.clearance
    left = to_left - base - np.where(kappa < 0.0, sweep, 0.0)
    right = to_right - base - np.where(kappa < 0.0, 0.0, sweep)
    return left, right, normal


def test_lane_room_is_numpys() -> None:
    """A wiggly path between two noisy cone lines: the same room and normals."""
    rng = np.random.default_rng(0)
    s = np.arange(0.0, 25.0, 0.5)
    path = np.column_stack([s, 1.5 * np.sin(s / 4.0)])
    cones = np.arange(-1.0, 27.0, 2.0)
    lines = [
        np.column_stack([cones, 1.5 * np.sin(cones / 4.0) + side + rng.normal(0, 0.05, len(cones))])
        for side in (1.7, -1.7)
    ]
    segments = np.concatenate([np.stack([p[:-1], p[1:]], axis=1) for p in lines])
    got = kernels.lane_room(path, segments, 1.7, LANE)
    for a, b in zip(got, ref_lane_room(path, segments, 1.7), strict=True):
        assert_allclose(a, b, atol=1e-12)


def test_lane_path_keeps_its_room_and_its_ends() -> None:
    """The band moves no point beyond its room, and the first two and last two not at all."""
    s = np.arange(0.0, 20.0, 0.5)
    path = np.column_stack([s, 0.3 * np.sin(s)])
    normal = np.tile([0.0, 1.0], (len(s), 1))
    left = np.full(len(s), 0.4)
    right = np.full(len(s), 0.2)
    moved = kernels.lane_path(path, left, right, normal, LANE)
    offset = moved[:, 1] - path[:, 1]
    assert np.all(offset <= 0.4 + 1e-12) and np.all(offset >= -0.2 - 1e-12)
    assert_allclose(offset[[0, 1, -2, -1]], 0.0, atol=1e-15)
    wiggle = float(np.sum(np.diff(moved[:, 1], 2) ** 2))
    assert wiggle < float(np.sum(np.diff(path[:, 1], 2) ** 2))
    assert math.isfinite(wiggle)
