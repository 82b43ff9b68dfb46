"""The friction-limited lap time along the true centreline: the yardstick.

A quasi-steady-state (QSS) lap simulation, the standard first estimate of a
car's lap time in vehicle dynamics (e.g. Milliken & Milliken, "Race Car
Vehicle Dynamics", ch. 2): the car follows the centreline, at every point as
fast as the tyres allow, accelerating and braking at the car's limits in
between. Hand-written because no maintained Python package does a QSS lap for
a given path and car (the open lap-time simulators are MATLAB, or full
optimal-control stacks); it is three array passes.

For the ``VehicleParams`` car (the same limits the simulated car has):

* grip: ``a_max(v) = mu * D * (g + 0.5 rho ClA v^2 / m)`` (the Pacejka peak on
  the static plus aerodynamic load);
* cornering speed: ``v^2 |kappa| = a_max(v)``, so
  ``v_corner = sqrt(mu D g / (|kappa| - mu D 0.5 rho ClA / m))`` (unbounded when the
  downforce grows faster than the curvature needs: capped at the top speed);
* forward pass: ``dv^2/ds = 2 a_x`` with ``a_x = min(max_accel, (min(F_max, P / v) -
  F_drag - F_roll) / m)`` inside the friction ellipse
  ``a_x <= a_max sqrt(1 - (v^2 kappa / a_max)^2)``;
* backward pass: the same with ``max_decel``.

A loop is a flying lap (the passes run twice around so the speed at the line
is periodic); the simulated car's first lap includes a standing start, so
compare against its best lap. An open lane (acceleration) starts from rest
where the car starts and is timed between its two timing lines, as the
simulated run is.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray
from scipy.interpolate import splev, splprep

from conesim.core.polyline import Polyline
from conesim.sim.vehicle_params import VehicleParams

FloatArray = NDArray[np.float64]
STEP_M = 0.25  # [m] resampling step of the centreline


def centreline_grid(points: FloatArray, closed: bool) -> tuple[FloatArray, FloatArray]:
    """Arc-length stations and curvature along ``points``, ``STEP_M`` apart.

    An interpolating cubic spline (``splprep`` with s = 0, periodic for a
    loop) goes through the given points, which lie on the curve; it is
    sampled every ``STEP_M`` of its arc length, and the curvature at each
    sample is the polyline's through the samples (``Polyline.curvature``,
    the circle through a sample and its neighbours).

    Returns:
        (s (k,) [m], kappa (k,) [1/m]).
    """
    pts = np.asarray(points, dtype=float)
    if closed:
        pts = np.vstack([pts, pts[:1]])
    seg = np.hypot(*np.diff(pts, axis=0).T)
    pts = pts[np.concatenate([[True], seg > 1e-9])]
    tck, _ = splprep(pts.T, s=0.0, per=1 if closed else 0, k=3)
    dense = np.linspace(0.0, 1.0, 20 * len(pts))
    x, y = splev(dense, tck)
    s_dense = np.concatenate([[0.0], np.cumsum(np.hypot(np.diff(x), np.diff(y)))])
    length = float(s_dense[-1])
    n = max(8, round(length / STEP_M))
    s = np.linspace(0.0, length, n, endpoint=not closed)
    samples = np.column_stack(splev(np.interp(s, s_dense, dense), tck))
    return s, Polyline(samples, closed).curvature()


def qss_speed_profile(
    s: FloatArray, kappa: FloatArray, closed: bool, p: VehicleParams, v_start: float = 0.0
) -> FloatArray:
    """Quasi-steady-state speed at each station [m/s] (see the module docstring)."""
    mu_peak = p.mu * p.tyre_front.D
    k_aero = 0.5 * p.air_density * p.lift_area / p.mass
    k_drag = 0.5 * p.air_density * p.drag_area / p.mass
    v_top = _top_speed(p)
    denom = np.abs(kappa) - mu_peak * k_aero
    with np.errstate(divide="ignore"):
        v_corner = np.where(
            denom > 0, np.sqrt(mu_peak * p.gravity / np.maximum(denom, 1e-12)), v_top
        )
    v_lim = np.minimum(v_corner, v_top)
    n = len(s)
    ds = np.diff(s) if not closed else np.full(n, s[1] - s[0])

    def a_available(v: float, k: float) -> float:
        a_max = mu_peak * (p.gravity + k_aero * v * v)
        lat = min(1.0, v * v * abs(k) / a_max)
        return a_max * math.sqrt(max(0.0, 1.0 - lat * lat))

    def forward(v: FloatArray, laps: int, v0: float | None) -> FloatArray:
        out = v.copy()
        if v0 is not None:
            out[0] = min(out[0], v0)
        for _ in range(laps):
            for i in range(n - 1 if not closed else n):
                j = (i + 1) % n
                vi = out[i]
                f_drive = min(p.max_drive_force, p.max_power / max(vi, 0.1)) / p.mass
                resist = k_drag * vi * vi + p.rolling_resistance * p.gravity
                a = min(p.max_accel, f_drive - resist, a_available(vi, kappa[i]))
                out[j] = min(out[j], math.sqrt(vi * vi + 2.0 * max(a, 0.0) * ds[i]))
        return out

    def backward(v: FloatArray, laps: int) -> FloatArray:
        out = v.copy()
        for _ in range(laps):
            for i in range(n - 1 if not closed else n, 0, -1):
                j = i % n
                k = i - 1
                vj = out[j]
                a = min(p.max_decel, a_available(vj, kappa[k]))  # braking on segment k -> j
                out[k] = min(out[k], math.sqrt(vj * vj + 2.0 * a * ds[k]))
        return out

    laps = 2 if closed else 1
    v = forward(v_lim, laps, None if closed else v_start)
    return backward(v, laps)


def _top_speed(p: VehicleParams) -> float:
    """Speed where the drive force meets drag and rolling resistance [m/s]."""
    v = 10.0
    for _ in range(100):  # fixed point of P / v = drag(v) + roll
        drive = min(p.max_drive_force, p.max_power / v)
        resist = (
            0.5 * p.air_density * p.drag_area * v * v + p.rolling_resistance * p.mass * p.gravity
        )
        v = v * (drive / resist) ** (1.0 / 3.0)
    return v


def limit_lap_time(
    centreline: FloatArray,
    closed: bool,
    params: VehicleParams | None = None,
    *,
    start_s: float = 0.0,
    timed_from_s: float | None = None,
    timed_to_s: float | None = None,
) -> float:
    """QSS lap time along ``centreline`` for the car ``params`` [s].

    A loop is timed as a flying lap. An open path starts from rest at station
    ``start_s`` and is timed from ``timed_from_s`` (default ``start_s``) to
    ``timed_to_s`` (default its end), as a timed run past two timing lines.
    """
    p = params or VehicleParams()
    s, kappa = centreline_grid(centreline, closed)
    if closed:
        v = qss_speed_profile(s, kappa, closed, p)
        ds = np.full(len(s), s[1] - s[0])
        return float(np.sum(2.0 * ds / np.maximum(v + np.roll(v, -1), 1e-6)))
    # From rest exactly at start_s: the grid's first station at or after it
    # would start the run up to STEP_M late (a 4 mm late start read 1 ms slow).
    keep = s > start_s + 1e-9
    kappa = np.concatenate([[np.interp(start_s, s, kappa)], kappa[keep]])
    s = np.concatenate([[start_s], s[keep]])
    v = qss_speed_profile(s, kappa, closed, p, v_start=0.0)
    t = np.concatenate([[0.0], np.cumsum(2.0 * np.diff(s) / np.maximum(v[:-1] + v[1:], 1e-6))])
    t0 = float(np.interp(start_s if timed_from_s is None else timed_from_s, s, t))
    t1 = float(np.interp(s[-1] if timed_to_s is None else timed_to_s, s, t))
    return t1 - t0
