"""The compiled speed profile (``planner.kernels.speed_profile``) is the numpy steps.

The reference (``speed_profile_reference``) is ``speed_profile``'s numpy and
Python body as it stood before it was compiled (friction-ellipse passes,
jerk limit, downforce), compared byte for byte; the drive pass and the
curvature alone too, as the autopilot and the global speed plan call them.
"""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from numpy.testing import assert_allclose, assert_array_equal

from conesim.planner import SpeedProfileConfig
from conesim.planner.geometry import arc_length
from conesim.planner.speed_profile import forward_pass, profile_curvature, speed_profile
from tests.planner.kernels import speed_profile_reference as ref
from tests.planner.kernels.speed_profile_reference import ref_speed_profile


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
# 0.25 m exactly: int() of an integer), horizon stop; and the steering-rate
# limit's weight floor below its default 1, and the brake ellipse's lateral share.
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
] + [SpeedProfileConfig(steering_weight_min=w) for w in (0.0, 0.4)]
PROFILE_CONFIGS += [SpeedProfileConfig(brake_lateral_share=q) for q in (0.5, 0.8)]
PROFILE_CONFIGS += [SpeedProfileConfig(drive_lateral_share=q) for q in (1.2, 2.0)]


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
    from conesim.tracks import load_track, shipped_tracks
    from conesim.tracks.global_path import global_path_for_track

    for name in shipped_tracks():
        path = global_path_for_track(load_track(name))
        pts = np.asarray(path.xy, dtype=float)
        laps = np.vstack([pts, pts, pts, pts[:1]]) if path.closed else pts
        for config in PROFILE_CONFIGS[::7]:
            assert_bits_equal(speed_profile(laps, config), ref_speed_profile(laps, config))


def test_drive_pass_is_the_numpy_pass() -> None:
    """``forward_pass`` (the autopilot's, compiled) is the reference's closed form,
    bit for bit: random limits and steps, zero steps, NaN and inf limits."""
    rng = np.random.default_rng(29)
    for trial in range(400):
        n = int(rng.integers(0, 80))
        s = np.cumsum(rng.choice([0.0, 0.25, 0.5], n) if trial % 3 == 0 else rng.uniform(0, 1, n))
        limit = rng.uniform(0.0, 30.0, n)
        if n > 4 and trial % 5 == 0:
            limit[int(rng.integers(0, n))] = [math.nan, math.inf][trial % 2]
        a_drive = float(rng.choice([0.5, 3.0, 9.81]))
        with np.errstate(invalid="ignore"):
            expected = ref.forward_pass(s, limit, a_drive)
        assert_bits_equal(forward_pass(s, limit, a_drive), expected)


def reference_curvature(points: np.ndarray, window: float) -> np.ndarray:
    """The curvature as the global speed plan computed it with the numpy steps."""
    kappa = ref.menger_curvature(points)
    if window > 0.0 and len(points) > 2:
        kappa = ref.window_mean(kappa, float(arc_length(points)[-1]) / (len(points) - 1), window)
    return kappa


def test_curvature_is_the_numpy_steps() -> None:
    """``profile_curvature`` is Menger's curvature and its window mean as the numpy
    steps compute them, bit for bit, for windows of none, one, several and all samples,
    on random paths and along each shipped track's global path."""
    from conesim.tracks import load_track, shipped_tracks
    from conesim.tracks.global_path import global_path_for_track

    rng = np.random.default_rng(30)
    cases = [p for p in profile_cases(rng, 400) if np.isfinite(p).all()]
    cases += [np.asarray(global_path_for_track(load_track(name)).xy) for name in shipped_tracks()]
    for i, points in enumerate(cases):
        window = [0.0, 0.3, 1.0, 2.0, 4.0, 1e6][i % 6]
        config = SpeedProfileConfig(curvature_window=window)
        assert_bits_equal(profile_curvature(points, config), reference_curvature(points, window))


def test_reference_brake_pass_is_the_textbook_loop() -> None:
    """The reference's closed-form brake pass equals the textbook loop (the drive
    pass is held to its loop in ``tests/planner/test_speed_profile.py``)."""
    rng = np.random.default_rng(1)
    s = np.cumsum(rng.uniform(0.1, 1.0, 200))
    bwd = rng.uniform(1.0, 20.0, 200)
    expected = ref.backward_pass(s, bwd, 6.0)
    for i in range(198, -1, -1):
        bwd[i] = min(bwd[i], math.sqrt(bwd[i + 1] ** 2 + 2 * 6.0 * (s[i + 1] - s[i])))
    assert_allclose(expected, bwd, rtol=1e-9)


def test_reference_friction_ellipse_on_a_circle_from_rest() -> None:
    """On R = 10 m (V^2 = a_lat R = 60), dv^2/ds = 2 a_d sqrt(1 - (v^2 / V^2)^2) from rest.

    So arcsin(v^2 / V^2) = 2 a_d s / V^2: at s = 5 m, v^2 = 60 sin(0.5) = 28.77,
    v = 5.363 m/s (a straight line gives sqrt(30) = 5.477); V is reached at
    s = pi V^2 / (4 a_d) = 15.71 m. Fine steps: Euler error < 0.5 %.
    """
    s = np.arange(0.0, 30.0, 0.01)
    kappa = np.full_like(s, 0.1)
    limit = np.full_like(s, math.sqrt(60.0))
    limit[0] = 0.0
    v = ref.ellipse_forward_pass(s, limit, kappa, 3.0, a_lat_max=6.0)
    assert v[500] == pytest.approx(math.sqrt(60.0 * math.sin(0.5)), rel=5e-3)
    assert v[1500] < math.sqrt(60.0) < v[1600] + 1e-9


def test_reference_friction_ellipse_brakes_less_in_the_corner() -> None:
    """Braking to 5 m/s at the end of R = 10 m: the ellipse leaves less than a_brake.

    Backwards from v^2 = 25 at the end: dv^2/ds = 2 a_b sqrt(1 - (v^2 / 60)^2),
    so arcsin(v^2 / 60) grows by 2 a_b ds / 60 = 0.2 rad per metre with a_b = 6:
    1 m back v^2 = 60 sin(arcsin(25 / 60) + 0.2) = 35.87 (without: 37).
    On a straight (kappa = 0) the loops equal the closed-form passes.
    """
    s = np.arange(0.0, 10.001, 0.001)
    limit = np.full_like(s, math.sqrt(60.0))
    limit[-1] = 5.0
    v = ref.ellipse_backward_pass(s, limit, np.full_like(s, 0.1), 6.0, a_lat_max=6.0)
    expected = 60.0 * math.sin(math.asin(25.0 / 60.0) + 0.2)
    assert v[-1001] ** 2 == pytest.approx(expected, rel=1e-3)
    rng = np.random.default_rng(0)
    s = np.cumsum(rng.uniform(0.1, 1.0, 100))
    lim = rng.uniform(1.0, 20.0, 100)
    zero = np.zeros(100)
    assert_allclose(
        ref.ellipse_forward_pass(s, lim, zero, 3.0, a_lat_max=6.0), ref.forward_pass(s, lim, 3.0)
    )
    assert_allclose(
        ref.ellipse_backward_pass(s, lim, zero, 6.0, a_lat_max=6.0), ref.backward_pass(s, lim, 6.0)
    )


def test_reference_curvature_limit_near_full_lock() -> None:
    """R 4 m with a 3 m lock radius: share 1 - 0.75^4 = 0.6836, v = sqrt(14 * 0.6836 * 4)
    = 6.187 m/s; at R 3 m the share is lock_share_min 0.15: v = sqrt(14 * 0.15 * 3)."""
    cfg = SpeedProfileConfig(a_lat_max=14.0, a_lat_aero=0.0, lock_radius=3.0)
    v = ref.curvature_limit(np.array([0.25, -1.0 / 3.0]), cfg)
    assert_allclose(v, [math.sqrt(14.0 * (1.0 - 0.75**4) * 4.0), math.sqrt(6.3)], rtol=1e-12)
    p = np.column_stack([4.0 * np.cos(np.linspace(0, 2, 40)), 4.0 * np.sin(np.linspace(0, 2, 40))])
    cfg = SpeedProfileConfig(
        a_lat_max=14.0, a_lat_aero=0.0, curvature_window=0.0, lateral_jerk_max=math.inf,
        horizon_stop=False,
    )  # fmt: skip
    compiled = speed_profile(p, cfg)
    assert_allclose(compiled[5:-5], 6.187, atol=2e-3)


def test_reference_curvature_limit_with_downforce() -> None:
    """v^2 |kappa| = a_lat_max + a_lat_aero v^2: |kappa| = 0.05 1/m, 6 m/s^2, 0.01 1/m
    gives v = sqrt(6 / (0.05 - 0.01)) = 12.247 m/s; |kappa| <= 0.0167 1/m, v_max."""
    cfg = SpeedProfileConfig(a_lat_max=6.0, a_lat_aero=0.01, v_max=30.0, lock_radius=0.0)
    v = ref.curvature_limit(np.array([0.05, -0.05, 0.01, 0.0]), cfg)
    assert_allclose(v[:2], math.sqrt(150.0), rtol=1e-12)
    assert_allclose(v[2:], 30.0)


def test_reference_jerk_limit_on_a_curvature_ramp() -> None:
    """Curvature rising 0.01 1/m per metre: v <= (60 / 0.01)^(1/3) = 18.17 m/s.

    Samples 0.5 m apart, the slope over a 4 m window (8 steps); flat curvature:
    no limit. With J = inf there is none at all.
    """
    kappa = np.concatenate([np.zeros(20), 0.005 * np.arange(1, 21), np.full(20, 0.1)])
    cfg = SpeedProfileConfig(lateral_jerk_max=60.0, jerk_window=4.0)
    v = ref.jerk_limit(kappa, 0.5, cfg)
    assert v is not None
    assert_allclose(v[28:32], (60.0 / 0.01) ** (1 / 3), rtol=1e-9)
    assert v[28] == pytest.approx(18.17, abs=0.01)
    assert np.all(np.isinf(v[:15])) and np.all(np.isinf(v[-15:]))
    assert ref.jerk_limit(kappa, 0.5, SpeedProfileConfig(lateral_jerk_max=math.inf)) is None
