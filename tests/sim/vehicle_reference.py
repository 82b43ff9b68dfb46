"""The car model's readable formulation, the reference its compiled kernels are checked against.

The single-track model and the tyre formulas exist once in the package, as the
numba kernels of ``sim.vehicle_dynamics`` and ``sim.tyres`` (their module
docstrings derive them). These are the plain-Python functions they replaced,
kept here so that ``test_vehicle_kernels.py`` keeps comparing the kernels
with them exactly (bit for bit): the same IEEE operations in the same order.
"""

from __future__ import annotations

import math

from conesim.sim.tyres import U_MIN, PacejkaParams
from conesim.sim.vehicle_dynamics import (
    AxleLoads,
    BodyVelocity,
    LongitudinalForces,
    Wrench,
)
from conesim.sim.vehicle_params import VehicleParams

_POWER_SPEED_FLOOR = 0.1  # [m/s], as sim.vehicle_dynamics'


def slip_angles(
    vx: float, vy: float, yaw_rate: float, steer: float, *, lf: float, lr: float
) -> tuple[float, float]:
    """Front and rear axle slip angles of the single-track model.

    Args:
        vx: longitudinal velocity of the CG, body frame [m/s].
        vy: lateral velocity of the CG, body frame [m/s].
        yaw_rate: yaw rate r [rad/s].
        steer: front wheel angle delta [rad].
        lf: CG to front axle [m].
        lr: CG to rear axle [m].

    Returns:
        (alpha_f, alpha_r) [rad]; positive gives a leftward force.
    """
    c, s = math.cos(steer), math.sin(steer)
    vy_f = vy + lf * yaw_rate
    u_f = vx * c + vy_f * s
    w_f = -vx * s + vy_f * c
    alpha_f = -math.atan(w_f / max(abs(u_f), U_MIN))
    alpha_r = -math.atan((vy - lr * yaw_rate) / max(abs(vx), U_MIN))
    return alpha_f, alpha_r


def lateral_force(alpha: float, fz: float, tyre: PacejkaParams, mu: float = 1.0) -> float:
    """Pure-slip lateral force of one axle, magic formula.

    Args:
        alpha: slip angle [rad] (positive: force to the left).
        fz: normal load on the axle [N], >= 0.
        tyre: magic formula coefficients.
        mu: surface friction scale [-] (1 = the tyre's reference surface).

    Returns:
        Lateral force Fy0 [N], |Fy0| <= mu * D * fz.
    """
    b_alpha = tyre.B * alpha
    phi = b_alpha - tyre.E * (b_alpha - math.atan(b_alpha))
    return mu * tyre.D * fz * math.sin(tyre.C * math.atan(phi))


def friction_ellipse(fx: float, fy0: float, fz: float, mu_peak: float) -> tuple[float, float]:
    """Combine a longitudinal demand and a pure-slip lateral force on one axle.

    Args:
        fx: longitudinal force demand [N].
        fy0: pure-slip lateral force [N], |fy0| <= mu_peak * fz.
        fz: normal load [N].
        mu_peak: peak friction coefficient mu * D [-].

    Returns:
        (Fx, Fy) [N] on or inside the ellipse of radius mu_peak * fz.
    """
    f_max = mu_peak * fz
    if f_max <= 0.0:
        return 0.0, 0.0
    fx = min(max(fx, -f_max), f_max)
    ratio = fx / f_max
    return fx, fy0 * math.sqrt(max(0.0, 1.0 - ratio * ratio))


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
