"""conesim's messages as ROS 2 messages (Humble types, through ``rosbags``).

One function per seed topic (``envs.bag`` has the topic table), each taking
the message the loop produced and returning the ``rosbags`` message object
that a ROS node would have published. Stamps become ``builtin_interfaces/Time``
of the simulation time; the simulation starts at 0, so a bag begins at the
epoch.

Choices where conesim's message is not a ROS one:

* IMU (``sensor_msgs/Imu``): planar, so the orientation is not given
  (``orientation_covariance[0] = -1``, as sensor_msgs documents), the angular
  velocity is (0, 0, yaw rate) with the yaw-rate variance at [2, 2], and the
  linear acceleration is the measured (x, y) specific force with
  z = +9.80665 m/s^2, what an accelerometer reads on level ground.
* Heading: ``/global_yaw`` is the ROS pipeline's ``std_msgs/Float32`` [rad] (no
  stamp, no variance). The same measurement, stamped at capture with its
  variance, is an orientation-only ``sensor_msgs/Imu`` in ``gps_antenna``
  (its yaw about z in the ENU ``reference``, variance at [2, 2], roll and
  pitch unmeasured: ``UNMEASURED_VARIANCE``; no angular velocity or
  acceleration: their covariance[0] = -1), as the u-blox driver's
  ``navheading`` carries a dual-antenna heading in its GPS frame.
* Wheel speed: ``geometry_msgs/TwistWithCovarianceStamped`` in the sensor's
  frame: linear.x the speed [m/s], covariance[0] its variance; the other
  components are not measured (zero, variance ``UNMEASURED_VARIANCE``).
  robot_localization takes a twist this way.
* Cone detections: the ROS pipeline's custom ``ModifiedFloat32MultiArray``
  (``CONE_ARRAY_DEFINITION``, registered as ``CONE_ARRAY_TYPE``): the
  header, a layout of two dimensions (``cones`` of size n, ``xyz`` of size
  3) and the cones as x, y, z float32 triples [m], nearest first. It has no
  colour field; the detector's colour labels are not recorded.
* ``/final_waypoints`` and ``/waypoint_speed_bars`` are MarkerArrays as in
  the ROS pipeline, each holding one list marker (a SPHERE_LIST of the waypoints; a
  LINE_LIST of vertical bars, ``SPEED_BAR_SCALE`` metres per m/s) rather than
  one marker per waypoint: the same picture at a quarter of the writing
  cost (0.8 against 3.4 ms for both topics at 40 waypoints; rosbags builds
  and serialises each marker field by field in Python).
"""

from __future__ import annotations

import functools
from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from rosbags.typesys import Stores, get_types_from_msg, get_typestore
from rosbags.typesys.store import Typestore
from rosbags.typesys.stores import ros2_humble as ros

from conesim.core.messages import (
    FRAME_GPS_ANTENNA,
    ConeDetections,
    Header,
    HeadingStamped,
    Imu,
    NavSatFix,
    PointStamped,
    WheelSpeed,
)
from conesim.core.pose import Pose2D
from conesim.envs.bag import CONE_ARRAY_TYPE
from conesim.localization.frames import TransformStamped
from conesim.localization.frames.rigid import quat_from_yaw
from conesim.planner.messages import BridgeLines, ConeMarker, LocalPath, Midpoints, Waypoints
from conesim.tracks.global_path import GlobalPath

# The Humble message classes (typed dataclasses).
Duration = ros.builtin_interfaces__msg__Duration
Time = ros.builtin_interfaces__msg__Time
Point = ros.geometry_msgs__msg__Point
RosPointStamped = ros.geometry_msgs__msg__PointStamped
Pose = ros.geometry_msgs__msg__Pose
PoseStamped = ros.geometry_msgs__msg__PoseStamped
PoseWithCovariance = ros.geometry_msgs__msg__PoseWithCovariance
Quaternion = ros.geometry_msgs__msg__Quaternion
Transform = ros.geometry_msgs__msg__Transform
RosTransformStamped = ros.geometry_msgs__msg__TransformStamped
Twist = ros.geometry_msgs__msg__Twist
TwistWithCovariance = ros.geometry_msgs__msg__TwistWithCovariance
TwistWithCovarianceStamped = ros.geometry_msgs__msg__TwistWithCovarianceStamped
Vector3 = ros.geometry_msgs__msg__Vector3
Odometry = ros.nav_msgs__msg__Odometry
RosPath = ros.nav_msgs__msg__Path
CompressedImage = ros.sensor_msgs__msg__CompressedImage
RosImu = ros.sensor_msgs__msg__Imu
RosNavSatFix = ros.sensor_msgs__msg__NavSatFix
RosNavSatStatus = ros.sensor_msgs__msg__NavSatStatus
ColorRGBA = ros.std_msgs__msg__ColorRGBA
Float32 = ros.std_msgs__msg__Float32
RosHeader = ros.std_msgs__msg__Header
MultiArrayDimension = ros.std_msgs__msg__MultiArrayDimension
MultiArrayLayout = ros.std_msgs__msg__MultiArrayLayout
TFMessage = ros.tf2_msgs__msg__TFMessage
Marker = ros.visualization_msgs__msg__Marker
MarkerArray = ros.visualization_msgs__msg__MarkerArray
MeshFile = ros.visualization_msgs__msg__MeshFile

CONE_ARRAY_DEFINITION = """\
# The ROS pipeline's /sorted_cones_time: std_msgs/Float32MultiArray with a header.
# data: the detected cones as x, y, z triples [m] in header.frame_id
# (os_sensor), nearest first; layout.dim: [cones (size n, stride 3 n),
# xyz (size 3, stride 3)]; header.stamp: the capture time.
std_msgs/Header header
std_msgs/MultiArrayLayout layout
float32[] data
"""

STANDARD_GRAVITY = 9.80665  # [m/s^2] the z specific force of a level IMU
SPEED_BAR_SCALE = 0.1  # [m per m/s] height of a waypoint's speed bar
NOT_GIVEN = -1.0  # covariance[0] of a field a sensor_msgs message does not carry

# Marker sizes (x, y, z) [m]: sphere diameters; a line's width is x.
CONE = (0.3, 0.3, 0.3)
WAYPOINT = (0.2, 0.2, 0.2)
MIDPOINT = (0.15, 0.15, 0.15)
SPEED_BAR = (0.1, 0.0, 0.0)
BRIDGE_LINE = (0.05, 0.0, 0.0)
PATH_LINE = (0.1, 0.0, 0.0)

# RViz colours (r, g, b, a) of the ROS pipeline's markers and the cone kinds.
BLUE = (0.0, 0.0, 1.0, 1.0)
YELLOW = (1.0, 1.0, 0.0, 1.0)
MAGENTA = (1.0, 0.0, 1.0, 1.0)
GREEN = (0.0, 0.8, 0.0, 1.0)
RED = (1.0, 0.0, 0.0, 1.0)
GREY = (0.6, 0.6, 0.6, 1.0)
BAR_GREEN = (0.0, 1.0, 0.0, 0.5)
CONE_KIND_COLOURS = {
    "blue": BLUE,
    "yellow": YELLOW,
    "orange": (1.0, 0.5, 0.0, 1.0),
    "big_orange": (1.0, 0.3, 0.0, 1.0),
    "unknown": GREY,
}

_NO_TEXTURE = CompressedImage(
    header=RosHeader(stamp=Time(sec=0, nanosec=0), frame_id=""),
    format="",
    data=np.zeros(0, dtype=np.uint8),
)
_NO_MESH = MeshFile(filename="", data=np.zeros(0, dtype=np.uint8))
_FOREVER = Duration(sec=0, nanosec=0)  # a marker's lifetime: until replaced
_IDENTITY = Quaternion(x=0.0, y=0.0, z=0.0, w=1.0)


@functools.cache
def typestore() -> Typestore:
    """ROS 2 Humble's types plus ``CONE_ARRAY_TYPE``."""
    store = get_typestore(Stores.ROS2_HUMBLE)
    store.register(get_types_from_msg(CONE_ARRAY_DEFINITION, CONE_ARRAY_TYPE))
    return store


def nanoseconds(t: float) -> int:
    """Simulation time [s] in whole nanoseconds."""
    return round(t * 1e9)


def ros_time(t: float) -> Time:
    """``builtin_interfaces/Time`` of a simulation time [s]."""
    sec, nanosec = divmod(nanoseconds(t), 1_000_000_000)
    return Time(sec=sec, nanosec=nanosec)


def ros_header(header: Header) -> RosHeader:
    """``std_msgs/Header``: the same stamp and frame."""
    return RosHeader(stamp=ros_time(header.stamp), frame_id=header.frame_id)


def _yaw_quaternion(yaw: float) -> Quaternion:
    x, y, z, w = quat_from_yaw(yaw)
    return Quaternion(x=x, y=y, z=z, w=w)


UNMEASURED_VARIANCE = 1e6
"""The variance of a component a message carries but nothing measured (ROS has no
"unknown" per component; a huge variance tells a filter to give it no weight)."""


def _diagonal3(a: float, b: float, c: float) -> NDArray[np.float64]:
    """A row-major 3 x 3 covariance with ``a``, ``b``, ``c`` on its diagonal."""
    return np.array((a, 0.0, 0.0, 0.0, b, 0.0, 0.0, 0.0, c))


def _not_given() -> NDArray[np.float64]:
    covariance = np.zeros(9)
    covariance[0] = NOT_GIVEN
    return covariance


def _points(xy: ArrayLike) -> list[Point]:
    """(n, 2) [m] as geometry_msgs/Point on the ground (z = 0)."""
    return [Point(x=x, y=y, z=0.0) for x, y in np.asarray(xy, dtype=float).reshape(-1, 2).tolist()]


def _colour(rgba: tuple[float, float, float, float]) -> ColorRGBA:
    r, g, b, a = rgba
    return ColorRGBA(r=r, g=g, b=b, a=a)


def _marker(
    header: RosHeader,
    ns: str,
    kind: int,
    points: list[Point],
    *,
    scale: tuple[float, float, float],
    colour: tuple[float, float, float, float],
    colours: Sequence[tuple[float, float, float, float]] = (),
) -> Marker:
    """A list-type marker (points in ``header.frame_id``), id 0, added or replaced."""
    sx, sy, sz = scale
    return Marker(
        header=header,
        ns=ns,
        id=0,
        type=kind,
        action=Marker.ADD,
        pose=Pose(position=Point(x=0.0, y=0.0, z=0.0), orientation=_IDENTITY),
        scale=Vector3(x=sx, y=sy, z=sz),
        color=_colour(colour),
        lifetime=_FOREVER,
        frame_locked=False,
        points=points,
        colors=[_colour(c) for c in colours],
        texture_resource="",
        texture=_NO_TEXTURE,
        uv_coordinates=[],
        text="",
        mesh_resource="",
        mesh_file=_NO_MESH,
        mesh_use_embedded_materials=False,
    )


def _marker_array(marker: Marker) -> MarkerArray:
    """A MarkerArray of one marker.

    rosbags' Humble MarkerArray class is annotated with the Dashing Marker
    (Humble's Marker has the texture and mesh fields); its typestore
    serialises Humble's, so the annotation alone is cast away.
    """
    markers: list[Any] = [marker]
    return MarkerArray(markers=markers)


# -- sensors and localization ---------------------------------------------------------------


def nav_sat_fix(fix: NavSatFix) -> RosNavSatFix:
    """``/ublox_gps_node/fix``: the fix with its stated ENU covariance (type KNOWN)."""
    return RosNavSatFix(
        header=ros_header(fix.header),
        status=RosNavSatStatus(status=int(fix.status), service=RosNavSatStatus.SERVICE_GPS),
        latitude=fix.latitude,
        longitude=fix.longitude,
        altitude=fix.altitude,
        position_covariance=np.asarray(fix.position_covariance, dtype=np.float64).reshape(9),
        position_covariance_type=RosNavSatFix.COVARIANCE_TYPE_KNOWN,
    )


def local_xy(point: PointStamped) -> RosPointStamped:
    """``/local_xy``: ``gps_to_local_cartesian``'s point in ``reference``."""
    return RosPointStamped(
        header=ros_header(point.header), point=Point(x=point.x, y=point.y, z=point.z)
    )


def global_yaw(heading: HeadingStamped) -> Float32:
    """``/global_yaw``: the ROS pipeline's bare heading [rad]."""
    return Float32(data=heading.yaw)


def heading_orientation(heading: HeadingStamped) -> RosImu:
    """The heading as an orientation-only ``sensor_msgs/Imu`` (see the module docs)."""
    # The orientation of the antenna's body frame in the world, as the u-blox
    # driver's navheading gives its GPS frame's; roll and pitch unmeasured.
    header = Header(heading.header.stamp, FRAME_GPS_ANTENNA)
    return RosImu(
        header=ros_header(header),
        orientation=_yaw_quaternion(heading.yaw),
        orientation_covariance=_diagonal3(
            UNMEASURED_VARIANCE, UNMEASURED_VARIANCE, heading.variance
        ),
        angular_velocity=Vector3(x=0.0, y=0.0, z=0.0),
        angular_velocity_covariance=_not_given(),
        linear_acceleration=Vector3(x=0.0, y=0.0, z=0.0),
        linear_acceleration_covariance=_not_given(),
    )


def imu(msg: Imu) -> RosImu:
    """The planar IMU as ``sensor_msgs/Imu`` (see the module docs)."""
    return RosImu(
        header=ros_header(msg.header),
        orientation=_IDENTITY,
        orientation_covariance=_not_given(),
        angular_velocity=Vector3(x=0.0, y=0.0, z=msg.yaw_rate),
        angular_velocity_covariance=_diagonal3(0.0, 0.0, msg.yaw_rate_variance),
        linear_acceleration=Vector3(x=msg.accel_x, y=msg.accel_y, z=STANDARD_GRAVITY),
        linear_acceleration_covariance=_diagonal3(msg.accel_variance, msg.accel_variance, 0.0),
    )


def wheel_speed(msg: WheelSpeed) -> TwistWithCovarianceStamped:
    """The wheel speed as a twist: linear.x [m/s] with its variance at [0, 0].

    The other five components are zero and unmeasured (``UNMEASURED_VARIANCE``).
    """
    covariance = np.diag([msg.variance] + [UNMEASURED_VARIANCE] * 5).ravel()
    return TwistWithCovarianceStamped(
        header=ros_header(msg.header),
        twist=TwistWithCovariance(
            twist=Twist(
                linear=Vector3(x=msg.speed, y=0.0, z=0.0),
                angular=Vector3(x=0.0, y=0.0, z=0.0),
            ),
            covariance=covariance,
        ),
    )


def cone_array(detections: ConeDetections) -> object:
    """``/sorted_cones_time`` as ``CONE_ARRAY_TYPE``."""
    n = len(detections)
    cls = typestore().types[CONE_ARRAY_TYPE]
    return cls(
        header=ros_header(detections.header),
        layout=MultiArrayLayout(
            dim=[
                MultiArrayDimension(label="cones", size=n, stride=3 * n),
                MultiArrayDimension(label="xyz", size=3, stride=3),
            ],
            data_offset=0,
        ),
        data=np.asarray(detections.points, dtype=np.float32).reshape(-1),
    )


def _transform(transform: TransformStamped) -> RosTransformStamped:
    tx, ty, tz, qx, qy, qz, qw = transform.rigid
    return RosTransformStamped(
        header=RosHeader(stamp=ros_time(transform.stamp), frame_id=transform.frame_id),
        child_frame_id=transform.child_frame_id,
        transform=Transform(
            translation=Vector3(x=tx, y=ty, z=tz),
            rotation=Quaternion(x=qx, y=qy, z=qz, w=qw),
        ),
    )


def tf_message(transforms: Sequence[TransformStamped]) -> TFMessage:
    """``/tf`` or ``/tf_static``: the transforms as the frame tree got them."""
    return TFMessage(transforms=[_transform(t) for t in transforms])


# -- the planner ----------------------------------------------------------------------------


def cone_marker(marker: ConeMarker) -> Marker:
    """``/left_cone_marker`` (blue) or ``/right_cone_marker`` (yellow): a SPHERE_LIST."""
    header = ros_header(marker.header)
    colour = BLUE if marker.side == "left" else YELLOW
    points = _points(marker.points)
    return _marker(
        header, f"{marker.side}_cones", Marker.SPHERE_LIST, points, scale=CONE, colour=colour
    )


def local_path(path: LocalPath) -> RosPath:
    """``/local_planned_path``: a pose per path point, heading along the path."""
    header = ros_header(path.header)
    poses = [
        PoseStamped(
            header=header,
            pose=Pose(position=Point(x=x, y=y, z=0.0), orientation=_yaw_quaternion(yaw)),
        )
        for (x, y), yaw in zip(path.points.tolist(), path.yaw.tolist(), strict=True)
    ]
    return RosPath(header=header, poses=poses)


def waypoint_markers(waypoints: Waypoints) -> MarkerArray:
    """``/final_waypoints``: the waypoints as small magenta spheres (ns ``final_wp``)."""
    header = ros_header(waypoints.header)
    points = _points(waypoints.points)
    marker = _marker(header, "final_wp", Marker.SPHERE_LIST, points, scale=WAYPOINT, colour=MAGENTA)
    return _marker_array(marker)


def speed_bar_markers(waypoints: Waypoints) -> MarkerArray:
    """``/waypoint_speed_bars``: a vertical green bar per waypoint, as tall as its
    speed times ``SPEED_BAR_SCALE``."""
    header = ros_header(waypoints.header)
    points = []
    for (x, y), v in zip(waypoints.points.tolist(), waypoints.speeds.tolist(), strict=True):
        points += [Point(x=x, y=y, z=0.0), Point(x=x, y=y, z=v * SPEED_BAR_SCALE)]
    marker = _marker(
        header, "speed_bars", Marker.LINE_LIST, points, scale=SPEED_BAR, colour=BAR_GREEN
    )
    return _marker_array(marker)


def bridge_marker(bridges: BridgeLines) -> Marker:
    """``/delaunay_internal_lines``: a LINE_LIST, green where the edge's midpoint is used."""
    header = ros_header(bridges.header)
    points = _points(np.asarray(bridges.lines).reshape(-1, 2))
    colours = [GREEN if used else GREY for used in bridges.used.tolist() for _ in range(2)]
    return _marker(
        header, "delaunay_lines", Marker.LINE_LIST, points,
        scale=BRIDGE_LINE, colour=GREEN, colours=colours,
    )  # fmt: skip


def midpoint_marker(midpoints: Midpoints) -> Marker:
    """``/delaunay_internal_midpoints``: a SPHERE_LIST of the ordered midpoints."""
    header = ros_header(midpoints.header)
    points = _points(midpoints.points)
    return _marker(
        header, "delaunay_midpoints", Marker.SPHERE_LIST, points, scale=MIDPOINT, colour=RED
    )


def global_path_marker(path: GlobalPath, frame_id: str) -> Marker:
    """``/global_path_marker``: the ROS pipeline's LINE_STRIP, red where cov > threshold, else
    green (a closed path ends at its first point), stamped 0."""
    xy, red = np.asarray(path.xy), path.high_covariance
    if path.closed:
        xy, red = np.vstack([xy, xy[:1]]), np.concatenate([red, red[:1]])
    header = RosHeader(stamp=ros_time(0.0), frame_id=frame_id)
    colours = [RED if r else GREEN for r in red.tolist()]
    return _marker(
        header, "global_path", Marker.LINE_STRIP, _points(xy),
        scale=PATH_LINE, colour=GREEN, colours=colours,
    )  # fmt: skip


# -- ground truth ---------------------------------------------------------------------------


def odometry(
    t: float,
    frame_id: str,
    child_frame_id: str,
    *,
    pose: Pose2D,
    velocity: tuple[float, float],
    yaw_rate: float,
) -> Odometry:
    """``/ground_truth/odom``: a pose in ``frame_id`` and the twist in ``child_frame_id``.

    Args:
        t: stamp [s].
        frame_id: the world frame.
        child_frame_id: the body frame the twist is expressed in.
        pose: the body's pose in ``frame_id``.
        velocity: (forward, left) velocity in the body frame [m/s].
        yaw_rate: [rad/s].
    """
    vx, vy = velocity
    return Odometry(
        header=RosHeader(stamp=ros_time(t), frame_id=frame_id),
        child_frame_id=child_frame_id,
        pose=PoseWithCovariance(
            pose=Pose(
                position=Point(x=pose.x, y=pose.y, z=0.0), orientation=_yaw_quaternion(pose.yaw)
            ),
            covariance=np.zeros(36),
        ),
        twist=TwistWithCovariance(
            twist=Twist(
                linear=Vector3(x=vx, y=vy, z=0.0), angular=Vector3(x=0.0, y=0.0, z=yaw_rate)
            ),
            covariance=np.zeros(36),
        ),
    )


def cone_truth_marker(
    t: float, frame_id: str, positions: ArrayLike, kinds: Sequence[str]
) -> Marker:
    """``/ground_truth/cones``: every cone where it is, coloured by kind (SPHERE_LIST)."""
    header = RosHeader(stamp=ros_time(t), frame_id=frame_id)
    colours = [CONE_KIND_COLOURS.get(kind, GREY) for kind in kinds]
    return _marker(
        header, "cones", Marker.SPHERE_LIST, _points(positions),
        scale=CONE, colour=GREY, colours=colours,
    )  # fmt: skip
