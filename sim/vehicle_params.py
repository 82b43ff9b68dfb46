"""Parameters of the simulated Formula Student driverless car.

One frozen dataclass, a unit and a source on every field. The defaults are one
consistent car: AMZ's gotthard as published in fssim's ``car.yaml`` (mass,
yaw inertia, wheelbase, CG, tyres, aero), with the input ranges, steering rate
and control delay of the EUFS simulator (REFERENCES.md "Vehicle"; EUFS
``eufs_racecar/racecars/qev3/configDry.yaml`` and ``pluginParams.yaml``).
Figures marked "assumed" have no published source and are typical FS values.

Body frame: x forward, y left, origin at the CG (REP 103).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, fields

from conesim.sim.tyres import PacejkaParams


@dataclass(frozen=True, slots=True)
class VehicleParams:
    """Vehicle, tyre, powertrain, steering and footprint parameters.

    Attributes:
        mass: total mass including sensors [kg].
        yaw_inertia: moment of inertia about the vertical axis through the CG [kg m^2].
        wheelbase: front to rear axle L [m].
        cg_to_front: CG to front axle lf [m]; lr = L - lf.
        cg_height: CG height h for longitudinal load transfer [m]; 0 disables it.
        gravity: gravitational acceleration g [m/s^2].
        tyre_front: magic formula of the front axle.
        tyre_rear: magic formula of the rear axle.
        mu: surface friction scale [-]; peak friction coefficient = mu * D.
        air_density: rho [kg/m^3].
        drag_area: Cd * A [m^2]; drag = 0.5 rho CdA vx^2.
        lift_area: Cl * A [m^2]; downforce = 0.5 rho ClA vx^2 (0 for no aero).
        aero_balance_front: share of the downforce on the front axle [-].
        rolling_resistance: coefficient Crr [-]; F = Crr * (total normal load).
        max_accel: largest accepted acceleration demand [m/s^2].
        max_decel: largest accepted braking demand (a positive number) [m/s^2].
        max_drive_force: motor force limit at the wheels, all axles [N].
        max_power: motor power limit at the wheels [W]; sets the top speed.
        drive_front_share: share of the drive force on the front axle [-]; 0 = RWD.
        brake_front_share: share of the brake force on the front axle [-].
        max_steer: front wheel angle limit [rad].
        max_steer_rate: front wheel angle rate limit [rad/s].
        steer_time_constant: first-order lag of the steering actuator [s]; 0 = none.
        blend_speed_low: below this speed the car follows the kinematic model [m/s].
        blend_speed_high: above this speed the car follows the dynamic model [m/s].
        length: footprint length, front wing to rear end [m].
        width: footprint width [m].
        front_overhang: front axle to the front wing tip [m].
        antenna_x: GPS antenna ahead of the CG [m] (negative: behind).
        antenna_y: GPS antenna left of the CG [m].
        contact_friction: pymunk friction of the body shape against cones [-].
        contact_elasticity: pymunk elasticity of the body shape [-].
    """

    # Mass and geometry: fssim car.yaml (AMZ gotthard).
    mass: float = 190.0  # [kg] fssim car.yaml m (REFERENCES.md: 190 kg)
    yaw_inertia: float = 110.0  # [kg m^2] fssim car.yaml I_z (REFERENCES.md)
    wheelbase: float = 1.53  # [m] fssim car.yaml l (REFERENCES.md)
    cg_to_front: float = 0.765  # [m] fssim car.yaml w_front = 0.5: lf = l * (1 - w_front)
    cg_height: float = 0.262  # [m] fssim car.yaml h_cg
    gravity: float = 9.81  # [m/s^2] fssim car.yaml g

    # Tyres: fssim car.yaml B/C/D/E, the same tyre on both axles.
    tyre_front: PacejkaParams = field(default_factory=PacejkaParams)
    tyre_rear: PacejkaParams = field(default_factory=PacejkaParams)
    mu: float = 1.0  # [-] fssim car.yaml tire_coefficient (dry)

    # Aero and rolling resistance.
    air_density: float = 1.225  # [kg/m^3] ISA sea level
    drag_area: float = 1.143  # [m^2] fssim C_drag = 0.7 N s^2/m^2 = 0.5 rho CdA
    lift_area: float = 3.107  # [m^2] fssim C_Down = 1.22*2.6*0.6 = 1.903 = 0.5 rho ClA
    aero_balance_front: float = 0.5  # [-] fssim splits downforce like the weight
    rolling_resistance: float = 0.015  # [-] assumed, slicks 0.01-0.02

    # Powertrain and brakes: all-wheel drive (fssim drivetrain nm_wheels: 4).
    max_accel: float = 3.0  # [m/s^2] EUFS input range (REFERENCES.md: +3)
    max_decel: float = 10.0  # [m/s^2] EUFS input range (REFERENCES.md: -10)
    max_drive_force: float = 5000.0  # [N] fssim drivetrain Cm1
    max_power: float = 20_000.0  # [W] assumed: top speed 29.7 m/s, EUFS caps 30, FSDS ~27
    drive_front_share: float = 0.5  # [-] assumed, equal motors front and rear
    brake_front_share: float = 0.6  # [-] assumed; ideal at -10 m/s^2 is 0.67 here

    # Steering actuator: EUFS QEV3 range, EUFS lock time and control delay.
    max_steer: float = 0.47  # [rad] EUFS qev3 configDry.yaml steering max
    max_steer_rate: float = 0.63  # [rad/s] EUFS: range 2 * 0.47 rad in steering_lock_time 1.5 s
    steer_time_constant: float = 0.035  # [s] EUFS control_delay 35 ms (REFERENCES.md)

    # Kinematic/dynamic blend: fssim f_kin_correction (blend = 0.5 * (v - 1.5)).
    blend_speed_low: float = 1.5  # [m/s] fssim vehicle.cpp
    blend_speed_high: float = 3.5  # [m/s] fssim vehicle.cpp

    # Footprint for contacts (pymunk box) and the GPS antenna.
    length: float = 2.9  # [m] assumed, FS cars are 2.9-3.1 m with wings
    width: float = 1.4  # [m] fssim track 1.22 m (distances.yaml) + EUFS tyre width 0.2 m
    front_overhang: float = 0.75  # [m] assumed, front axle to front wing tip
    antenna_x: float = -0.3  # [m] assumed: on the main hoop just behind the driver
    antenna_y: float = 0.0  # [m] on the centreline
    contact_friction: float = 0.5  # [-] assumed, car body against cones
    contact_elasticity: float = 0.0  # [-] assumed, cones do not bounce off the car

    def __post_init__(self) -> None:
        for f in fields(self):
            value = getattr(self, f.name)
            if isinstance(value, float | int) and not math.isfinite(value):
                raise ValueError(f"VehicleParams.{f.name} must be finite, got {value!r}")
        inf = math.inf
        # (field, low, high, low inclusive, high inclusive, unit)
        ranges: tuple[tuple[str, float, float, bool, bool, str], ...] = (
            ("mass", 0.0, inf, False, False, "kg"),
            ("yaw_inertia", 0.0, inf, False, False, "kg m^2"),
            ("wheelbase", 0.0, inf, False, False, "m"),
            ("cg_to_front", 0.0, self.wheelbase, False, False, "m"),
            ("cg_height", 0.0, inf, True, False, "m"),
            ("gravity", 0.0, inf, False, False, "m/s^2"),
            ("mu", 0.0, inf, False, False, "-"),
            ("air_density", 0.0, inf, True, False, "kg/m^3"),
            ("drag_area", 0.0, inf, True, False, "m^2"),
            ("lift_area", 0.0, inf, True, False, "m^2"),
            ("aero_balance_front", 0.0, 1.0, True, True, "-"),
            ("rolling_resistance", 0.0, inf, True, False, "-"),
            ("max_accel", 0.0, inf, False, False, "m/s^2"),
            ("max_decel", 0.0, inf, False, False, "m/s^2"),
            ("max_drive_force", 0.0, inf, False, False, "N"),
            ("max_power", 0.0, inf, False, False, "W"),
            ("drive_front_share", 0.0, 1.0, True, True, "-"),
            ("brake_front_share", 0.0, 1.0, True, True, "-"),
            ("max_steer", 0.0, math.pi / 2, False, False, "rad"),
            ("max_steer_rate", 0.0, inf, False, False, "rad/s"),
            ("steer_time_constant", 0.0, inf, True, False, "s"),
            ("blend_speed_low", 0.0, inf, True, False, "m/s"),
            ("blend_speed_high", self.blend_speed_low, inf, False, False, "m/s"),
            ("length", self.cg_to_front + self.front_overhang, inf, False, False, "m"),
            ("width", 0.0, inf, False, False, "m"),
            ("front_overhang", 0.0, inf, True, False, "m"),
            ("contact_friction", 0.0, inf, True, False, "-"),
            ("contact_elasticity", 0.0, 1.0, True, True, "-"),
        )
        for name, lo, hi, lo_incl, hi_incl, unit in ranges:
            _check_range(
                name, getattr(self, name), lo, hi, lo_incl=lo_incl, hi_incl=hi_incl, unit=unit
            )
        rolling = self.rolling_resistance * self.mass * self.gravity
        if not self.max_drive_force > rolling:
            raise ValueError(
                f"VehicleParams.max_drive_force = {self.max_drive_force!r} N does not move the "
                f"car: the rolling resistance at rest, rolling_resistance * mass * gravity, "
                f"is {rolling:.6g} N"
            )
        for name in ("tyre_front", "tyre_rear"):
            if not isinstance(getattr(self, name), PacejkaParams):
                raise ValueError(f"VehicleParams.{name} must be a PacejkaParams")

    @property
    def cg_to_rear(self) -> float:
        """CG to rear axle lr = L - lf [m]."""
        return self.wheelbase - self.cg_to_front

    @property
    def mu_front(self) -> float:
        """Peak friction coefficient of the front axle, mu * D [-]."""
        return self.mu * self.tyre_front.D

    @property
    def mu_rear(self) -> float:
        """Peak friction coefficient of the rear axle, mu * D [-]."""
        return self.mu * self.tyre_rear.D


def _check_range(
    name: str, value: float, lo: float, hi: float, *, lo_incl: bool, hi_incl: bool, unit: str
) -> None:
    """Raise ValueError naming the field and its allowed range if value is outside it."""
    above = value >= lo if lo_incl else value > lo
    below = value <= hi if hi_incl else value < hi
    if above and below:
        return
    left = "[" if lo_incl else "("
    right = "]" if hi_incl else ")"
    raise ValueError(
        f"VehicleParams.{name} must be in {left}{lo:g}, {hi:g}{right} [{unit}], got {value!r}"
    )
