"""The speed profile as numpy and Python steps: the reference its kernels are held to.

``planner.speed_profile`` runs the compiled kernels (``planner.kernels.speed_profile``);
these are the step functions they were written from, as they stood: the
same operations in the same order, so ``tests/planner/kernels/test_speed_profile.py``
compares the two bit for bit. The steps are those of ``planner.speed_profile``'s
docstring (curvature, curvature limit, jerk limit, drive and brake passes,
with and without the friction ellipse).

Inputs the steps reject differ from the kernels': they raise on an infinite
window (``int(inf)``) or on a negative square root (a decreasing ``s``),
where the kernels average over the whole path and give NaN.
"""

from __future__ import annotations

import math

import numpy as np

from conesim.planner.config import SpeedProfileConfig
from conesim.planner.geometry import FloatArray


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
    """Step 2: min(v_max, sqrt(a_lat_max share / (|kappa| - a_lat_aero))) [m/s], shape of
    ``kappa``, share = max(1 - (|kappa| lock_radius)^4, lock_share_min)."""
    k = np.abs(kappa) - config.a_lat_aero
    floor = config.a_lat_max / config.v_max**2  # below this, v_max binds
    x = np.abs(kappa) * config.lock_radius
    x = x * x
    share = np.maximum(1.0 - x * x, config.lock_share_min)
    a_lat = config.a_lat_max * share
    return np.where(k > floor, np.sqrt(a_lat / np.maximum(k, floor)), config.v_max)


def _slope(kappa: FloatArray, spacing: float, half: int) -> FloatArray:
    """|dkappa/ds| (n,) [1/m^2] over 2 half samples, the ends held."""
    n = len(kappa)
    slope = np.zeros(n)
    slope[half:-half] = np.abs(kappa[2 * half :] - kappa[: -2 * half]) / (2 * half * spacing)
    slope[:half], slope[-half:] = slope[half], slope[-half - 1]
    return slope


def steering_limit(
    kappa: FloatArray, spacing: float, config: SpeedProfileConfig
) -> FloatArray | None:
    """Step 2c: steering_rate_max (1 + (L kappa)^2) / (L |dkappa/ds| |kappa| R_lock)
    [m/s] (n,): delta = atan(L kappa) changes at v L kappa' / (1 + (L kappa)^2),
    weighed by how near full lock the path turns, at least steering_weight_min."""
    n = len(kappa)
    half = round(config.jerk_window / (2.0 * spacing)) if spacing > 0.0 else 0
    if not config.steering_rate_max < math.inf or half < 1 or n < 2 * half + 1:
        return None
    slope = _slope(kappa, spacing, half)
    x = config.wheelbase * kappa
    lock = config.lock_radius
    q = (
        np.maximum(np.abs(kappa) * lock, config.steering_weight_min)
        if lock > 0.0
        else np.ones_like(kappa)
    )
    with np.errstate(divide="ignore", invalid="ignore"):
        lim = config.steering_rate_max * (1.0 + x * x) / (config.wheelbase * slope * q)
    return np.where((slope > 0.0) & (q > 0.0), lim, np.inf)


def jerk_limit(kappa: FloatArray, spacing: float, config: SpeedProfileConfig) -> FloatArray | None:
    """Step 2b: (J / |dkappa/ds|)^(1/3) [m/s] (n,), the slope over ``jerk_window``.

    Args:
        kappa: (n,) curvature [1/m] at waypoints ``spacing`` [m] apart.
        config: ``lateral_jerk_max`` J [m/s^3] and ``jerk_window`` [m].

    Returns:
        The limits, or None when J is inf or the path is too short.
    """
    n = len(kappa)
    half = round(config.jerk_window / (2.0 * spacing)) if spacing > 0.0 else 0
    if not config.lateral_jerk_max < math.inf or half < 1 or n < 2 * half + 1:
        return None
    slope = np.zeros(n)
    slope[half:-half] = np.abs(kappa[2 * half :] - kappa[: -2 * half]) / (2 * half * spacing)
    slope[:half], slope[-half:] = slope[half], slope[-half - 1]
    with np.errstate(divide="ignore"):
        return np.cbrt(config.lateral_jerk_max / slope)


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


def _ellipse_scale(v: float, kappa: float, a_lat_max: float, a_lat_aero: float) -> float:
    """sqrt(1 - (v^2 |kappa| / a_lat(v))^2), 0 beyond the lateral limit."""
    v2 = v * v
    lat = v2 * abs(kappa) / (a_lat_max + a_lat_aero * v2)
    return math.sqrt(1.0 - lat * lat) if lat < 1.0 else 0.0


def ellipse_forward_pass(
    s: FloatArray,
    v_limit: FloatArray,
    kappa: FloatArray,
    a_drive: float,
    *,
    a_lat_max: float,
    a_lat_aero: float = 0.0,
) -> FloatArray:
    """Step 3 inside the friction ellipse: speeds (n,) [m/s].

    v_i^2 = min(v_i^2, v_{i-1}^2 + 2 a_drive sqrt(1 - (v_{i-1}^2 |kappa_{i-1}| / a_lat)^2) ds)
    with a_lat = a_lat_max + a_lat_aero v_{i-1}^2.
    """
    out = [float(x) for x in v_limit]
    k = [float(x) for x in kappa]
    ds = np.diff(s).tolist()
    for i in range(1, len(out)):
        v = out[i - 1]
        a = a_drive * _ellipse_scale(v, k[i - 1], a_lat_max, a_lat_aero)
        out[i] = min(out[i], math.sqrt(v * v + 2.0 * a * ds[i - 1]))
    return np.array(out)


def ellipse_backward_pass(
    s: FloatArray,
    v_limit: FloatArray,
    kappa: FloatArray,
    a_brake: float,
    *,
    a_lat_max: float,
    a_lat_aero: float = 0.0,
) -> FloatArray:
    """Step 4 inside the friction ellipse: speeds (n,) [m/s].

    v_i^2 = min(v_i^2, v_{i+1}^2 + 2 a_brake sqrt(1 - (v_{i+1}^2 |kappa_i| / a_lat)^2) ds)
    with a_lat = a_lat_max + a_lat_aero v_{i+1}^2.
    """
    out = [float(x) for x in v_limit]
    k = [float(x) for x in kappa]
    ds = np.diff(s).tolist()
    for i in range(len(out) - 2, -1, -1):
        v = out[i + 1]
        a = a_brake * _ellipse_scale(v, k[i], a_lat_max, a_lat_aero)
        out[i] = min(out[i], math.sqrt(v * v + 2.0 * a * ds[i]))
    return np.array(out)


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
    steer = steering_limit(kappa, float(s[-1]) / (n - 1), config) if n > 2 else None
    if steer is not None:
        v = np.minimum(v, steer)
    jerk = jerk_limit(kappa, float(s[-1]) / (n - 1), config) if n > 2 else None
    if jerk is not None:
        v = np.minimum(v, jerk)
    if v_start is not None:
        v[0] = min(v[0], max(v_start, 0.0))
    if config.friction_ellipse:
        c = config
        q = c.drive_lateral_share
        v = ellipse_forward_pass(
            s, v, kappa, c.a_drive, a_lat_max=c.a_lat_max * q, a_lat_aero=c.a_lat_aero * q
        )
    else:
        v = forward_pass(s, v, config.a_drive)
    if config.horizon_stop:
        v[-1] = 0.0 if v_end is None else min(v[-1], max(v_end, 0.0))
    if config.friction_ellipse:
        c = config
        share = c.brake_lateral_share
        return ellipse_backward_pass(
            s, v, kappa, c.a_brake, a_lat_max=c.a_lat_max * share,
            a_lat_aero=c.a_lat_aero * share,
        )  # fmt: skip
    return backward_pass(s, v, config.a_brake)
