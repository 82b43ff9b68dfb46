"""Single-track (bicycle) force model, blended with the kinematic model at low speed.

Pure functions of the body-frame state: no pymunk here, so the model can be
read and tested on its own. ``sim.vehicle`` applies the resulting force and
moment to a pymunk body, which integrates them (integrator apart from model,
like f1tenth_gym's ``integrator.py`` beside its models). Tyre formulas live
in ``sim.tyres``. Hand-written because the Python vehicle models that exist
(CommonRoad's ``vehicle_dynamics_st``, f1tenth_gym's) return state
derivatives for their own integrators; a pymunk body needs forces, and the
low-speed blend and the braking-at-rest rule must be expressed as forces too.

State (body frame at the CG, x forward, y left): vx, vy [m/s], r [rad/s];
input: front wheel angle delta [rad], acceleration demand a_cmd [m/s^2].

Normal loads per axle (static + longitudinal load transfer + downforce)::

    Fz_f = m g lr / L - m ax h / L + 0.5 rho ClA vx^2 * balance_f
    Fz_r = m g lf / L + m ax h / L + 0.5 rho ClA vx^2 * (1 - balance_f)

    ax is the body-frame longitudinal acceleration of the previous step (a
    one-step lag breaks the algebraic loop, like the chassis' pitch lag).

Longitudinal demand (an ideal low-level controller turns the acceleration
demand into wheel force, so that a_cmd is what the car does on a straight)::

    F = m a_cmd + F_drag(vx) + F_roll        (feed-forward of the resistances)
    F >= 0: drive = min(F, F_drive_max, P_max / vx), split drive_front_share
    F <  0: brake = -F, split brake_front_share
    each axle: |Fx| <= mu_peak Fz (the longitudinal extreme of the ellipse)

Brakes, rolling resistance and drag are Coulomb-like: they oppose motion and
never reverse it. Within one step of dt, with the drive force Fd::

    v_free = vx + Fd dt / m
    |v_free| <= F_diss dt / m  ->  stick: the dissipative forces stop the car
                                   exactly (vx_next = 0), a braked car holds
    otherwise                  ->  slide: F_diss acts against sign(v_free)

Dynamic single-track model (Rajamani ch. 2; fssim ``vehicle.cpp``)::

    alpha_f, alpha_r from sim.tyres.slip_angles
    Fy_i = friction_ellipse(Fx_i, Pacejka(alpha_i, Fz_i))
    Fx_body = Fx_f cos(delta) - Fy_f sin(delta) + Fx_r - F_drag - F_roll
    Fy_body = Fx_f sin(delta) + Fy_f cos(delta) + Fy_r
    Mz      = lf (Fx_f sin(delta) + Fy_f cos(delta)) - lr Fy_r

Kinematic single-track model (PythonRobotics / Rajamani 2.2), CG reference::

    vx_next = vx + dt (Fx_f + Fx_r - F_drag - F_roll) / m
    vy_kin  = vx_next lr tan(delta) / L
    r_kin   = vx_next tan(delta) / L

    It is imposed as a velocity target reached in one step: the force and
    moment that take (vx, vy, r) to (vx_next, vy_kin, r_kin) over dt,
        F = m (R(dpsi) [vx_next, vy_kin] - [vx, vy]) / dt,
        M = I (r_kin - r) / dt,
    with dpsi the heading change of the step (the target is expressed in the
    body frame at the END of the step), capped by the friction of both axles.

Blend (fssim ``f_kin_correction``; linear in speed v = hypot(vx, vy))::

    w = clip((v - v_low) / (v_high - v_low), 0, 1)
    F = w F_dyn + (1 - w) F_kin,   M = w M_dyn + (1 - w) M_kin

Why the blend: the dynamic model's lateral dynamics have eigenvalues near
-(C_f + C_r) / (m vx) that grow without bound as vx -> 0 (stiff, and the slip
angles are undefined at rest); the kinematic model is exact at low speed
where the tyres do not slip. At 200 Hz and v_low = 1.5 m/s, dt (C_f + C_r) /
(m v_low) = 0.9, inside explicit Euler's stability limit of 2.
"""

from __future__ import annotations

import math
from typing import NamedTuple

from conesim.sim.tyres import friction_ellipse, lateral_force, slip_angles
from conesim.sim.vehicle_params import VehicleParams

#: Speed floor for the power limit P / v [m/s].
_POWER_SPEED_FLOOR = 0.1


class AxleLoads(NamedTuple):
    """Normal loads on the two axles [N]."""

    front: float
    rear: float


class LongitudinalForces(NamedTuple):
    """Longitudinal forces after the friction and stick/slip limits [N].

    Attributes:
        front: along the steered front wheel [N].
        rear: along body x at the rear axle [N].
        resistance: drag plus rolling resistance, along body x at the CG [N].
    """

    front: float
    rear: float
    resistance: float


class BodyVelocity(NamedTuple):
    """Velocity of the CG in the body frame and the yaw rate."""

    vx: float  # [m/s] forward
    vy: float  # [m/s] left
    yaw_rate: float  # [rad/s] counter-clockwise


class Wrench(NamedTuple):
    """Resultant force at the CG (body frame) and moment about the CG."""

    fx: float  # [N]
    fy: float  # [N]
    mz: float  # [N m]


def axle_loads(p: VehicleParams, vx: float, ax: float) -> AxleLoads:
    """Static loads plus longitudinal load transfer and downforce.

    Args:
        p: vehicle parameters.
        vx: longitudinal speed [m/s] (for the downforce).
        ax: body-frame longitudinal acceleration [m/s^2] (for the transfer).

    Returns:
        Front and rear normal loads [N], each >= 0.
    """
    down = 0.5 * p.air_density * p.lift_area * vx * vx
    transfer = p.mass * ax * p.cg_height / p.wheelbase
    weight = p.mass * p.gravity
    front = weight * p.cg_to_rear / p.wheelbase + down * p.aero_balance_front - transfer
    rear = weight * p.cg_to_front / p.wheelbase + down * (1.0 - p.aero_balance_front) + transfer
    return AxleLoads(max(front, 0.0), max(rear, 0.0))


def resistance_magnitude(p: VehicleParams, vx: float, loads: AxleLoads) -> float:
    """Drag plus rolling resistance magnitude, 0.5 rho CdA vx^2 + Crr Fz [N]."""
    drag = 0.5 * p.air_density * p.drag_area * vx * vx
    return drag + p.rolling_resistance * (loads.front + loads.rear)


def drive_brake_demand(
    p: VehicleParams, accel_cmd: float, vx: float, loads: AxleLoads
) -> tuple[float, float]:
    """Map an acceleration demand to total drive and brake forces.

    The resistances are fed forward while the car rolls forward (vx > 0), so
    the demand is the acceleration the car achieves on a straight. At rest no
    rolling resistance is fed forward: a zero or negative demand never drives.

    Args:
        p: vehicle parameters.
        accel_cmd: acceleration demand [m/s^2], already clipped to the limits.
        vx: longitudinal speed [m/s].
        loads: normal loads [N].

    Returns:
        (drive, brake) totals [N], both >= 0, at most one of them non-zero.
    """
    v_fwd = max(vx, 0.0)
    feed_forward = resistance_magnitude(p, v_fwd, loads) if vx > 0.0 else 0.0
    demand = p.mass * accel_cmd + feed_forward
    if demand >= 0.0:
        power_limit = p.max_power / max(v_fwd, _POWER_SPEED_FLOOR)
        return min(demand, p.max_drive_force, power_limit), 0.0
    return 0.0, -demand


def longitudinal_forces(
    p: VehicleParams, accel_cmd: float, vx: float, loads: AxleLoads, dt: float
) -> LongitudinalForces:
    """Axle drive/brake forces and resistances, friction-limited, stick/slip resolved.

    Args:
        p: vehicle parameters.
        accel_cmd: acceleration demand [m/s^2], already clipped to the limits.
        vx: longitudinal speed [m/s].
        loads: normal loads [N].
        dt: step [s].

    Returns:
        The longitudinal forces [N].
    """
    drive, brake = drive_brake_demand(p, accel_cmd, vx, loads)
    lim_f = p.mu_front * loads.front
    lim_r = p.mu_rear * loads.rear
    drive_f = min(drive * p.drive_front_share, lim_f)
    drive_r = min(drive * (1.0 - p.drive_front_share), lim_r)
    brake_f = min(brake * p.brake_front_share, lim_f)
    brake_r = min(brake * (1.0 - p.brake_front_share), lim_r)
    resist = resistance_magnitude(p, vx, loads)

    dissipative = brake_f + brake_r + resist
    v_free = vx + (drive_f + drive_r) * dt / p.mass
    if abs(v_free) * p.mass <= dissipative * dt:
        # Stick: scale the dissipative forces so that vx_next = 0 exactly.
        scale = p.mass * v_free / (dissipative * dt) if dissipative > 0.0 else 0.0
    else:
        scale = 1.0 if v_free > 0.0 else -1.0
    return LongitudinalForces(drive_f - scale * brake_f, drive_r - scale * brake_r, -scale * resist)


def dynamic_wrench(
    p: VehicleParams, vel: BodyVelocity, steer: float, loads: AxleLoads, lon: LongitudinalForces
) -> Wrench:
    """Force and moment of the dynamic single-track model with Pacejka tyres.

    Args:
        p: vehicle parameters.
        vel: body-frame velocity and yaw rate.
        steer: front wheel angle [rad].
        loads: normal loads [N].
        lon: longitudinal forces [N].

    Returns:
        Resultant at the CG in the body frame, and the yaw moment.
    """
    lf, lr = p.cg_to_front, p.cg_to_rear
    alpha_f, alpha_r = slip_angles(vel.vx, vel.vy, vel.yaw_rate, steer, lf=lf, lr=lr)
    fy0_f = lateral_force(alpha_f, loads.front, p.tyre_front, p.mu)
    fy0_r = lateral_force(alpha_r, loads.rear, p.tyre_rear, p.mu)
    fx_f, fy_f = friction_ellipse(lon.front, fy0_f, loads.front, p.mu_front)
    fx_r, fy_r = friction_ellipse(lon.rear, fy0_r, loads.rear, p.mu_rear)
    c, s = math.cos(steer), math.sin(steer)
    front_lat = fx_f * s + fy_f * c
    return Wrench(
        fx=fx_f * c - fy_f * s + fx_r + lon.resistance,
        fy=front_lat + fy_r,
        mz=lf * front_lat - lr * fy_r,
    )


def kinematic_wrench(
    p: VehicleParams,
    vel: BodyVelocity,
    steer: float,
    loads: AxleLoads,
    lon: LongitudinalForces,
    *,
    dt: float,
    heading_change: float,
) -> Wrench:
    """Force and moment that bring the body onto the kinematic model in one step.

    Args:
        p: vehicle parameters.
        vel: body-frame velocity and yaw rate.
        steer: front wheel angle [rad].
        loads: normal loads [N] (for the friction cap).
        lon: longitudinal forces [N].
        dt: step [s].
        heading_change: heading change of the body during this step [rad]
            (pymunk integrates the angle with the current yaw rate first).

    Returns:
        Resultant at the CG in the body frame (start of the step), and the moment.
    """
    vx, vy, yaw_rate = vel
    vx_next = vx + dt * (lon.front + lon.rear + lon.resistance) / p.mass
    tan_d = math.tan(steer)
    vy_kin = vx_next * p.cg_to_rear * tan_d / p.wheelbase
    r_kin = vx_next * tan_d / p.wheelbase
    c, s = math.cos(heading_change), math.sin(heading_change)
    fx = p.mass * (c * vx_next - s * vy_kin - vx) / dt
    fy = p.mass * (s * vx_next + c * vy_kin - vy) / dt
    mz = p.yaw_inertia * (r_kin - yaw_rate) / dt
    # Friction cap: the tyres cannot hold the car on the kinematic path
    # against more than their combined grip (matters only in collisions).
    f_max = p.mu_front * loads.front + p.mu_rear * loads.rear
    f_norm = math.hypot(fx, fy)
    if f_norm > f_max:
        fx, fy = fx * f_max / f_norm, fy * f_max / f_norm
    m_max = p.mu_front * loads.front * p.cg_to_front + p.mu_rear * loads.rear * p.cg_to_rear
    mz = min(max(mz, -m_max), m_max)
    return Wrench(fx, fy, mz)


def blend_weight(p: VehicleParams, speed: float) -> float:
    """Weight of the dynamic model, 0 below blend_speed_low, 1 above blend_speed_high."""
    w = (speed - p.blend_speed_low) / (p.blend_speed_high - p.blend_speed_low)
    return min(max(w, 0.0), 1.0)


def blended_wrench(
    p: VehicleParams,
    vel: BodyVelocity,
    steer: float,
    accel_cmd: float,
    *,
    ax_prev: float,
    dt: float,
    heading_change: float,
) -> Wrench:
    """The force and moment to apply to the body for one step.

    The dynamic model's wrench, the kinematic one's (``kinematic_wrench``,
    whose arguments ``p``, ``vel``, ``steer``, ``dt`` and ``heading_change``
    these are), or a blend by speed (``blend_weight``).

    Args:
        accel_cmd: acceleration demand [m/s^2], already clipped to the limits.
        ax_prev: body-frame longitudinal acceleration of the previous step [m/s^2]
            (for the axle loads).

    Returns:
        Resultant at the CG in the body frame, and the yaw moment.
    """
    loads = axle_loads(p, vel.vx, ax_prev)
    lon = longitudinal_forces(p, accel_cmd, vel.vx, loads, dt)
    w = blend_weight(p, math.hypot(vel.vx, vel.vy))
    if w >= 1.0:
        return dynamic_wrench(p, vel, steer, loads, lon)
    kin = kinematic_wrench(p, vel, steer, loads, lon, dt=dt, heading_change=heading_change)
    if w <= 0.0:
        return kin
    dyn = dynamic_wrench(p, vel, steer, loads, lon)
    return Wrench(
        w * dyn.fx + (1.0 - w) * kin.fx,
        w * dyn.fy + (1.0 - w) * kin.fy,
        w * dyn.mz + (1.0 - w) * kin.mz,
    )
