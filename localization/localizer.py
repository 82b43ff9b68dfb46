"""The car's localization: measurements in, the frame tree out (spec 000).

One :class:`Localizer` per car wires the ROS pipeline's localization nodes into one
frame tree, in one of five modes (``LOCALIZATION_MODES``):

- ``fused`` (default): every measurement goes into the fusion EKF
  (``localization.ekf``); the broadcaster publishes its estimate.
- ``cones``: as ``fused``, and each cone scan is matched to a known cone map
  and updates the filter's pose (``localization.cones``).
- ``slam``: as ``fused``, and the cone scans build the map the filter
  localizes against, the landmarks in its state (``localization.slam``).
- ``raw``: the ROS pipeline as written: ``/ublox_gps_node/fix`` ->
  ``gps_to_local_cartesian`` -> ``/local_xy``, and ``/global_yaw``, cached
  by the broadcaster.
- ``truth``: the broadcaster publishes the true pose the caller passes (a
  baseline and a debugging aid; the only mode that reads the truth).

In every mode each fix also becomes a ``/local_xy`` point, and the
broadcaster publishes ``reference -> gps_antenna`` on its 20 Hz grid and
``gps_antenna -> os_sensor`` once (``localization.broadcaster``).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

from conesim.core.geodesy import DEFAULT_ORIGIN, ReferenceOrigin
from conesim.core.messages import (
    FRAME_GPS_ANTENNA,
    FRAME_REFERENCE,
    HeadingStamped,
    Message,
    NavSatFix,
    PointStamped,
)
from conesim.core.pose import Pose2D
from conesim.localization.broadcaster import BroadcasterConfig, VehicleTfBroadcaster
from conesim.localization.cones import ConeUpdate
from conesim.localization.ekf import EkfConfig, Estimate, FusionEkf
from conesim.localization.frames import LATEST, Buffer, TransformError, TransformStamped
from conesim.localization.gps_to_local import GpsToLocalCartesian
from conesim.localization.modes import LOCALIZATION_MODES, LocalizationMode
from conesim.localization.slam import SlamUpdate


@dataclass(frozen=True, slots=True)
class LocalizationStep:
    """What localization passed on in one tick.

    Attributes:
        local_xy: the ``/local_xy`` points made from this tick's fixes.
        transform: the ``reference -> gps_antenna`` transform broadcast, or None.
    """

    local_xy: tuple[PointStamped, ...]
    transform: TransformStamped | None


# What most ticks pass on (no fix delivered, no broadcast due): one shared, immutable step.
_QUIET = LocalizationStep((), None)


class Localizer:
    """GPS-to-local, the fusion EKF and the TF broadcaster around one frame tree.

    Args:
        mode: ``fused``, ``raw``, ``truth``, ``cones`` or ``slam``.
        ekf: the filter's settings (``fused``, ``cones``, ``slam``; see ``ekf.for_profile``).
        origin: the geodetic origin of ``reference``.
        broadcaster: the broadcaster's rate and frame names (its mode is ``mode``).
        cones: the cone map and its update (required in ``cones`` mode, else unused).
        slam: the map-building update (``slam`` mode; default ``SlamUpdate()``,
            starting at the first fix).

    Attributes:
        frames: the frame tree (tf2's buffer) the car's software reads.
        ekf: the fusion filter in ``fused``, ``cones`` and ``slam`` modes, else None.
        broadcaster: the vehicle TF broadcaster.

    Raises:
        ValueError: an unknown mode, or ``cones`` without a map.
    """

    def __init__(
        self,
        mode: str = "fused",
        ekf: EkfConfig | None = None,
        origin: ReferenceOrigin = DEFAULT_ORIGIN,
        broadcaster: BroadcasterConfig | None = None,
        *,
        cones: ConeUpdate | None = None,
        slam: SlamUpdate | None = None,
    ) -> None:
        if mode not in LOCALIZATION_MODES:
            raise ValueError(
                f"unknown localization mode {mode!r}; allowed: {list(LOCALIZATION_MODES)}"
            )
        self.mode = LocalizationMode(mode)
        self.frames = Buffer()
        if self.mode is LocalizationMode.CONES and cones is None:
            raise ValueError("localization mode 'cones' needs the cone map (cones=ConeUpdate(...))")
        self.ekf: FusionEkf | None = None
        if self.mode is LocalizationMode.FUSED:
            self.ekf = FusionEkf(ekf)
        elif self.mode is LocalizationMode.CONES:
            self.ekf = FusionEkf(ekf, cones)
        elif self.mode is LocalizationMode.SLAM:
            self.ekf = FusionEkf(ekf, slam or SlamUpdate())
        self._gps_to_local = GpsToLocalCartesian(origin)
        config = dataclasses.replace(broadcaster or BroadcasterConfig(), mode=self.mode)
        self.broadcaster = VehicleTfBroadcaster(self.frames, config, ekf=self.ekf)

    def step(self, t: float, messages: list[Message], truth: Pose2D) -> LocalizationStep:
        """Handle the messages delivered at ``t`` [s], then broadcast if due.

        Args:
            t: the tick's time [s].
            messages: the measurements delivered now, in stamp order.
            truth: the antenna's true pose now (published in ``truth`` mode only).
        """
        points = tuple(self.handle(messages)) if messages else ()  # most ticks deliver nothing
        transform = self.broadcaster.step(t, truth)
        if not points and transform is None:
            return _QUIET
        return LocalizationStep(points, transform)

    def handle(self, messages: list[Message]) -> list[PointStamped]:
        """Each message to the ROS pipeline's nodes and the filter; the ``/local_xy`` points."""
        points: list[PointStamped] = []
        broadcaster = self.broadcaster
        ekf = self.ekf
        for msg in messages:
            if isinstance(msg, NavSatFix):
                point = self._gps_to_local(msg)
                if point is not None:
                    points.append(point)
                    broadcaster.on_local_xy(point)
            elif isinstance(msg, HeadingStamped):
                broadcaster.on_global_yaw(msg)
            if ekf is not None:
                ekf.process(msg)
        return points

    def published_pose(self) -> Pose2D | None:
        """``reference -> gps_antenna`` as the frame tree holds it now (the last
        broadcast), or None before the first one."""
        try:
            return self.frames.lookup_pose2d(FRAME_REFERENCE, FRAME_GPS_ANTENNA, LATEST)
        except TransformError:
            return None

    def estimate(self, t: float) -> Estimate | None:
        """The filter's estimate at ``t`` [s] (``fused``, ``cones``, ``slam``; once initialised)."""
        if self.ekf is None or not self.ekf.initialised:
            return None
        return self.ekf.estimate(t)
