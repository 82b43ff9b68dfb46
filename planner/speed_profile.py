"""The speed profile along the local path: curvature limit, drive and brake passes.

For waypoints p_0..p_{n-1} at arc lengths s_i:

1. ``menger_curvature``: kappa_i of the circle through p_{i-1}, p_i, p_{i+1}::

       kappa = 2 cross(p_i - p_{i-1}, p_{i+1} - p_i)
               / (|p_i - p_{i-1}| |p_{i+1} - p_i| |p_{i+1} - p_{i-1}|)

   exactly 1/R for points on a circle of radius R (+ left turn); the end
   points take their neighbour's value.
2. ``curvature_limit``: v_i = min(v_max, sqrt(a_lat_max / |kappa_i|)).
3. ``forward_pass`` (drive limit a_d, from the current speed v_start):
   v_i^2 = min(v_i^2, v_{i-1}^2 + 2 a_d (s_i - s_{i-1})). Unrolled, this is
   v_i^2 = min_{j<=i} (w_j + 2 a_d (s_i - s_j)) with w the squared limits, so
   ``2 a_d s_i + cumulative_min(w_j - 2 a_d s_j)``: one numpy pass.
4. ``backward_pass`` (brake limit a_b), the same from the end:
   v_i^2 = min_{j>=i} (w_j + 2 a_b (s_j - s_i)). With ``horizon_stop`` the last
   waypoint's speed is 0: the car can always stop on the path it has seen.

Written for speed (per plan, on ~60 waypoints): ``speed_profile`` runs the
steps in one compiled loop (``planner.kernels.speed_profile``), with the same
floating-point operations as the numpy functions below, which stay as the
reference (``tests/planner/test_kernels.py`` compares them bit for bit).
"""

from __future__ import annotations

import numpy as np

from planner import kernels
from planner.config import SpeedProfileConfig
from planner.geometry import FloatArray, arc_length

_DEFAULT_CONFIG = SpeedProfileConfig()  # frozen: built once


def menger_curvature(points: FloatArray) -> FloatArray:
    """Signed curvature (n,) [1/m] of an (n, 2) polyline, + turning left."""
    step = points[1:] - points[:-1]
    return _menger(points, step, np.hypot(step[:, 0], step[:, 1]))


def _menger(points: FloatArray, step: FloatArray, step_length: FloatArray) -> FloatArray:
    """``menger_curvature`` given the (n - 1, 2) steps and their lengths."""
    n = len(points)
    if n < 3:
        return np.zeros(n)
    ab, bc, ac = step[:-1], step[1:], points[2:] - points[:-2]
    cross = ab[:, 0] * bc[:, 1] - ab[:, 1] * bc[:, 0]
    denom = step_length[:-1] * step_length[1:] * np.hypot(ac[:, 0], ac[:, 1])
    kappa = np.zeros(n)  # 0 where the division is skipped
    np.divide(2.0 * cross, denom, out=kappa[1:-1], where=denom > 0.0)
    kappa[0], kappa[-1] = kappa[1], kappa[-2]
    return kappa


def window_mean(values: FloatArray, spacing: float, window: float) -> FloatArray:
    """Centred moving average over ``window`` [m] of samples ``spacing`` [m] apart
    (the ends average what the window holds)."""
    half = int(window / (2.0 * spacing)) if spacing > 0.0 else 0
    if half < 1:
        return values
    c = np.concatenate([[0.0], np.cumsum(values)])
    n = len(values)
    lo = np.clip(np.arange(n) - half, 0, n)
    hi = np.clip(np.arange(n) + half + 1, 0, n)
    return (c[hi] - c[lo]) / (hi - lo)


def curvature_limit(kappa: FloatArray, config: SpeedProfileConfig) -> FloatArray:
    """Step 2: min(v_max, sqrt(a_lat_max / |kappa|)) [m/s], shape of ``kappa``."""
    k = np.abs(kappa)
    floor = config.a_lat_max / config.v_max**2  # below this, v_max binds
    return np.where(k > floor, np.sqrt(config.a_lat_max / np.maximum(k, floor)), config.v_max)


def forward_pass(s: FloatArray, v_limit: FloatArray, a_drive: float) -> FloatArray:
    """Step 3: speeds (n,) [m/s] reachable accelerating at most ``a_drive`` [m/s^2]."""
    reach = 2.0 * a_drive * s
    w = v_limit**2 - reach
    return np.sqrt(np.maximum(reach + np.minimum.accumulate(w), 0.0))


def backward_pass(s: FloatArray, v_limit: FloatArray, a_brake: float) -> FloatArray:
    """Step 4: speeds (n,) [m/s] from which braking at ``a_brake`` [m/s^2] meets the limits."""
    reach = 2.0 * a_brake * s
    w = (v_limit**2 + reach)[::-1]
    return np.sqrt(np.maximum(np.minimum.accumulate(w)[::-1] - reach, 0.0))


def speed_profile(
    points: FloatArray,
    config: SpeedProfileConfig | None = None,
    v_start: float | None = None,
    *,
    s: FloatArray | None = None,
    v_end: float | None = None,
) -> FloatArray:
    """Target speed (n,) [m/s] at each waypoint of an (n, 2) path [m].

    Args:
        points: the waypoints, in driving order.
        config: the limits.
        v_start: speed at the first waypoint [m/s]; None leaves it free.
        s: ``arc_length(points)`` [m] if known.
        v_end: with ``horizon_stop``, the speed allowed at the last waypoint
            [m/s] instead of 0 (the global path says what lies beyond it).
    """
    config = config or _DEFAULT_CONFIG
    n = len(points)
    if n == 0:
        return np.zeros(0)
    if s is None:
        s = arc_length(points)
    # The steps below in one compiled call (``kernels.speed_profile``; the
    # functions above are the same steps in numpy, the same numbers).
    speeds: FloatArray = kernels.speed_profile(
        np.ascontiguousarray(points, dtype=float),
        np.ascontiguousarray(s, dtype=float),
        config.curvature_window,
        config.a_lat_max,
        config.v_max,
        config.a_lat_max / config.v_max**2,  # curvature_limit's floor
        v_start is not None,
        0.0 if v_start is None else v_start,
        config.a_drive,
        config.horizon_stop,
        v_end is not None,
        0.0 if v_end is None else v_end,
        config.a_brake,
    )
    return speeds
