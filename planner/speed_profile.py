"""The speed profile along the local path: curvature limit, drive and brake passes.

For waypoints p_0..p_{n-1} at arc lengths s_i:

1. ``menger_curvature``: kappa_i of the circle through p_{i-1}, p_i, p_{i+1}::

       kappa = 2 cross(p_i - p_{i-1}, p_{i+1} - p_i)
               / (|p_i - p_{i-1}| |p_{i+1} - p_i| |p_{i+1} - p_{i-1}|)

   exactly 1/R for points on a circle of radius R (+ left turn); the end
   points take their neighbour's value.
2. ``curvature_limit``: v_i = min(v_max, sqrt(a_lat_max / |kappa_i|)); with
   downforce the lateral limit grows with speed, a_lat(v) = a_lat_max +
   a_lat_aero v^2, and v^2 |kappa| = a_lat(v) gives
   v_i = sqrt(a_lat_max / (|kappa_i| - a_lat_aero)) (v_max where
   |kappa_i| <= a_lat_aero + a_lat_max / v_max^2).
   With ``lateral_jerk_max`` J, also ``jerk_limit``: v_i <= (J / |dkappa/ds|)^(1/3).
   Where the curvature changes (into a corner, through an S-bend or the
   skidpad's crossing) the lateral acceleration changes at v^3 dkappa/ds,
   and the car (steering rate, yaw inertia, the tyres' slip building up)
   follows only so fast: at 20 m/s through the trackdrive's R 21 m S-bend
   it spun, at 11 m/s through the skidpad's crossing (curvature -1/9.1 to
   +1/9.1 at once) it ran 1.1 m wide. The curvature slope is taken over
   ``jerk_window`` [m] of the window-averaged curvature.
3. ``forward_pass`` (drive limit a_d, from the current speed v_start):
   v_i^2 = min(v_i^2, v_{i-1}^2 + 2 a_d (s_i - s_{i-1})). Unrolled, this is
   v_i^2 = min_{j<=i} (w_j + 2 a_d (s_i - s_j)) with w the squared limits, so
   ``2 a_d s_i + cumulative_min(w_j - 2 a_d s_j)``: one numpy pass.
4. ``backward_pass`` (brake limit a_b), the same from the end:
   v_i^2 = min_{j>=i} (w_j + 2 a_b (s_j - s_i)). With ``horizon_stop`` the last
   waypoint's speed is 0: the car can always stop on the path it has seen.

With ``friction_ellipse`` the passes share the tyre's grip with the corner,
as the quasi-steady-state lap simulation does (Milliken & Milliken, "Race Car
Vehicle Dynamics", ch. 2): on a step the longitudinal limit is
``a * sqrt(1 - (v^2 |kappa| / a_lat(v))^2)``, evaluated at the speed the step
starts from (``ellipse_forward_pass``, ``ellipse_backward_pass``). Without it
the car plans to brake at the full ``a_brake`` while already cornering at
``a_lat_max``, more than the tyres give, and slides. These passes are loops
(the limit depends on the speed).

Why ``speed_profile`` is compiled: it runs on every plan (twice per detection
with the global speed plan), and composed from the numpy and Python step
functions below it took 0.10 ms per 60 waypoints with the default limits
(0.04 ms without the ellipse and the jerk limit), a fifth of the planning
step's 0.5 ms budget (issue 5). Compiled (``kernels.profile_limits`` and
``kernels.profile_passes``) it takes 7.6 us (4.1 us); the same operations in
the same order, so the same numbers bit for bit, which
``tests/planner/kernels/test_speed_profile.py`` checks against the step
functions composed for every switch. The jerk limit's cube root stays
``numpy.cbrt`` between the two kernels: on CPUs with AVX-512 numpy takes it
from SVML, whose last bit differs from libm's (and numba's) in about half the
cases. The step functions stay as the reference, for the worked-number
tests, and for the callers that need one step (``global_speed``, the
autopilot).

Inputs the step functions reject differ: they raise on an infinite window
(``int(inf)``) or on a negative square root (a decreasing ``s``), where the
kernels average over the whole path and give NaN.
"""

from __future__ import annotations

import math

import numpy as np

from conesim.planner import kernels
from conesim.planner.config import SpeedProfileConfig
from conesim.planner.geometry import FloatArray

_DEFAULT_CONFIG = SpeedProfileConfig()  # frozen: built once
_NO_ARC = np.zeros(0)  # ``profile_limits``' s when it computes the arc length


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
    """Step 2: min(v_max, sqrt(a_lat_max / (|kappa| - a_lat_aero))) [m/s], shape of ``kappa``."""
    k = np.abs(kappa) - config.a_lat_aero
    floor = config.a_lat_max / config.v_max**2  # below this, v_max binds
    return np.where(k > floor, np.sqrt(config.a_lat_max / np.maximum(k, floor)), config.v_max)


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


def speed_profile(
    points: FloatArray,
    config: SpeedProfileConfig | None = None,
    v_start: float | None = None,
    *,
    s: FloatArray | None = None,
    v_end: float | None = None,
    check: bool = True,
) -> FloatArray:
    """Target speed (n,) [m/s] at each waypoint of an (n, 2) path [m].

    Steps 1-4 above, compiled (``kernels.profile_limits`` and
    ``kernels.profile_passes``, with ``numpy.cbrt`` between them): the
    numbers of the step functions of this module composed (see
    ``tests/planner/kernels/test_speed_profile.py``), bit for bit.

    Args:
        points: the waypoints, in driving order.
        config: the limits.
        v_start: speed at the first waypoint [m/s]; None leaves it free.
        s: ``arc_length(points)`` [m] if known.
        v_end: with ``horizon_stop``, the speed allowed at the last waypoint
            [m/s] instead of 0 (the global path says what lies beyond it).
        check: check the arguments (below); False gives what the kernels do
            with any input, NaN and inf included, which the kernels' tests
            hold to the numpy steps bit for bit.

    Raises:
        ValueError: ``points`` not (n, 2) or not finite, ``s`` not (n,) or
            not finite, ``v_start`` or ``v_end`` not finite (a NaN would
            otherwise pass every limit and read as top speed).
    """
    c = config or _DEFAULT_CONFIG
    pts = np.ascontiguousarray(points, dtype=float)
    if pts.size == 0:  # no waypoints (an empty list too)
        return np.zeros(0)
    arc = _NO_ARC if s is None else np.ascontiguousarray(s, dtype=float)
    if check:
        _check_profile_inputs(pts, arc if s is not None else None, v_start, v_end)
    limits = kernels.profile_limits(pts, arc, s is not None, c.limit_settings)
    return profile_speeds(limits, c, v_start, v_end)


def _check_profile_inputs(
    pts: FloatArray, s: FloatArray | None, v_start: float | None, v_end: float | None
) -> None:
    """``speed_profile``'s argument checks (see its Raises)."""
    if pts.ndim != 2 or pts.shape[1] != 2:
        raise ValueError(f"speed_profile: points must be (n, 2) [m], got shape {pts.shape}")
    if not np.isfinite(pts).all():
        raise ValueError("speed_profile: points must be finite (got NaN or inf)")
    if s is not None and (s.shape != (len(pts),) or not np.isfinite(s).all()):
        raise ValueError(
            f"speed_profile: s must be ({len(pts)},) finite arc lengths [m], got shape {s.shape}"
        )
    for name, v in (("v_start", v_start), ("v_end", v_end)):
        if v is not None and not math.isfinite(v):
            raise ValueError(f"speed_profile: {name} must be a finite speed [m/s], got {v!r}")


def profile_speeds(
    limits: tuple[FloatArray, FloatArray, FloatArray, FloatArray],
    config: SpeedProfileConfig | None = None,
    v_start: float | None = None,
    v_end: float | None = None,
) -> FloatArray:
    """The speeds (n,) [m/s] from ``kernels.profile_limits``' (s, kappa, v, ratio).

    The jerk limit's cube root (``numpy.cbrt``) and the passes
    (``kernels.profile_passes``, which changes ``v`` in place); the rest of
    ``speed_profile``, for a caller that had the limits computed in a
    compiled call of its own (``kernel_chains.check_and_limit``).
    """
    c = config or _DEFAULT_CONFIG
    arc, kappa, v, ratio = limits
    speeds: FloatArray = kernels.profile_passes(
        arc,
        kappa,
        v,
        np.cbrt(ratio) if len(ratio) else ratio,  # jerk_limit's cube root, numpy's
        v_start is not None,
        0.0 if v_start is None else float(v_start),
        v_end is not None,
        0.0 if v_end is None else float(v_end),
        c.pass_settings,
    )
    return speeds
