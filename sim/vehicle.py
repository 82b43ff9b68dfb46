"""The car as a pymunk rigid body driven by the single-track model.

The body has the car's mass and yaw inertia, its CG at the body origin, and a
box footprint (``pymunk.Poly``) so that it can push cones. pymunk knows no
ground in 2D: the space must have zero gravity and no damping, and the shape's
friction only acts on contacts with other shapes. The tyres are modelled by
``sim.vehicle_dynamics``; each physics step:

1. ``pre_step(dt)`` moves the steering actuator (first-order lag, then rate
   and angle limits), reads the body-frame velocity, computes the blended
   dynamic/kinematic force and moment, and applies them to the body as ONE
   force at the CG (``apply_force_at_local_point``, body frame) plus a torque
   (``body.torque``). The kinematic region is force-based too: the force is
   the one that reaches the kinematic velocity in one step, so the car never
   has its velocity overwritten and contacts stay physical.
2. ``space.step(dt)`` integrates. Chipmunk advances the pose with the current
   velocity, then the velocity with the forces (semi-implicit Euler), and
   resolves contacts; the heading change of a step is therefore yaw_rate*dt,
   known before the step.
3. ``post_step()`` records the body-frame acceleration of the step, as an
   integrating accelerometer reports it: the velocity change over the step
   seen from the mid-step heading, ax, ay = R(-(yaw_start + r dt / 2))
   (v_end - v_start) / dt (the body turns by r dt during the step). It
   differs from the applied force / mass by that half-step rotation; with
   contacts it includes the impulse, as a real accelerometer would.

``step(space, vehicle, dt)`` runs the three for a space holding one car; a
world with several bodies calls ``pre_step`` on every car, ``space.step``
once, then ``post_step`` on every car.

The longitudinal command is an acceleration demand: negative values brake, the
car has no reverse gear, and a braked car at rest stays at rest.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import pymunk

from conesim.core.pose import Pose2D
from conesim.sim.bodies import remove_from_space, spend_bias
from conesim.sim.vehicle_dynamics import packed, wrench
from conesim.sim.vehicle_params import VehicleParams

#: pymunk collision type of the car's footprint.
VEHICLE_COLLISION_TYPE = 1

_ORIGIN = Pose2D(0.0, 0.0, 0.0)  # a new pymunk body's pose

# (x, y, yaw, vx, vy, yaw_rate, ax, ay, yaw_accel): ``VehicleState``'s motion as floats.
Kinematics = tuple[float, float, float, float, float, float, float, float, float]


@dataclass(frozen=True, slots=True)
class VehicleState:
    """Ground-truth state of the car at one instant.

    Attributes:
        x: CG position east, reference frame [m].
        y: CG position north, reference frame [m].
        yaw: heading, counter-clockwise from east, wrapped to [-pi, pi) [rad].
        vx: longitudinal velocity of the CG, body frame [m/s].
        vy: lateral velocity of the CG, body frame [m/s].
        yaw_rate: yaw rate [rad/s].
        steer: actual front wheel angle (after the actuator) [rad].
        ax: longitudinal acceleration of the CG over the last step, body frame [m/s^2].
        ay: lateral acceleration of the CG over the last step, body frame [m/s^2].
        yaw_accel: yaw acceleration over the last step [rad/s^2].
        antenna_x: GPS antenna lever arm ahead of the CG, body frame [m].
        antenna_y: GPS antenna lever arm left of the CG, body frame [m].
    """

    x: float
    y: float
    yaw: float
    vx: float
    vy: float
    yaw_rate: float
    steer: float
    ax: float
    ay: float
    yaw_accel: float
    antenna_x: float
    antenna_y: float

    @property
    def speed(self) -> float:
        """Magnitude of the CG velocity [m/s], >= 0."""
        return math.hypot(self.vx, self.vy)

    @property
    def pose(self) -> Pose2D:
        """Pose of the CG in the reference frame."""
        return Pose2D(self.x, self.y, self.yaw)

    def point_pose(self, dx: float, dy: float) -> Pose2D:
        """Pose of a body-fixed point (dx ahead, dy left of the CG [m]), reference frame."""
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        return Pose2D(self.x + c * dx - s * dy, self.y + s * dx + c * dy, self.yaw)

    def point_velocity(self, dx: float, dy: float) -> tuple[float, float]:
        """Velocity of a body-fixed point, reference frame [m/s]: v_cg + r x d."""
        bx = self.vx - self.yaw_rate * dy
        by = self.vy + self.yaw_rate * dx
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        return c * bx - s * by, s * bx + c * by

    def antenna_pose(self) -> Pose2D:
        """Pose of the GPS antenna (``gps_antenna`` frame) in the reference frame."""
        return self.point_pose(self.antenna_x, self.antenna_y)

    def antenna_velocity(self) -> tuple[float, float]:
        """Velocity of the GPS antenna in the reference frame [m/s]."""
        return self.point_velocity(self.antenna_x, self.antenna_y)


class SteeringActuator:
    """Front wheel angle actuator: first-order lag, then rate and angle limits.

    The lag is discretised exactly for a command held over the step::

        delta_lag = delta + (delta_cmd - delta) * (1 - exp(-dt / tau))
        delta_next = clip(delta + clip(delta_lag - delta, +-rate_max dt), +-delta_max)
    """

    def __init__(self, params: VehicleParams) -> None:
        self._p = params
        self.angle = 0.0  # [rad]
        self._step: tuple[float, float, float] = (math.nan, 0.0, 0.0)  # (dt, gain, max change)

    def update(self, command: float, dt: float) -> float:
        """Advance by dt [s] towards command [rad]; return the new angle [rad]."""
        p = self._p
        step_dt, gain, max_change = self._step
        if dt != step_dt:  # the same dt every physics step: the gain is worked out once
            tau = p.steer_time_constant
            gain = 1.0 - math.exp(-dt / tau) if tau > 0.0 else 1.0
            max_change = p.max_steer_rate * dt
            self._step = (dt, gain, max_change)
        change = (command - self.angle) * gain
        change = min(max(change, -max_change), max_change)
        self.angle = min(max(self.angle + change, -p.max_steer), p.max_steer)
        return self.angle


class Vehicle:
    """A car in a pymunk space.

    Args:
        space: the pymunk space; gravity must be (0, 0) and damping 1 (none).
        params: vehicle parameters.
        pose: start pose of the CG in the reference frame.
        speed: start speed along the heading [m/s].

    Raises:
        ValueError: if the space has gravity or damping, or dt <= 0 in pre_step.
    """

    def __init__(
        self, space: pymunk.Space, params: VehicleParams, pose: Pose2D, speed: float = 0.0
    ) -> None:
        _check_space(space)
        self.params = params
        self._packed = packed(params)  # the car model's parameters, as its kernels read them
        self._body = pymunk.Body(params.mass, params.yaw_inertia)
        nose = params.cg_to_front + params.front_overhang
        tail = nose - params.length
        half_w = 0.5 * params.width
        self._shape = pymunk.Poly(
            self._body, [(tail, -half_w), (nose, -half_w), (nose, half_w), (tail, half_w)]
        )
        self._shape.friction = params.contact_friction
        self._shape.elasticity = params.contact_elasticity
        self._shape.collision_type = VEHICLE_COLLISION_TYPE
        space.add(self._body, self._shape)
        self._steering = SteeringActuator(params)
        self.reset(pose, speed)
        # The model's kernels compile (or load from the cache) here, while the
        # world is built, rather than in its first step (a pure call).
        wrench(self._packed, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1e-3, 0.0)

    @property
    def body(self) -> pymunk.Body:
        """The pymunk body (sim-internal)."""
        return self._body

    @property
    def shape(self) -> pymunk.Poly:
        """The pymunk footprint (sim-internal)."""
        return self._shape

    @property
    def command(self) -> tuple[float, float]:
        """The held command after clipping: (steer [rad], accel [m/s^2])."""
        return self._steer_cmd, self._accel_cmd

    def renew(self, space: pymunk.Space, pose: Pose2D, speed: float = 0.0) -> None:
        """Move the car into ``space`` (a new episode's) and :meth:`reset` it there.

        The car is then as a new ``Vehicle(space, params, pose, speed)`` is, bit
        for bit, on the same body and footprint (``sim.bodies``: a new body is
        what a world's reset spends its time on).

        Raises:
            ValueError: if the space has gravity or damping.
        """
        _check_space(space)
        remove_from_space([self._body])
        spend_bias([self._body])
        # Where a new body stands: Chipmunk indexes a shape where its body is
        # when it joins a space, and the index's layout shapes later steps.
        self.reset(_ORIGIN)
        space.add(self._body, self._shape)
        self.reset(pose, speed)

    def reset(self, pose: Pose2D, speed: float = 0.0) -> None:
        """Place the CG at pose with speed [m/s] along the heading, wheels straight,
        no force or torque held."""
        b = self._body
        b.position = (pose.x, pose.y)
        b.angle = pose.yaw
        b.velocity = (speed * math.cos(pose.yaw), speed * math.sin(pose.yaw))
        b.angular_velocity = 0.0
        b.force = (0.0, 0.0)
        b.torque = 0.0
        self._steering.angle = 0.0
        self._steer_cmd = 0.0
        self._accel_cmd = 0.0
        self._ax_force = 0.0  # applied fx / m of the last step, for load transfer
        self._accel = (0.0, 0.0, 0.0)  # ax, ay, yaw_accel
        self._pre: tuple[float, float, float, float, float] | None = None
        # The body's (angle, vx, vy, r) as post_step read them: the next
        # pre_step starts from them (nothing moves the body in between).
        self._read: tuple[float, float, float, float] | None = None

    def set_command(self, steer_rad: float, accel_mps2: float) -> None:
        """Hold a command until the next call, clipped to the vehicle's limits.

        Args:
            steer_rad: front wheel angle demand [rad], clipped to +-max_steer.
            accel_mps2: acceleration demand [m/s^2], clipped to
                [-max_decel, max_accel]; negative brakes.
        """
        p = self.params
        if not (math.isfinite(steer_rad) and math.isfinite(accel_mps2)):
            raise ValueError(f"command must be finite, got ({steer_rad!r}, {accel_mps2!r})")
        self._steer_cmd = min(max(steer_rad, -p.max_steer), p.max_steer)
        self._accel_cmd = min(max(accel_mps2, -p.max_decel), p.max_accel)

    def pre_step(self, dt: float) -> None:
        """Move the actuator and apply the tyre, drive and drag forces for a step.

        Args:
            dt: the coming ``space.step`` [s], > 0.
        """
        if not dt > 0.0:
            raise ValueError(f"dt must be > 0 [s], got {dt!r}")
        steer = self._steering.update(self._steer_cmd, dt)
        b = self._body
        read = self._read
        if read is None:
            yaw = b.angle
            vwx, vwy = b.velocity
            r = b.angular_velocity
        else:
            yaw, vwx, vwy, r = read
            self._read = None
        c, s = math.cos(yaw), math.sin(yaw)
        # The target of the kinematic model is the body frame at the end of
        # the step; pymunk turns the body by r * dt before it applies forces.
        fx, fy, mz = wrench(
            self._packed,
            c * vwx + s * vwy,
            -s * vwx + c * vwy,
            r,
            steer,
            self._accel_cmd,
            self._ax_force,
            dt,
            r * dt,
        )
        b.apply_force_at_local_point((fx, fy), (0.0, 0.0))
        b.torque = b.torque + mz
        self._ax_force = fx / self.params.mass
        self._pre = (vwx, vwy, r, yaw, dt)

    def post_step(self) -> Kinematics:
        """Record the accelerations of the step just taken by ``space.step``.

        Returns:
            :meth:`kinematics` after the step, from the same reads of the body
            (the world reads them every physics step).
        """
        if self._pre is None:
            raise RuntimeError("post_step() needs a pre_step(dt) before space.step(dt)")
        vwx0, vwy0, r0, yaw0, dt = self._pre
        b = self._body
        vwx, vwy = b.velocity
        r = b.angular_velocity
        dvx, dvy = (vwx - vwx0) / dt, (vwy - vwy0) / dt
        # Mean body-frame acceleration over the step: the body turned by r0 * dt
        # during it, so the world-frame velocity change is seen from the
        # mid-step heading (what an integrating accelerometer reports).
        yaw_mid = yaw0 + 0.5 * r0 * dt
        c, s = math.cos(yaw_mid), math.sin(yaw_mid)
        self._accel = (
            c * dvx + s * dvy,
            -s * dvx + c * dvy,
            (r - r0) / dt,
        )
        self._pre = None
        x, y = b.position
        angle = b.angle
        self._read = (angle, vwx, vwy, r)
        return self._motion(x, y, angle, velocity=(vwx, vwy, r))

    def kinematics(self) -> Kinematics:
        """The state's motion now as plain floats, without building a ``VehicleState``.

        Returns:
            (x, y, yaw, vx, vy, yaw_rate, ax, ay, yaw_accel), the fields of
            :attr:`state` with the same values bit for bit (the world reads
            them every physics step and builds the state only when asked).
        """
        b = self._body
        x, y = b.position
        vwx, vwy = b.velocity
        return self._motion(x, y, b.angle, velocity=(vwx, vwy, b.angular_velocity))

    def _motion(
        self, x: float, y: float, yaw: float, *, velocity: tuple[float, float, float]
    ) -> Kinematics:
        """:meth:`kinematics` from the body's position, angle and its world-frame
        velocity and angular velocity (vx, vy, r)."""
        vwx, vwy, r = velocity
        c, s = math.cos(yaw), math.sin(yaw)
        ax, ay, yaw_accel = self._accel
        return (
            x,
            y,
            (yaw + math.pi) % (2.0 * math.pi) - math.pi,
            c * vwx + s * vwy,
            -s * vwx + c * vwy,
            r,
            ax,
            ay,
            yaw_accel,
        )

    @property
    def steer(self) -> float:
        """The actual front wheel angle now (after the actuator) [rad]."""
        return self._steering.angle

    @property
    def state(self) -> VehicleState:
        """The ground-truth state now."""
        x, y, yaw, vx, vy, yaw_rate, ax, ay, yaw_accel = self.kinematics()
        steer, p = self._steering.angle, self.params
        # The fields in their order (x y yaw vx vy yaw_rate steer ax ay yaw_accel antenna).
        return VehicleState(
            x, y, yaw, vx, vy, yaw_rate, steer, ax, ay, yaw_accel, p.antenna_x, p.antenna_y
        )

    def antenna_pose(self) -> Pose2D:
        """Pose of the GPS antenna in the reference frame."""
        return self.state.antenna_pose()


def _check_space(space: pymunk.Space) -> None:
    """Refuse a space with gravity or damping (the car knows no ground in 2D)."""
    if tuple(space.gravity) != (0.0, 0.0) or space.damping != 1.0:
        raise ValueError(
            "Vehicle needs a space with gravity (0, 0) and damping 1.0, got "
            f"gravity {tuple(space.gravity)} and damping {space.damping}"
        )


def step(space: pymunk.Space, vehicle: Vehicle, dt: float) -> VehicleState:
    """One physics step of a space holding one car: pre_step, space.step, post_step.

    Args:
        space: the car's space.
        vehicle: the car.
        dt: step [s].

    Returns:
        The car's state after the step.
    """
    vehicle.pre_step(dt)
    space.step(dt)
    vehicle.post_step()
    return vehicle.state
