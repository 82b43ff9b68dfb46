"""Message types: what travels between the simulated car and its software.

Each mirrors the ROS message the ROS pipeline uses, reduced to what a 2D car needs, and
carries a ``Header`` with the capture stamp (simulation time [s]) and frame.
A dependency-free leaf module (numpy only): the simulator's sensor models build
these messages and ``localization``/``planner`` consume them, as every ROS node
shares ``sensor_msgs``.

Messages do not validate their numbers: a real driver can publish a NaN, and
the consumers (the EKF, the planner) must reject such a message with a counted
reason. Shapes are checked, since a wrong shape is a programming error.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import IntEnum

import numpy as np
from numpy.typing import NDArray

FRAME_REFERENCE = "reference"
FRAME_GPS_ANTENNA = "gps_antenna"
FRAME_OS_SENSOR = "os_sensor"

# Colour labels a cone detector may attach (sensor_msgs has no cone type; these
# are the FS cone colours plus "unknown" for a LiDAR-only detection).
CONE_COLOURS = ("blue", "yellow", "orange", "big_orange", "unknown")


@dataclass(frozen=True, slots=True)
class Header:
    """std_msgs/Header: capture time and frame.

    Attributes:
        stamp: capture time in simulation time [s].
        frame_id: the frame the data is expressed in.
    """

    stamp: float
    frame_id: str


class NavSatStatus(IntEnum):
    """sensor_msgs/NavSatStatus.status values."""

    NO_FIX = -1
    FIX = 0
    SBAS_FIX = 1
    GBAS_FIX = 2  # ground-based augmentation, e.g. RTK


@dataclass(frozen=True, slots=True)
class NavSatFix:
    """sensor_msgs/NavSatFix (the ROS pipeline's ``/ublox_gps_node/fix``).

    Attributes:
        header: stamp and frame (``gps_antenna``).
        latitude: [deg].
        longitude: [deg].
        altitude: [m].
        position_covariance: (3, 3) ENU covariance [m^2], row-major as in ROS.
        status: fix status.
    """

    header: Header
    latitude: float
    longitude: float
    altitude: float
    position_covariance: NDArray[np.float64]
    status: NavSatStatus = NavSatStatus.FIX

    def __post_init__(self) -> None:
        if np.shape(self.position_covariance) != (3, 3):
            raise ValueError(
                f"NavSatFix.position_covariance must be (3, 3), got "
                f"{np.shape(self.position_covariance)}"
            )


@dataclass(frozen=True, slots=True)
class PointStamped:
    """geometry_msgs/PointStamped (the ROS pipeline's ``/local_xy``) [m]."""

    header: Header
    x: float
    y: float
    z: float = 0.0


@dataclass(frozen=True, slots=True)
class HeadingStamped:
    """The ROS pipeline's ``/global_yaw`` (std_msgs/Float32 in radians), stamped.

    Attributes:
        header: stamp and frame (``reference``: yaw of ``gps_antenna`` in it).
        yaw: heading, counter-clockwise from east [rad].
        variance: the sensor's stated variance [rad^2].
    """

    header: Header
    yaw: float
    variance: float


@dataclass(frozen=True, slots=True)
class Imu:
    """The planar part of sensor_msgs/Imu, in the vehicle frame.

    Attributes:
        header: stamp and frame (``gps_antenna``).
        yaw_rate: angular velocity about z [rad/s].
        accel_x: longitudinal specific force [m/s^2].
        accel_y: lateral specific force [m/s^2].
        yaw_rate_variance: [rad^2/s^2].
        accel_variance: per axis [m^2/s^4].
    """

    header: Header
    yaw_rate: float
    accel_x: float
    accel_y: float
    yaw_rate_variance: float
    accel_variance: float


@dataclass(frozen=True, slots=True)
class WheelSpeed:
    """Vehicle speed from the wheel encoders [m/s], with its variance [m^2/s^2]."""

    header: Header
    speed: float
    variance: float


@dataclass(frozen=True, slots=True)
class ConeDetections:
    """The ROS pipeline's ``/sorted_cones_time``: cones in ``os_sensor``, nearest first.

    Attributes:
        header: capture stamp and frame (``os_sensor``).
        points: (n, 3) cone positions [m], sorted by distance from the sensor.
        colours: n colour labels from ``CONE_COLOURS``, or None for a
            colour-blind detector.
    """

    header: Header
    points: NDArray[np.float64]
    colours: tuple[str, ...] | None = None

    def __post_init__(self) -> None:
        shape = np.shape(self.points)
        if len(shape) != 2 or shape[1] != 3:
            raise ValueError(f"ConeDetections.points must be (n, 3), got {shape}")
        if self.colours is not None:
            if len(self.colours) != shape[0]:
                raise ValueError(
                    f"ConeDetections.colours has {len(self.colours)} labels for {shape[0]} points"
                )
            unknown = set(self.colours).difference(CONE_COLOURS)
            if unknown:
                raise ValueError(
                    f"ConeDetections.colours: unknown labels {sorted(unknown)}; "
                    f"allowed: {list(CONE_COLOURS)}"
                )

    def __len__(self) -> int:
        return int(np.shape(self.points)[0])


Message = NavSatFix | HeadingStamped | Imu | WheelSpeed | ConeDetections | PointStamped
