"""Step 7: the speed profile's limits and passes (``speed_profile``).

``profile_limits``: arc length, curvature, its window mean, the curvature
limit and the jerk limit's ratio; ``profile_passes``: the start speed, the
forward (drive) pass, the horizon stop and the backward (brake) pass, with
or without the friction ellipse. The jerk limit's cube root is taken with
``numpy.cbrt`` between the two (see the package docstring).
"""

from __future__ import annotations

import math

import numpy as np

from conesim.core.compiled import cached_njit


def _probe() -> None:
    """Nothing: what ``cached_njit`` asks numba to cache, from this file's directory."""


# Cached beside this file (or under NUMBA_CACHE_DIR); with no writable cache
# directory, compiled in every process (a cold compile: see the package docstring).
_compiled = cached_njit(_probe, "conesim.planner.kernels.speed_profile")


@_compiled
def _half_window(window, spacing, n, rounded):
    """The half width [samples] of a ``window`` [m] at ``spacing`` [m], capped at n.

    ``int(x)`` (``window_mean``) or Python's ``round(x)`` (half to even,
    ``jerk_limit``) of ``x = window / (2 spacing)``, 0 unless spacing > 0. A
    half of n or more averages (or spans) the whole path, as any larger
    half does: the cap only keeps the conversion to an integer defined.
    """
    if not spacing > 0.0:
        return 0
    x = window / (2.0 * spacing)
    if not x < n:  # also NaN
        return n
    return round(x) if rounded else int(x)


@_compiled
def profile_limits(points, s, has_s, limits):
    """``speed_profile`` up to the jerk limit's cube root, for (n, 2) points [m].

    The arc length (unless ``has_s``: then ``s`` (n,) [m]; ``numpy.cumsum``
    of the ``np.hypot`` steps), the Menger curvature, its window mean when
    ``limits.curvature_window > 0`` and n > 2, the curvature limit and the
    jerk limit's ratio ``lateral_jerk_max / slope``, and the steering-rate
    limit ``steering_rate_max (1 + (L kappa)^2) / (L slope |kappa| lock_radius)``
    taken into the curvature limit (inf where the slope is
    0), each with the reference's operations in its order
    (``tests/planner/kernels/speed_profile_reference.py``). ``limits`` is a
    ``settings.LimitSettings``.

    Returns:
        s (n,) [m], the curvature kappa (n,) [1/m] the passes read, the
        curvature limit v (n,) [m/s], and the ratio (n,) [m^3/s^3] (empty
        without a jerk limit). Its cube root is left to
        ``numpy.cbrt``: on CPUs with AVX-512 numpy takes it from SVML, whose
        last bit differs from libm's (and numba's) in about half the cases.
    """
    window = limits.curvature_window
    a_lat = limits.a_lat_max
    a_lat_aero = limits.a_lat_aero
    floor = limits.curvature_floor
    v_max = limits.v_max
    jerk_max = limits.lateral_jerk_max
    jerk_window = limits.jerk_window
    n = len(points)
    step_length = np.empty(max(n - 1, 0))
    for i in range(n - 1):
        step_length[i] = np.hypot(points[i + 1, 0] - points[i, 0], points[i + 1, 1] - points[i, 1])
    if not has_s:
        s = np.zeros(n)
        if n > 1:
            s[1] = step_length[0]
        for i in range(2, n):
            s[i] = s[i - 1] + step_length[i - 1]
    kappa = np.zeros(n)
    if n >= 3:
        for i in range(1, n - 1):
            abx = points[i, 0] - points[i - 1, 0]
            aby = points[i, 1] - points[i - 1, 1]
            bcx = points[i + 1, 0] - points[i, 0]
            bcy = points[i + 1, 1] - points[i, 1]
            cross = abx * bcy - aby * bcx
            denom = (
                step_length[i - 1]
                * step_length[i]
                * np.hypot(points[i + 1, 0] - points[i - 1, 0], points[i + 1, 1] - points[i - 1, 1])
            )
            if denom > 0.0:
                kappa[i] = 2.0 * cross / denom
        kappa[0] = kappa[1]
        kappa[n - 1] = kappa[n - 2]
    spacing = s[n - 1] / (n - 1) if n > 2 else 0.0
    if window > 0.0 and n > 2:
        half = _half_window(window, spacing, n, False)
        if half >= 1:
            c = np.empty(n + 1)  # numpy.concatenate([[0.0], numpy.cumsum(kappa)])
            c[0] = 0.0
            c[1] = kappa[0]
            for i in range(1, n):
                c[i + 1] = c[i] + kappa[i]
            smooth = np.empty(n)
            for i in range(n):
                lo = min(max(i - half, 0), n)
                hi = min(max(i + half + 1, 0), n)
                smooth[i] = (c[hi] - c[lo]) / (hi - lo)
            kappa = smooth
    lock = limits.lock_radius
    share_min = limits.lock_share_min
    v = np.empty(n)
    for i in range(n):
        k = abs(kappa[i]) - a_lat_aero
        x = abs(kappa[i]) * lock
        x = x * x
        share = max(1.0 - x * x, share_min)
        v[i] = math.sqrt(a_lat * share / k) if k > floor else v_max
    ratio = np.empty(0)
    steer_rate = limits.steering_rate_max
    wheelbase = limits.wheelbase
    weight_min = limits.steering_weight_min
    half = _half_window(jerk_window, spacing, n, True) if n > 2 else 0
    if (jerk_max < math.inf or steer_rate < math.inf) and half >= 1 and n >= 2 * half + 1:
        slope = np.zeros(n)
        run = 2 * half * spacing
        for i in range(half, n - half):
            slope[i] = abs(kappa[i + half] - kappa[i - half]) / run
        for i in range(half):
            slope[i] = slope[half]
        for i in range(n - half, n):
            slope[i] = slope[n - half - 1]
        if steer_rate < math.inf:
            for i in range(n):
                x = wheelbase * kappa[i]
                q = max(abs(kappa[i]) * lock, weight_min) if lock > 0.0 else 1.0
                if slope[i] > 0.0 and q > 0.0:
                    lim = steer_rate * (1.0 + x * x) / (wheelbase * slope[i] * q)
                    if lim < v[i]:  # noqa: PLR1730
                        v[i] = lim
    if jerk_max < math.inf and half >= 1 and n >= 2 * half + 1:
        ratio = np.empty(n)
        for i in range(n):
            # numpy's jerk_max / slope: +inf at a zero slope (jerk_max > 0)
            ratio[i] = jerk_max / slope[i] if slope[i] != 0.0 else math.inf
    return s, kappa, v, ratio


@_compiled
def _ellipse_scale(v, kappa, a_lat_max, a_lat_aero):
    """The friction ellipse's share left: sqrt(1 - (v^2 |kappa| / a_lat(v))^2), 0 beyond."""
    v2 = v * v
    lat = v2 * abs(kappa) / (a_lat_max + a_lat_aero * v2)
    return math.sqrt(1.0 - lat * lat) if lat < 1.0 else 0.0


@_compiled
def profile_passes(s, kappa, v, jerk, has_start, v_start, has_end, v_end, passes):  # noqa: PLR0917
    """The rest of ``speed_profile``: speeds (n,) [m/s] at n waypoints.

    The minimum of the curvature limit ``v`` (n,) [m/s] (changed in place)
    and the jerk limit ``jerk`` (n,) [m/s] (skipped when empty), the start
    speed, the drive pass (with the friction ellipse, reading ``kappa`` (n,)
    [1/m], or in closed form), the horizon stop and the brake pass, along
    arc lengths ``s`` (n,) [m]. ``passes`` is a ``settings.PassSettings``;
    with ``passes.brake`` False the speeds after the horizon stop are
    returned (``v`` itself). n >= 1 with the horizon stop.

    Each with the reference's operations in its order: the closed-form
    passes' running minima in the same direction (``numpy.minimum.accumulate``,
    NaN kept); Python's ``min`` and ``max`` (the first argument unless the
    second is strictly less or greater) for the start and end speeds and in
    the ellipse passes.
    """
    ellipse = passes.friction_ellipse
    a_drive = passes.a_drive
    a_brake = passes.a_brake
    a_lat = passes.a_lat_max
    a_lat_aero = passes.a_lat_aero
    horizon_stop = passes.horizon_stop
    n = len(v)
    if len(jerk):
        for i in range(n):
            if not math.isnan(v[i]) and (math.isnan(jerk[i]) or jerk[i] < v[i]):
                v[i] = jerk[i]
    if has_start:
        start = 0.0 if v_start < 0.0 else v_start  # Python's max(v_start, 0.0)
        if start < v[0]:  # noqa: PLR1730 (Python's min(v[0], start))
            v[0] = start
    if ellipse:
        drive_lat = a_lat * passes.drive_lateral_share
        drive_aero = a_lat_aero * passes.drive_lateral_share
        for i in range(1, n):
            u = v[i - 1]
            a = a_drive * _ellipse_scale(u, kappa[i - 1], drive_lat, drive_aero)
            x = math.sqrt(u * u + 2.0 * a * (s[i] - s[i - 1]))
            if x < v[i]:  # noqa: PLR1730 (Python's min(v[i], x))
                v[i] = x
    else:
        # sqrt(max(reach + running min of (v^2 - reach), 0))
        reach_d = 2.0 * a_drive
        low = math.inf
        for i in range(n):
            reach = reach_d * s[i]
            w = v[i] * v[i] - reach
            if i == 0 or w < low or math.isnan(w):
                low = w if not math.isnan(low) else low
            x = reach + low
            v[i] = math.sqrt(x if x >= 0.0 or math.isnan(x) else 0.0)
    if horizon_stop:
        if has_end:
            end = 0.0 if v_end < 0.0 else v_end
            if end < v[n - 1]:  # noqa: PLR1730
                v[n - 1] = end
        else:
            v[n - 1] = 0.0
    if not passes.brake:
        return v
    out = np.empty(n)
    if ellipse:
        share = passes.brake_lateral_share
        brake_lat = a_lat * share
        brake_aero = a_lat_aero * share
        out[n - 1] = v[n - 1]
        for i in range(n - 2, -1, -1):
            u = out[i + 1]
            a = a_brake * _ellipse_scale(u, kappa[i], brake_lat, brake_aero)
            x = math.sqrt(u * u + 2.0 * a * (s[i + 1] - s[i]))
            out[i] = x if x < v[i] else v[i]
        return out
    # sqrt(max(running min from the end of (v^2 + reach) - reach, 0))
    reach_b = 2.0 * a_brake
    low = math.inf
    for i in range(n - 1, -1, -1):
        reach = reach_b * s[i]
        w = v[i] * v[i] + reach
        if i == n - 1 or w < low or math.isnan(w):
            low = w if not math.isnan(low) else low
        x = low - reach
        out[i] = math.sqrt(x if x >= 0.0 or math.isnan(x) else 0.0)
    return out
