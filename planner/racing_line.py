"""The racing line: a minimum-curvature line inside the track, less the car and a margin.

A closed lane (a loop, or the skidpad's timed circle) is a ``Corridor``: a
reference line and the two boundaries, polylines through the cones. A line
is the reference moved along its normals by offsets alpha (n,) [m]::

    P_i = r_i + alpha_i n_i,     lower_i <= alpha_i <= upper_i

The bounds keep the car's centre ``clearance`` = half its width plus
``MARGIN_M`` from both boundary polylines: ``upper_i = d_left,i -
clearance``, ``lower_i = -(d_right,i - clearance)`` with d the distance
from r_i to the nearest point of that boundary. The nearest point is never
further than the one along the normal, so a point moved by |alpha| <= d -
clearance keeps at least ``clearance`` from the boundary (the triangle
inequality), and from every cone on it. The bounds are then smoothed over
``SMOOTHING_M``, only ever inward (``_smooth_below``): measured against the
chords between cones they are scalloped, and a line pressed against a
scalloped bound (the shortest path along the inside of a long corner)
wiggles, and its curvature with it. Where the lane is narrower than twice
the clearance, the line is held at the middle of what there is.

**Minimum curvature** (Braghin et al., "Race driver model", Computers &
Structures 86, 2008; Heilmeier et al., Vehicle System Dynamics 58(10),
2020, TUM's ``opt_min_curv``): the curvature of the offset line, to first
order in alpha and its derivatives along the reference's arc length s
(with t' = kappa_r n and n' = -kappa_r t, P' = (1 - alpha kappa_r) t +
alpha' n, and kappa = cross(P', P'') / |P'|^3)::

    kappa_i ~= kappa_r,i + alpha''_i + kappa_r,i^2 alpha_i = (c + M alpha)_i
    c = kappa_r,   M = D2 / h^2 + diag(kappa_r^2)

with the reference resampled every h [m], kappa_r its curvature
(``Polyline.curvature``) and D2 the periodic second difference. The QP
``min ||c + M alpha||^2`` subject to the box is solved with OSQP. (The
plain second difference of the points, n_i . D2 P / h^2, is no curvature
here: it is the parametric acceleration, whose normal part is kappa_r +
alpha'' - kappa_r^2 alpha, with the sign of the last term wrong; on a ring
it prefers the inner circle.) The linearisation holds for small offsets and
heading changes, so the solution becomes the next reference (resampled to
the same step, its bounds measured again) and the QP is solved again:
``ITERATIONS`` times in all, as Heilmeier et al. iterate theirs.

**Shortest path** on the last reference, ``min sum |P_{i+1} - P_i|^2``,
exactly quadratic in alpha (TUM's ``opt_shortest_path``), plus a little of
the curvature's objective (``SHORTEST_SMOOTHING``): pressed on the bounds
for whole corners, the plain shortest path follows the polygon of the
cones, whose kinks a QSS lap reads as slow corners.

**Between the points** the spline through them (the line the QSS lap
times) can pass closer to a cone than the points themselves, on the inside
of a corner: ``clearance_lacking`` measures both lines every
``CHECK_STEP_M``, the bounds of the points about a shortfall are tightened
by it and both QPs solved again, up to ``TIGHTENING_ROUNDS`` times, until
no shortfall exceeds ``TOLERANCE_M``.

**Why both**: the minimum-curvature line is not the fastest one where the
corners are long: on a ring of constant width it is the outermost circle,
whose lap time 2 pi sqrt(r / a_lat) grows with its radius r, so the
innermost circle is faster. Braghin et al. take the fastest blend of the two
lines, ``(1 - eps) alpha_curv + eps alpha_short`` (inside the same box: it
is convex); ``envs.limit_lap`` times the blends and keeps the fastest.

Hand-written around OSQP because TUM's ``trajectory-planning-helpers`` pins
old numpy/scipy versions and builds its QP from splines of the reference
that this needs none of; the QP itself is OSQP's, a maintained solver.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import osqp
from numpy.typing import NDArray
from scipy import sparse
from scipy.interpolate import splev, splprep
from scipy.ndimage import maximum_filter1d, minimum_filter1d, uniform_filter1d
from scipy.spatial import cKDTree

from conesim.core.polyline import Polyline

FloatArray = NDArray[np.float64]

MARGIN_M = 0.25  # [m] clearance beyond half the car's width (a cone's base is 0.23 m wide)
STEP_M = 1.0  # [m] spacing of the QP's points along the reference
ITERATIONS = 3  # minimum-curvature QPs, each linearised about the previous line
TIGHTENING_ROUNDS = 3  # at most, to keep the splines between the QP's points inside
CHECK_STEP_M = 0.1  # [m] the splines are checked this often
BOUNDARY_STEP_M = 0.02  # [m] the boundaries' points the check measures to
TOLERANCE_M = 0.002  # [m] the clearance the splines may lack
# [m^4] weight of the squared curvatures in the shortest path's objective: a
# ripple of wavelength l costs (2 pi / l)^2 this much more in curvature than in
# length, so ripples shorter than the cone spacing are smoothed away while a
# corner's shape (tens of metres) is still the shortest path's.
SHORTEST_SMOOTHING = 4.0
SUBSTEPS = 10  # the bounds' distances are measured this many times a step
SMOOTHING_M = 5.0  # [m] the bounds are smoothed over this much (FS cones are <= 5 m apart)
_REGULARISATION = 1e-9  # [1/m^4] added to the QP's diagonal: a unique solution on straights


class RacingLineError(ValueError):
    """The QP could not be solved (a lane too odd to hold a line)."""


@dataclass(frozen=True)
class Corridor:
    """A closed lane: where a line may run.

    Attributes:
        centre: (n, 2) the reference line, a loop (first point not repeated) [m].
        left: the left boundary, a closed polyline through its cones [m].
        right: the right boundary [m].
        clearance: the car's centre keeps this far from both [m].
        body_half_width: half the car's width [m], for ``body_front``.
        body_front: the car's front end ahead of the point on the line [m]
            (the rear axle, which pure pursuit steers along it; 0: no sweep):
            outside a turn of radius R the front corner runs
            sqrt((R + w/2)^2 + f^2) - R - w/2 wider than the side at the
            axle (``sweep``), and the line keeps that much more from the
            outer boundary.
    """

    centre: FloatArray
    left: Polyline
    right: Polyline
    clearance: float
    body_half_width: float = 0.0
    body_front: float = 0.0


@dataclass(frozen=True)
class RacingLines:
    """The two lines of the last reference, and their blends.

    Attributes:
        reference: (n, 2) the last reference line [m], ``STEP_M`` apart.
        normals: (n, 2) its unit left normals.
        lower: (n,) the smallest admissible offset [m] (right of the reference).
        upper: (n,) the largest admissible offset [m] (left).
        min_curvature: (n,) the minimum-curvature line's offsets [m].
        shortest: (n,) the shortest path's offsets [m].
    """

    reference: FloatArray
    normals: FloatArray
    lower: FloatArray
    upper: FloatArray
    min_curvature: FloatArray
    shortest: FloatArray

    def line(self, blend: float = 0.0) -> FloatArray:
        """(n, 2) the line ``(1 - blend)`` minimum curvature + ``blend`` shortest [m]."""
        alpha = (1.0 - blend) * self.min_curvature + blend * self.shortest
        return self.reference + alpha[:, None] * self.normals


def racing_lines(corridor: Corridor) -> RacingLines:
    """The minimum-curvature and shortest lines through ``corridor`` (module docstring).

    Raises:
        RacingLineError: OSQP found no solution.
    """
    reference = Polyline(corridor.centre, True).resample(STEP_M).points
    normals, lower, upper = offset_bounds(reference, corridor)
    alpha = min_curvature_offsets(reference, lower, upper)
    for _ in range(ITERATIONS - 1):
        line = reference + alpha[:, None] * normals
        reference = Polyline(line, True).resample(STEP_M).points
        normals, lower, upper = offset_bounds(reference, corridor)
        alpha = min_curvature_offsets(reference, lower, upper)
    shortest = shortest_path_offsets(reference, normals, lower, upper)
    for _ in range(TIGHTENING_ROUNDS):
        lack_left, lack_right = np.zeros(len(reference)), np.zeros(len(reference))
        for offsets in (alpha, shortest):
            left, right = clearance_lacking(reference + offsets[:, None] * normals, corridor)
            lack_left, lack_right = np.maximum(lack_left, left), np.maximum(lack_right, right)
        if max(lack_left.max(), lack_right.max()) <= TOLERANCE_M:
            break
        upper = np.maximum(upper - lack_left - TOLERANCE_M * (lack_left > 0), lower)
        lower = np.minimum(lower + lack_right + TOLERANCE_M * (lack_right > 0), upper)
        alpha = min_curvature_offsets(reference, lower, upper)
        shortest = shortest_path_offsets(reference, normals, lower, upper)
    return RacingLines(reference, normals, lower, upper, alpha, shortest)


def spline_grid(points: FloatArray, closed: bool, step: float) -> tuple[FloatArray, FloatArray]:
    """The interpolating cubic spline through ``points`` (n, 2) [m], sampled every
    ~``step`` [m] of its arc length: stations (k,) [m] and points (k, 2) [m].

    ``splprep`` with s = 0 (periodic for a loop), evaluated densely to measure
    its arc length; a loop's samples end one step before its start.
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
    n = max(8, round(length / step))
    s = np.linspace(0.0, length, n, endpoint=not closed)
    return s, np.column_stack(splev(np.interp(s, s_dense, dense), tck))


def clearance_lacking(line: FloatArray, corridor: Corridor) -> tuple[FloatArray, FloatArray]:
    """How much the spline through the loop ``line`` (n, 2) comes closer than the
    clearance to the left and to the right boundary, by point (n,) [m] (0 where it
    does not): the most of the samples nearest to each point and its two neighbours.

    Distances to a boundary are to its points every ``BOUNDARY_STEP_M`` (a k-d
    tree, not the exact projection: 0.1 mm shorter at most, many times faster).
    """
    samples = spline_grid(line, True, CHECK_STEP_M)[1]
    nearest = cKDTree(line).query(samples)[1]
    out = []
    for boundary in (corridor.left, corridor.right):
        dense = boundary.resample(BOUNDARY_STEP_M).points
        lack = np.maximum(corridor.clearance - cKDTree(dense).query(samples)[0], 0.0)
        per_point = np.zeros(len(line))
        np.maximum.at(per_point, nearest, lack)
        out.append(np.maximum(per_point, np.maximum(np.roll(per_point, 1), np.roll(per_point, -1))))
    return out[0], out[1]


def offset_bounds(
    reference: FloatArray, corridor: Corridor
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Unit left normals (n, 2) of a closed ``reference`` and its offsets' bounds (n,) [m].

    A point left of the left boundary, or right of the right one, has a
    negative distance to it; where the bounds cross, both are the middle of
    the two.
    """
    ring = Polyline(reference, True)
    tangents = ring.tangents()
    normals = np.column_stack([-tangents[:, 1], tangents[:, 0]])
    # The distances are measured every 1 / SUBSTEPS of a step too: the nearest
    # approach of a chord between cones falls between the points, and the
    # running minimum of the points alone misses it by up to h^2 / 8 R (a few mm
    # at 1 m, in a ripple a line pressed on the bound takes, and a speed plan
    # reads: 2 mm at 3.5 m cost a R 15 m ring 1 % of its lap).
    dense = _between(reference)
    d_left = -corridor.left.project(dense).lateral
    d_right = corridor.right.project(dense).lateral
    step = float(np.mean(ring.segment_lengths))
    window = max(1, 2 * round(0.5 * SMOOTHING_M / step) + 1)  # odd, about SMOOTHING_M
    sweeps = [np.zeros(len(dense)), np.zeros(len(dense))]  # [to the left, to the right]
    if corridor.body_front > 0.0:
        # The tightest turn within the window either way (the body sweeps out of a
        # right turn to the left, of a left turn to the right), smoothed: the
        # reference is the last QP's line, and a bound that follows its
        # curvature point by point puts that curvature's ripple back in.
        kappa = ring.curvature()
        for side, sign in enumerate((-1.0, 1.0)):
            tight = maximum_filter1d(np.maximum(sign * kappa, 0.0), window, mode="wrap")
            smooth = uniform_filter1d(tight, window, mode="wrap")
            body = sweep(smooth, corridor.body_half_width, corridor.body_front)
            sweeps[side] = np.repeat(body, SUBSTEPS)
    sweep_left, sweep_right = sweeps
    upper = _smooth_below(d_left - corridor.clearance - sweep_left, window)
    lower = -_smooth_below(d_right - corridor.clearance - sweep_right, window)
    # Where they cross, the middle of the smoothed bounds: the middle of the
    # raw distances follows the chords between the cones, and a line held to
    # it zigzags (a 0.1 m ripple at the cones' 3 m spacing is a curvature of 0.4 1/m).
    middle = uniform_filter1d(0.5 * (lower + upper), window, mode="wrap")
    narrow = lower > upper
    return normals, np.where(narrow, middle, lower), np.where(narrow, middle, upper)


def _between(reference: FloatArray) -> FloatArray:
    """(n * SUBSTEPS, 2) the closed ``reference`` (n, 2) and ``SUBSTEPS`` - 1 points
    between each two on the periodic cubic spline through it (the curve, not the
    chords, which lie h^2 / 8 R inside it) [m]."""
    pts = np.vstack([reference, reference[:1]])
    tck, u = splprep(pts.T, s=0.0, per=1, k=3)
    share = np.arange(SUBSTEPS) / SUBSTEPS
    at = (u[:-1, None] + share[None, :] * np.diff(u)[:, None]).ravel()
    return np.column_stack(splev(at, tck))


def sweep(kappa: FloatArray, half_width: float, front: float) -> FloatArray:
    """How much wider than its side at the axle the front corner runs outside a turn of
    curvature kappa >= 0 (n,) [1/m] at the axle: sqrt((R + w/2)^2 + f^2) - R - w/2,
    R = 1 / kappa, written f^2 kappa / (sqrt((1 + w/2 kappa)^2 + (f kappa)^2) + 1 + w/2 kappa)
    to hold at kappa = 0 [m]."""
    k = np.asarray(kappa, dtype=float)
    base = 1.0 + half_width * k
    out: FloatArray = front * front * k / (np.hypot(base, front * k) + base)
    return out


def _smooth_below(bound: FloatArray, window: int) -> FloatArray:
    """A smooth cyclic function (n,) at the points that is nowhere above ``bound``
    (n * SUBSTEPS,), given at the points and ``SUBSTEPS`` - 1 between each two.

    The running minimum over ``window`` points (all the samples they span), then
    the running mean over as many points: each point's mean is of minima over
    windows that contain it, so it is at most its own value (a morphological
    opening, smoothed).
    """
    half = (window // 2) * SUBSTEPS
    low = minimum_filter1d(bound, 2 * half + 1, mode="wrap")[::SUBSTEPS]
    smooth: FloatArray = uniform_filter1d(low, window, mode="wrap")
    return np.minimum(smooth, bound[::SUBSTEPS])  # the mean's rounding


def min_curvature_offsets(
    reference: FloatArray, lower: FloatArray, upper: FloatArray
) -> FloatArray:
    """Offsets (n,) [m] of the minimum-curvature line, linearised about ``reference``."""
    m, kappa = _curvature_model(reference)
    return _box_qp(2.0 * (m.T @ m), 2.0 * (m.T @ kappa), lower, upper)


def _curvature_model(reference: FloatArray) -> tuple[sparse.csc_matrix, FloatArray]:
    """(M (n, n), c (n,)): the curvature of the offset line is c + M alpha (module
    docstring), c = kappa_r, M = D2 / h^2 + diag(kappa_r^2)."""
    line = Polyline(reference, True)
    h2 = float(np.mean(line.segment_lengths)) ** 2
    kappa = line.curvature()
    d2 = _periodic_difference(len(reference), (1.0, -2.0, 1.0))
    return (d2 / h2 + sparse.diags(kappa**2)).tocsc(), kappa


def shortest_path_offsets(
    reference: FloatArray, normals: FloatArray, lower: FloatArray, upper: FloatArray
) -> FloatArray:
    """Offsets (n,) [m] of the line of least sum of squared step lengths, plus
    ``SHORTEST_SMOOTHING`` times its sum of squared curvatures."""
    d1 = _periodic_difference(len(reference), (-1.0, 1.0))
    m, kappa = _curvature_model(reference)
    hess = SHORTEST_SMOOTHING * 2.0 * (m.T @ m)
    grad = SHORTEST_SMOOTHING * 2.0 * (m.T @ kappa)
    for axis in range(2):
        b = d1 @ sparse.diags(normals[:, axis])
        hess = hess + 2.0 * (b.T @ b)
        grad = grad + 2.0 * (b.T @ (d1 @ reference[:, axis]))
    return _box_qp(hess, grad, lower, upper)


def _periodic_difference(n: int, stencil: tuple[float, ...]) -> sparse.csr_matrix:
    """(n, n) the cyclic difference with ``stencil`` on offsets -1, 0, +1 (three
    weights) or 0, +1 (two)."""
    offsets = (-1, 0, 1) if len(stencil) == 3 else (0, 1)
    rows = np.repeat(np.arange(n), len(offsets))
    cols = (rows + np.tile(offsets, n)) % n
    return sparse.csr_matrix((np.tile(stencil, n), (rows, cols)), shape=(n, n))


def _box_qp(
    hessian: sparse.spmatrix, gradient: FloatArray, lower: FloatArray, upper: FloatArray
) -> FloatArray:
    """``argmin 0.5 x' H x + g' x`` subject to ``lower <= x <= upper``, with OSQP.

    The solution is clipped into the box (OSQP meets its constraints to its
    tolerance, about 1e-5 m here).

    Raises:
        RacingLineError: OSQP did not solve it.
    """
    n = len(gradient)
    hess = sparse.triu(hessian + _REGULARISATION * sparse.identity(n), format="csc")
    solver = osqp.OSQP()
    solver.setup(
        hess, np.asarray(gradient, dtype=float), sparse.identity(n, format="csc"),
        lower, upper, verbose=False, eps_abs=1e-5, eps_rel=1e-5, max_iter=50_000,
        polishing=True,
    )  # fmt: skip
    result = solver.solve(raise_error=False)
    # A solution at the iteration limit is clipped into the box like any other:
    # an admissible line, if not quite the optimal one.
    solved = (
        osqp.SolverStatus.OSQP_SOLVED,
        osqp.SolverStatus.OSQP_SOLVED_INACCURATE,
        osqp.SolverStatus.OSQP_MAX_ITER_REACHED,
    )
    if result.info.status_val not in solved or not np.all(np.isfinite(result.x)):
        raise RacingLineError(f"the racing line's QP failed: {result.info.status}")
    return np.clip(np.asarray(result.x, dtype=float), lower, upper)
