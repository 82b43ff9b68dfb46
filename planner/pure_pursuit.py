"""Pure pursuit on the local path: steering from the bicycle geometry about the rear axle.

For a target point at distance L_d from the rear axle, seen at angle alpha
from the car's heading, the circle through the rear axle tangent to the
heading and through the target has curvature ``kappa = 2 sin(alpha) / L_d``
(Coulter 1992). A kinematic bicycle of wheelbase L follows it with the front
wheel angle::

    delta = atan(L * kappa) = atan(2 L sin(alpha) / L_d)

clipped to +-max_steer; with ``slip_stiffness`` alpha is measured from the
rear axle's velocity, alpha + alpha_r (``rear_slip_angle``). The lookahead
distance grows with speed,
``L_d = clip(lookahead_min + lookahead_gain * v, lookahead_min, lookahead_max)``,
and the target is where the path leaves the circle of radius L_d about the
rear axle, searching forward from the path point nearest the axle
(interpolated on the segment that crosses the circle). When the whole path
lies inside the circle, the target is its last point; when the point nearest
the axle already lies outside it, that point. Either way the formula uses the
target's actual distance.

**Curvature feed-forward** (``feedforward``, off by default). Pure pursuit's
arc is the mean curvature of the path over the chord ahead, so where the
path's curvature changes the car leads it: it turns in early and cuts a
corner's entry, and straightens early at its exit (0.95 s times v dkappa/ds
of lateral error, measured on generated tracks, 0.4 m at the entry of a
R 8 m corner at 11 m/s). With the feed-forward the command is::

    kappa = 2 sin(alpha) / L_d  -  2 sin(alpha_0) / L_0  +  kappa_path(s_q + v tau)

alpha_0, L_0 the same construction for a car on the path at the axle's
projection q, heading along it, and kappa_path the path's own curvature
``feedforward_preview`` tau ahead of q (the steering's lag): on the path the
first two terms cancel and the car steers the path's curvature; off it,
their difference is pure pursuit's correction of the error (the
feed-forward-and-feedback split of Kapania and Gerdes, "Design of a
feedback-feedforward steering controller for accurate path tracking and
stability at the limits of handling", Vehicle System Dynamics 53(12), 2015).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from conesim.planner.config import PurePursuitConfig
from conesim.planner.geometry import FloatArray

_GRAVITY = 9.81  # [m/s^2]


@dataclass(frozen=True, slots=True)
class SteeringResult:
    """One pure-pursuit step.

    Attributes:
        steering: front wheel angle, + left, within the limits [rad].
        target: (2,) lookahead point in the path's frame [m].
        index: index of the path point at or after the target.
        alpha: angle of the target from the heading, seen from the rear axle [rad].
        distance: distance from the rear axle to the target [m].
        lookahead: the lookahead distance asked for [m].
    """

    steering: float
    target: FloatArray
    index: int
    alpha: float
    distance: float
    lookahead: float


def lookahead_distance(speed: float, config: PurePursuitConfig) -> float:
    """L_d = clip(lookahead_min + lookahead_gain * |v|, min, max) [m] for speed v [m/s]."""
    raw = config.lookahead_min + config.lookahead_gain * abs(speed)
    return min(max(raw, config.lookahead_min), config.lookahead_max)


def find_lookahead_point(
    path: FloatArray, centre: FloatArray, distance: float
) -> tuple[FloatArray, int]:
    """Where the (n, 2) path leaves the circle of ``distance`` [m] about ``centre`` (2,).

    Returns:
        The target point (2,) and the index of the first path point at or
        beyond it.
    """
    d = np.hypot(path[:, 0] - centre[0], path[:, 1] - centre[1])
    nearest = int(np.argmin(d))
    beyond = np.flatnonzero(d[nearest:] >= distance)
    if len(beyond) == 0:
        return path[-1].copy(), len(path) - 1
    i = nearest + int(beyond[0])
    if i == nearest:
        return path[i].copy(), i
    a, b = path[i - 1] - centre, path[i] - centre
    seg = b - a
    # |a + t seg| = distance, the root in [0, 1] (a inside, b outside).
    qa = float(seg @ seg)
    qb = 2.0 * float(a @ seg)
    qc = float(a @ a) - distance**2
    t = (-qb + math.sqrt(max(qb * qb - 4.0 * qa * qc, 0.0))) / (2.0 * qa)
    return path[i - 1] + min(max(t, 0.0), 1.0) * seg, i


def pure_pursuit_angle(target: FloatArray, wheelbase: float) -> tuple[float, float, float]:
    """delta = atan(2 L sin(alpha) / L_d) for a target (2,) in the rear-axle frame.

    Returns:
        (delta [rad] unclipped, alpha [rad], L_d [m]).
    """
    x, y = float(target[0]), float(target[1])
    distance = math.hypot(x, y)
    if distance == 0.0:
        return 0.0, 0.0, 0.0
    alpha = math.atan2(y, x)
    return math.atan(2.0 * wheelbase * math.sin(alpha) / distance), alpha, distance


def rear_slip_angle(
    speed: float, alpha: float, distance: float, config: PurePursuitConfig
) -> float:
    """Expected slip angle of the rear axle on the pursuit arc [rad], + when turning left.

    Cornering, the rear tyres run at a slip angle: the rear axle moves at
    alpha_r outward of the car's heading, and pure pursuit's arc, tangent to
    the heading, turns less than the path. The car then settles outside the
    path (0.6 m at 15 m/s in the trackdrive's R 14 m corner). Measuring the
    target's angle from the axle's velocity instead adds alpha_r to alpha.
    With the linear tyre (slope B C D per radian of the friction used, the
    friction used being the lateral acceleration over the normal load per
    mass, g plus downforce)::

        a_lat   = v^2 * 2 sin(alpha) / L_d            (the pursuit arc)
        alpha_r = a_lat / (slip_stiffness * (g + downforce_per_mass * v^2))

    Args:
        speed: [m/s].
        alpha: the target's angle from the heading [rad].
        distance: the target's distance from the rear axle [m].
        config: ``slip_stiffness`` (inf: no slip) and ``downforce_per_mass``.
    """
    if not config.slip_stiffness < math.inf or distance <= 0.0:
        return 0.0
    a_lat = speed * speed * 2.0 * math.sin(alpha) / distance
    load = _GRAVITY + config.downforce_per_mass * speed * speed
    return a_lat / (config.slip_stiffness * load)


def pure_pursuit(
    path: FloatArray,
    speed: float,
    config: PurePursuitConfig,
    lookahead_cap: float | None = None,
    curvature: FloatArray | None = None,
) -> SteeringResult:
    """Steer toward the lookahead point of a path (n, 2) in the vehicle's frame [m].

    Args:
        path: the local path in ``os_sensor`` (x forward, y left), n >= 1.
        speed: current speed [m/s].
        config: geometry, limits and lookahead law.
        lookahead_cap: the lookahead distance is at most this [m] (not below
            ``lookahead_min``); None: the law alone.
        curvature: (n,) the path's curvature at its points [1/m], + left, for
            the feed-forward (``config.feedforward``; module docstring);
            None, or another length: pure pursuit alone.

    Raises:
        ValueError: ``path`` not (n, 2) with n >= 1 or not finite, or
            ``speed`` not finite (a NaN would pass the steering clip).
    """
    pts = np.asarray(path, dtype=float)
    if pts.ndim != 2 or pts.shape[1] != 2 or len(pts) == 0:
        raise ValueError(f"pure_pursuit: path must be (n, 2) [m] with n >= 1, got {pts.shape}")
    if not (math.isfinite(speed) and np.isfinite(pts).all()):
        raise ValueError(f"pure_pursuit: path and speed must be finite, speed {speed!r}")
    path = pts
    axle = np.array([config.rear_axle_x, 0.0])
    lookahead = lookahead_distance(speed, config)
    if lookahead_cap is not None:
        lookahead = max(min(lookahead, lookahead_cap), config.lookahead_min)
    target, index = find_lookahead_point(path, axle, lookahead)
    delta, alpha, distance = pure_pursuit_angle(target - axle, config.wheelbase)
    slip = rear_slip_angle(speed, alpha, distance, config)
    if slip != 0.0:
        delta = math.atan(2.0 * config.wheelbase * math.sin(alpha + slip) / distance)
    if config.feedforward and curvature is not None and len(curvature) == len(path) > 1:
        correction = _feedforward_correction(
            path, curvature, axle, lookahead=lookahead, speed=speed, config=config
        )
        arc = 2.0 * math.sin(alpha + slip) / distance if distance > 0.0 else 0.0
        delta = math.atan(config.wheelbase * (arc + correction))
    steering = min(max(delta, -config.max_steer), config.max_steer)
    return SteeringResult(steering, target, index, alpha, distance, lookahead)


def _feedforward_correction(
    path: FloatArray,
    curvature: FloatArray,
    axle: FloatArray,
    *,
    lookahead: float,
    speed: float,
    config: PurePursuitConfig,
) -> float:
    """kappa_path(s_q + v tau) - 2 sin(alpha_0) / L_0 [1/m] (module docstring): the
    path's curvature ahead of the axle's projection q less pure pursuit's arc
    from q, heading along the path."""
    seg = np.diff(path, axis=0)
    length2 = np.maximum(np.einsum("ij,ij->i", seg, seg), 1e-12)
    t = np.clip(np.einsum("ij,ij->i", axle - path[:-1], seg) / length2, 0.0, 1.0)
    foot = path[:-1] + t[:, None] * seg
    i = int(np.argmin(np.hypot(foot[:, 0] - axle[0], foot[:, 1] - axle[1])))
    q = foot[i]
    # The tangent at q, between its segment's ends' (second-order differences):
    # the segment's own direction is the tangent at its middle only.
    lo = min(max(i - 1, 0), max(len(path) - 3, 0))
    near = path[lo : lo + 3]
    ends = np.gradient(near, axis=0, edge_order=2 if len(near) == 3 else 1)[i - lo : i - lo + 2]
    direction = (1.0 - t[i]) * ends[0] + t[i] * ends[-1]
    heading = math.atan2(float(direction[1]), float(direction[0]))
    rest = np.vstack([q, path[i + 1 :]])
    target, _ = find_lookahead_point(rest, q, lookahead)
    dx, dy = float(target[0] - q[0]), float(target[1] - q[1])
    chord = math.hypot(dx, dy)
    if chord <= 0.0:
        return 0.0
    alpha0 = math.atan2(dy, dx) - heading
    s = np.concatenate([[0.0], np.cumsum(np.sqrt(length2))])
    s_q = float(s[i] + t[i] * math.sqrt(float(length2[i])))
    ahead = float(np.interp(s_q + abs(speed) * config.feedforward_preview, s, curvature))
    return ahead - 2.0 * math.sin(alpha0) / chord
