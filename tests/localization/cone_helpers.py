"""A small cone map, scans of it and an initialised filter, for the cone localization tests."""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from conesim.core.messages import (
    FRAME_OS_SENSOR,
    FRAME_REFERENCE,
    ConeDetections,
    Header,
    HeadingStamped,
)
from conesim.core.pose import Pose2D
from conesim.localization.cones import ConeUpdate, ConeUpdateConfig, LandmarkMap
from conesim.localization.ekf import EkfConfig, FusionEkf
from conesim.localization.ekf.synthetic import fix_message

FloatArray = NDArray[np.float64]


def lane_map(n_pairs: int = 5, spacing: float = 4.0, width: float = 3.0) -> LandmarkMap:
    """Two rows of cones ahead of the origin along +x: blue at y = +w/2, yellow at -w/2."""
    xs = 2.0 + spacing * np.arange(n_pairs)
    left = np.column_stack([xs, np.full(n_pairs, 0.5 * width)])
    right = np.column_stack([xs, np.full(n_pairs, -0.5 * width)])
    return LandmarkMap(np.vstack([left, right]), ["blue"] * n_pairs + ["yellow"] * n_pairs)


def in_sensor(pose: Pose2D, world: FloatArray) -> FloatArray:
    """World points (k, 2) in the sensor frame of an antenna at ``pose`` (no offset)."""
    c, s = math.cos(pose.yaw), math.sin(pose.yaw)
    d = world - np.array([pose.x, pose.y])
    return np.column_stack([c * d[:, 0] + s * d[:, 1], -s * d[:, 0] + c * d[:, 1]])


def noisy(points: FloatArray, cfg: ConeUpdateConfig, rng: np.random.Generator) -> FloatArray:
    """Points with the detector's range and bearing noise (as ``sim.sensors.cone_detector``)."""
    r = np.hypot(points[:, 0], points[:, 1])
    b = np.arctan2(points[:, 1], points[:, 0])
    r = r + cfg.range_sigma * rng.standard_normal(len(r))
    b = b + cfg.bearing_sigma * rng.standard_normal(len(b))
    return np.column_stack([r * np.cos(b), r * np.sin(b)])


def scan(stamp: float, points: FloatArray, colours: list[str] | None = None) -> ConeDetections:
    """A ``ConeDetections`` message of planar points (k, 2) in ``os_sensor``."""
    xyz = np.column_stack([points, np.zeros(len(points))])
    return ConeDetections(
        Header(stamp, FRAME_OS_SENSOR), xyz, None if colours is None else tuple(colours)
    )


def filter_at(
    pose: Pose2D,
    sigma_xy: float,
    sigma_yaw: float,
    update: ConeUpdate,
    config: EkfConfig | None = None,
) -> FusionEkf:
    """A filter with the cone map, initialised at ``pose`` with these sigmas at t = 0."""
    ekf = FusionEkf(config or EkfConfig(), update)
    ekf.process(fix_message(0.0, pose.x, pose.y, sigma_xy))
    ekf.process(HeadingStamped(Header(0.0, FRAME_REFERENCE), pose.yaw, sigma_yaw**2))
    assert ekf.initialised
    return ekf


def assert_closed_loop_nis(counts: dict[str, float] | None) -> None:
    """A closed loop's cone updates (``RunResult.cone_associations``): NIS per dof
    within 10 % of 1, and >= 85 % of the scans used inside their 95 % band."""
    assert counts is not None
    used = counts["scans"] - counts["scans_gated"]
    assert 0.9 <= counts["nis_sum"] / counts["dof_sum"] <= 1.1
    assert counts["nis_in_band"] / used >= 0.85
