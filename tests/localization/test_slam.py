"""EKF-SLAM on cone landmarks: a small loop's map, candidates, re-observation, the map's book."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from numpy.testing import assert_allclose

from conesim.core.messages import (
    FRAME_GPS_ANTENNA,
    FRAME_REFERENCE,
    Header,
    HeadingStamped,
    Imu,
    Message,
    WheelSpeed,
)
from conesim.core.pose import Pose2D
from conesim.envs.map_quality import map_quality
from conesim.localization.cones import ConeUpdateConfig
from conesim.localization.cones.landmarks import LandmarkMap
from conesim.localization.ekf import EkfConfig, FusionEkf
from conesim.localization.ekf.synthetic import (
    Path,
    SensorNoise,
    fix_message,
    make_truth,
    messages,
)
from conesim.localization.slam import MapBook, SlamConfig, SlamUpdate
from tests.localization.cone_helpers import in_sensor, lane_map, noisy, scan

RADIUS = 10.0  # [m] the loop's centre line; the car drives it at 5 m/s, 0.5 rad/s
LATENCY = 0.2  # [s] the scans' delivery delay (each one replays the history after it)


def ring_cones() -> tuple[np.ndarray, list[str]]:
    """16 blue cones on a 8 m circle and 24 yellow ones on a 12 m circle, about 3.1 m apart."""
    inner = [(8.0 * math.cos(a), 8.0 * math.sin(a)) for a in np.linspace(0, 2 * math.pi, 17)[:-1]]
    outer = [(12.0 * math.cos(a), 12.0 * math.sin(a)) for a in np.linspace(0, 2 * math.pi, 25)[:-1]]
    return np.array(inner + outer), ["blue"] * 16 + ["yellow"] * 24


def loop_run(seed: int, duration: float = 17.0) -> tuple[FusionEkf, np.ndarray]:
    """The filter after ``duration`` [s] around the ring: 0.5 m GPS, the IMU, heading, wheel
    speed and 10 Hz scans (15 m, the front half, coloured within 10 m), starting on the
    true start pose."""
    rng = np.random.default_rng(seed)
    path = Path(w0=0.5, w1=0.0, v0=5.0, v1=0.0, c=0.0, yaw0=0.0, start=(0.0, -RADIUS))
    truth = make_truth(path, duration)
    cones, colours = ring_cones()
    cfg = ConeUpdateConfig()
    ekf = FusionEkf(EkfConfig(), SlamUpdate(cfg, SlamConfig(), start=truth.pose(0.0)))
    out: list[tuple[float, int, Message]] = [
        (d, 0, msg) for d, msg in messages(truth, SensorNoise(gps=0.5), rng)
    ]
    for k in range(0, len(truth.t), 20):
        t = float(truth.t[k])
        rel = in_sensor(truth.pose(t), cones)
        r = np.hypot(rel[:, 0], rel[:, 1])
        seen = (r <= 15.0) & (rel[:, 0] > 0.0)
        points = noisy(rel[seen], cfg, rng)
        labels = [c if d <= 10.0 else "unknown" for c, d in zip(colours, r, strict=True)]
        out.append(
            (
                t + LATENCY,
                1,
                scan(t, points, [lab for lab, s in zip(labels, seen, strict=True) if s]),
            )
        )
    out.sort(key=lambda item: (item[0], item[1]))
    for _, _, msg in out:
        ekf.process(msg)
    return ekf, cones


def test_small_loop_map_converges_to_the_cones_within_its_covariance() -> None:
    """1.35 laps of a 10 m ring with 0.5 m GPS: all 40 cones mapped once, none spurious,
    the loop closed; each landmark within its own 99.9 % ellipse (chi2 2 dof, 13.8), the
    map's NEES per dof below 1, its sigmas and its error centimetres."""
    ekf, cones = loop_run(0)
    state = ekf.landmark_state()
    assert state is not None
    xy, cov, book = state
    counts = ekf.health.landmarks
    assert counts is not None and counts.loop_closed
    q = map_quality(xy, cov, cones)
    assert (q.landmarks, q.missed, q.spurious) == (40, 0, 0)
    err = xy[:, None, :] - cones[None, :, :]
    nearest = cones[np.argmin(np.linalg.norm(err, axis=2), axis=1)]
    e = xy - nearest
    nees = np.einsum("qi,qi->q", e, np.linalg.solve(cov, e[..., None])[..., 0])
    assert nees.max() < 13.8
    assert q.nees_per_dof < 1.0  # honest or cautious, never overconfident
    sigma = np.sqrt(np.trace(cov, axis1=1, axis2=2) / 2.0)
    assert sigma.max() < 0.1  # from the 0.5 m of GPS to centimetres
    assert q.mean_error_m < 0.05
    assert "unknown" not in book.labels()


def test_same_seed_same_map() -> None:
    """Two runs with one seed give the same landmarks, bit for bit."""
    a, _ = loop_run(5, duration=6.0)
    b, _ = loop_run(5, duration=6.0)
    sa, sb = a.landmark_state(), b.landmark_state()
    assert sa is not None and sb is not None
    assert len(sa[0]) > 5
    assert np.array_equal(sa[0], sb[0]) and np.array_equal(sa[1], sb[1])


def test_compressed_map_gives_the_dense_filters_numbers() -> None:
    """The ring's 17 s (the map built, the loop closed, then frozen), seed 3: the pose and
    landmarks 0, 17 and 39 with landmark 17's covariance are the numbers the filter gave
    with the whole (n, n) P in its state (commit 5e3939e), to 1e-9."""
    ekf, _ = loop_run(3)
    state = ekf.landmark_state()
    assert state is not None
    xy, cov, _ = state
    est = ekf.estimate()
    assert len(xy) == 40 and len(est.state) == 7  # the estimate: the vehicle's states
    pose = [est.pose.x, est.pose.y, est.pose.yaw]
    assert_allclose(pose, [7.94150393444832, 6.049959590898539, 2.2169620089395465], atol=1e-9)
    assert_allclose(
        np.diag(est.pose_covariance),
        [0.001155356225893306, 0.0011172336806638565, 2.447901731276478e-07],
        rtol=0, atol=1e-12,
    )  # fmt: skip
    assert_allclose(
        xy[[0, 17, 39]],
        [[7.972149650111921, 0.03818413525429518], [-0.04886936250521091, 8.026509598576984],
         [-0.04935122773316097, -11.975021214861385]],
        rtol=0, atol=1e-9,
    )  # fmt: skip
    assert_allclose(
        cov[17],
        [[0.0012200407493159584, 2.0852590938103596e-05],
         [2.0852590938103596e-05, 0.0012150775358210249]],
        rtol=0, atol=1e-12,
    )  # fmt: skip


def _static_filter(update: SlamUpdate) -> FusionEkf:
    """A filter at the origin (1 mm, 0.01 deg), the car standing still."""
    from tests.localization.cone_helpers import filter_at

    return filter_at(Pose2D(0.0, 0.0, 0.0), 1e-3, math.radians(0.01), update)  # type: ignore[arg-type]


def _still(ekf: FusionEkf, t: float) -> None:
    """An IMU sample, a wheel speed, a heading (0.01 deg) and a fix (1 mm) of a car standing
    still at the origin at ``t`` [s]."""
    ekf.process(Imu(Header(t, FRAME_GPS_ANTENNA), 0.0, 0.0, 0.0, 1e-8, 1e-6))
    ekf.process(WheelSpeed(Header(t, FRAME_GPS_ANTENNA), 0.0, 1e-6))
    ekf.process(HeadingStamped(Header(t, FRAME_REFERENCE), 0.0, math.radians(0.01) ** 2))
    ekf.process(fix_message(t, 0.0, 0.0, 1e-3))


def test_false_positive_seen_once_never_becomes_a_landmark() -> None:
    """Ten cones in five scans, a ghost 6 m ahead in the first only: ten landmarks, and the
    ghost's candidate is gone after the 0.5 s timeout."""
    lmap = lane_map()
    cfg = ConeUpdateConfig()
    ekf = _static_filter(SlamUpdate(cfg, SlamConfig()))
    rng = np.random.default_rng(0)
    truth = in_sensor(Pose2D(0.0, 0.0, 0.0), lmap.positions)
    for i in range(8):
        t = 0.1 * (i + 1)
        _still(ekf, t)
        points = noisy(truth, cfg, rng)
        if i == 0:
            points = np.vstack([points, [[6.0, 0.2]]])
        ekf.process(scan(t, points))
    counts = ekf.health.landmarks
    assert counts is not None
    assert (counts.confirmed, counts.tentative, counts.pruned) == (10, 0, 0)
    state = ekf.landmark_state()
    assert state is not None
    assert np.linalg.norm(state[0] - [6.0, 0.2], axis=1).min() > 1.0


def test_landmark_covariance_shrinks_with_each_reobservation() -> None:
    """A cone 5 m ahead from a pose known to 1 mm: confirmed from its third sighting with
    P = R_z = diag(0.05^2, (5 x 0.007)^2); after k more scans P = R_z / (1 + k), to 5 %."""
    cfg = ConeUpdateConfig()
    ekf = _static_filter(SlamUpdate(cfg, SlamConfig()))
    rng = np.random.default_rng(1)
    r_z = np.diag([0.05**2, (5.0 * 0.007) ** 2])
    seen = []
    for i in range(7):
        t = 0.1 * (i + 1)
        _still(ekf, t)
        ekf.process(scan(t, noisy(np.array([[5.0, 0.0]]), cfg, rng)))
        state = ekf.landmark_state()
        assert state is not None
        seen.append(state[1][0] if len(state[0]) else None)
    assert seen[0] is None and seen[1] is None  # two sightings: a candidate only
    for k, cov in enumerate(seen[2:]):
        assert_allclose(np.diag(cov), np.diag(r_z) / (1 + k), rtol=0.05)


def test_landmark_missed_too_often_is_pruned() -> None:
    """A cone seen in three scans, then in view and missed: gone after prune_misses (5)
    more misses than hits (its hit at confirmation counts), in the 9th scan after it."""
    cfg = ConeUpdateConfig()
    ekf = _static_filter(SlamUpdate(cfg, SlamConfig()))
    rng = np.random.default_rng(2)
    anchor = np.array([[5.0, -3.0], [5.0, 3.0], [9.0, -3.0], [9.0, 3.0]])
    ghost = np.array([[7.0, 0.0]])
    removed_at = None
    for i in range(16):
        t = 0.1 * (i + 1)
        _still(ekf, t)
        points = anchor if i >= 3 else np.vstack([anchor, ghost])
        ekf.process(scan(t, noisy(points, cfg, rng)))
        counts = ekf.health.landmarks
        assert counts is not None
        if counts.pruned and removed_at is None:
            removed_at = i
    counts = ekf.health.landmarks
    assert counts is not None
    assert (counts.confirmed, counts.pruned, counts.ever_confirmed) == (4, 1, 5)
    assert removed_at == 3 + 6 - 1


def test_book_candidates_confirm_after_three_sightings_and_vote_colours() -> None:
    """Worked: a detection at (1, 1) seen at t = 0, 0.1, 0.2 within 0.5 m confirms with
    votes (2 blue, 1 unknown): blue; a detection 1 m away is a second candidate."""
    cfg = SlamConfig()
    book = MapBook.empty()
    pts = [np.array([[1.0, 1.0]]), np.array([[1.1, 0.9], [2.0, 1.0]]), np.array([[0.95, 1.05]])]
    classes = [np.array([0]), np.array([-1, 1]), np.array([0])]
    confirmed = []
    for t, (p, c) in enumerate(zip(pts, classes, strict=True)):
        book, confirm, votes = book.sighted(p, c, 0.1 * t, cfg)
        confirmed.append((confirm.tolist(), votes.tolist()))
    assert confirmed[:2] == [([], []), ([], [])]
    assert confirmed[2] == ([0], [[2.0, 0.0, 0.0]])
    assert len(book.cand_seen) == 1 and book.cand_seen[0] == 1  # the one at (2, 1)
    book = book.added(np.array([[2.0, 0.0, 0.0]]))
    assert book.labels() == ["blue"]
    book, _, _ = book.sighted(np.zeros((0, 2)), None, 0.2 + cfg.candidate_timeout + 0.01, cfg)
    assert len(book.cand_seen) == 0  # timed out


def test_book_but_is_dataclasses_replace_for_every_field() -> None:
    """The book's own replace (``MapBook._but``, cheaper than ``dataclasses.replace``)
    carries every field: changing any one gives ``dataclasses.replace``'s book, and a field
    added to MapBook and not to ``_but`` fails here."""
    book = MapBook.empty()
    same = book._but()
    assert all(getattr(same, f.name) is getattr(book, f.name) for f in dataclasses.fields(MapBook))
    for i, field in enumerate(dataclasses.fields(MapBook)):
        value = object() if field.name != "closed" else True
        changed = book._but(**{field.name: value})
        expected = dataclasses.replace(book, **{field.name: value})
        assert all(
            getattr(changed, f.name) is getattr(expected, f.name)
            for f in dataclasses.fields(MapBook)
        ), (i, field.name)


def test_book_classes_are_the_vote_majority_and_make_the_landmark_map() -> None:
    """Worked: votes (2 blue), (none), (1 yellow, 1 orange) are classes 0, -1 and 1 (a tie
    goes to the first), the labels blue, unknown, yellow; a LandmarkMap takes the classes
    as they are, and refuses a class outside -1..2."""
    book = dataclasses.replace(
        MapBook.empty(),
        votes=np.array([[2.0, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 1.0, 1.0]]),
        hits=np.ones(3, dtype=np.intp),
        misses=np.zeros(3, dtype=np.intp),
    )
    assert book.classes().tolist() == [0, -1, 1]
    assert book.labels() == ["blue", "unknown", "yellow"]
    positions = np.array([[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]])
    lmap = LandmarkMap(positions, book.classes())
    assert lmap.classes.tolist() == LandmarkMap(positions, book.labels()).classes.tolist()
    with pytest.raises(ValueError, match="classes"):
        LandmarkMap(positions, np.array([0, 1, 5]))
