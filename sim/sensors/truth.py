"""What the simulator hands to the sensors at a physics step.

Ground truth enters the sensor models only through ``TruthSample``, so the
models stay independent of pymunk and of the world class.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from conesim.core.pose import Pose2D
from conesim.sim.sensors.cone_map import ConeMap


def _no_cones() -> NDArray[np.float64]:
    return np.zeros((0, 2))


@dataclass(frozen=True, slots=True)
class TruthSample:
    """The true state at one physics step.

    Attributes:
        t: simulation time [s]; increases from one call to the next.
        antenna_pose: ``gps_antenna`` in ``reference`` (x, y [m], yaw [rad]);
            ``os_sensor`` has the same planar pose, 0.1 m lower.
        speed: forward speed of the body at the antenna, v_x [m/s].
        yaw_rate: mean over the last physics step [rad/s], counter-clockwise
            positive (what an integrating gyro sees).
        accel_x: longitudinal specific force at the IMU (at the antenna), mean
            over the last physics step [m/s^2].
        accel_y: lateral specific force, positive to the left [m/s^2].
        cone_positions: (n, 2) cone positions in ``reference`` [m].
        cone_kinds: n kinds from ``CONE_COLOURS``.
        cone_map: optional index of the same cones (positions updated by the
            world each step); without it the detector scans all n cones.
    """

    t: float
    antenna_pose: Pose2D
    speed: float = 0.0
    yaw_rate: float = 0.0
    accel_x: float = 0.0
    accel_y: float = 0.0
    cone_positions: NDArray[np.float64] = field(default_factory=_no_cones)
    cone_kinds: tuple[str, ...] = ()
    cone_map: ConeMap | None = None

    def __post_init__(self) -> None:
        shape = np.shape(self.cone_positions)
        if len(shape) != 2 or shape[1] != 2:
            raise ValueError(f"TruthSample.cone_positions must be (n, 2), got {shape}")
        if len(self.cone_kinds) != shape[0]:
            raise ValueError(
                f"TruthSample.cone_kinds has {len(self.cone_kinds)} kinds for {shape[0]} cones"
            )
        if self.cone_map is not None and len(self.cone_map) != shape[0]:
            raise ValueError(
                f"TruthSample.cone_map has {len(self.cone_map)} cones, positions {shape[0]}"
            )

    @classmethod
    def trusted(
        cls,
        t: float,
        antenna_pose: Pose2D,
        *,
        speed: float,
        yaw_rate: float,
        accel_x: float,
        accel_y: float,
        cone_positions: NDArray[np.float64],
        cone_kinds: tuple[str, ...],
        cone_map: ConeMap | None,
    ) -> TruthSample:
        """A sample built without the shape checks of ``__init__``.

        For a caller that passes the same, already checked cone arrays at
        every physics step (``World``); everything else uses the constructor.
        """
        self = object.__new__(cls)
        setattr_ = object.__setattr__
        setattr_(self, "t", t)
        setattr_(self, "antenna_pose", antenna_pose)
        setattr_(self, "speed", speed)
        setattr_(self, "yaw_rate", yaw_rate)
        setattr_(self, "accel_x", accel_x)
        setattr_(self, "accel_y", accel_y)
        setattr_(self, "cone_positions", cone_positions)
        setattr_(self, "cone_kinds", cone_kinds)
        setattr_(self, "cone_map", cone_map)
        return self
