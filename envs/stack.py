"""The vehicle stack the env hosts: world, localization and the frame tree.

One control period of the closed loop (``VehicleStack.run_physics_steps``),
for each physics substep (``physics_rate / control_rate`` of them):

1. ``world.step()``: physics, cones, race control, sensors; the measurements
   delivered at this step come back in stamp order;
2. localization handles each message as the seed's nodes would:
   ``/ublox_gps_node/fix`` -> ``gps_to_local_cartesian`` -> ``/local_xy``
   (raw mode), ``/global_yaw``, IMU and wheel speed into the EKF (fused mode);
3. the vehicle TF broadcaster publishes ``reference -> gps_antenna`` into the
   buffer on its 20 Hz grid (``os_sensor`` is static, sent once); at each
   broadcast the published pose and the antenna's true pose are kept as a
   ``LocalizationSample``, the localization error as the rest of the car's
   software sees it.

What went through localization in the last control period is kept in
``VehicleStack.traffic``, each item with the simulation time it was passed
on: every measurement delivered (at its delivery step), every ``/local_xy``
point ``gps_to_local_cartesian`` made, every ``reference -> gps_antenna``
transform broadcast. A recorder (``envs.bag``) reads it; nothing in the loop
does.

The stack never decides the actuator command: the env's action (or the
autopilot policy acting through it) does.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from conesim.core.messages import (
    FRAME_GPS_ANTENNA,
    FRAME_REFERENCE,
    HeadingStamped,
    Message,
    NavSatFix,
)
from conesim.core.pose import Pose2D
from conesim.envs.config import LOCALIZATION_MODES
from conesim.localization.broadcaster import BroadcasterConfig, BroadcastMode, VehicleTfBroadcaster
from conesim.localization.ekf import PROFILES as EKF_PROFILES
from conesim.localization.ekf import Estimate, FusionEkf, for_profile
from conesim.localization.frames import LATEST, Buffer, TransformError, TransformStamped
from conesim.localization.gps_to_local import GpsToLocalCartesian
from conesim.sim.world import World, WorldConfig
from conesim.tracks import Track
from conesim.tracks.global_path import GlobalPath, global_path_for_track

Traffic = list[tuple[float, Message | TransformStamped]]
"""``(time [s], item)`` in the order localization passed them on: measurements
delivered, ``/local_xy`` points (``PointStamped``) and dynamic transforms."""


@dataclass(frozen=True, slots=True)
class LocalizationSample:
    """One broadcast of ``reference -> gps_antenna`` against the truth.

    Attributes:
        t: broadcast time [s].
        published: the pose the frame tree holds for ``t``.
        truth: the antenna's true pose at ``t``.
    """

    t: float
    published: Pose2D
    truth: Pose2D

    @property
    def position_error(self) -> float:
        """Distance between published and true antenna position [m]."""
        return math.hypot(self.published.x - self.truth.x, self.published.y - self.truth.y)

    @property
    def yaw_error(self) -> float:
        """Absolute heading error, wrapped [rad]."""
        return abs(math.remainder(self.published.yaw - self.truth.yaw, 2.0 * math.pi))


class VehicleStack:
    """World + localization + frame tree for one car.

    Args:
        track: the track.
        world_config: physics, sensors and vehicle settings.
        localization: ``fused`` (EKF, default), ``raw`` (the seed's /local_xy +
            /global_yaw) or ``truth``.
        seed: episode seed.
    """

    def __init__(
        self,
        track: Track,
        world_config: WorldConfig,
        localization: str = "fused",
        seed: int = 0,
        start_pose: Pose2D | None = None,
    ) -> None:
        if localization not in LOCALIZATION_MODES:
            raise ValueError(
                f"unknown localization mode {localization!r}; allowed: {list(LOCALIZATION_MODES)}"
            )
        self.track = track
        self.world_config = world_config
        self.localization = localization
        self.global_path: GlobalPath = global_path_for_track(track, world_config.origin)
        self.start_pose = start_pose
        self.initial_messages = self.reset(seed)

    def reset(self, seed: int) -> list[Message]:
        """New episode: world at t = 0, a fresh filter and frame tree.

        Returns:
            The measurements captured at t = 0 (already given to localization).
        """
        self.world = World(self.track, self.world_config, seed=seed, start_pose=self.start_pose)
        first = self.world.initial_messages  # the t = 0 captures
        self.buffer = Buffer()
        profile = self.world_config.sensor_profile.name
        self.ekf = FusionEkf(for_profile(profile if profile in EKF_PROFILES else "rtk"))
        self.gps_to_local = GpsToLocalCartesian(self.world_config.origin)
        mode = BroadcastMode(self.localization)
        self.broadcaster = VehicleTfBroadcaster(
            self.buffer,
            BroadcasterConfig(mode=mode),
            ekf=self.ekf if mode == BroadcastMode.FUSED else None,
        )
        self.localization_samples: list[LocalizationSample] = []
        self.traffic: Traffic = []  # this period's; reset(): the t = 0 ones
        self._handle(first)
        self._broadcast()
        return first

    @property
    def time(self) -> float:
        """Simulation time [s]."""
        return self.world.time

    def run_physics_steps(self, n: int) -> list[Message]:
        """Advance ``n`` physics steps with the held command; all deliveries, in order."""
        out: list[Message] = []
        self.traffic = []
        for _ in range(n):
            delivered = self.world.step()
            self._handle(delivered)
            self._broadcast()
            out.extend(delivered)
        return out

    def _broadcast(self) -> None:
        truth = self.world.antenna_pose
        t = self.world.time
        sent = self.broadcaster.step(t, truth)
        if sent is not None:
            self.localization_samples.append(LocalizationSample(t, sent.to_pose2d(), truth))
            self.traffic.append((t, sent))

    def _handle(self, messages: list[Message]) -> None:
        t = self.world.time
        traffic = self.traffic
        for msg in messages:
            traffic.append((t, msg))
            if isinstance(msg, NavSatFix):
                point = self.gps_to_local(msg)
                if point is not None:
                    traffic.append((t, point))
                    self.broadcaster.on_local_xy(point)
            elif isinstance(msg, HeadingStamped):
                self.broadcaster.on_global_yaw(msg)
            if self.localization == "fused":
                self.ekf.process(msg)

    def published_pose(self) -> Pose2D | None:
        """``reference -> gps_antenna`` as the frame tree holds it now (the last
        broadcast, all three modes), or None before the first one."""
        try:
            return self.buffer.lookup_pose2d(FRAME_REFERENCE, FRAME_GPS_ANTENNA, LATEST)
        except TransformError:
            return None

    def estimate(self) -> Estimate | None:
        """The filter's estimate now (fused mode, once initialised), else None."""
        if self.localization != "fused" or not self.ekf.initialised:
            return None
        return self.ekf.estimate(self.world.time)
