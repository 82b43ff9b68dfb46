"""Tests for sim.sensors.cone_detector, cone_map, occlusion and cone_colour."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
from numpy.testing import assert_allclose

from conesim.core.messages import ConeDetections
from conesim.core.pose import Pose2D
from conesim.sim.sensors.cone_colour import sample_colours
from conesim.sim.sensors.cone_detector import ConeDetector, ConeDetectorConfig
from conesim.sim.sensors.cone_map import ConeMap
from conesim.sim.sensors.profiles import get_profile
from conesim.sim.sensors.truth import TruthSample

KINDS = ("blue", "yellow", "orange", "big_orange", "unknown")
# Geometry only: no noise, no misses, no false positives, no occlusion, perfect colour.
EXACT = replace(get_profile("ideal").cones, fov=2 * math.pi, min_range=0.0, max_range=100.0)


PARKED = Pose2D(0.0, 0.0, 0.0)


def scan(
    config: ConeDetectorConfig,
    cones: np.ndarray,
    kinds: tuple[str, ...],
    *,
    pose: Pose2D = PARKED,
    seed: int = 0,
    n: int = 1,
    use_map: bool = False,
) -> list[ConeDetections]:
    """n scans of a parked car."""
    detector = ConeDetector(config, seed)
    cmap = ConeMap(cones, kinds) if use_map else None
    return [
        detector.capture(
            TruthSample(
                k / config.rate, pose, cone_positions=cones, cone_kinds=kinds, cone_map=cmap
            )
        )
        for k in range(n)
    ]


def ring(radius: float, n: int, phase: float = 0.0) -> np.ndarray:
    """n points evenly on a circle about the origin [m], (n, 2)."""
    a = phase + np.linspace(0.0, 2 * math.pi, n, endpoint=False)
    return radius * np.column_stack([np.cos(a), np.sin(a)])


def test_ideal_detector_equals_truth_in_os_sensor() -> None:
    """ideal: points = R(yaw)^T (p - p_antenna) for cones in 1-15 m and +-90 deg, exactly."""
    rng = np.random.default_rng(0)
    cones = rng.uniform(-30.0, 30.0, (600, 2))
    kinds = tuple(KINDS[i] for i in rng.integers(0, 5, 600))
    pose = Pose2D(2.5, -1.5, 0.7)
    cfg = get_profile("ideal").cones
    (msg,) = scan(cfg, cones, kinds, pose=pose)
    c, s = math.cos(pose.yaw), math.sin(pose.yaw)
    d = cones - [pose.x, pose.y]
    local = np.column_stack([c * d[:, 0] + s * d[:, 1], -s * d[:, 0] + c * d[:, 1]])
    r = np.hypot(local[:, 0], local[:, 1])
    keep = (r >= 1.0) & (r <= 15.0) & (local[:, 0] >= 0.0)
    order = np.argsort(r[keep], kind="stable")
    expected = local[keep][order]
    kept_kinds = [k for k, ok in zip(kinds, keep, strict=True) if ok]
    heights = np.array([0.505 if kinds_i == "big_orange" else 0.325 for kinds_i in kept_kinds])
    assert msg.header.frame_id == "os_sensor"
    assert len(msg) == len(expected) > 20
    assert_allclose(msg.points[:, :2], expected, rtol=0, atol=1e-12)
    assert_allclose(msg.points[:, 2], (heights / 2 - 1.0)[order], rtol=0, atol=1e-12)
    assert msg.colours == tuple(kept_kinds[i] for i in order)


def test_cone_map_gives_the_same_scan_as_a_full_search() -> None:
    """With or without a ConeMap the rtk detector returns bit-identical scans."""
    rng = np.random.default_rng(1)
    cones = rng.uniform(-40.0, 40.0, (1000, 2))
    kinds = tuple(KINDS[i] for i in rng.integers(0, 5, 1000))
    cfg = get_profile("rtk").cones
    a = scan(cfg, cones, kinds, pose=Pose2D(1.0, 2.0, -2.0), seed=5, n=5)
    b = scan(cfg, cones, kinds, pose=Pose2D(1.0, 2.0, -2.0), seed=5, n=5, use_map=True)
    for ma, mb in zip(a, b, strict=True):
        assert np.array_equal(ma.points, mb.points) and ma.colours == mb.colours


def test_cone_map_queries_see_knocked_cones_where_they_are() -> None:
    """After a 3 cm and a 5.5 m knock the queries answer on the new positions."""
    cones = np.array([[0.0, 0.0], [5.0, 0.0], [10.0, 0.0]])
    cmap = ConeMap(cones, ("blue",) * 3)
    assert list(cmap.query([0.0, 0.0], 5.0)) == [0, 1]
    knocked = cones + np.array([[0.0, 0.0], [0.03, 0.0], [0.0, 0.0]])
    cmap.update(knocked)
    assert list(cmap.query([0.0, 0.0], 5.0)) == [0]  # cone 1 now at 5.03 m
    assert list(cmap.query([0.0, 0.0], 5.03)) == [0, 1]
    cmap.update(knocked + np.array([[0.0, 0.0], [0.0, 0.0], [-5.5, 0.0]]))
    assert list(cmap.query([0.0, 0.0], 5.0)) == [0, 2]  # cone 2 knocked to 4.5 m
    knocked[1] = (9.0, 9.0)  # the caller's array is copied, not held
    assert list(cmap.query([0.0, 0.0], 5.03)) == [0, 1, 2]


def test_range_and_field_of_view_limits_hold() -> None:
    """Cones at 0.5 m, 15.5 m and behind are dropped; false positives stay inside too."""
    cones = np.array([[0.5, 0.0], [5.0, 0.0], [15.5, 0.0], [-5.0, 0.0], [0.1, 4.9], [0.1, -14.9]])
    cfg = replace(get_profile("ideal").cones, false_positive_rate=3.0)
    msgs = scan(cfg, cones, ("blue",) * 6, n=300)
    all_points = np.vstack([m.points for m in msgs])
    r = np.hypot(all_points[:, 0], all_points[:, 1])
    b = np.arctan2(all_points[:, 1], all_points[:, 0])
    assert np.all((r >= 1.0 - 1e-12) & (r <= 15.0 + 1e-12) & (np.abs(b) <= math.pi / 2))
    true_hits = [p for p in all_points if np.min(np.hypot(*(cones - p[:2]).T)) < 1e-9]
    assert {tuple(np.round(p[:2], 6)) for p in true_hits} == {(5.0, 0.0), (0.1, 4.9), (0.1, -14.9)}
    assert abs(len(all_points) / 300 - 3 - 3.0) < 0.3  # 3 real + Poisson(3); SE 0.1


def test_occlusion_hides_a_cone_directly_behind_another() -> None:
    """Cone at 8 m behind one at 5 m (half-width asin(0.114 / 5) = 0.0228 rad) is hidden."""
    cones = np.array([[5.0, 0.0], [8.0, 0.0], [8.0, 0.1], [8.0, 0.3], [8.0, -0.2]])
    cfg = replace(EXACT, occlusion=True)
    (msg,) = scan(cfg, cones, ("blue",) * 5)
    # bearings: 0, 0.0125 (hidden), 0.0375 (visible), -0.025 (visible: > 0.0228)
    assert_allclose(msg.points[:, :2], [[5.0, 0.0], [8.0, -0.2], [8.0, 0.3]], atol=1e-12)
    big = scan(cfg, cones, ("big_orange", "blue", "blue", "blue", "blue"))[0]
    # a big cone's half-width asin(0.1425 / 5) = 0.0285 rad also hides the one at -0.025
    assert_allclose(big.points[:, :2], [[5.0, 0.0], [8.0, 0.3]], atol=1e-12)
    assert len(scan(EXACT, cones, ("blue",) * 5)[0]) == 5


def test_detection_probability_follows_one_minus_r_over_100() -> None:
    """fssim law: 80 % of cones at 20 m and 50 % at 50 m are detected (20,000 tries each)."""
    cfg = replace(EXACT, detection_probability_slope=0.01)
    for radius, expected in ((20.0, 0.8), (50.0, 0.5)):
        msgs = scan(cfg, ring(radius, 400), ("blue",) * 400, n=50)
        rate = sum(len(m) for m in msgs) / 20_000
        assert abs(rate - expected) < 0.015  # SE 0.0035


def test_range_and_bearing_noise_std() -> None:
    """fssim sigmas 0.05 m and 0.007 rad over 20,000 detections, within 5 %."""
    cfg = replace(EXACT, range_sigma=0.05, bearing_sigma=0.007)
    msgs = scan(cfg, ring(10.0, 100), ("blue",) * 100, n=200)
    pts = np.vstack([m.points for m in msgs])
    r = np.hypot(pts[:, 0], pts[:, 1])
    bearing = np.arctan2(pts[:, 1], pts[:, 0])
    nearest = np.round(bearing / (2 * math.pi / 100)) * (2 * math.pi / 100)
    db = (bearing - nearest + math.pi) % (2 * math.pi) - math.pi
    assert_allclose(np.std(r - 10.0), 0.05, rtol=0.05)
    assert_allclose(np.std(db), 0.007, rtol=0.05)


def test_false_positives_are_poisson_and_uniform_over_the_field_of_view() -> None:
    """lambda = 2: mean count 2, half of them inside r = sqrt((1 + 225) / 2) = 10.63 m."""
    cfg = replace(get_profile("ideal").cones, false_positive_rate=2.0)
    msgs = scan(cfg, np.zeros((0, 2)), (), n=5000)
    counts = np.array([len(m) for m in msgs])
    assert abs(counts.mean() - 2.0) < 0.1  # SE 0.02
    assert abs(counts.var() - 2.0) < 0.3
    pts = np.vstack([m.points for m in msgs])
    r = np.hypot(pts[:, 0], pts[:, 1])
    assert abs(np.mean(r < math.sqrt(113.0)) - 0.5) < 0.02
    assert abs(np.mean(pts[:, 1] > 0.0) - 0.5) < 0.02
    assert set(np.concatenate([m.colours or () for m in msgs])) == {"unknown"}


def test_colour_confusion_frequencies_match_the_matrix() -> None:
    """20,000 detections per true class; every reported frequency within 0.01 of the matrix."""
    confusion = (
        (0.90, 0.05, 0.00, 0.05),
        (0.10, 0.85, 0.05, 0.00),
        (0.00, 0.10, 0.80, 0.10),
        (0.25, 0.25, 0.25, 0.25),
    )
    cfg = replace(EXACT, confusion=confusion, report_big_orange=False)
    names = ("blue", "yellow", "orange", "unknown")
    # one class per radius so that each point's true class is known from its range
    cones = np.vstack([ring(4.0 + i, 100, phase=0.01 * i) for i in range(4)])
    kinds = tuple(name for name in names for _ in range(100))
    counts = np.zeros((4, 4))
    for msg in scan(cfg, cones, kinds, n=200):
        true = np.rint(np.hypot(msg.points[:, 0], msg.points[:, 1]) - 4.0).astype(int)
        for t, label in zip(true, msg.colours or (), strict=True):
            counts[t, names.index(label)] += 1
    assert_allclose(counts.sum(axis=1), 20_000)
    assert_allclose(counts / 20_000, confusion, atol=0.01)  # SE <= 0.0031


def test_colour_only_within_colour_range_at_its_probability() -> None:
    """fssim: at 5 m 80 % keep their colour, 20 % 'unknown'; at 12 m all 'unknown'."""
    cfg = replace(EXACT, colour_range=10.0, colour_probability=0.8)
    near = scan(cfg, ring(5.0, 100), ("yellow",) * 100, n=200)
    labels = np.concatenate([m.colours or () for m in near])
    assert abs(np.mean(labels == "yellow") - 0.8) < 0.01  # SE 0.0028
    assert set(labels) == {"yellow", "unknown"}
    far = scan(cfg, ring(12.0, 100), ("yellow",) * 100)[0]
    assert set(far.colours or ()) == {"unknown"}


def test_big_orange_reported_as_big_orange_or_orange() -> None:
    """Big cones: 'big_orange' by default, 'orange' with report_big_orange=False; z = 0.2525 - h."""
    cones = np.array([[4.0, 0.0]])
    (msg,) = scan(EXACT, cones, ("big_orange",))
    assert msg.colours == ("big_orange",)
    assert_allclose(msg.points[0, 2], 0.505 / 2 - 1.0)
    (plain,) = scan(replace(EXACT, report_big_orange=False), cones, ("big_orange",))
    assert plain.colours == ("orange",)
    (blind,) = scan(replace(EXACT, report_colour=False), cones, ("big_orange",))
    assert blind.colours is None


def test_output_sorted_by_measured_distance() -> None:
    """rtk scans are nearest-first by planar distance."""
    rng = np.random.default_rng(3)
    cones = rng.uniform(-15.0, 15.0, (300, 2))
    for msg in scan(get_profile("rtk").cones, cones, ("blue",) * 300, n=20):
        d = np.hypot(msg.points[:, 0], msg.points[:, 1])
        assert np.all(np.diff(d) >= 0.0)


@pytest.mark.parametrize("bad", [np.zeros((3, 3)), np.zeros(4)])
def test_truth_rejects_bad_cone_shapes(bad: np.ndarray) -> None:
    """TruthSample.cone_positions must be (n, 2) with n kinds."""
    with pytest.raises(ValueError, match="cone_positions"):
        TruthSample(0.0, Pose2D(0.0, 0.0, 0.0), cone_positions=bad, cone_kinds=("blue",) * 3)


def test_sample_colours_is_the_array_formulation() -> None:
    """The per-detection labels equal those of the numpy formulation they
    replaced (cumulative row, first edge above u; unknown when not coloured;
    big_orange for a big cone labelled orange), on a confusion that mixes all."""
    rng = np.random.default_rng(12)
    confusion = rng.dirichlet(np.ones(4), size=4)
    cdf = np.cumsum(confusion, axis=1)
    cdf[:, -1] = 1.0
    for n in (0, 1, 7, 40):
        true_class = rng.integers(0, 4, n)
        is_big = rng.random(n) < 0.3
        coloured = rng.random(n) < 0.7
        u = rng.random(n)
        for big_orange in (True, False):
            reported = np.minimum(np.sum(u[:, None] >= cdf[true_class], axis=1), 3)
            reported = np.where(coloured, reported, 3)
            want = [("blue", "yellow", "orange", "unknown")[k] for k in reported.tolist()]
            if big_orange:
                for i in np.flatnonzero(is_big & (reported == 2)):
                    want[i] = "big_orange"
            got = sample_colours(
                true_class, is_big, coloured, u, confusion_cdf=cdf, report_big_orange=big_orange
            )
            assert got == tuple(want)
