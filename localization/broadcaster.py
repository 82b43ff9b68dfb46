"""The ROS pipeline's ``vehicle_tf_broadcaster``: the vehicle's frames into the frame tree.

Spec 000, "Vehicle Pose TF Broadcaster" and "Integrating GPS-IMU Fusion into
the TF Chain". Whatever the pose source, the broadcaster publishes the same
two links into a :class:`~localization.frames.Buffer`::

    reference --(dynamic, 20 Hz)--> gps_antenna --(static, once: z = -0.1 m, identity)--> os_sensor

Modes (:class:`LocalizationMode`):

* ``raw``: the ROS pipeline as written. ``on_local_xy`` caches the last ``/local_xy``
  (x, y, z) and ``on_global_yaw`` the last ``/global_yaw``; each broadcast sends
  translation (x, y, z) and the rotation ``setRPY(0, 0, yaw)``, i.e. the
  quaternion (0, 0, sin(yaw/2), cos(yaw/2)). Unlike the ROS pipeline, whose cached
  values start at zero, nothing is sent until both have arrived (a car at the
  origin facing east is a wrong pose, not a default), and a non-finite value
  is dropped with a logged warning instead of being broadcast.
* ``fused`` (the default): the fusion EKF's estimate at the broadcast time
  (predicted from its newest input), at z = 0; nothing before it initialises.
* ``cones``: the same, from the filter that also fuses the cone scans
  against the map (``localization.cones``).
* ``truth``: a pose the caller passes at each step (ground truth, for
  debugging and RL baselines; only ``sim``/``envs`` have it).

The dynamic transform is stamped with the broadcast time (the ROS pipeline stamps it
with ``now()``); :meth:`VehicleTfBroadcaster.step` is called at every loop
tick and publishes at the first tick at or after each 1 / ``rate`` grid time.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass

from conesim.core.messages import (
    FRAME_GPS_ANTENNA,
    FRAME_OS_SENSOR,
    FRAME_REFERENCE,
    HeadingStamped,
    PointStamped,
)
from conesim.core.pose import Pose2D
from conesim.localization.ekf import FusionEkf
from conesim.localization.frames import Buffer, TransformStamped
from conesim.localization.modes import LocalizationMode

TIME_EPS = 1e-9  # [s] tolerance of the broadcast clock

_log = logging.getLogger(__name__)


@dataclass(frozen=True, slots=True)
class BroadcasterConfig:
    """Settings of the vehicle TF broadcaster.

    Attributes:
        mode: ``raw``, ``fused`` or ``truth``.
        rate: broadcast rate of the dynamic transform [Hz].
        reference_frame: the world frame.
        antenna_frame: the vehicle frame (prefix it for several cars: ``car1/gps_antenna``).
        sensor_frame: the cone sensor's frame.
        sensor_offset: ``sensor_frame`` origin in ``antenna_frame`` (x, y, z) [m].
        authority: name recorded with every transform.
    """

    mode: LocalizationMode = LocalizationMode.FUSED
    rate: float = 20.0  # [Hz] spec 000
    reference_frame: str = FRAME_REFERENCE
    antenna_frame: str = FRAME_GPS_ANTENNA
    sensor_frame: str = FRAME_OS_SENSOR
    sensor_offset: tuple[float, float, float] = (0.0, 0.0, -0.1)  # [m] spec 000
    authority: str = "vehicle_tf_broadcaster"

    def __post_init__(self) -> None:
        allowed = [m.value for m in LocalizationMode]
        if self.mode not in allowed:
            raise ValueError(f"unknown broadcast mode {self.mode!r}; allowed: {allowed}")
        object.__setattr__(self, "mode", LocalizationMode(self.mode))
        if not (math.isfinite(self.rate) and self.rate > 0.0):
            raise ValueError(f"BroadcasterConfig.rate = {self.rate!r} out of range: allowed > 0 Hz")


class VehicleTfBroadcaster:
    """Publishes the vehicle's frames into a buffer (see the module docstring).

    The static ``gps_antenna -> os_sensor`` link is sent once, here, and kept
    as ``static_transform``.

    Args:
        buffer: the frame tree to publish into.
        config: settings; default ``fused`` at 20 Hz.
        ekf: the fusion filter (required in ``fused`` mode).

    Raises:
        ValueError: ``fused`` mode without a filter.
    """

    def __init__(
        self, buffer: Buffer, config: BroadcasterConfig | None = None, ekf: FusionEkf | None = None
    ) -> None:
        self.buffer = buffer
        self.config = config or BroadcasterConfig()
        if self.config.mode.uses_ekf and ekf is None:
            raise ValueError(
                f"broadcast mode {self.config.mode.value!r} needs the FusionEkf (ekf=...)"
            )
        self.ekf = ekf
        self.published = 0
        self._next_time: float | None = None
        self._xyz: tuple[float, float, float] | None = None
        self._yaw: float | None = None
        cfg = self.config
        self.static_transform = TransformStamped(
            cfg.antenna_frame, cfg.sensor_frame, 0.0, translation=cfg.sensor_offset
        )
        buffer.set_transform_static(self.static_transform, cfg.authority)

    # -- the ROS pipeline's subscriptions (raw mode) ----------------------------------------

    def on_local_xy(self, point: PointStamped) -> None:
        """Cache the last ``/local_xy`` position (x, y, z) [m] in ``reference``."""
        xyz = (point.x, point.y, point.z)
        if not all(math.isfinite(v) for v in xyz):
            _log.warning("vehicle_tf_broadcaster: dropped non-finite /local_xy %s", xyz)
            return
        self._xyz = xyz

    def on_global_yaw(self, heading: HeadingStamped) -> None:
        """Cache the last ``/global_yaw`` [rad]."""
        if not math.isfinite(heading.yaw):
            _log.warning("vehicle_tf_broadcaster: dropped non-finite /global_yaw %r", heading.yaw)
            return
        self._yaw = heading.yaw

    # -- broadcasting ------------------------------------------------------------------------

    def step(self, t: float, truth: Pose2D | None = None) -> TransformStamped | None:
        """Call at every loop tick; publishes when a 1 / rate grid time has come.

        Args:
            t: current time [s].
            truth: the true ``gps_antenna`` pose (``truth`` mode only).

        Returns:
            The dynamic transform published, or None (not due, or no pose yet).
        """
        if self._next_time is not None and t < self._next_time - TIME_EPS:
            return None
        rate = self.config.rate
        self._next_time = (math.floor(t * rate + TIME_EPS) + 1) / rate
        return self.publish(t, truth)

    def publish(self, t: float, truth: Pose2D | None = None) -> TransformStamped | None:
        """Publish ``reference -> gps_antenna`` at ``t`` [s] now, if a pose is available.

        Raises:
            ValueError: ``truth`` mode without a ``truth`` pose.
        """
        pose_z = self._pose(t, truth)
        if pose_z is None:
            return None
        pose, z = pose_z
        cfg = self.config
        transform = TransformStamped.from_pose2d(cfg.reference_frame, cfg.antenna_frame, t, pose, z)
        self.buffer.set_transform(transform, cfg.authority)
        self.published += 1
        return transform

    def _pose(self, t: float, truth: Pose2D | None) -> tuple[Pose2D, float] | None:
        """The pose and height to send in the current mode, or None if there is none yet."""
        mode = self.config.mode
        if mode == LocalizationMode.TRUTH:
            if truth is None:
                raise ValueError("broadcast mode 'truth' needs the true pose (truth=...)")
            return truth, 0.0
        if mode == LocalizationMode.RAW:
            if self._xyz is None or self._yaw is None:
                return None
            x, y, z = self._xyz
            return Pose2D(x, y, self._yaw), z
        assert self.ekf is not None  # checked in __init__
        if not self.ekf.initialised:
            return None
        try:
            return self.ekf.estimate(t).pose, 0.0
        except ValueError as err:  # t older than the filter's history
            _log.warning("vehicle_tf_broadcaster: no fused pose at %r s: %s", t, err)
            return None
