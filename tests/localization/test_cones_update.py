"""Cone scans against a known map update the EKF's pose: worked numbers on a small lane."""

from __future__ import annotations

import math

import numpy as np
from numpy.testing import assert_allclose
from scipy.stats import chi2

from conesim.core.pose import Pose2D
from conesim.localization.cones import ConeUpdate, ConeUpdateConfig
from conesim.localization.cones.observation import detection_covariance, h_cones, jacob_h_cones
from conesim.localization.ekf import RejectReason, Sensor
from tests.localization.cone_helpers import filter_at, in_sensor, lane_map, noisy, scan

TRUTH = Pose2D(0.0, 0.0, 0.0)
OFFSET = Pose2D(0.5, 0.3, math.radians(2.0))  # the prior's error: (0.5 m, 0.3 m, 2 deg)


def test_jacobian_matches_finite_differences() -> None:
    """H of h_cones against central differences of h_cones, to 1e-7, with the map offset
    at index 7 (x, y, yaw and the offset's columns; zero elsewhere)."""
    lmap = lane_map()
    x = np.zeros((9, 1))
    x[:3, 0] = (0.4, -0.2, 0.3)
    x[7:, 0] = (0.05, -0.03)
    h = jacob_h_cones(x, lmap.positions, 9, bias=7)
    for i in (0, 1, 2, 7, 8):
        step = np.zeros((9, 1))
        step[i] = 1e-6
        fd = (
            h_cones(x + step, lmap.positions, (0.0, 0.0), bias=7)
            - h_cones(x - step, lmap.positions, (0.0, 0.0), bias=7)
        ) / 2e-6
        assert_allclose(h[:, i : i + 1], fd, atol=1e-7)
    assert not h[:, 3:7].any()
    assert_allclose(h[:, 7:], -h[:, :2])  # the map moving is the car moving back


def test_detection_covariance_worked_numbers() -> None:
    """A cone 10 m ahead: sigma_r^2 + map^2 along, (10 sigma_b)^2 + map^2 across."""
    cfg = ConeUpdateConfig(range_sigma=0.05, bearing_sigma=0.007, map_sigma=0.03)
    cov = detection_covariance(np.array([[10.0, 0.0]]), cfg)[0]
    assert_allclose(cov, np.diag([0.05**2 + 0.03**2, 0.07**2 + 0.03**2]), atol=1e-15)


def test_offset_pose_corrected_by_one_scan_of_ten_cones() -> None:
    """(0.5 m, 0.3 m, 2 deg) off, one scan of 10 cones: the error is inside the posterior's
    99.9 % ellipsoid, the posterior is the information-form one, and it is centimetres."""
    cfg = ConeUpdateConfig()
    lmap = lane_map()
    update = ConeUpdate(lmap, cfg)
    prior = Pose2D(TRUTH.x + OFFSET.x, TRUTH.y + OFFSET.y, TRUTH.yaw + OFFSET.yaw)
    ekf = filter_at(prior, 0.6, math.radians(3.0), update)
    assert ekf.layout.map_bias_index == 7  # the map's 2 cm offset is in the state
    idx = np.ix_([0, 1, 2, 7, 8], [0, 1, 2, 7, 8])
    p0 = ekf.estimate(0.0).covariance[idx]
    points = noisy(in_sensor(TRUTH, lmap.positions), cfg, np.random.default_rng(0))
    result = ekf.process(scan(0.0, points))
    assert result is not None and result.accepted and result.dof == 20
    assert ekf.health.cones.matched == 10
    est = ekf.estimate(0.0)
    err = np.array([est.pose.x - TRUTH.x, est.pose.y - TRUTH.y, est.pose.yaw - TRUTH.yaw])
    p = est.covariance[:3, :3]
    # The posterior as information: P+^-1 = P^-1 + H' R^-1 H (x, y, yaw and the map's
    # offset; linearised at the prior; the other states are uncorrelated with these).
    x = np.zeros((9, 1))
    x[:3, 0] = (prior.x, prior.y, prior.yaw)
    h = jacob_h_cones(x, lmap.positions, 9, bias=7)[:, [0, 1, 2, 7, 8]]
    blocks = detection_covariance(points, cfg)
    r_inv = np.zeros((20, 20))
    for i, block in enumerate(blocks):
        r_inv[2 * i : 2 * i + 2, 2 * i : 2 * i + 2] = np.linalg.inv(block)
    expected = np.linalg.inv(np.linalg.inv(p0) + h.T @ r_inv @ h)
    assert_allclose(est.covariance[idx], expected, rtol=1e-6)
    nees = float(err @ np.linalg.solve(p, err))
    assert nees <= chi2.ppf(0.999, 3)
    assert math.hypot(err[0], err[1]) < 0.05  # from 0.58 m
    assert abs(math.degrees(err[2])) < 0.2  # from 2 deg
    # 10 cones at 2-18 m with 3-5 cm each place the car on the map to 1.74 cm along the
    # lane and 3.04 cm across (across is tied to the yaw, which the cones' spread in range
    # pins to 0.245 deg); the map's own 2 cm offset adds in quadrature:
    # sqrt(1.74^2 + 2^2) = 2.65 cm, sqrt(3.04^2 + 2^2) = 3.64 cm.
    along, across = math.hypot(0.0174, 0.02), math.hypot(0.0304, 0.02)
    assert_allclose(np.sqrt(np.diag(p)), [along, across, math.radians(0.245)], rtol=0.02)


def test_false_positive_08_m_from_a_map_cone_is_gated() -> None:
    """A ghost 0.8 m beside a cone: d^2 = 0.64 / S ~ 100 > chi2(0.999, 2) = 13.8; it is
    counted as a false positive and the state is exactly that of the ten true cones."""
    cfg = ConeUpdateConfig()
    lmap = lane_map()
    update = ConeUpdate(lmap, cfg)
    points = noisy(in_sensor(TRUTH, lmap.positions), cfg, np.random.default_rng(1))
    ghost = in_sensor(TRUTH, lmap.positions[2:3] + np.array([[0.0, 0.8]]))  # towards the centre
    clean = filter_at(TRUTH, 0.05, math.radians(0.2), update)
    clean.process(scan(0.0, points))
    dirty = filter_at(TRUTH, 0.05, math.radians(0.2), update)
    result = dirty.process(scan(0.0, np.vstack([points, ghost])))
    assert result is not None and result.accepted
    counts = dirty.health.cones
    assert (counts.matched, counts.false_positives, counts.ambiguous) == (10, 1, 0)
    assert_allclose(dirty.estimate(0.0).state, clean.estimate(0.0).state, atol=1e-12)


def test_associations_stay_correct_under_colour_swaps() -> None:
    """Three detections with blue and yellow swapped: with colours trusted they are
    rejected as colour mismatches, the other seven matched to their own cones; with
    colours ignored all ten are matched to their own cones."""
    lmap = lane_map()
    points = in_sensor(TRUTH, lmap.positions)
    colours = ["blue"] * 5 + ["yellow"] * 5
    swapped = list(colours)
    for i in (0, 3, 7):
        swapped[i] = "yellow" if colours[i] == "blue" else "blue"
    update = ConeUpdate(lmap, ConeUpdateConfig())
    ekf = filter_at(TRUTH, 0.3, math.radians(1.0), update)
    meas = update.measurement(scan(0.0, points, swapped))
    est = ekf.estimate(0.0)
    found = update.associate(est.state.reshape(-1, 1), est.covariance, meas, ekf.layout)
    assert found.counts.colour_mismatches == 3
    assert_allclose(found.detections, [1, 2, 4, 5, 6, 8, 9])
    assert_allclose(found.landmarks, found.detections)  # detection i is cone i
    blind = ConeUpdate(lmap, ConeUpdateConfig(use_colours=False))
    meas = blind.measurement(scan(0.0, points, swapped))
    found = blind.associate(est.state.reshape(-1, 1), est.covariance, meas, ekf.layout)
    assert_allclose(found.landmarks, np.arange(10))
    assert_allclose(found.detections, np.arange(10))


def test_dense_cones_with_a_wide_prior_resolved_by_consensus() -> None:
    """Cones 1.2 m apart, a prior 1.5 m off: every detection has several gated cones;
    the consensus offset picks each detection's own cone."""
    lmap = lane_map(n_pairs=10, spacing=1.2, width=3.0)
    update = ConeUpdate(lmap, ConeUpdateConfig(use_colours=False))
    prior = Pose2D(1.0, -1.1, math.radians(1.0))
    ekf = filter_at(prior, 1.5, math.radians(2.0), update)
    est = ekf.estimate(0.0)
    meas = update.measurement(scan(0.0, in_sensor(TRUTH, lmap.positions)))
    found = update.associate(est.state.reshape(-1, 1), est.covariance, meas, ekf.layout)
    assert len(found) >= 15
    assert_allclose(found.landmarks, found.detections)


def test_scan_with_no_association_is_rejected_and_counted() -> None:
    """Points far from every cone: no association, the state untouched."""
    lmap = lane_map()
    update = ConeUpdate(lmap, ConeUpdateConfig())
    ekf = filter_at(TRUTH, 0.05, math.radians(0.2), update)
    before = ekf.estimate(0.0).state.copy()
    result = ekf.process(scan(0.0, np.array([[5.0, 8.0], [6.0, -9.0]])))
    assert result is not None and result.reason is RejectReason.NO_ASSOCIATION
    assert ekf.health.rejected[(Sensor.CONES, RejectReason.NO_ASSOCIATION)] == 1
    assert ekf.health.cones.false_positives == 2
    assert_allclose(ekf.estimate(0.0).state, before, atol=0.0)
