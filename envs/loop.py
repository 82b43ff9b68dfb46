"""The closed loop: one car's world, localization and driver on one clock.

:meth:`ClosedLoop.step` is one control period (``1 / control_rate``)::

    for each physics step of the period (physics_rate / control_rate of them):
        1. the world steps: physics, cones, race control, sensors; it
           delivers the measurements due now, and the step's events;
        2. localization handles them (GPS-to-local, the EKF) and the
           broadcaster publishes into the frame tree;
    3. the driver (the autopilot), if there is one, plans from the period's
       messages, the frame tree and the global path, and returns a command;
    4. the command goes to the world, which holds it over the next period.

Without a driver the caller passes the command (the gym env: its action).
Each step returns a :class:`StepRecord` of what happened: the messages
delivered, the transforms broadcast (with the truth at each), the driver's
outputs, the command, the truth and the events, and the end of the episode
with its reason. The runner, its metrics, the bag recorder and the renderer
read records; none of them reads another object's private state.

The world's seed: :func:`world_seed` draws it from a generator, as the env
does from its ``np_random``, so ``conesim run --seed S`` and
``env.reset(seed=S)`` drive the same episode.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass
from enum import StrEnum
from typing import Protocol

import numpy as np
from numpy.typing import NDArray

from conesim.core.messages import Message
from conesim.core.pose import Pose2D
from conesim.envs.ekf_tuning import matched_cone_update, matched_ekf
from conesim.localization.cones import ConeUpdate, ConeUpdateConfig, LandmarkMap
from conesim.localization.ekf import EkfConfig
from conesim.localization.frames import Buffer, TransformStamped
from conesim.localization.localizer import Localizer
from conesim.localization.slam import SlamConfig, SlamUpdate
from conesim.planner.autopilot import CONTROL_RATE, AutopilotStep
from conesim.planner.messages import ControlCommand
from conesim.sim.events import Event, RaceStanding
from conesim.sim.race_control import RaceRules
from conesim.sim.vehicle import VehicleState
from conesim.sim.world import World, WorldConfig
from conesim.tracks import Track
from conesim.tracks.global_path import GlobalPath, global_path_for_track
from conesim.tracks.survey import ConeSurvey, PathSurvey, surveyed, surveyed_cones

FloatArray = NDArray[np.float64]
_TIME_EPS = 1e-9  # [s] tolerance of the time limit


class Driver(Protocol):
    """What drives the car from the car's software side: the autopilot, or a policy's adapter."""

    def step(self, t: float, messages: Sequence[Message], /) -> AutopilotStep:
        """One control step at ``t`` [s], given the messages delivered since the last."""
        ...


class DriverFactory(Protocol):
    """Builds a driver on an episode's frame tree and global path (``Autopilot`` is one)."""

    def __call__(
        self, frames: Buffer, global_path: GlobalPath, /, *, control_rate: float
    ) -> Driver: ...


class EndReason(StrEnum):
    """Why an episode ended."""

    LAPS_COMPLETED = "laps_completed"
    OFF_TRACK = "off_track"
    STUCK = "stuck"
    TIME_LIMIT = "time_limit"

    @property
    def truncated(self) -> bool:
        """Whether the end is a truncation (the time limit), not a terminal state."""
        return self is EndReason.TIME_LIMIT


@dataclass(frozen=True)
class EpisodeRules:
    """When an episode ends.

    The stuck rule: race control finds the car stuck when it has made less
    than ``stuck_progress`` of net progress along the centreline in the last
    ``stuck_time`` (``sim.race_control``); the episode ends on it only from
    ``stuck_grace`` on, so a car is never stuck before it had a chance to move.

    Attributes:
        laps: laps to complete [-] (an open lane is one run, whatever this says).
        time_limit: truncation time [s]; None: 60 s per lap plus 30 s.
        end_on_off_track: end when the car leaves the track.
        end_on_stuck: end when race control finds the car stuck.
        stuck_time: the stuck rule's window [s] (race control's ``stuck_time_s``).
        stuck_progress: net progress below which the car is stuck [m]
            (race control's ``stuck_progress_m``).
        stuck_grace: no end on the stuck rule before this time [s].
    """

    laps: int = 1
    time_limit: float | None = None  # [s]
    end_on_off_track: bool = True
    end_on_stuck: bool = True
    stuck_time: float = 5.0  # [s]
    stuck_progress: float = 0.5  # [m]
    stuck_grace: float = 0.0  # [s]

    def __post_init__(self) -> None:
        if not (isinstance(self.laps, int) and self.laps >= 1):
            raise ValueError(f"EpisodeRules.laps must be an integer >= 1, got {self.laps!r}")
        limit = self.time_limit
        if limit is not None and not (math.isfinite(limit) and limit > 0.0):
            raise ValueError(f"EpisodeRules.time_limit must be finite and > 0 [s], got {limit!r}")
        for name, low, closed in (
            ("stuck_time", 0.0, False),
            ("stuck_progress", 0.0, True),
            ("stuck_grace", 0.0, True),
        ):
            value = getattr(self, name)
            inside = value >= low if closed else value > low
            if not (math.isfinite(value) and inside):
                bound = ">=" if closed else ">"
                raise ValueError(f"EpisodeRules.{name} must be finite and {bound} 0, got {value!r}")

    def race_rules(self, rules: RaceRules) -> RaceRules:
        """Race control's settings ``rules`` with this stuck rule's window and threshold."""
        return dataclasses.replace(
            rules, stuck_time_s=self.stuck_time, stuck_progress_m=self.stuck_progress
        )

    @property
    def time_limit_s(self) -> float:
        """The truncation time [s]."""
        return self.time_limit if self.time_limit is not None else 60.0 * self.laps + 30.0


@dataclass(frozen=True, slots=True)
class Delivery:
    """A message as localization received it: at simulation time ``t`` [s]
    (a measurement's capture stamp plus its latency; a ``/local_xy`` point's fix's)."""

    t: float
    message: Message


@dataclass(frozen=True, slots=True)
class Broadcast:
    """One ``reference -> gps_antenna`` broadcast and the antenna's true pose then.

    Attributes:
        transform: the transform published (stamped with the broadcast time).
        truth: the antenna's true pose at that time.
    """

    transform: TransformStamped
    truth: Pose2D

    @property
    def t(self) -> float:
        """Broadcast time [s]."""
        return self.transform.stamp

    @property
    def published(self) -> Pose2D:
        """The pose the frame tree holds from this broadcast."""
        return self.transform.to_pose2d()

    @property
    def position_error(self) -> float:
        """Distance between published and true antenna position [m]."""
        pose = self.published
        return math.hypot(pose.x - self.truth.x, pose.y - self.truth.y)

    @property
    def yaw_error(self) -> float:
        """Absolute heading error, wrapped [rad]."""
        return abs(math.remainder(self.published.yaw - self.truth.yaw, 2.0 * math.pi))


@dataclass(frozen=True, slots=True)
class Truth:
    """The world's truth at the end of a step (for metrics, rewards and recording only).

    Attributes:
        state: the car's true state (CG pose and velocities, steering).
        antenna: the antenna's true pose (``gps_antenna`` in ``reference``).
        cones: (n, 2) the cones' positions now [m] (read-only; a new array
            only when a cone moved, see ``cones_moved``).
        cones_moved: whether a cone moved during the step.
        race: laps, progress, cones hit and down, excursions so far.
    """

    state: VehicleState
    antenna: Pose2D
    cones: FloatArray
    cones_moved: bool
    race: RaceStanding


@dataclass(frozen=True, slots=True)
class StepRecord:
    """What one step of the loop did (``ClosedLoop.reset``'s record: t = 0).

    Attributes:
        t: simulation time at the end of the step [s].
        deliveries: the measurements delivered, in delivery order.
        local_xy: the ``/local_xy`` points made from the fixes, with their time.
        broadcasts: the ``reference -> gps_antenna`` transforms broadcast.
        driver: the driver's output (its command and plans), or None.
        command: the command the world holds after the step.
        truth: the truth at the end of the step.
        events: what happened in the world during the step, in order.
        end: why the episode ended at this step, or None.
    """

    t: float
    deliveries: tuple[Delivery, ...]
    local_xy: tuple[Delivery, ...]
    broadcasts: tuple[Broadcast, ...]
    driver: AutopilotStep | None
    command: ControlCommand
    truth: Truth
    events: tuple[Event, ...]
    end: EndReason | None

    @property
    def messages(self) -> list[Message]:
        """The measurements delivered, in delivery order."""
        return [d.message for d in self.deliveries]


def world_seed(rng: np.random.Generator) -> int:
    """The world's seed, drawn from an episode's generator (every stream derives from it)."""
    return int(rng.integers(0, 2**31 - 1))


class ClosedLoop:
    """One car's closed loop on one clock (see the module docstring).

    Args:
        track: the track.
        world: physics, sensors and vehicle settings.
        localization: ``fused`` (EKF), ``raw`` (the ROS pipeline's) or ``truth``.
        control_rate: steps per simulated second [Hz]; ``world.physics_rate``
            is a whole multiple of it.
        rules: when an episode ends; its stuck window and threshold replace
            ``world.rules``' (race control's detector is the rule's).
        driver: builds the driver for each episode (``Autopilot``, or a
            ``functools.partial`` of it with its config); None: the caller
            passes the command to :meth:`step`.
        ekf: the filter's settings; default the ones matched to the world's
            sensor profile (``envs.ekf_tuning.matched_ekf``: its shipped
            tuning, else rtk's, with its receiver's error model).
        survey: how far the global path the driver gets is off the track's
            (``tracks.survey``); default exact.
        cone_map: how far the cone map (``cones`` localization) is off the
            cones as they stand (``tracks.survey.ConeSurvey``); default a few cm.
        cones: the cone update's settings (``cones`` and ``slam``
            localization); default matched to the world's cone detector
            (``envs.ekf_tuning``).
        slam: the map building's settings (``slam`` localization); the
            filter starts on the track's start pose (the antenna's there).

    Attributes:
        track, world_config, rules, control_rate, substeps: as given or derived.
        global_path: the track's global path (a track asset) in ``reference``,
            as surveyed.
        cone_update: the cone map and its update (``cones`` localization), else None.
        world: the simulated world of the current episode.
        localizer: localization of the current episode; its ``frames`` is the frame tree.
        driver: the current episode's driver, or None.
        record: the last step's record (None before :meth:`reset`).
    """

    def __init__(
        self,
        track: Track,
        world: WorldConfig | None = None,
        *,
        localization: str = "fused",
        control_rate: float = CONTROL_RATE,
        rules: EpisodeRules | None = None,
        driver: DriverFactory | None = None,
        ekf: EkfConfig | None = None,
        survey: PathSurvey | None = None,
        cone_map: ConeSurvey | None = None,
        cones: ConeUpdateConfig | None = None,
        slam: SlamConfig | None = None,
    ) -> None:
        self.track = track
        self.rules = rules or EpisodeRules()
        world = world or WorldConfig()
        # The episode's stuck rule is race control's: one detector, set here.
        self.world_config = dataclasses.replace(world, rules=self.rules.race_rules(world.rules))
        self.localization = localization
        if not (math.isfinite(control_rate) and control_rate > 0.0):
            raise ValueError(f"ClosedLoop: control_rate must be > 0 [Hz], got {control_rate!r}")
        ratio = self.world_config.physics_rate / control_rate
        if abs(ratio - round(ratio)) > 1e-9 or round(ratio) < 1:
            raise ValueError(
                f"ClosedLoop: physics_rate ({self.world_config.physics_rate} Hz) must be a "
                f"whole multiple of control_rate ({control_rate} Hz)"
            )
        self.control_rate = float(control_rate)
        self.substeps = round(ratio)
        self.ekf_config = ekf or matched_ekf(self.world_config.sensor_profile)
        self.global_path = surveyed(
            global_path_for_track(track, self.world_config.origin), survey or PathSurvey()
        )
        self.cone_update: ConeUpdate | None = None
        self.cone_config = cones or matched_cone_update(self.world_config.sensor_profile)
        self.slam_config = slam or SlamConfig()
        if localization == "cones":
            landmarks = LandmarkMap(
                surveyed_cones(track.cones, cone_map or ConeSurvey()), track.kinds
            )
            self.cone_update = ConeUpdate(landmarks, self.cone_config)
        self._driver_factory = driver
        self._world: World | None = None
        self.driver: Driver | None = None
        self.record: StepRecord | None = None
        self._cones: FloatArray = np.zeros((0, 2))

    @property
    def time(self) -> float:
        """Simulation time [s]."""
        return self.world.time

    @property
    def laps_to_drive(self) -> int:
        """Laps that end the episode: ``rules.laps``, or 1 on an open lane (one run)."""
        return 1 if self.track.layout == "open" else self.rules.laps

    def reset(self, seed: int = 0, start_pose: Pose2D | None = None) -> StepRecord:
        """A new episode at t = 0: the world, a fresh filter and frame tree, the driver.

        The first reset builds the world; the later ones reset it
        (``World.reset``: the same episode as a new world's, a fraction of the cost).

        Args:
            seed: the world's seed (every random stream derives from it).
            start_pose: the CG's pose to start from; default the track's start.

        Returns:
            The t = 0 record: the first captures, the first broadcast, the
            driver's first command.
        """
        world = self._world
        if world is None:  # the first episode builds the world; later ones reset it
            self._world = world = World(self.track, self.world_config, seed, start_pose)
            first = world.initial_messages
        else:  # the same episode as a new world's, bit for bit (World.reset)
            first = world.reset(seed, start_pose)
        self.world = world
        slam = None
        if self.localization == "slam":
            slam = SlamUpdate(self.cone_config, self.slam_config, start=world.antenna_pose)
        self.localizer = Localizer(
            self.localization, self.ekf_config, self.world_config.origin,
            cones=self.cone_update, slam=slam,
        )  # fmt: skip
        sent = self.localizer.step(0.0, first, world.antenna_pose)
        factory = self._driver_factory
        self.driver = (
            None
            if factory is None
            else factory(self.localizer.frames, self.global_path, control_rate=self.control_rate)
        )
        self._cones = np.array(world.cones.positions)
        self._cones.setflags(write=False)
        self._cone_version = world.cones.version
        self._command = ControlCommand(0.0, 0.0, 0.0)
        deliveries = tuple(Delivery(0.0, m) for m in first)
        local_xy = tuple(Delivery(0.0, p) for p in sent.local_xy)
        broadcasts = (
            () if sent.transform is None else (Broadcast(sent.transform, world.antenna_pose),)
        )
        self.record = self._finish(deliveries, local_xy, broadcasts, [], first)
        return self.record

    def step(self, command: ControlCommand | None = None) -> StepRecord:
        """One control period; ``command`` (without a driver) is held over it."""
        if self.record is None:
            raise RuntimeError("ClosedLoop.step() before reset()")
        if command is not None:
            self._set_command(command)
        world, localizer = self.world, self.localizer
        deliveries: list[Delivery] = []
        local_xy: list[Delivery] = []
        broadcasts: list[Broadcast] = []
        events: list[Event] = []
        for _ in range(self.substeps):
            tick = world.step()  # 1. physics, race control, sensors
            sent = localizer.step(tick.t, tick.messages, world.antenna_pose)  # 2. frame tree
            if tick.messages:  # most physics steps deliver nothing
                deliveries += [Delivery(tick.t, m) for m in tick.messages]
                if sent.local_xy:
                    local_xy += [Delivery(tick.t, p) for p in sent.local_xy]
            if sent.transform is not None:
                broadcasts.append(Broadcast(sent.transform, world.antenna_pose))
            if tick.events:
                events += tick.events
        messages = [d.message for d in deliveries]
        self.record = self._finish(
            tuple(deliveries), tuple(local_xy), tuple(broadcasts), events, messages
        )  # 3. and 4., the driver and its command
        return self.record

    def _finish(
        self,
        deliveries: tuple[Delivery, ...],
        local_xy: tuple[Delivery, ...],
        broadcasts: tuple[Broadcast, ...],
        events: list[Event],
        messages: list[Message],
    ) -> StepRecord:
        """The driver's step and command, then the record with the truth and the end."""
        world = self.world
        t = world.time
        out = None if self.driver is None else self.driver.step(t, messages)
        if out is not None:
            self._set_command(out.command)
        cones = world.cones
        moved = cones.version != self._cone_version
        if moved:
            self._cone_version = cones.version
            self._cones = np.array(cones.positions)
            self._cones.setflags(write=False)
        race = world.standing()
        truth = Truth(world.state, world.antenna_pose, self._cones, moved, race)
        return StepRecord(
            t=t,
            deliveries=deliveries,
            local_xy=local_xy,
            broadcasts=broadcasts,
            driver=out,
            command=self._command,
            truth=truth,
            events=tuple(events),
            end=self._end(t, race),
        )

    def _set_command(self, command: ControlCommand) -> None:
        self._command = command
        self.world.set_command(command.steering, command.acceleration)

    def _end(self, t: float, race: RaceStanding) -> EndReason | None:
        """Why the episode ends now, or None (in this order of precedence)."""
        rules = self.rules
        if race.laps_completed >= self.laps_to_drive:
            return EndReason.LAPS_COMPLETED
        if rules.end_on_off_track and race.off_track_events:
            return EndReason.OFF_TRACK
        if rules.end_on_stuck and race.stuck and t >= rules.stuck_grace - _TIME_EPS:
            return EndReason.STUCK
        if t >= rules.time_limit_s - _TIME_EPS:
            return EndReason.TIME_LIMIT
        return None
