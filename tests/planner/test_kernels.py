"""The compiled kernels (``planner.kernels``) give the numpy code's numbers, bit for bit.

Each reference below is the numpy formulation the kernel replaced (as it
stood before the kernels), compared exactly on random inputs that include
ties (points on a grid), zero-length steps and closed (wrapped) station
axes. The whole planning step was also compared before and after on 718
recorded scenes (synthetic winding tracks and every shipped track, ideal and
noisy detectors): identical outputs. The speed profile's reference is
``speed_profile``'s numpy and Python body as it stood before it was compiled
(friction-ellipse passes, jerk limit, downforce), compared byte for byte.
"""

from __future__ import annotations

import itertools
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from numpy.testing import assert_array_equal
from scipy.interpolate import BSpline, splev, splprep
from scipy.spatial import Delaunay, QhullError

from localization.global_path import global_path_from_centreline
from planner import MidlineConfig, SpeedProfileConfig
from planner.bridges import (
    ConeSet,
    TrackEstimate,
    boundary_edges,
    delaunay_edges,
    estimate_track,
    find_bridges,
    pair_table,
    virtual_partners,
)
from planner.geometry import PathProjector, StationAxis, arc_length, station_difference
from planner.kernels._common import wrapped_difference
from planner.kernels.spline import _spline_at
from planner.midline import boundary_cones, in_view
from planner.ordering import start_index
from planner.speed_profile import (
    _menger,
    backward_pass,
    curvature_limit,
    ellipse_backward_pass,
    ellipse_forward_pass,
    forward_pass,
    jerk_limit,
    speed_profile,
    window_mean,
)
from planner.spline import spline_through

REPO = Path(__file__).resolve().parents[2]  # the child processes import from here


def run_child(script: str) -> None:
    """Run ``script`` in a fresh Python process from the repository; it must print "ok"."""
    done = subprocess.run(
        [sys.executable, "-c", script],
        capture_output=True,
        text=True,
        check=False,
        timeout=600,
        cwd=REPO,
    )
    assert done.returncode == 0, done.stdout + done.stderr
    assert done.stdout.strip() == "ok"


# ---------------------------------------------------------------- references


def ref_speed_profile(
    points: np.ndarray,
    config: SpeedProfileConfig,
    v_start: float | None = None,
    *,
    s: np.ndarray | None = None,
    v_end: float | None = None,
) -> np.ndarray:
    """``speed_profile`` as numpy and Python steps: its body before it was compiled."""
    n = len(points)
    if n == 0:
        return np.zeros(0)
    step = points[1:] - points[:-1]
    step_length = np.hypot(step[:, 0], step[:, 1])
    if s is None:
        s = np.zeros(n)
        np.cumsum(step_length, out=s[1:])  # arc_length(points)
    kappa = _menger(points, step, step_length)
    if config.curvature_window > 0.0 and n > 2:
        kappa = window_mean(kappa, float(s[-1]) / (n - 1), config.curvature_window)
    v = curvature_limit(kappa, config)
    jerk = jerk_limit(kappa, float(s[-1]) / (n - 1), config) if n > 2 else None
    if jerk is not None:
        v = np.minimum(v, jerk)
    if v_start is not None:
        v[0] = min(v[0], max(v_start, 0.0))
    if config.friction_ellipse:
        c = config
        v = ellipse_forward_pass(
            s, v, kappa, c.a_drive, a_lat_max=c.a_lat_max, a_lat_aero=c.a_lat_aero
        )
    else:
        v = forward_pass(s, v, config.a_drive)
    if config.horizon_stop:
        v[-1] = 0.0 if v_end is None else min(v[-1], max(v_end, 0.0))
    if config.friction_ellipse:
        c = config
        return ellipse_backward_pass(
            s, v, kappa, c.a_brake, a_lat_max=c.a_lat_max, a_lat_aero=c.a_lat_aero
        )
    return backward_pass(s, v, config.a_brake)


def ref_spline_through(points: np.ndarray, config: MidlineConfig) -> np.ndarray | None:
    """``spline_through`` with scipy's ``BSpline`` and numpy's ``interp``."""
    m = len(points)
    degree = min(config.spline_degree, m - 1)
    length = float(arc_length(points)[-1])
    count = max(int(length * 2 / config.spacing) + 2, 2 * m)
    try:
        ((knots, coefficients, k), _), _, ier, _ = splprep(
            points.T, s=m * config.spline_sigma**2, k=degree, full_output=True
        )
        if ier > 0:
            return None
        spline = BSpline.construct_fast(knots, np.column_stack(coefficients), k)
        u = np.arange(count) * (1.0 / (count - 1))
        u[-1] = 1.0
        s = arc_length(spline(u))
        stations = np.arange(0.0, float(s[-1]), config.spacing)
        if s[-1] - stations[-1] > 1e-9:
            stations = np.concatenate([stations, s[-1:]])
        path = spline(np.interp(stations, s, u))
    except (ValueError, TypeError):
        return None
    return path if np.isfinite(path).all() else None


def ref_projection(
    projector: PathProjector, points: np.ndarray, prefer: tuple[float, float, float] | None
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Every segment measured with numpy; least score, then nearest midpoint, then index."""
    table = projector._table
    rx = points[:, 0, None] - table[:, 0]
    ry = points[:, 1, None] - table[:, 1]
    dx, dy = table[:, 2], table[:, 3]
    t = (rx * dx + ry * dy) * table[:, 4]
    np.maximum(t, 0.0, out=t)
    np.minimum(t, 1.0, out=t)
    gx, gy = rx - t * dx, ry - t * dy
    d2 = gx * gx + gy * gy
    score = d2
    if prefer is not None:
        centre, half, penalty = prefer
        away = np.abs(projector.axis.difference(table[:, 5], centre))
        score = np.sqrt(d2) + np.where(away <= half + table[:, 6], 0.0, penalty)
    mx = points[:, 0, None] - (table[:, 0] + 0.5 * dx)
    my = points[:, 1, None] - (table[:, 1] + 0.5 * dy)
    mid2 = mx * mx + my * my
    seg = np.array(
        [np.lexsort((np.arange(len(table)), mid2[i], score[i]))[0] for i in range(len(points))],
        dtype=np.intp,
    )
    rows = np.arange(len(points))
    return seg, t[rows, seg], d2[rows, seg]


def ref_pairs(cones: ConeSet, config: MidlineConfig) -> tuple[np.ndarray, ...]:
    """``pair_table``'s arrays with numpy (distance everywhere)."""
    left = (cones.side > 0).nonzero()[0]
    right = (cones.side < 0).nonzero()[0]
    pl, pr = cones.points[left], cones.points[right]
    dist = np.hypot(np.subtract.outer(pl[:, 0], pr[:, 0]), np.subtract.outer(pl[:, 1], pr[:, 1]))
    gap = np.abs(
        station_difference(
            cones.station[right][None, :],
            cones.station[left][:, None],
            cones.axis.length,
            cones.axis.closed,
        )
    )
    ol, or_ = cones.offset[left], cones.offset[right]
    return (
        left,
        right,
        dist,
        gap <= config.max_station_gap,
        np.subtract.outer(ol, or_),
        0.5 * (np.add.outer(ol, or_)),
    )


def ref_track(cones: ConeSet, config: MidlineConfig) -> TrackEstimate:
    """``estimate_track`` with numpy masks, argmins and ``numpy.median``."""
    _, _, dist, same, span, middle = ref_pairs(cones, config)
    valid = (
        same
        & (span >= config.min_track_width)
        & (span <= config.max_track_width)
        & (dist <= config.max_bridge_length)
    )
    rows = np.nonzero(valid.any(axis=1))[0]
    cols = np.nonzero(valid.any(axis=0))[0]
    if len(rows) == 0 or len(rows) + len(cols) < config.min_width_samples:
        return TrackEstimate(config.nominal_track_width, 0.0, measured=False)
    masked = np.where(valid, dist, np.inf)
    width = valid.shape[1]
    picks = np.concatenate(
        [rows * width + masked.argmin(axis=1)[rows], masked.argmin(axis=0)[cols] * width + cols]
    )
    return TrackEstimate(
        float(np.median(span.take(picks))), float(np.median(middle.take(picks))), measured=True
    )


def ref_bridges(
    cones: ConeSet, edges: np.ndarray, config: MidlineConfig, track: TrackEstimate
) -> tuple[np.ndarray, ...]:
    """``find_bridges`` with numpy."""
    i, j = edges[:, 0], edges[:, 1]
    side_i = cones.side[i]
    across = side_i != cones.side[j]
    i, j = i[across], j[across]
    swap = side_i[across] < 0
    left, right = np.where(swap, j, i), np.where(swap, i, j)
    start = cones.points[left]
    vec = cones.points[right] - start
    length = np.hypot(vec[:, 0], vec[:, 1])
    span = cones.offset[left] - cones.offset[right]
    station = cones.station[left]
    ds = cones.axis.difference(cones.station[right], station)
    valid = (
        (span >= config.min_track_width)
        & (span <= config.max_track_width)
        & (length <= config.max_bridge_length)
        & (np.abs(ds) <= config.max_station_gap)
        & ~(cones.virtual[left] & cones.virtual[right])
    )
    if track.measured:
        valid &= np.abs(span - track.width) <= config.width_tolerance
    used = valid.copy()
    if valid.any():
        best = np.full(len(cones), np.inf)
        np.minimum.at(best, left[valid], length[valid])
        np.minimum.at(best, right[valid], length[valid])
        used = valid & ((length <= best[left]) | (length <= best[right]))
    return left, right, length, valid, used, start + 0.5 * vec, station + 0.5 * ds


# ---------------------------------------------------------------- scenes


def random_cones(rng: np.random.Generator, n: int, closed: bool, grid: bool = False) -> ConeSet:
    """Cones on both sides of a wobbly track, some strays; optionally on a 0.5 m grid."""
    x = np.sort(rng.uniform(0.0, 40.0, n))
    side = np.where(rng.random(n) > 0.5, 1, -1).astype(np.int8)
    offset = side * rng.normal(1.75, 0.4, n)
    offset[rng.random(n) < 0.1] *= 0.2  # strays near the middle
    points = np.column_stack([x, offset + 0.3 * np.sin(x / 5.0)])
    if grid:
        points = np.round(points * 2.0) / 2.0
        offset = np.round(offset * 2.0) / 2.0
    station = (x + 50.0) % 60.0 if closed else x.copy()
    tangent = np.tile([1.0, 0.0], (n, 1))
    return ConeSet(
        points=points,
        side=side,
        offset=offset,
        station=station,
        tangent=tangent,
        virtual=np.zeros(n, dtype=bool),
        axis=StationAxis(60.0 if closed else 200.0, closed),
    )


def loop_projector(closed: bool, grid: bool = False) -> PathProjector:
    """A wobbly loop of 400 points (integer coordinates when ``grid``: exact ties)."""
    s = np.linspace(0.0, 2 * math.pi, 400, endpoint=False)
    xy = np.column_stack([30 * np.cos(s) + 3 * np.cos(7 * s), 20 * np.sin(s)])
    if grid:
        xy = np.round(xy)
        xy = xy[np.r_[True, np.any(np.diff(xy, axis=0) != 0.0, axis=1)]]
    return PathProjector(global_path_from_centreline(xy, closed=closed))


# ---------------------------------------------------------------- tests


@pytest.mark.parametrize("closed", [True, False])
@pytest.mark.parametrize("grid", [False, True])
@pytest.mark.parametrize("prefer", [None, (5.0, 27.5, 2.0), (150.0, 27.5, math.inf), (0, 3, 0.5)])
def test_nearest_segments_is_the_exhaustive_search(
    closed: bool, grid: bool, prefer: tuple[float, float, float] | None
) -> None:
    """Least score over every segment; ties to the nearer midpoint, then the lower index."""
    projector = loop_projector(closed, grid)
    rng = np.random.default_rng(20)
    for _ in range(10):
        points = rng.uniform(-45.0, 45.0, (60, 2))
        if grid:
            points = np.round(points * 2.0) / 2.0
        got = projector._project(np.ascontiguousarray(points), prefer)
        seg, t, d2 = ref_projection(projector, points, prefer)
        assert_array_equal(got.segment, seg)
        assert_array_equal(got.distance, np.sqrt(d2))
        table = projector._table.take(seg, axis=0)
        assert_array_equal(got.station, table[:, 8] + t * table[:, 7])
        assert_array_equal(got.foot, table[:, 0:2] + t[:, None] * table[:, 2:4])


def test_station_wrap_is_numpy_remainder() -> None:
    """The fmod-free wrap gives ``station_difference``'s numbers, edges included."""
    rng = np.random.default_rng(21)
    for length in (60.0, 0.1, 1234.5678, 3.0):
        diff = np.concatenate(
            [
                rng.uniform(-2 * length, 2 * length, 2000),
                [0.0, -0.0, 0.5 * length, -0.5 * length, length, -length, 1.5 * length],
                [2 * length, -2 * length, 1e300, math.nan, math.inf],
            ]
        )
        with np.errstate(invalid="ignore"):  # the NaN and inf rows
            expected = station_difference(diff, 0.0, length, True)
        got = np.array([wrapped_difference(d, length, True) for d in diff])
        assert_array_equal(got, expected)
    assert wrapped_difference(5.0, 0.0, True) == 5.0


@pytest.mark.parametrize("closed", [True, False])
def test_boundary_cones_pairs_track_and_partners(closed: bool) -> None:
    """In view, pair table (on the same stretch), track estimate, boundary filter, partners."""
    rng = np.random.default_rng(22)
    config = MidlineConfig()
    for trial in range(150):
        cones = random_cones(rng, int(rng.integers(0, 60)), closed, grid=trial % 3 == 0)
        keep = (
            (cones.points[:, 0] >= config.min_x)
            & (np.hypot(cones.points[:, 0], cones.points[:, 1]) <= config.max_range)
            & (np.abs(cones.offset) >= config.min_boundary_offset)
            & (np.abs(cones.offset) <= config.max_boundary_offset)
        )
        assert_array_equal(in_view(cones, config), keep)
        real = cones.select(keep)
        track = ref_track(real, config)
        assert estimate_track(pair_table(real, config), config) == track
        if track.measured:
            real = real.select(track.boundary_offset(real) >= -config.boundary_tolerance)
        got, pairs, got_track, dropped = boundary_cones(cones, config)
        assert got_track == track
        assert dropped == len(cones) - len(real)
        assert_array_equal(got.points, real.points)
        left, right, dist, same, span, middle = ref_pairs(real, config)
        for name, value in zip(
            ("left", "right", "same_stretch", "span", "middle"),
            (left, right, same, span, middle),
            strict=True,
        ):
            assert_array_equal(getattr(pairs, name), value, err_msg=name)
        assert_array_equal(pairs.dist[same], dist[same])
        assert np.isinf(pairs.dist[~same]).all()
        # Virtual partners: nobody across within the radius, on the boundary line.
        close = same & (dist <= config.partner_radius)
        near = np.zeros(len(real), dtype=bool)
        near[left] = close.any(axis=1)
        near[right] = close.any(axis=0)
        need = ~near & (np.abs(track.boundary_offset(real)) <= config.partner_offset_tolerance)
        partners = virtual_partners(got, pairs, config, track)
        assert_array_equal(partners.station, real.station[need])


@pytest.mark.parametrize("closed", [True, False])
def test_delaunay_bridges_and_boundary_edges(closed: bool) -> None:
    """Edges in scipy's neighbour order; bridges and boundary edges as numpy finds them."""
    rng = np.random.default_rng(23)
    config = MidlineConfig()
    for trial in range(100):
        cones = random_cones(rng, int(rng.integers(3, 90)), closed, grid=trial % 3 == 0)
        if trial % 4 == 0:
            cones = cones.join(virtual_partners(cones, pair_table(cones, config), config,
                                                ref_track(cones, config)))  # fmt: skip
        try:
            indptr, indices = Delaunay(cones.points).vertex_neighbor_vertices
        except QhullError:  # degenerate: no triangulation either way
            continue
        rows = np.repeat(np.arange(len(cones)), np.diff(indptr))
        edges = np.column_stack([rows, indices])[rows < indices].astype(np.intp)
        assert_array_equal(delaunay_edges(cones.points), edges)
        track = ref_track(cones, config)
        got = find_bridges(cones, edges, config, track)
        names = ("left", "right", "length", "valid", "used", "midpoints", "station")
        for name, value in zip(names, ref_bridges(cones, edges, config, track), strict=True):
            assert_array_equal(getattr(got, name), value, err_msg=name)
        i, j = edges[:, 0], edges[:, 1]
        along = (
            (cones.side[i] == cones.side[j])
            & (np.abs(cones.offset[i] - cones.offset[j]) < config.min_track_width)
            & (cones.station_gap(i, j) <= config.max_station_gap)
        )
        assert_array_equal(boundary_edges(cones, edges, config), edges[along])


def test_start_index_is_the_masked_argmin() -> None:
    """The nearest midpoint in front within the station window, first of equals."""
    rng = np.random.default_rng(24)
    config = MidlineConfig()
    for trial in range(300):
        m = int(rng.integers(0, 30))
        mid = rng.integers(-4, 20, (m, 2)) * 0.5 if trial % 2 else rng.normal(5.0, 6.0, (m, 2))
        axis = StationAxis(50.0, closed=trial % 3 == 0)
        station = mid[:, 0] + rng.normal(0.0, 3.0, m) + 45.0
        sensor = 45.0 + rng.normal(0.0, 2.0)
        expected = None
        if m:
            ahead = axis.difference(station, sensor)
            ok = (
                (mid[:, 0] > config.start_min_x)
                & (ahead >= -config.start_station_back)
                & (ahead <= config.start_station_ahead)
            )
            if ok.any():
                expected = int(np.where(ok, np.hypot(mid[:, 0], mid[:, 1]), np.inf).argmin())
        assert start_index(mid, station, sensor, axis, config) == expected


def assert_bits_equal(got: np.ndarray, expected: np.ndarray) -> None:
    """The same dtype, shape and bytes (so -0.0 is not 0.0, and NaN is NaN)."""
    assert got.dtype == expected.dtype and got.shape == expected.shape
    if got.tobytes() != expected.tobytes():
        assert_array_equal(got, expected)  # shows where
        raise AssertionError(f"bits differ: {got!r} != {expected!r}")


# Every combination of the profile's switches: friction ellipse, jerk limit
# (off, default, tight; a jerk window of 1.25 m on 0.25 m steps rounds a tie,
# 2.5 -> 2, 0.25 m gives no window), downforce (none, default, more than
# some paths' curvature), curvature window (off, default, 1.0 m = 4 steps of
# 0.25 m exactly: int() of an integer), horizon stop.
PROFILE_CONFIGS = [
    SpeedProfileConfig(
        friction_ellipse=ellipse,
        lateral_jerk_max=jerk,
        jerk_window=jerk_window,
        a_lat_aero=aero,
        curvature_window=window,
        horizon_stop=stop,
    )
    for ellipse in (True, False)
    for jerk, jerk_window in ((math.inf, 4.0), (60.0, 4.0), (5.0, 1.25), (60.0, 0.25))
    for aero in (0.0, 0.0143, 0.5)
    for window in (0.0, 2.0, 1.0)
    for stop in (True, False)
]


def profile_cases(rng: np.random.Generator, trials: int) -> list[np.ndarray]:
    """Paths: random walks of several step sizes, smooth curves, walks on a
    0.25 m grid (exact arc lengths and spacings, collinear steps, reversals),
    repeated points, NaN points, and every length from 0 to 5."""
    cases = [np.zeros((n, 2)) for n in range(3)]
    cases += [np.cumsum(rng.normal(0.0, 1.0, (n, 2)), axis=0) for n in range(1, 6)]
    cases.append(np.repeat(rng.normal(0.0, 1.0, (1, 2)), 7, axis=0))  # one point, 7 times
    moves = np.array([[0.25, 0.0], [0.0, 0.25], [0.0, -0.25], [-0.25, 0.0]])
    for trial in range(trials):
        n = int(rng.integers(0, 90))
        kind = trial % 4
        if kind == 0:
            points = np.cumsum(rng.normal(0.0, rng.choice([0.05, 0.5, 3.0]), (n, 2)), axis=0)
        elif kind == 1:
            t = np.cumsum(rng.uniform(0.3, 0.6, n))
            points = np.column_stack([t, rng.uniform(1.0, 8.0) * np.sin(t / rng.uniform(3, 20))])
        elif kind == 2:
            points = np.cumsum(moves[rng.choice(4, n, p=[0.6, 0.15, 0.15, 0.1])], axis=0)
        else:
            points = np.cumsum(rng.normal(0.0, 0.5, (n, 2)), axis=0)
            if n > 6:
                points[5] = points[4]
                points[n - 1] = points[n - 2]
        if n > 8 and trial % 97 == 0:
            points[int(rng.integers(0, n)), int(rng.integers(0, 2))] = math.nan
        cases.append(points)
    return cases


def test_speed_profile_is_the_numpy_steps() -> None:
    """The compiled profile is the numpy steps, bit for bit, for every switch.

    Each case goes through a config of ``PROFILE_CONFIGS`` in turn (about 6
    cases per config), with the start and end speeds free, negative, -0.0,
    NaN, inf and ordinary, and with the arc length given (as computed, and
    scaled, which the profile takes as it comes) or not.
    """
    rng = np.random.default_rng(25)
    starts = [None, 0.0, -0.0, -1.0, 3.7, 100.0, math.nan, math.inf]
    ends = [None, 2.5, -0.5, -0.0, math.inf]
    cases = profile_cases(rng, 2000)
    for i, points in enumerate(cases):
        config = PROFILE_CONFIGS[i % len(PROFILE_CONFIGS)]
        v_start = starts[i % len(starts)]
        v_end = ends[i % len(ends)]
        with np.errstate(invalid="ignore"):  # the NaN cases
            expected = ref_speed_profile(points, config, v_start, v_end=v_end)
        assert_bits_equal(
            speed_profile(points, config, v_start, v_end=v_end, check=False), expected
        )
        if len(points):
            # as computed; scaled; evenly spaced (finite also where a point is NaN)
            s = [arc_length(points), 1.1 * arc_length(points), 0.4 * np.arange(len(points))][i % 3]
            with np.errstate(invalid="ignore", over="ignore"):
                expected = ref_speed_profile(points, config, v_start, s=s, v_end=v_end)
            assert_bits_equal(
                speed_profile(points, config, v_start, s=s, v_end=v_end, check=False), expected
            )


def test_speed_profile_edge_cases_for_every_switch() -> None:
    """Every config, start and end speed on paths of 1 to 3 points, and on
    paths with NaN: a NaN point (curvature 0 around it; its arc length NaN
    from there, or an even finite one), a NaN arc length in the middle (NaN
    steps in the passes), coordinates of 1e155 m whose curvature overflows
    to inf / inf = NaN (NaN curvature, window means and jerk limits)."""
    rng = np.random.default_rng(27)
    starts = [None, 0.0, -0.0, -1.0, 3.7, math.nan, math.inf]
    ends = [None, 0.0, -0.0, 2.5, -0.5, math.nan, math.inf]
    nan_path = np.cumsum(rng.normal(0.0, 0.5, (14, 2)), axis=0)
    nan_path[6, 1] = math.nan
    paths = [
        (np.zeros((1, 2)), None),
        (rng.normal(0.0, 1.0, (2, 2)), None),
        (rng.normal(0.0, 1.0, (3, 2)), None),
        (nan_path, None),
        (nan_path, 0.4 * np.arange(14)),
        (nan_path, np.where(np.arange(14) == 9, math.nan, 0.4 * np.arange(14))),
        (np.cumsum(rng.normal(0.0, 1e155, (14, 2)), axis=0), 0.4 * np.arange(14)),
    ]
    for (points, s), config in itertools.product(paths, PROFILE_CONFIGS):
        speeds = list(itertools.product(starts, ends))
        if len(points) > 3:  # the NaN paths: each start and each end once
            speeds = list(zip(starts, ends, strict=True))
        for v_start, v_end in speeds:
            with np.errstate(invalid="ignore", over="ignore"):
                expected = ref_speed_profile(points, config, v_start, s=s, v_end=v_end)
            got = speed_profile(points, config, v_start, s=s, v_end=v_end, check=False)
            assert_bits_equal(got, expected)


def test_speed_profile_is_the_numpy_steps_on_the_global_paths() -> None:
    """Along each shipped track's global path, open and (closed) over three laps,
    as ``GlobalSpeedPlan`` profiles it, with the default limits."""
    from localization.global_path import global_path_for_track
    from tracks import load_track, shipped_tracks

    for name in shipped_tracks():
        path = global_path_for_track(load_track(name))
        pts = np.asarray(path.xy, dtype=float)
        laps = np.vstack([pts, pts, pts, pts[:1]]) if path.closed else pts
        for config in PROFILE_CONFIGS[::7]:
            assert_bits_equal(speed_profile(laps, config), ref_speed_profile(laps, config))


def test_spline_path_is_bspline_and_interp() -> None:
    """The compiled evaluation, arc length, stations and interp: scipy's and numpy's numbers."""
    rng = np.random.default_rng(26)
    config = MidlineConfig()
    for trial in range(300):
        m = int(rng.integers(2, 40))
        x = np.cumsum(rng.uniform(0.2, 3.0, m))
        y = np.cumsum(rng.normal(0.0, 0.8, m))
        points = np.column_stack([x, y])
        if trial % 7 == 0:
            points = np.round(points)
        expected = ref_spline_through(points, config)
        got = spline_through(points, config)
        if expected is None:
            assert got is None
        else:
            assert got is not None
            assert_array_equal(got, expected)


def test_spline_evaluation_is_splev_for_every_degree() -> None:
    """De Boor's recursion as scipy runs it: splev's numbers at knots, ends and inside."""
    rng = np.random.default_rng(27)
    work = np.empty(12)
    for trial in range(200):
        m = int(rng.integers(2, 25))
        points = np.vstack([np.cumsum(rng.uniform(1.0, 4.0, m)), rng.normal(0.0, 2.0, m)])
        k = min(int(rng.integers(1, 6)), m - 1)
        tck, _ = splprep(points, s=0.0 if trial % 2 else 0.05 * m, k=k)
        u = np.concatenate([[0.0, 1.0], tck[0], rng.uniform(0.0, 1.0, 30)])
        c = np.column_stack(tck[1])
        out = np.empty((len(u), 2))
        prev = k
        for i, x in enumerate(u):
            prev = _spline_at(tck[0], c, k, x, out, i, prev, work)
        assert_array_equal(out, np.column_stack(splev(u, tck)))


def test_kernels_are_deterministic() -> None:
    """Same inputs, same outputs, bit for bit, call after call."""
    rng = np.random.default_rng(28)
    config = MidlineConfig()
    cones = random_cones(rng, 70, closed=True)
    first = boundary_cones(cones, config)
    again = boundary_cones(cones, config)
    assert_array_equal(first[0].points, again[0].points)
    assert first[2] == again[2]
    projector = loop_projector(True)
    points = rng.uniform(-40.0, 40.0, (50, 2))
    a = projector.project_around(points, 20.0, 35.0, 2.0)
    b = projector.project_around(points, 20.0, 35.0, 2.0)
    assert_array_equal(a.offset, b.offset)


def test_import_without_a_writable_cache_directory() -> None:
    """No cache directory numba can write: the planner's (each module of ``kernels``,
    ``fused``) and the EKF's kernels compile uncached, each module with its warning."""

    script = """
import pkgutil
import warnings
import numba.core.caching as caching

def unwritable(self):
    raise OSError("read-only")

caching._CacheLocator.ensure_cache_path = unwritable  # every locator fails
with warnings.catch_warnings(record=True) as caught:
    warnings.simplefilter("always")
    from planner import kernels
    from localization.ekf import kernels as ekf_kernels
import numpy as np
owners = {str(w.message).split(":")[0] for w in caught if "no writable cache" in str(w.message)}
modules = {f"planner.kernels.{m.name}" for m in pkgutil.iter_modules(kernels.__path__)}
assert len(modules) == 10, modules
assert owners == modules | {"planner.fused", "localization.ekf.kernels"}, caught
assert kernels.arc_length(np.array([[0.0, 0.0], [3.0, 4.0]])).tolist() == [0.0, 5.0]
p = np.array([[1.0, 2.0], [4.0, 3.0]])
assert ekf_kernels.symmetrised(p).tolist() == [[1.0, 3.0], [3.0, 3.0]]
print("ok")
"""
    run_child(script)


def test_building_an_autopilot_loads_every_kernel_the_planning_step_calls() -> None:
    """After ``warm_up_planner`` (in ``Autopilot()``), planning along a winding
    track with the local and the global speed source calls no kernel, and no
    argument types, that the warm-up did not already load (a fresh process)."""

    script = """
import dataclasses, importlib, math, pkgutil
import numpy as np
from numba.core.registry import CPUDispatcher
from localization.frames import Buffer, TransformStamped
from localization.global_path import global_path_from_centreline
from localization.messages import ConeDetections, Header
from localization.pose import Pose2D
from planner import AutopilotConfig, fused, kernels
from planner.autopilot import Autopilot
from planner.midline import PlanStatus

modules = [fused] + [importlib.import_module(f"planner.kernels.{m.name}")
                     for m in pkgutil.iter_modules(kernels.__path__)]

def loaded():
    return {f"{module.__name__}.{k}": len(v.signatures) for module in modules
            for k, v in vars(module).items()
            if isinstance(v, CPUDispatcher) and v.signatures and v.__module__ == module.__name__}

x = np.arange(0.0, 200.0, 0.5)
centre = np.column_stack([x, 4.0 * np.sin(x / 8.0)])
t = np.gradient(centre, axis=0)
t /= np.hypot(t[:, 0], t[:, 1])[:, None]
normal = np.column_stack([-t[:, 1], t[:, 0]])
cones = np.vstack([centre + 1.75 * normal, centre - 1.75 * normal])[::5]
path = global_path_from_centreline(centre, closed=False)
assert not loaded()
pilots = [Autopilot(Buffer(), path)]
after_warm_up = loaded()
assert AutopilotConfig().speed_source == "global"
pilots.append(Autopilot(Buffer(), path, dataclasses.replace(
    AutopilotConfig(), speed_source="local")))
ok = 0
for pilot in pilots:
    for k, i in enumerate(range(10, 300, 15)):
        d = centre[i + 1] - centre[i]
        pose = Pose2D(float(centre[i, 0]), float(centre[i, 1]), math.atan2(d[1], d[0]))
        pilot.buffer.set_transform(
            TransformStamped.from_pose2d("reference", "os_sensor", float(k), pose))
        local = pose.inverse_transform_points(cones)
        local = local[(local[:, 0] > -2.0) & (local[:, 0] < 30.0)]
        local = local[np.argsort(np.hypot(local[:, 0], local[:, 1]))]
        plan = pilot.on_detections(ConeDetections(
            Header(float(k), "os_sensor"), np.column_stack([local, np.zeros(len(local))])))
        ok += plan is not None and plan.status is PlanStatus.OK
assert ok > 30, ok
assert loaded() == after_warm_up, (after_warm_up, loaded())
assert {"profile_limits", "profile_passes", "spline_path", "project_around", "plan_cones",
        "plan_midpoints", "window_overlaps"} <= {k.rsplit(".", 1)[1] for k in loaded()}
print("ok")
"""
    run_child(script)
