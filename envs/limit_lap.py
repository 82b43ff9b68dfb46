"""The yardstick: the fastest lap of this car on a racing line inside the track.

A quasi-steady-state (QSS) lap simulation, the standard first estimate of a
car's lap time in vehicle dynamics (e.g. Milliken & Milliken, "Race Car
Vehicle Dynamics", ch. 2): the car follows a line (the racing line, or the
centreline for the figure beside it), at every point as fast as the tyres
allow, accelerating and braking at the car's limits in between.
Hand-written because no maintained Python package does a QSS lap for a
given path and car (the open lap-time simulators are MATLAB, or full
optimal-control stacks); it is three array passes.

For the ``VehicleParams`` car, with the limits the simulated car has
(``envs.traction.AxleLimits``: each axle's friction ellipse on its load,
with the load transfer, the drive and brake splits and the downforce of
``sim.vehicle_dynamics``):

* cornering speed: the largest speed at which both axles hold the turn,
  ``v^2 |kappa| = mu D (g + 0.5 rho ClA v^2 / m)`` for the defaults (the
  Pacejka peak on the static plus aerodynamic load; capped at the top speed
  where the downforce grows faster than the curvature needs);
* forward pass: ``dv^2/ds = 2 a_x`` with a_x the largest acceleration the
  demand limit (``max_accel``), the motor (``min(F_max, P / v)`` less drag
  and rolling resistance on the static plus aerodynamic load) and both
  axles' ellipses allow beside the corner's lateral force;
* backward pass: the same with ``max_decel`` and the brake split: braking
  into a corner, the unloaded rear axle runs out of grip first.

A loop is a flying lap (the passes start at its slowest corner, so the
speed at the line is periodic); the simulated car's first lap includes a standing start, so
compare against its best lap. An open lane (acceleration) starts from rest
where the car starts and is timed between its two timing lines, as the
simulated run is.

**The limit of a track** (``track_lap_limit``): a loop's, and the skidpad's
timed circle's, is the fastest of the lines ``planner.racing_line`` offers, the
blends ``BLENDS`` of its minimum-curvature line with its shortest path (and
``BLEND_REFINE`` either side of the fastest of them), all inside the cones
less half the car's width and ``racing_line.MARGIN_M``, each timed by the
QSS above; never slower than the centreline (where no line beats it, or
none can be found, the limit is the centreline's, with a warning in the
latter case). An open lane's racing line is its centreline (the
acceleration lane is straight), timed from rest. The centreline's figure is
kept beside the limit. Both are computed once per track and car.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.ndimage import uniform_filter1d
from scipy.optimize import brentq

from conesim.core.polyline import Polyline
from conesim.envs.traction import AxleLimits
from conesim.planner.racing_line import MARGIN_M, Corridor, racing_lines, spline_grid
from conesim.sim.progress import PolylineProgress
from conesim.sim.race_control import line_crossings_along
from conesim.sim.vehicle_params import VehicleParams
from conesim.tracks import Layout, Track

FloatArray = NDArray[np.float64]
STEP_M = 0.25  # [m] resampling step of the centreline
CURVATURE_WINDOW_M = 2.0  # [m] the curvature is averaged over this much of the line
BLENDS = (0.0, 0.25, 0.5, 0.75, 1.0)  # shares of the shortest path in the lines timed,
BLEND_REFINE = 0.125  # then these either side of the fastest

_LOG = logging.getLogger(__name__)


def centreline_grid(points: FloatArray, closed: bool) -> tuple[FloatArray, FloatArray]:
    """Arc-length stations and curvature along ``points``, ``STEP_M`` apart.

    An interpolating cubic spline (``splprep`` with s = 0, periodic for a
    loop) goes through the given points, which lie on the curve; it is
    sampled every ``STEP_M`` of its arc length, and the curvature at each
    sample is the polyline's through the samples (``Polyline.curvature``,
    the circle through a sample and its neighbours), averaged over
    ``CURVATURE_WINDOW_M`` (a car a wheelbase long does not feel a ripple
    shorter than itself; TUM's lap-time tools, too, take the curvature over a
    preview and a review of the path). The average keeps a circle's 1/R.

    Returns:
        (s (k,) [m], kappa (k,) [1/m]).
    """
    s, samples = spline_grid(points, closed, STEP_M)
    kappa = Polyline(samples, closed).curvature()
    window = max(1, round(CURVATURE_WINDOW_M / STEP_M))
    return s, uniform_filter1d(kappa, window, mode="wrap" if closed else "nearest")


def qss_speed_profile(
    s: FloatArray, kappa: FloatArray, closed: bool, p: VehicleParams, v_start: float = 0.0
) -> FloatArray:
    """Quasi-steady-state speed at each station [m/s] (see the module docstring)."""
    axles = AxleLimits(p)
    v_lim = axles.corner_speed(kappa, _top_speed(p))
    n = len(s)
    ds = (np.diff(s) if not closed else np.full(n, s[1] - s[0])).tolist()
    k_abs = np.abs(kappa).tolist()
    drive, brake, sqrt = axles.drive, axles.brake, math.sqrt

    def forward(out: list[float], laps: int) -> None:
        for _ in range(laps):
            for i in range(n - 1 if not closed else n):
                j = i + 1 if i + 1 < n else 0
                vi = out[i]
                a = drive(vi, k_abs[i])
                out[j] = min(out[j], sqrt(vi * vi + 2.0 * max(a, 0.0) * ds[i]))

    def backward(out: list[float], laps: int) -> None:
        for _ in range(laps):
            for i in range(n - 1 if not closed else n, 0, -1):
                j = i % n
                k = i - 1
                vj = out[j]
                a = brake(vj, k_abs[k])  # braking on segment k -> j
                out[k] = min(out[k], sqrt(vj * vj + 2.0 * a * ds[k]))

    if not closed:
        v = v_lim.tolist()
        v[0] = min(v[0], v_start)
        forward(v, 1)
        backward(v, 1)
        return np.array(v)
    # A loop from its slowest corner: no pass lowers the smallest limit (both
    # only take minima with speeds reached from a lower one), so the speed
    # there is known and one pass round each way is periodic.
    first = int(np.argmin(v_lim))
    ds = ds[first:] + ds[:first]
    k_abs = k_abs[first:] + k_abs[:first]
    v = np.roll(v_lim, -first).tolist()
    forward(v, 1)
    backward(v, 1)
    return np.roll(np.array(v), first)


def _top_speed(p: VehicleParams) -> float:
    """Speed where the drive force meets drag and rolling resistance [m/s]; inf for a
    car with neither (``AxleLimits.resistance``, the physics' own).

    ``min(F_max, P / v) - R(v)`` falls with v, and is positive at rest
    (``VehicleParams`` requires the motor to beat the rolling resistance), so
    the root is bracketed by doubling and found by scipy's ``brentq``.
    """
    axles = AxleLimits(p)
    if axles.resistance(1.0) == 0.0:  # no drag, no rolling resistance: no top speed
        return math.inf

    def excess(v: float) -> float:
        return min(p.max_drive_force, p.max_power / v) - axles.resistance(v)

    hi = 1.0
    while excess(hi) > 0.0:
        hi *= 2.0
    lo = hi / 2.0
    while excess(lo) <= 0.0 and lo > 1e-9:  # a top speed below 1 m/s
        lo /= 2.0
    return float(brentq(excess, lo, hi, xtol=1e-9, rtol=1e-12))


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


@dataclass(frozen=True)
class LapLimit:
    """The limit of a track's timed lap for one car.

    Attributes:
        limit_s: the fastest QSS lap found on a line inside the track [s].
        centreline_s: the QSS lap along the centreline [s].
        racing_line: (k, 2) the line of ``limit_s`` [m], a loop: the spline
            the QSS times, sampled every ``STEP_M``; None where it is the
            centreline (an open lane, or no line could be found).
        blend: the shortest path's share in that line [-]; None with the
            centreline.
    """

    limit_s: float
    centreline_s: float
    racing_line: FloatArray | None = None
    blend: float | None = None


def track_lap_limit(track: Track, params: VehicleParams | None = None) -> LapLimit:
    """The limit of ``track``'s timed lap for the car ``params`` (module docstring).

    Cached per track and car: a sweep's runs on one track compute it once.
    """
    p = params or VehicleParams()
    key = (track.name, track.layout, track.cones.tobytes(), track.kinds, track.start_pose, p)
    if key not in _LIMITS:
        if len(_LIMITS) >= _CACHE_SIZE:
            del _LIMITS[next(iter(_LIMITS))]  # the oldest
        _LIMITS[key] = _compute_limit(track, p)
    return _LIMITS[key]


_CACHE_SIZE = 16  # tracks x cars whose limits are kept
_LIMITS: dict[tuple[object, ...], LapLimit] = {}


def _compute_limit(track: Track, p: VehicleParams) -> LapLimit:
    centre = np.asarray(track.centreline)
    clearance = 0.5 * p.width + MARGIN_M
    if track.layout == Layout.CLOSED:
        corridor = Corridor(
            centre,
            Polyline(track.left_boundary, True),
            Polyline(track.right_boundary, True),
            clearance,
        )
    else:
        mask = _skidpad_circle(track) if track.layout == Layout.SKIDPAD else None
        if mask is None:  # an open lane, or a skidpad whose circle cannot be found
            lane = _open_lane_time(track, p)
            return LapLimit(limit_s=lane, centreline_s=lane)
        corridor = Corridor(
            centre[mask],
            Polyline(np.asarray(track.left_boundary)[mask], True),
            Polyline(np.asarray(track.right_boundary)[mask], True),
            clearance,
        )
    centreline_s = limit_lap_time(corridor.centre, True, p)
    try:
        lines = racing_lines(corridor)
        times = {blend: limit_lap_time(lines.line(blend), True, p) for blend in BLENDS}
        coarse = min(times, key=times.__getitem__)
        for blend in (coarse - BLEND_REFINE, coarse + BLEND_REFINE):
            if 0.0 < blend < 1.0:
                times[blend] = limit_lap_time(lines.line(blend), True, p)
    except (ValueError, ArithmeticError) as exc:  # RacingLineError, or a line too odd
        _LOG.warning("%s: no racing line (%s); the limit is the centreline's", track.name, exc)
        return LapLimit(limit_s=centreline_s, centreline_s=centreline_s)
    best = min(times, key=times.__getitem__)
    if times[best] > centreline_s:  # no line inside the margins beats the centreline
        return LapLimit(limit_s=centreline_s, centreline_s=centreline_s)
    return LapLimit(
        limit_s=times[best],
        centreline_s=centreline_s,
        racing_line=spline_grid(lines.line(best), True, STEP_M)[1],
        blend=best,
    )


def _skidpad_circle(track: Track) -> NDArray[np.bool_] | None:
    """The centreline points of the skidpad's timed circle: between the first two
    crossings of the timing line (None if it crosses it less often)."""
    centre = np.asarray(track.centreline)
    s = Polyline(centre).stations
    finishes = line_crossings_along(centre, False, np.asarray(track.finish_line))
    if len(finishes) < 2:
        return None
    return (s >= finishes[0]) & (s < finishes[1])


def _open_lane_time(track: Track, p: VehicleParams) -> float:
    """From rest at the car's start, timed from the start line to the finish line,
    as race control times the simulated run [s]."""
    centre = np.asarray(track.centreline)
    line = Polyline(centre)
    starts = line_crossings_along(centre, False, np.asarray(track.start_finish))
    finishes = line_crossings_along(centre, False, np.asarray(track.finish_line))
    start_s = float(PolylineProgress(line).project(track.start_pose.xy).station[0])
    return limit_lap_time(
        centre,
        False,
        p,
        start_s=start_s,
        timed_from_s=starts[0] if starts else start_s,
        timed_to_s=finishes[0] if finishes else None,
    )
