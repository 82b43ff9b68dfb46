"""The car's g-g limits, per axle, from the physics' own model (``sim.vehicle_dynamics``).

What the quasi-steady-state lap (``envs.limit_lap``) may ask of the car: the
largest cornering speed, and the largest drive and brake acceleration while
cornering. Each axle i (front f, rear r) has the friction ellipse of
``sim.tyres.friction_ellipse``, ``Fx_i^2 + Fy_i^2 <= (mu D Fz_i)^2``, on the
loads of ``sim.vehicle_dynamics.axle_loads``::

    Fz_f = m g lr / L - m ax h / L + D(v) balance_f
    Fz_r = m g lf / L + m ax h / L + D(v) (1 - balance_f),   D(v) = 0.5 rho ClA v^2

In a steady turn of lateral acceleration ay = v^2 |kappa| the axles share
the lateral force by the yaw moment balance, ``Fy_f = m ay lr / L``,
``Fy_r = m ay lf / L``. The longitudinal force is the car's own: the
acceleration demand plus the resistances fed forward (``drive_brake_demand``),
``m ax + R(v)``, split ``drive_front_share`` when driving and
``brake_front_share`` when braking. For a demand x >= 0 (drive: ax = x,
brake: ax = -x) each axle's ellipse is then a quadratic inequality::

    c^2 (m x + rho)^2 + Fy^2 - mu^2 (Z0 + sigma u x)^2 <= 0
    u = m h / L;  drive: rho = +R, sigma = -1 front / +1 rear;
                  brake: rho = -R, sigma = +1 front / -1 rear

whose largest root below the actuator's limit is the axle's limit. Under
braking the rear axle unloads and still brakes with 40 % of the force, so
it runs out of grip first when braking into a corner: the whole-car ellipse
(``ax^2 + ay^2 <= (mu D g')^2``) would promise more than the car has.

Cornering speed: each axle's lateral limit with ax = 0, ``(m l_o / L) v^2
|kappa| <= mu D (Z0 + d v^2)`` (l_o the other axle's distance from the CG,
Z0 the static load, d the axle's downforce per speed squared), solved for
v; the smaller speed of the two axles. With the defaults (lf = lr, the
downforce split like the weight) both axles give ``v^2 |kappa| = mu D (g +
0.5 rho ClA v^2 / m)``.

Hand-written: it is the physics' own model turned round, a few lines per
axle; no lap-time package takes this car's brake split and load transfer.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from conesim.sim.vehicle_params import VehicleParams

FloatArray = NDArray[np.float64]
# (static load [N], downforce per v^2 [N s^2/m^2], lateral force per ay [kg], peak
# friction [-], share of the longitudinal force [-], load transfer sign [-])
_Axle = tuple[float, float, float, float, float, float]


class AxleLimits:
    """The per-axle limits of one car (module docstring).

    Args:
        p: the car.
    """

    def __init__(self, p: VehicleParams) -> None:
        self.p = p
        m, length = p.mass, p.wheelbase
        self.u = m * p.cg_height / length
        down = 0.5 * p.air_density * p.lift_area
        # (static load, downforce per v^2, lateral force per ay, peak friction) per axle
        self.front = (
            m * p.gravity * p.cg_to_rear / length,
            down * p.aero_balance_front,
            m * p.cg_to_rear / length,
            p.mu_front,
        )
        self.rear = (
            m * p.gravity * p.cg_to_front / length,
            down * (1.0 - p.aero_balance_front),
            m * p.cg_to_front / length,
            p.mu_rear,
        )
        self.k_drag = 0.5 * p.air_density * p.drag_area
        self.down = down
        # with (share of the longitudinal force, sign of the load transfer per demand)
        f, r = self.front, self.rear
        drive, brake = p.drive_front_share, p.brake_front_share
        self._drive = ((*f, drive, -1.0), (*r, 1.0 - drive, 1.0))
        self._brake = ((*f, brake, 1.0), (*r, 1.0 - brake, -1.0))

    def corner_speed(self, kappa: FloatArray, v_top: float) -> FloatArray:
        """The largest steady speed (n,) [m/s] on curvatures ``kappa`` (n,) [1/m], at
        most ``v_top``: ``m v^2 |kappa| l_other / L <= mu D (Z0 + down v^2)`` per axle."""
        k = np.abs(np.asarray(kappa, dtype=float))
        v = np.full(len(k), float(v_top))
        for z0, down, lat, mu in (self.front, self.rear):
            # lat v^2 k <= mu (z0 + down v^2)  <=>  v^2 (lat k - mu down) <= mu z0
            denom = lat * k - mu * down
            with np.errstate(divide="ignore"):
                axle = np.where(denom > 0, np.sqrt(mu * z0 / np.maximum(denom, 1e-300)), np.inf)
            v = np.minimum(v, axle)
        return v

    def resistance(self, v: float) -> float:
        """Drag plus rolling resistance on the static and aerodynamic load [N]."""
        p = self.p
        v2 = v * v
        return self.k_drag * v2 + p.rolling_resistance * (p.mass * p.gravity + self.down * v2)

    def drive(self, v: float, kappa: float) -> float:
        """The largest forward acceleration [m/s^2] at speed ``v`` on ``kappa``: the
        demand limit, the motor's force and power less the resistances, each axle."""
        p = self.p
        resist = self.resistance(v)
        motor = (min(p.max_drive_force, p.max_power / max(v, 0.1)) - resist) / p.mass
        limit = min(p.max_accel, motor)
        if limit <= 0.0:
            return limit
        return self._axles(self._drive, resist, v, abs(kappa), limit)

    def brake(self, v: float, kappa: float) -> float:
        """The largest deceleration [m/s^2] (positive) at speed ``v`` on ``kappa``."""
        return self._axles(self._brake, -self.resistance(v), v, abs(kappa), self.p.max_decel)

    def _axles(
        self, axles: tuple[_Axle, _Axle], rho: float, v: float, kappa: float, x_max: float
    ) -> float:
        """The largest demand x in [0, x_max] inside both axles' ellipses (module
        docstring): per axle, ``x_max`` where it fits, else the largest root of the
        quadratic below it, else 0."""
        m, u, v2 = self.p.mass, self.u, v * v
        ay = v2 * kappa
        for z0, down, lat, mu, share, sigma in axles:
            z = z0 + down * v2
            fy = lat * ay
            fx = share * (m * x_max + rho)
            fz = max(z + sigma * u * x_max, 0.0)
            if fx * fx + fy * fy <= mu * mu * fz * fz:
                continue
            a = share * share * m * m - mu * mu * u * u
            b = 2.0 * share * share * m * rho - 2.0 * mu * mu * sigma * z * u
            c = share * share * rho * rho + fy * fy - mu * mu * z * z
            if abs(a) < 1e-12:
                roots = [-c / b] if abs(b) > 1e-12 else []
            else:
                disc = b * b - 4.0 * a * c
                if disc < 0.0:
                    return 0.0
                sq = math.sqrt(disc)
                roots = [(-b - sq) / (2.0 * a), (-b + sq) / (2.0 * a)]
            below = [r for r in roots if 0.0 <= r < x_max]
            if not below:
                return 0.0
            x_max = max(below)
        return x_max
