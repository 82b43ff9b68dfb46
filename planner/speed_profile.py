"""The speed profile along the local path: curvature limit, drive and brake passes.

For waypoints p_0..p_{n-1} at arc lengths s_i:

1. Curvature: kappa_i of the circle through p_{i-1}, p_i, p_{i+1} (Menger)::

       kappa = 2 cross(p_i - p_{i-1}, p_{i+1} - p_i)
               / (|p_i - p_{i-1}| |p_{i+1} - p_i| |p_{i+1} - p_{i-1}|)

   exactly 1/R for points on a circle of radius R (+ left turn); the end
   points take their neighbour's value (``Polyline.curvature``, compiled
   here); averaged over ``curvature_window`` (``profile_curvature``).
2. Curvature limit: v_i = min(v_max, sqrt(a_lat_max / |kappa_i|)); with
   downforce the lateral limit grows with speed, a_lat(v) = a_lat_max +
   a_lat_aero v^2, and v^2 |kappa| = a_lat(v) gives
   v_i = sqrt(a_lat_max / (|kappa_i| - a_lat_aero)) (v_max where
   |kappa_i| <= a_lat_aero + a_lat_max / v_max^2).
   With ``lateral_jerk_max`` J, also the jerk limit v_i <= (J / |dkappa/ds|)^(1/3):
   where the curvature changes (into a corner, through an S-bend or the
   skidpad's crossing) the lateral acceleration changes at v^3 dkappa/ds,
   which the car (steering rate, yaw inertia, the tyres' slip building up)
   follows only so fast. The curvature slope is taken over ``jerk_window``
   [m] of the window-averaged curvature.
3. Drive pass (limit a_d, from the current speed v_start):
   v_i^2 = min(v_i^2, v_{i-1}^2 + 2 a_d (s_i - s_{i-1})). Unrolled, this is
   v_i^2 = min_{j<=i} (w_j + 2 a_d (s_i - s_j)) with w the squared limits:
   ``2 a_d s_i + running min of (w_j - 2 a_d s_j)`` (``forward_pass``).
4. Brake pass (limit a_b), the same from the end:
   v_i^2 = min_{j>=i} (w_j + 2 a_b (s_j - s_i)). With ``horizon_stop`` the last
   waypoint's speed is 0: the car can always stop on the path it has seen.

With ``friction_ellipse`` the passes share the tyre's grip with the corner,
as the quasi-steady-state lap simulation does (Milliken & Milliken, "Race Car
Vehicle Dynamics", ch. 2): on a step the longitudinal limit is
``a * sqrt(1 - (v^2 |kappa| / a_lat(v))^2)``, evaluated at the speed the step
starts from. Without it the car plans to brake at the full ``a_brake`` while
already cornering at ``a_lat_max``, more than the tyres give, and slides.

Compiled (``kernels.profile_limits`` and ``kernels.profile_passes``): it runs
on every plan. The jerk limit's cube root is taken between the two kernels
with ``numpy.cbrt``, whose SIMD (SVML) cube root is not libm's.
"""

from __future__ import annotations

import functools
import math

import numpy as np

from conesim.planner import kernels
from conesim.planner.config import SpeedProfileConfig
from conesim.planner.geometry import FloatArray
from conesim.planner.settings import PassSettings

_DEFAULT_CONFIG = SpeedProfileConfig()  # frozen: built once
_EMPTY = np.zeros(0)  # no arc length given (``profile_limits`` computes it), no values


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

    Steps 1-4 above (``kernels.profile_limits``, ``numpy.cbrt``, then
    ``profile_speeds``).

    Args:
        points: the waypoints, in driving order.
        config: the limits.
        v_start: speed at the first waypoint [m/s]; None leaves it free.
        s: ``arc_length(points)`` [m] if known.
        v_end: with ``horizon_stop``, the speed allowed at the last waypoint
            [m/s] instead of 0 (the global path says what lies beyond it).
        check: check the arguments (below); False gives what the kernels do
            with any input, NaN and inf included.

    Raises:
        ValueError: ``points`` not (n, 2) or not finite, ``s`` not (n,) or
            not finite, ``v_start`` or ``v_end`` not finite (a NaN would
            otherwise pass every limit and read as top speed).
    """
    c = config or _DEFAULT_CONFIG
    pts = np.ascontiguousarray(points, dtype=float)
    if pts.size == 0:  # no waypoints (an empty list too)
        return np.zeros(0)
    arc = _EMPTY if s is None else np.ascontiguousarray(s, dtype=float)
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
        np.cbrt(ratio) if len(ratio) else ratio,  # the jerk limit's cube root, numpy's
        v_start is not None,
        0.0 if v_start is None else float(v_start),
        v_end is not None,
        0.0 if v_end is None else float(v_end),
        c.pass_settings,
    )
    return speeds


def forward_pass(s: FloatArray, v_limit: FloatArray, a_drive: float) -> FloatArray:
    """Step 3 alone: speeds (n,) [m/s] reachable accelerating at most ``a_drive`` [m/s^2].

    ``kernels.profile_passes`` without the ellipse, the horizon stop and the
    brake pass: the specialisation the planning step loads.

    Args:
        s: (n,) arc lengths [m], non-decreasing.
        v_limit: (n,) the speed limits [m/s].
        a_drive: the acceleration limit [m/s^2].

    Raises:
        ValueError: ``s`` and ``v_limit`` of different shapes.
    """
    arc = np.ascontiguousarray(s, dtype=float)
    v = np.array(v_limit, dtype=float)  # a copy: the kernel changes it in place
    if arc.shape != v.shape or arc.ndim != 1:
        raise ValueError(
            f"forward_pass: s and v_limit must be (n,) alike, got {arc.shape} and {v.shape}"
        )
    speeds: FloatArray = kernels.profile_passes(
        arc, _EMPTY, v, _EMPTY, False, 0.0, False, 0.0, _drive_only(float(a_drive))
    )
    return speeds


@functools.lru_cache(maxsize=8)
def _drive_only(a_drive: float) -> PassSettings:
    """``forward_pass``' settings: the closed-form drive pass at ``a_drive`` [m/s^2] alone."""
    return PassSettings(
        friction_ellipse=False,
        a_drive=a_drive,
        a_brake=0.0,
        a_lat_max=0.0,
        a_lat_aero=0.0,
        horizon_stop=False,
        brake=False,
    )


def profile_curvature(points: FloatArray, config: SpeedProfileConfig | None = None) -> FloatArray:
    """Step 1: the curvature (n,) [1/m] the profile reads along an (n, 2) path [m].

    ``Polyline(points).curvature()`` (Menger's, + turning left), computed in
    the compiled ``kernels.profile_limits`` with the same numbers, averaged
    over ``config.curvature_window`` (point by point when it is 0).
    """
    c = config or _DEFAULT_CONFIG
    pts = np.ascontiguousarray(points, dtype=float).reshape(-1, 2)
    kappa: FloatArray = kernels.profile_limits(pts, _EMPTY, False, c.limit_settings)[1]
    return kappa
