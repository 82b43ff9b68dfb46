"""The simulated world: one place that advances physics and sensors by the clock.

``World`` owns the truth: the pymunk space, the car, the cones, race control
and the sensor suite. Each call to :meth:`World.step` runs one physics step
(default 200 Hz) with the current actuator command, then hands the truth of
that instant to the sensors and returns the measurements whose delivery time
has come, in stamp order, with the events of the step (``sim.events``: cone
hits, cones down or out, leaving and rejoining the track, laps). The closed
loop (``envs.loop``) steps it; nothing else steps pymunk.

Step skeleton (fixed order, one physics step of ``dt``):

1. ``vehicle.pre_step(dt)``: actuator lag, tyre forces applied to the body.
2. ``space.step(dt)``: pymunk integrates and resolves car-cone contacts.
3. ``vehicle.post_step()``; ``cones.update(t)``: hits, down-or-out cones.
4. ``race.update(...)``: progress, laps (crossing interpolated in the step),
   off-track, stuck.
5. ``sensors.step(truth)``: captures due at ``t``; returns deliveries due.
6. the step's events, from what changed in the cone field and race control.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import pymunk

from conesim.core.geodesy import DEFAULT_ORIGIN, ReferenceOrigin
from conesim.core.messages import Message
from conesim.core.pose import Pose2D
from conesim.sim.cones import ConeField, ConeParams
from conesim.sim.events import (
    BackOnTrack,
    ConeDown,
    ConeHit,
    Event,
    LapCompleted,
    OffTrack,
    RaceStanding,
    WorldStep,
)
from conesim.sim.race_control import RaceControl, RaceRules, RaceState, timed_lap_length
from conesim.sim.sensors import SensorProfile, SensorSuite, TruthSample, get_profile
from conesim.sim.sensors.cone_map import ConeMap
from conesim.sim.vehicle import Kinematics, Vehicle, VehicleState
from conesim.sim.vehicle_params import VehicleParams
from conesim.tracks import Track

SLEEP_TIME_THRESHOLD = 0.5  # [s] idle time before pymunk puts a cone to sleep
IDLE_SPEED_THRESHOLD = 0.02  # [m/s] below this a body counts as idle


@dataclass(frozen=True)
class WorldConfig:
    """Settings of the simulated world.

    Attributes:
        physics_rate: physics steps per second [Hz].
        sensors: sensor profile, or the name of a shipped one
            (``ideal``, ``rtk``, ``consumer``, ``consumer_white``).
        vehicle: the car's parameters.
        cones: cone physics.
        rules: race control.
        origin: geodetic origin of `reference`.
    """

    physics_rate: float = 200.0  # [Hz] ARCHITECTURE.md default
    sensors: SensorProfile | str = "rtk"
    vehicle: VehicleParams = field(default_factory=VehicleParams)
    cones: ConeParams = field(default_factory=ConeParams)
    rules: RaceRules = field(default_factory=RaceRules)
    origin: ReferenceOrigin = DEFAULT_ORIGIN

    def __post_init__(self) -> None:
        if not (math.isfinite(self.physics_rate) and self.physics_rate > 0.0):
            raise ValueError(
                f"WorldConfig.physics_rate must be finite and > 0 [Hz], got {self.physics_rate!r}"
            )

    @property
    def dt(self) -> float:
        """Physics step [s]."""
        return 1.0 / self.physics_rate

    @property
    def sensor_profile(self) -> SensorProfile:
        """The sensor profile object."""
        if isinstance(self.sensors, str):
            return get_profile(self.sensors)
        return self.sensors


class World:
    """A car on a cone track with its sensors.

    Args:
        track: the track (cones, centreline, start pose, timing line).
        config: world settings.
        seed: episode seed; every random stream derives from it.
        start_pose: CG pose to start from; default the track's start pose.

    Attributes:
        initial_messages: the measurements captured at t = 0 by the
            constructor's reset (``reset`` returns them too).
    """

    vehicle: Vehicle
    cones: ConeField
    race: RaceControl

    def __init__(
        self,
        track: Track,
        config: WorldConfig | None = None,
        seed: int = 0,
        start_pose: Pose2D | None = None,
    ) -> None:
        self.track = track
        self.config = config or WorldConfig()
        self._built = False  # the car, the cones and race control: built by the first reset
        self.initial_messages = self.reset(seed, start_pose)

    def reset(self, seed: int = 0, start_pose: Pose2D | None = None) -> list[Message]:
        """Start the world again at ``t = 0`` for a new episode.

        The first reset (the constructor's) builds the car, the cones and
        race control; a later one puts the same car and cone bodies into a
        new pymunk space, each cone back on its mark, and starts race control
        again (``Vehicle.renew``, ``ConeField.renew``, ``RaceControl.start``).
        The episode is the one a new ``World(track, config, seed,
        start_pose)`` runs, bit for bit; building some 200 pymunk bodies was
        most of the cost of a reset.

        Returns:
            The measurements delivered at ``t = 0`` (latency-free captures).
        """
        cfg = self.config
        track = self.track
        self.seed = int(seed)
        self._dt = cfg.dt
        self.time = 0.0
        self.steps = 0
        self.space = pymunk.Space()
        self.space.gravity = (0.0, 0.0)
        self.space.sleep_time_threshold = SLEEP_TIME_THRESHOLD
        self.space.idle_speed_threshold = IDLE_SPEED_THRESHOLD
        pose = start_pose or track.start_pose
        kinds = tuple(str(k) for k in track.kinds)
        if self._built:
            self.vehicle.renew(self.space, pose)
            self.cones.renew(self.space)
        else:
            self.vehicle = Vehicle(self.space, cfg.vehicle, pose)
            self.cones = ConeField(self.space, track.cones, kinds, cfg.cones)
            self.race = self._race_control()
            self._built = True
        self.cone_map = ConeMap(track.cones, kinds)
        self._cone_version = self.cones.version
        self._cone_positions = self.cones.positions  # a read-only view, current at every step
        self._cone_kinds = self.cones.kinds
        # The per-step samples skip the shape checks (TruthSample.trusted):
        # check these arrays once.
        TruthSample(
            0.0,
            pose,
            cone_positions=self._cone_positions,
            cone_kinds=self._cone_kinds,
            cone_map=self.cone_map,
        )
        self.space.step(1e-9)  # let pymunk register the bodies before they sleep
        self.cones.sleep_all()
        self._state: VehicleState | None = None  # built when asked for
        self._pose: Pose2D | None = None  # likewise
        self._lever = (cfg.vehicle.antenna_x, cfg.vehicle.antenna_y)
        self._refresh()
        self._accel_prev = (0.0, 0.0)  # antenna acceleration of the last step, world [m/s^2]
        self.race.start(0.0, self.pose)
        self.sensors = SensorSuite(cfg.sensor_profile, seed=self.seed, origin=cfg.origin)
        return self.sensors.step(self._truth())

    def _race_control(self) -> RaceControl:
        """Race control on the track, for the car and the rules of the config."""
        track, cfg = self.track, self.config
        closed = track.layout == "closed"
        return RaceControl(
            track.centreline,
            closed,
            half_widths=0.5 * np.asarray(track.widths),
            start_finish=np.asarray(track.start_finish),
            finish_line=np.asarray(track.finish_line),
            lap_length=timed_lap_length(
                track.centreline, closed, track.start_finish, track.finish_line
            ),
            car_length=cfg.vehicle.length,
            car_width=cfg.vehicle.width,
            rules=cfg.rules,
        )

    @property
    def dt(self) -> float:
        """Physics step [s]."""
        return self.config.dt

    @property
    def state(self) -> VehicleState:
        """The car's true state after the last step (built when first asked for)."""
        state = self._state
        if state is None:
            x, y, yaw, vx, vy, w, ax, ay, dw = self._kin
            p = self.config.vehicle
            state = self._state = VehicleState(
                x, y, yaw, vx, vy, w, self._steer, ax, ay, dw, p.antenna_x, p.antenna_y
            )
        return state

    @property
    def pose(self) -> Pose2D:
        """The CG's true pose after the last step (``state.pose``, built when asked for)."""
        pose = self._pose
        if pose is None:
            x, y, yaw = self._kin[0], self._kin[1], self._kin[2]
            pose = self._pose = Pose2D(x, y, yaw)
        return pose

    @property
    def antenna_pose(self) -> Pose2D:
        """The antenna's true pose after the last step (``state.antenna_pose()``, once per step)."""
        return self._antenna_pose

    def _refresh(self, kin: Kinematics | None = None) -> None:
        """Read the car after a step: its motion as floats, the CG and antenna poses.

        The same values and operations as ``VehicleState.pose`` and
        ``VehicleState.antenna_pose()``; the ``VehicleState`` itself is built
        only when :attr:`state` is read.

        Args:
            kin: the car's ``kinematics()`` if already read (``post_step``'s).
        """
        vehicle = self.vehicle
        kin = self._kin = vehicle.kinematics() if kin is None else kin
        self._steer = vehicle.steer
        self._state = None
        x, y, yaw = kin[0], kin[1], kin[2]
        self._pose = None
        dx, dy = self._lever
        c, s = math.cos(yaw), math.sin(yaw)
        self._antenna_pose = Pose2D(x + c * dx - s * dy, y + s * dx + c * dy, yaw)

    @property
    def race_state(self) -> RaceState:
        """Laps, off-track events, progress, stuck flag."""
        return self.race.state

    def set_command(self, steer_rad: float, accel_mps2: float) -> None:
        """Actuator demand held until changed (clipped to the car's limits)."""
        self.vehicle.set_command(steer_rad, accel_mps2)

    def step(self) -> WorldStep:
        """Advance one physics step: the measurements delivered now and the step's events."""
        dt = self._dt
        kin = self._kin
        prev_xy = (kin[0], kin[1])
        cones = self.cones
        race = self.race.state
        hits_before = len(cones.hit_events)
        laps_before = len(race.lap_times)
        off_before = race.is_off_track
        vehicle = self.vehicle
        vehicle.pre_step(dt)
        self.space.step(dt)
        moved = vehicle.post_step()
        self.steps += 1
        t = self.steps * dt  # no accumulated round-off: t is exact in steps
        new_down = cones.update(t)
        self._refresh(moved)
        kin = self._kin
        self.race.update_xy(self.time, t, prev_xy, (kin[0], kin[1], kin[2]))
        self.time = t
        if cones.version != self._cone_version:
            self.cone_map.update(cones.positions)
            self._cone_version = cones.version
        messages = self.sensors.step(self._truth())
        events: list[Event] = []
        if len(cones.hit_events) != hits_before or new_down:
            self._cone_events(hits_before, new_down, t, events)
        if race.is_off_track != off_before:
            kind = OffTrack if race.is_off_track else BackOnTrack
            events.append(kind(t, kin[0], kin[1]))
        if len(race.lap_times) != laps_before:
            lap = len(race.lap_times)
            events.append(LapCompleted(race.crossing_times[-1], lap, race.lap_times[-1]))
        return WorldStep(t, messages, events)

    def _cone_events(
        self, hits_before: int, new_down: list[int], t: float, out: list[Event]
    ) -> None:
        """The cone hits recorded since ``hits_before`` and the cones ``new_down`` at ``t``."""
        initial = self.cones.initial_positions
        for t_hit, i in self.cones.hit_events[hits_before:]:
            out.append(ConeHit(t_hit, i, float(initial[i, 0]), float(initial[i, 1])))
        for i in new_down:
            out.append(ConeDown(t, i, float(initial[i, 0]), float(initial[i, 1])))

    def advance(self, duration_s: float) -> list[Message]:
        """Run whole physics steps covering ``duration_s``; all measurements, in order."""
        n = max(1, round(duration_s / self.dt))
        out: list[Message] = []
        for _ in range(n):
            out.extend(self.step().messages)
        return out

    def standing(self) -> RaceStanding:
        """The race so far (laps, progress, cones, excursions), after the last step."""
        race = self.race.state
        return RaceStanding(
            progress_m=race.progress_m,
            laps_completed=race.laps_completed,
            lap_times=tuple(race.lap_times),
            cones_hit=len(self.cones.hit_ids),
            cones_down_or_out=len(self.cones.doo_ids),
            off_track_events=len(race.off_track),
            off_track=race.is_off_track,
            stuck=race.stuck,
        )

    def _truth(self) -> TruthSample:
        """The truth at the antenna, where the GPS, IMU and cone sensor sit.

        Called once per step (it keeps the last step's acceleration). Rigid-body
        kinematics move the CG's velocity and acceleration to the lever arm
        r = (rx, ry): v = v_cg + w x r, a = a_cg + dw/dt x r - w^2 r.

        pymunk moves the body over a step with the velocity and yaw rate it had
        at the step's start, then changes them. So that the motion a sensor
        reports is the motion the positions show:

        * the yaw rate is the mean over the last step, the rate that turned it
          (w - dw/dt dt);
        * the speed is the positions' own at this instant, the midpoint of the
          velocity that moved the body over the last step and the one that
          moves it over the next (the current velocity is half a step's change
          ahead: 7.5 mm/s at 3 m/s^2);
        * the acceleration is the positions' mean over the last step: the mean
          of their second differences at its two ends, i.e. of the last two
          steps' velocity changes per dt (world frame), seen from the
          mid-step heading, as an integrating accelerometer reports it. The
          step's own velocity change alone leads by half a step; in a steady
          turn that turns it by w dt / 2 and an IMU-integrating filter drifts
          by dt w |a| / 2 (13 mm/s per s at 0.75 rad/s, 7 m/s^2).
        """
        _, _, yaw, vx, _, w, s_ax, s_ay, dw = self._kin
        rx, ry = self._lever
        dt = self._dt
        yaw_rate = w - dw * dt if self.steps else w
        ax = s_ax - dw * ry - w * w * rx  # this step's, body frame at mid-step
        ay = s_ay + dw * rx - w * w * ry
        yaw_mid = yaw - 0.5 * yaw_rate * dt
        c, sn = math.cos(yaw_mid), math.sin(yaw_mid)
        awx, awy = c * ax - sn * ay, sn * ax + c * ay
        px, py = self._accel_prev
        self._accel_prev = (awx, awy)
        mx, my = 0.5 * (awx + px), 0.5 * (awy + py)
        return TruthSample.trusted(
            self.time,
            self._antenna_pose,
            speed=vx - w * ry - 0.5 * dt * ax,
            yaw_rate=yaw_rate,
            accel_x=c * mx + sn * my,
            accel_y=-sn * mx + c * my,
            cone_positions=self._cone_positions,
            cone_kinds=self._cone_kinds,
            cone_map=self.cone_map,
        )
