"""The compiled speed profile (``planner.kernels.speed_profile``) is the numpy steps.

The reference is ``speed_profile``'s numpy and Python body as it stood
before it was compiled (friction-ellipse passes, jerk limit, downforce),
compared byte for byte.
"""

from __future__ import annotations

import itertools
import math

import numpy as np
from numpy.testing import assert_array_equal

from conesim.planner import SpeedProfileConfig
from conesim.planner.geometry import arc_length
from conesim.planner.speed_profile import (
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
    from conesim.tracks import load_track, shipped_tracks
    from conesim.tracks.global_path import global_path_for_track

    for name in shipped_tracks():
        path = global_path_for_track(load_track(name))
        pts = np.asarray(path.xy, dtype=float)
        laps = np.vstack([pts, pts, pts, pts[:1]]) if path.closed else pts
        for config in PROFILE_CONFIGS[::7]:
            assert_bits_equal(speed_profile(laps, config), ref_speed_profile(laps, config))
