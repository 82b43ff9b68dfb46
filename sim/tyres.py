"""Tyre model: slip angles, a simplified Pacejka magic formula, the friction ellipse.

Why hand-written: no well-kept Python tyre library fits a pymunk car. The
Python Magic Formula packages implement the full MF 5.2/6.x tyre (dozens of
coefficients from a ``.tir`` file, per-wheel slip ratios, camber) and none
exposes the four-coefficient axle curve that the published FS simulators
(fssim, EUFS) are parametrised with. The four formulas below are all we need.

The car model runs them at every physics step, inside one compiled pass of
``sim.vehicle_dynamics``; so each is a numba kernel on floats (``_slip_angles``
and so on), and the functions of this module call them. No ``fastmath``: the
kernels' numbers are Python's, bit for bit (``math``'s functions are the C
library's in both; ``kernel_math.py_min``/``py_max`` are Python's ``min``/``max``).

Slip angles (single track, body frame x forward / y left, CG at the origin)::

    front axle velocity in the wheel frame (steered by delta):
        u_f =  vx * cos(delta) + (vy + lf * r) * sin(delta)
        w_f = -vx * sin(delta) + (vy + lf * r) * cos(delta)
    rear axle velocity (not steered):
        u_r = vx,   w_r = vy - lr * r
    alpha = -atan(w / max(|u|, U_MIN))

    For u > 0 this is the textbook alpha_f = delta - atan((vy + lf r) / vx),
    alpha_r = -atan((vy - lr r) / vx). Using |u| keeps the force opposing the
    lateral sliding when the car rolls backwards.

Pacejka magic formula, pure lateral slip, per axle::

    Fy0 = mu * D * Fz * sin(C * atan(B*alpha - E * (B*alpha - atan(B*alpha))))

Sign convention: a POSITIVE slip angle (the wheel points left of its velocity)
gives a POSITIVE (leftward) force, so C is positive. fssim's ``car.yaml``
writes C = -1.38 because it defines the slip angle with the opposite sign
(``alpha = atan(v_y / v_x) - delta``); the two conventions give the same
force. With B, C, D, E = 12.56, 1.38, 1.60, -0.58 the curve rises with slope
B*C*D = 27.7 /rad (times mu*Fz), peaks at mu*D*Fz at alpha = 0.140 rad (8.0 deg)
and falls to mu*D*Fz*sin(C*pi/2) = 0.83 mu*D*Fz at large slip.

Cornering stiffness (slope at alpha = 0; the E term has zero slope there)::

    C_alpha = dFy0/dalpha |_0 = B * C * D * mu * Fz      [N/rad]

Friction ellipse, per axle, with the peak friction coefficient mu_peak = mu*D::

    (Fx / (mu_peak Fz))^2 + (Fy / (mu_peak Fz))^2 <= 1
    Fx = clip(Fx_demand, -mu_peak Fz, mu_peak Fz)          (longitudinal first)
    Fy = Fy0 * sqrt(1 - (Fx / (mu_peak Fz))^2)             (lateral scaled)

Because |Fy0| <= mu_peak Fz, the scaled pair always lies on or inside the
ellipse, and the curve keeps its shape (no kink from clipping Fy).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from conesim.core.compiled import cached_njit
from conesim.sim.kernel_math import py_max, py_min

#: Smallest longitudinal wheel speed used in the slip angle [m/s]; keeps
#: atan(w/u) finite when the car slides exactly sideways.
U_MIN = 0.1


@dataclass(frozen=True, slots=True)
class PacejkaParams:
    """Four-coefficient magic formula of one axle (pure lateral slip).

    Defaults: fssim ``car.yaml`` (AMZ gotthard) B/C/D/E = 12.56 / -1.38 /
    1.60 / -0.58 (REFERENCES.md "Vehicle"), with C made positive for this
    module's slip sign (see the module docstring).

    Attributes:
        B: stiffness factor [1/rad].
        C: shape factor [-]; in (0, 2) so that the curve has a peak.
        D: peak friction coefficient on the reference surface [-].
        E: curvature factor [-]; <= 1 keeps the curve monotonic up to its peak.
    """

    B: float = 12.56  # [1/rad] fssim car.yaml
    C: float = 1.38  # [-] fssim car.yaml C = -1.38 with its opposite slip sign
    D: float = 1.60  # [-] fssim car.yaml
    E: float = -0.58  # [-] fssim car.yaml

    def __post_init__(self) -> None:
        checks = (
            ("B", self.B, 0.0 < self.B < math.inf, "> 0 [1/rad]"),
            (
                "C",
                self.C,
                0.0 < self.C < 2.0,
                "in (0, 2) [-] (fssim's C = -1.38 is 1.38 with this module's slip sign)",
            ),
            ("D", self.D, 0.0 < self.D < math.inf, "> 0 [-]"),
            ("E", self.E, -math.inf < self.E <= 1.0, "<= 1 [-]"),
        )
        for name, value, ok, allowed in checks:
            if not ok:
                raise ValueError(f"PacejkaParams.{name} must be {allowed}, got {value!r}")

    @property
    def stiffness_per_load(self) -> float:
        """Cornering stiffness per unit load and unit mu, B*C*D [1/rad]."""
        return self.B * self.C * self.D


def _probe() -> None:
    """Nothing: what ``cached_njit`` asks numba to cache, from this file's directory."""


_compiled = cached_njit(_probe, "conesim.sim.tyres")


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
    alpha_f, alpha_r = _slip_angles(vx, vy, yaw_rate, steer, lf, lr)
    return alpha_f, alpha_r


@_compiled
def _slip_angles(vx, vy, yaw_rate, steer, lf, lr):  # noqa: PLR0917
    """:func:`slip_angles`, compiled."""
    c, s = math.cos(steer), math.sin(steer)
    vy_f = vy + lf * yaw_rate
    u_f = vx * c + vy_f * s
    w_f = -vx * s + vy_f * c
    alpha_f = -math.atan(w_f / py_max(abs(u_f), U_MIN))
    alpha_r = -math.atan((vy - lr * yaw_rate) / py_max(abs(vx), U_MIN))
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
    return float(_lateral_force(alpha, fz, tyre.B, tyre.C, tyre.D, tyre.E, mu))


@_compiled
def _lateral_force(alpha, fz, b, c, d, e, mu):  # noqa: PLR0917
    """:func:`lateral_force` with the tyre's B, C, D, E, compiled."""
    b_alpha = b * alpha
    phi = b_alpha - e * (b_alpha - math.atan(b_alpha))
    return mu * d * fz * math.sin(c * math.atan(phi))


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
    fx_out, fy_out = _friction_ellipse(fx, fy0, fz, mu_peak)
    return fx_out, fy_out


@_compiled
def _friction_ellipse(fx, fy0, fz, mu_peak):
    """:func:`friction_ellipse`, compiled."""
    f_max = mu_peak * fz
    if f_max <= 0.0:
        return 0.0, 0.0
    fx = py_min(py_max(fx, -f_max), f_max)
    ratio = fx / f_max
    return fx, fy0 * math.sqrt(py_max(0.0, 1.0 - ratio * ratio))
