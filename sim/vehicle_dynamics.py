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

Compiled: the car calls :func:`wrench` at every physics step, so each formula
is a numba kernel on floats (``_axle_loads`` and so on, the tyres'
from ``sim.tyres``), the parameters packed once into an array
(:func:`packed`), and the functions of this module call them. No
``fastmath``, ``math``'s C functions, Python's ``min``/``max``
(``sim.kernel_math``): the numbers are Python's bit for bit. The
one step left to Python is ``math.hypot`` (the blend's speed, the kinematic
force's friction cap), whose CPython algorithm numba's differs from in the
last bit.
"""

from __future__ import annotations

import functools
import math
from typing import Final, NamedTuple

import numpy as np
from numpy.typing import NDArray

from conesim.core.compiled import cached_njit
from conesim.sim.kernel_math import py_max, py_min
from conesim.sim.tyres import _friction_ellipse, _lateral_force, _slip_angles
from conesim.sim.vehicle_params import VehicleParams

#: Speed floor for the power limit P / v [m/s].
_POWER_SPEED_FLOOR = 0.1

# Layout of ``packed``'s array: the parameters the kernels read, by index.
(MASS, YAW_INERTIA, WHEELBASE, LF, LR, CG_HEIGHT, GRAVITY, AIR_DENSITY, DRAG_AREA,
 LIFT_AREA, AERO_FRONT, ROLLING, MAX_DRIVE, MAX_POWER, DRIVE_FRONT, BRAKE_FRONT,
 MU, MU_FRONT, MU_REAR, BLEND_LOW, BLEND_HIGH, FRONT_B, FRONT_C, FRONT_D, FRONT_E,
 REAR_B, REAR_C, REAR_D, REAR_E) = range(29)  # fmt: skip
N_PARAMS: Final = 29


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


@functools.lru_cache(maxsize=64)
def packed(p: VehicleParams) -> NDArray[np.float64]:
    """The parameters the kernels read, as floats in the layout ``MASS`` ... ``REAR_E``
    (derived ones, such as ``cg_to_rear``, as the properties give them); read-only."""
    values = {
        MASS: p.mass, YAW_INERTIA: p.yaw_inertia, WHEELBASE: p.wheelbase, LF: p.cg_to_front,
        LR: p.cg_to_rear, CG_HEIGHT: p.cg_height, GRAVITY: p.gravity,
        AIR_DENSITY: p.air_density, DRAG_AREA: p.drag_area, LIFT_AREA: p.lift_area,
        AERO_FRONT: p.aero_balance_front, ROLLING: p.rolling_resistance,
        MAX_DRIVE: p.max_drive_force, MAX_POWER: p.max_power,
        DRIVE_FRONT: p.drive_front_share, BRAKE_FRONT: p.brake_front_share, MU: p.mu,
        MU_FRONT: p.mu_front, MU_REAR: p.mu_rear, BLEND_LOW: p.blend_speed_low,
        BLEND_HIGH: p.blend_speed_high, FRONT_B: p.tyre_front.B, FRONT_C: p.tyre_front.C,
        FRONT_D: p.tyre_front.D, FRONT_E: p.tyre_front.E, REAR_B: p.tyre_rear.B,
        REAR_C: p.tyre_rear.C, REAR_D: p.tyre_rear.D, REAR_E: p.tyre_rear.E,
    }  # fmt: skip
    out = np.array([float(values[i]) for i in range(N_PARAMS)])
    out.setflags(write=False)
    return out


def _floats(values: tuple[float, ...]) -> tuple[float, ...]:
    """The numbers as Python floats: the kernels compile once, for floats."""
    return tuple(float(v) for v in values)


def _probe() -> None:
    """Nothing: what ``cached_njit`` asks numba to cache, from this file's directory."""


_compiled = cached_njit(_probe, "conesim.sim.vehicle_dynamics")


def axle_loads(p: VehicleParams, vx: float, ax: float) -> AxleLoads:
    """Static loads plus longitudinal load transfer and downforce.

    Args:
        p: vehicle parameters.
        vx: longitudinal speed [m/s] (for the downforce).
        ax: body-frame longitudinal acceleration [m/s^2] (for the transfer).

    Returns:
        Front and rear normal loads [N], each >= 0.
    """
    return AxleLoads(*_axle_loads(packed(p), float(vx), float(ax)))


@_compiled
def _axle_loads(q, vx, ax):
    """:func:`axle_loads` on the packed parameters ``q``, compiled."""
    down = 0.5 * q[AIR_DENSITY] * q[LIFT_AREA] * vx * vx
    transfer = q[MASS] * ax * q[CG_HEIGHT] / q[WHEELBASE]
    weight = q[MASS] * q[GRAVITY]
    front = weight * q[LR] / q[WHEELBASE] + down * q[AERO_FRONT] - transfer
    rear = weight * q[LF] / q[WHEELBASE] + down * (1.0 - q[AERO_FRONT]) + transfer
    return py_max(front, 0.0), py_max(rear, 0.0)


def resistance_magnitude(p: VehicleParams, vx: float, loads: AxleLoads) -> float:
    """Drag plus rolling resistance magnitude, 0.5 rho CdA vx^2 + Crr Fz [N]."""
    return float(_resistance(packed(p), float(vx), *_floats(loads)))


@_compiled
def _resistance(q, vx, front, rear):
    """:func:`resistance_magnitude` on the packed parameters, compiled."""
    drag = 0.5 * q[AIR_DENSITY] * q[DRAG_AREA] * vx * vx
    return drag + q[ROLLING] * (front + rear)


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
    drive, brake = _drive_brake(packed(p), float(accel_cmd), float(vx), *_floats(loads))
    return drive, brake


@_compiled
def _drive_brake(q, accel_cmd, vx, front, rear):
    """:func:`drive_brake_demand` on the packed parameters, compiled."""
    v_fwd = py_max(vx, 0.0)
    feed_forward = _resistance(q, v_fwd, front, rear) if vx > 0.0 else 0.0
    demand = q[MASS] * accel_cmd + feed_forward
    if demand >= 0.0:
        power_limit = q[MAX_POWER] / py_max(v_fwd, _POWER_SPEED_FLOOR)
        return py_min(py_min(demand, q[MAX_DRIVE]), power_limit), 0.0
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
    return LongitudinalForces(
        *_longitudinal(packed(p), float(accel_cmd), float(vx), *_floats(loads), float(dt))
    )


@_compiled
def _longitudinal(q, accel_cmd, vx, front, rear, dt):  # noqa: PLR0917
    """:func:`longitudinal_forces` on the packed parameters, compiled."""
    drive, brake = _drive_brake(q, accel_cmd, vx, front, rear)
    lim_f = q[MU_FRONT] * front
    lim_r = q[MU_REAR] * rear
    drive_f = py_min(drive * q[DRIVE_FRONT], lim_f)
    drive_r = py_min(drive * (1.0 - q[DRIVE_FRONT]), lim_r)
    brake_f = py_min(brake * q[BRAKE_FRONT], lim_f)
    brake_r = py_min(brake * (1.0 - q[BRAKE_FRONT]), lim_r)
    resist = _resistance(q, vx, front, rear)

    dissipative = brake_f + brake_r + resist
    v_free = vx + (drive_f + drive_r) * dt / q[MASS]
    if abs(v_free) * q[MASS] <= dissipative * dt:
        # Stick: scale the dissipative forces so that vx_next = 0 exactly.
        scale = q[MASS] * v_free / (dissipative * dt) if dissipative > 0.0 else 0.0
    else:
        scale = 1.0 if v_free > 0.0 else -1.0
    return drive_f - scale * brake_f, drive_r - scale * brake_r, -scale * resist


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
    return Wrench(*_dynamic(packed(p), *_floats(vel), float(steer), *_floats(loads), *_floats(lon)))


@_compiled
def _dynamic(q, vx, vy, yaw_rate, steer, front, rear, lon_f, lon_r, resistance):  # noqa: PLR0917
    """:func:`dynamic_wrench` on the packed parameters, compiled."""
    lf, lr = q[LF], q[LR]
    alpha_f, alpha_r = _slip_angles(vx, vy, yaw_rate, steer, lf, lr)
    fy0_f = _lateral_force(alpha_f, front, q[FRONT_B], q[FRONT_C], q[FRONT_D], q[FRONT_E], q[MU])
    fy0_r = _lateral_force(alpha_r, rear, q[REAR_B], q[REAR_C], q[REAR_D], q[REAR_E], q[MU])
    fx_f, fy_f = _friction_ellipse(lon_f, fy0_f, front, q[MU_FRONT])
    fx_r, fy_r = _friction_ellipse(lon_r, fy0_r, rear, q[MU_REAR])
    c, s = math.cos(steer), math.sin(steer)
    front_lat = fx_f * s + fy_f * c
    return fx_f * c - fy_f * s + fx_r + resistance, front_lat + fy_r, lf * front_lat - lr * fy_r


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
    fx, fy, mz, f_max = _kinematic(
        packed(p), *_floats(vel), float(steer), *_floats(loads), *_floats(lon), float(dt),
        float(heading_change),
    )  # fmt: skip
    fx, fy = _friction_capped(fx, fy, f_max)
    return Wrench(fx, fy, mz)


@_compiled
def _kinematic(  # noqa: PLR0917
    q, vx, vy, yaw_rate, steer, front, rear, lon_f, lon_r, resistance, dt, heading_change
):
    """:func:`kinematic_wrench` on the packed parameters, compiled, up to the force's
    friction cap: (fx, fy, mz, the cap f_max) (``_friction_capped`` applies it)."""
    vx_next = vx + dt * (lon_f + lon_r + resistance) / q[MASS]
    tan_d = math.tan(steer)
    vy_kin = vx_next * q[LR] * tan_d / q[WHEELBASE]
    r_kin = vx_next * tan_d / q[WHEELBASE]
    c, s = math.cos(heading_change), math.sin(heading_change)
    fx = q[MASS] * (c * vx_next - s * vy_kin - vx) / dt
    fy = q[MASS] * (s * vx_next + c * vy_kin - vy) / dt
    mz = q[YAW_INERTIA] * (r_kin - yaw_rate) / dt
    # Friction cap: the tyres cannot hold the car on the kinematic path
    # against more than their combined grip (matters only in collisions).
    f_max = q[MU_FRONT] * front + q[MU_REAR] * rear
    m_max = q[MU_FRONT] * front * q[LF] + q[MU_REAR] * rear * q[LR]
    mz = py_min(py_max(mz, -m_max), m_max)
    return fx, fy, mz, f_max


def _friction_capped(fx: float, fy: float, f_max: float) -> tuple[float, float]:
    """The kinematic force (fx, fy) scaled down to ``f_max`` [N] when it is larger
    (in Python: ``math.hypot``'s last bit is CPython's own)."""
    f_norm = math.hypot(fx, fy)
    if f_norm > f_max:
        return fx * f_max / f_norm, fy * f_max / f_norm
    return fx, fy


def blend_weight(p: VehicleParams, speed: float) -> float:
    """Weight of the dynamic model, 0 below blend_speed_low, 1 above blend_speed_high."""
    return float(_blend_weight(packed(p), float(speed)))


@_compiled
def _blend_weight(q, speed):
    """:func:`blend_weight` on the packed parameters, compiled."""
    w = (speed - q[BLEND_LOW]) / (q[BLEND_HIGH] - q[BLEND_LOW])
    return py_min(py_max(w, 0.0), 1.0)


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
    vx, vy, r = _floats(vel)
    return Wrench(
        *wrench(packed(p), vx, vy, r, *_floats((steer, accel_cmd, ax_prev, dt, heading_change)))
    )


def wrench(  # noqa: PLR0917
    q: NDArray[np.float64],
    vx: float,
    vy: float,
    yaw_rate: float,
    steer: float,
    accel_cmd: float,
    ax_prev: float,
    dt: float,
    heading_change: float,
) -> tuple[float, float, float]:
    """:func:`blended_wrench` on plain floats and the packed parameters ``q``
    (``packed``): (fx [N], fy [N], mz [N m]); the car's per-step call."""
    w, dfx, dfy, dmz, kfx, kfy, kmz, f_max = _blended(
        q, vx, vy, yaw_rate, steer, accel_cmd, ax_prev, dt, heading_change, math.hypot(vx, vy)
    )
    if w >= 1.0:
        return dfx, dfy, dmz
    kfx, kfy = _friction_capped(kfx, kfy, f_max)
    if w <= 0.0:
        return kfx, kfy, kmz
    return w * dfx + (1.0 - w) * kfx, w * dfy + (1.0 - w) * kfy, w * dmz + (1.0 - w) * kmz


@_compiled
def _blended(q, vx, vy, yaw_rate, steer, accel_cmd, ax_prev, dt, heading_change, speed):  # noqa: PLR0917
    """The parts of :func:`wrench` (``speed`` = hypot(vx, vy), from Python): the
    blend weight w, the dynamic wrench (w > 0, else zeros), the kinematic one
    before its force's friction cap and that cap (w < 1, else zeros)."""
    front, rear = _axle_loads(q, vx, ax_prev)
    lon_f, lon_r, resistance = _longitudinal(q, accel_cmd, vx, front, rear, dt)
    w = _blend_weight(q, speed)
    dfx = dfy = dmz = kfx = kfy = kmz = f_max = 0.0
    if w > 0.0:
        dfx, dfy, dmz = _dynamic(q, vx, vy, yaw_rate, steer, front, rear, lon_f, lon_r, resistance)
    if w < 1.0:
        kfx, kfy, kmz, f_max = _kinematic(
            q, vx, vy, yaw_rate, steer, front, rear, lon_f, lon_r, resistance, dt, heading_change
        )
    return w, dfx, dfy, dmz, kfx, kfy, kmz, f_max
