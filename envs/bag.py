"""Recording a headless run to a ROS 2 bag (rosbag2, MCAP storage).

``conesim run --bag DIR`` and ``run_scenario(..., bag=DIR)`` write one
rosbag2 directory, ``DIR/metadata.yaml`` and ``DIR/DIR.mcap``, that
Foxglove Studio, ``ros2 bag play`` and rosbags' ``Reader`` open. It is
written with the pure-Python ``rosbags`` library (the ``ros`` extra), needs
no ROS installation, and carries every message definition, the custom cone
type's included.

The recorder consumes the closed loop's records (``envs.loop.StepRecord``),
one per control step: every measurement as delivered, every ``/local_xy``
point, every broadcast ``reference -> gps_antenna`` transform, the
autopilot's plans with their classification, and the truth. It steps
nothing and changes nothing, so a run with a bag is the run without one.

Topics: type; frame (header.frame_id); rate with the rtk sensors.

/ublox_gps_node/fix           sensor_msgs/NavSatFix; gps_antenna; 10 Hz
/local_xy                     geometry_msgs/PointStamped; reference; per fix
/global_yaw                   std_msgs/Float32 (no header); 20 Hz
/ublox_gps_node/navheading    sensor_msgs/Imu, orientation only; reference; 20 Hz
/imu/data                     sensor_msgs/Imu; gps_antenna; 100 Hz
/wheel_speed                  geometry_msgs/TwistWithCovarianceStamped; gps_antenna; 50 Hz
/sorted_cones_time            conesim_msgs/ModifiedFloat32MultiArray; os_sensor; 10 Hz
/tf                           tf2_msgs/TFMessage; reference -> gps_antenna; 20 Hz
/tf_static                    tf2_msgs/TFMessage; gps_antenna -> os_sensor; once
/left_cone_marker             visualization_msgs/Marker SPHERE_LIST; reference; per plan
/right_cone_marker            visualization_msgs/Marker SPHERE_LIST; reference; per plan
/local_planned_path           nav_msgs/Path; os_sensor; per plan
/final_waypoints              visualization_msgs/MarkerArray; os_sensor; per plan
/waypoint_speed_bars          visualization_msgs/MarkerArray; os_sensor; per plan
/delaunay_internal_lines      visualization_msgs/Marker LINE_LIST; os_sensor; per plan
/delaunay_internal_midpoints  visualization_msgs/Marker SPHERE_LIST; os_sensor; per plan
/global_path_marker           visualization_msgs/Marker LINE_STRIP; reference; once
/ground_truth/odom            nav_msgs/Odometry; reference (twist: gps_antenna); 50 Hz
/ground_truth/cones           visualization_msgs/Marker SPHERE_LIST; reference; at 0
                              and at each control step in which a cone moved

(How each conesim message maps onto its ROS type: ``envs.ros_messages``.)

Bag time is the simulation time [ns] at which a message was published: a
measurement at its delivery (its capture stamp plus the sensor's latency,
at the physics step), ``/local_xy`` with its fix, ``/tf`` at its broadcast,
the planner's topics at the control step whose autopilot call planned them,
the ground truth at each control step, the two "once" topics at 0. It is
non-decreasing per topic. Header stamps are what the messages carry: a
measurement's capture time, the planner's transform stamp (the cone
markers: the time of the transform the classifier used, the detection's
stamp, or the latest transform's when the autopilot fell back to it), the
truth's own time. The simulation starts at
0, so the bag starts at the epoch. Every plan the autopilot made is recorded,
at the control step that made it.

Format: rosbag2 metadata version 8 (its QoS profiles are a YAML string, as
Humble's rosbag2 reads them; version 9's list form is not read there),
MCAP storage with zstd-compressed chunks (the MCAP library's default, so
what ``ros2 bag record -s mcap`` writes; Foxglove reads them): a sixth of
the uncompressed size at no measurable cost in time. ``/tf_static`` and
``/global_path_marker`` are offered transient-local (latched), so a
subscriber that starts late still gets them on ``ros2 bag play``; the
other topics state no QoS, and ``ros2 bag play`` publishes them with its
default (reliable, volatile, keep last 10). ``metadata.yaml``'s ``custom_data`` holds the run's
track, seed, sensors and localization.

Nothing is written half: the bag goes to a temporary directory beside the
target (in its nearest existing ancestor) and is moved into place when the
run is over; on any failure the temporary directory is removed.
"""

from __future__ import annotations

import contextlib
import math
import os
import shutil
import tempfile
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType, TracebackType
from typing import TYPE_CHECKING, Any, Final

from conesim.core.messages import (
    ConeDetections,
    HeadingStamped,
    Imu,
    NavSatFix,
    PointStamped,
    WheelSpeed,
)
from conesim.envs.paths import missing_dirs, nearest_existing, os_reason, probe_writable
from conesim.localization.frames import TransformStamped

if TYPE_CHECKING:
    from rosbags.interfaces import Connection, Qos
    from rosbags.rosbag2 import Writer

    from conesim.envs.loop import ClosedLoop, StepRecord

BAG_VERSION: Final = 8  # rosbag2 metadata version (see the module docs)


@dataclass(frozen=True, slots=True)
class Topic:
    """One topic of the bag.

    Attributes:
        name: the topic.
        msgtype: its ROS 2 type (``pkg/msg/Name``).
        latched: offered transient-local (published once).
    """

    name: str
    msgtype: str
    latched: bool = False


CONE_ARRAY_TYPE = "conesim_msgs/msg/ModifiedFloat32MultiArray"  # defined in envs.ros_messages
TOPICS = (
    Topic("/ublox_gps_node/fix", "sensor_msgs/msg/NavSatFix"),
    Topic("/local_xy", "geometry_msgs/msg/PointStamped"),
    Topic("/global_yaw", "std_msgs/msg/Float32"),
    Topic("/ublox_gps_node/navheading", "sensor_msgs/msg/Imu"),
    Topic("/imu/data", "sensor_msgs/msg/Imu"),
    Topic("/wheel_speed", "geometry_msgs/msg/TwistWithCovarianceStamped"),
    Topic("/sorted_cones_time", CONE_ARRAY_TYPE),
    Topic("/tf", "tf2_msgs/msg/TFMessage"),
    Topic("/tf_static", "tf2_msgs/msg/TFMessage", latched=True),
    Topic("/left_cone_marker", "visualization_msgs/msg/Marker"),
    Topic("/right_cone_marker", "visualization_msgs/msg/Marker"),
    Topic("/local_planned_path", "nav_msgs/msg/Path"),
    Topic("/final_waypoints", "visualization_msgs/msg/MarkerArray"),
    Topic("/waypoint_speed_bars", "visualization_msgs/msg/MarkerArray"),
    Topic("/delaunay_internal_lines", "visualization_msgs/msg/Marker"),
    Topic("/delaunay_internal_midpoints", "visualization_msgs/msg/Marker"),
    Topic("/global_path_marker", "visualization_msgs/msg/Marker", latched=True),
    Topic("/ground_truth/odom", "nav_msgs/msg/Odometry"),
    Topic("/ground_truth/cones", "visualization_msgs/msg/Marker"),
)


Routes = tuple[tuple[Topic, Callable[[Any], object]], ...]
"""Where one kind of traffic item goes: (topic, conversion to its ROS message)."""


class BagError(ValueError):
    """A bag directory that cannot be written; the message starts with the path."""


def require_rosbags() -> None:
    """Raise gymnasium's ``DependencyNotInstalled`` naming the extra when rosbags is missing."""
    try:
        import rosbags  # noqa: F401, PLC0415
    except ImportError as exc:
        from gymnasium.error import DependencyNotInstalled  # noqa: PLC0415

        raise DependencyNotInstalled(
            'rosbags is not installed; install the ros extra: pip install "conesim[ros]"'
        ) from exc


def check_bag_target(path: str | os.PathLike[str]) -> Path:
    """The bag directory to write, checked before any simulation; nothing is created.

    It may not exist yet or be an empty directory; its nearest existing
    ancestor must be a writable directory.

    Raises:
        BagError: an empty name, an existing file or non-empty directory, or
            a place that cannot be written.
    """
    text = os.fspath(path)
    if not text.strip():
        raise BagError("(empty name): give the bag directory to create")
    target = Path(os.path.abspath(text))
    try:
        if target.is_dir():
            if any(target.iterdir()):
                raise BagError(f"{text}: exists and is not empty; give a new directory")
        elif target.exists() or target.is_symlink():
            raise BagError(f"{text}: exists and is not a directory")
        base = nearest_existing(target.parent)
        if not base.is_dir():
            raise BagError(f"{text}: {base} is not a directory")
        probe_writable(base)
    except OSError as exc:
        raise BagError(f"{text}: cannot write there ({os_reason(exc)})") from None
    return target


def remove_bag(path: str | os.PathLike[str], existed: bool, created: list[Path]) -> None:
    """Remove a finished bag again (its run's other outputs could not be written).

    Args:
        path: the bag directory.
        existed: it was an empty directory before the run (the user's): only
            its contents go, the directory stays.
        created: the parent directories made for it (``paths.missing_dirs``
            before the run), removed when empty, innermost first.
    """
    target = Path(os.path.abspath(path))
    if existed:
        for item in target.iterdir():
            if item.is_dir() and not item.is_symlink():
                shutil.rmtree(item, ignore_errors=True)
            else:
                item.unlink(missing_ok=True)
        return
    shutil.rmtree(target, ignore_errors=True)
    for directory in reversed(created):
        with contextlib.suppress(OSError):
            directory.rmdir()


class BagRecorder:
    """Records one run into a rosbag2 directory (see the module docs).

    Use as a context manager around the run: ``start`` after the episode's
    reset (and the policy's), ``record`` after every control step. On a
    clean exit the bag is closed and moved into place; on an exception it
    is discarded.

    Args:
        path: the bag directory to create (``check_bag_target``).
        custom_data: strings for ``metadata.yaml``'s ``custom_data``.

    Raises:
        BagError: the path cannot be written (checked here, before the run).
        gymnasium.error.DependencyNotInstalled: without the ``ros`` extra.
    """

    def __init__(
        self, path: str | os.PathLike[str], custom_data: Mapping[str, str] | None = None
    ) -> None:
        self.path = check_bag_target(path)
        self.display = os.fspath(path)
        self.existed = self.path.is_dir()  # an empty directory the user made
        require_rosbags()
        self.custom_data = dict(custom_data or {})
        self._tmp: Path | None = None
        self._writer: Writer | None = None
        self._connections: dict[str, Connection] = {}
        self._rm: ModuleType | None = None  # envs.ros_messages, once rosbags is known to be there
        self._traffic: dict[type, Routes] = {}
        self._frames = ("reference", "gps_antenna")  # (world, vehicle): start() sets them
        self._kinds: tuple[str, ...] = ()
        self._first = True

    # -- the directory -----------------------------------------------------------------------

    def __enter__(self) -> BagRecorder:
        """Open the bag in a temporary directory beside the target."""
        from rosbags.rosbag2 import (  # noqa: PLC0415
            CompressionFormat,
            CompressionMode,
            StoragePlugin,
            Writer,
        )

        from conesim.envs import ros_messages as rm  # noqa: PLC0415

        self._rm = rm
        store = rm.typestore()
        try:
            # An existing (empty) target gets the bag's files moved into it:
            # the unfinished bag lives inside it, so a symlink, a mount point
            # or another file system there is no different from a new name.
            base = self.path if self.existed else nearest_existing(self.path.parent)
            self._tmp = Path(tempfile.mkdtemp(prefix=f".{self.path.name}.", dir=base))
            writer = self._writer = Writer(
                self._tmp / self.path.name, version=BAG_VERSION, storage_plugin=StoragePlugin.MCAP
            )
            writer.set_compression(CompressionMode.STORAGE, CompressionFormat.ZSTD)
            writer.open()
            for key, value in self.custom_data.items():
                writer.set_custom_data(key, value)
            for topic in TOPICS:
                store.get_msgdef(topic.msgtype)  # generates its serialiser now, not in the run
                self._connections[topic.name] = writer.add_connection(
                    topic.name,
                    topic.msgtype,
                    typestore=store,
                    offered_qos_profiles=[_latched_qos()] if topic.latched else [],
                )
        except BaseException as exc:
            self._discard()
            if isinstance(exc, OSError):
                raise self._cannot_write(exc) from None
            raise
        self._traffic = _traffic_topics(rm)
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        """Close and move the bag into place, or discard it on an exception."""
        if exc_type is not None:
            self._discard()
            return
        self._finish()

    def _finish(self) -> None:
        assert self._writer is not None and self._tmp is not None
        created = [] if self.existed else missing_dirs(self.path.parent)
        written = self._tmp / self.path.name
        moved: list[Path] = []
        try:
            self._writer.close()
            self._writer = None
            if self.existed:
                for item in sorted(written.iterdir()):
                    os.replace(item, self.path / item.name)
                    moved.append(self.path / item.name)
            else:
                self.path.parent.mkdir(parents=True, exist_ok=True)
                os.replace(written, self.path)
        except OSError as exc:
            self._discard()
            for item in moved:
                item.unlink(missing_ok=True)
            for directory in reversed(created):
                with contextlib.suppress(OSError):
                    directory.rmdir()
            raise self._cannot_write(exc) from None
        shutil.rmtree(self._tmp, ignore_errors=True)
        self._tmp = None

    def _cannot_write(self, exc: OSError) -> BagError:
        return BagError(f"{self.display}: cannot write the bag ({os_reason(exc)})")

    def _discard(self) -> None:
        """Drop the unfinished bag and its temporary directory."""
        writer, self._writer = self._writer, None
        if writer is not None:
            with contextlib.suppress(Exception):
                writer.abort()
        if self._tmp is not None:
            shutil.rmtree(self._tmp, ignore_errors=True)
            self._tmp = None

    # -- recording ---------------------------------------------------------------------------

    def start(self, loop: ClosedLoop) -> None:
        """The topics published once (the static transform, the global path).

        Args:
            loop: the loop to be recorded, after its reset.
        """
        rm = self._ros_messages()
        broadcaster = loop.localizer.broadcaster
        frames = broadcaster.config
        self._frames = (frames.reference_frame, frames.antenna_frame)
        self._kinds = tuple(str(k) for k in loop.track.kinds)
        self._write("/tf_static", 0.0, rm.tf_message([broadcaster.static_transform]))
        marker = rm.global_path_marker(loop.global_path, frames.reference_frame)
        self._write("/global_path_marker", 0.0, marker)

    def record(self, record: StepRecord) -> None:
        """One control step: what localization passed on, the new plans, the truth."""
        items: list[tuple[float, object]] = [(d.t, d.message) for d in record.deliveries]
        items += [(d.t, d.message) for d in record.local_xy]
        items += [(b.t, b.transform) for b in record.broadcasts]
        items.sort(key=lambda item: item[0])  # stable: at one time, messages, points, transforms
        for t, item in items:
            for topic, convert in self._traffic[type(item)]:
                self._write(topic.name, t, convert(item))
        self._record_plans(record)
        self._record_truth(record)

    def _record_plans(self, record: StepRecord) -> None:
        rm = self._ros_messages()
        if record.driver is None:
            return
        t = record.t
        for planned in record.driver.plans:
            left, right = planned.classified.markers()
            self._write("/left_cone_marker", t, rm.cone_marker(left))
            self._write("/right_cone_marker", t, rm.cone_marker(right))
            plan = planned.plan
            waypoints = plan.waypoints()
            self._write("/local_planned_path", t, rm.local_path(plan.local_path()))
            self._write("/final_waypoints", t, rm.waypoint_markers(waypoints))
            self._write("/waypoint_speed_bars", t, rm.speed_bar_markers(waypoints))
            self._write("/delaunay_internal_lines", t, rm.bridge_marker(plan.bridge_message()))
            self._write(
                "/delaunay_internal_midpoints", t, rm.midpoint_marker(plan.midpoint_message())
            )

    def _record_truth(self, record: StepRecord) -> None:
        rm = self._ros_messages()
        t = record.t
        truth = record.truth
        world_frame, vehicle_frame = self._frames
        state = truth.state
        pose = truth.antenna
        vx, vy = state.antenna_velocity()  # reference frame
        c, s = math.cos(pose.yaw), math.sin(pose.yaw)
        odom = rm.odometry(
            t, world_frame, vehicle_frame,
            pose=pose, velocity=(c * vx + s * vy, c * vy - s * vx), yaw_rate=state.yaw_rate,
        )  # fmt: skip
        self._write("/ground_truth/odom", t, odom)
        if truth.cones_moved or self._first:
            self._first = False
            marker = rm.cone_truth_marker(t, world_frame, truth.cones, self._kinds)
            self._write("/ground_truth/cones", t, marker)

    def _ros_messages(self) -> ModuleType:
        assert self._rm is not None, "record within `with BagRecorder(...)`"
        return self._rm

    def _write(self, topic: str, t: float, message: object) -> None:
        """Serialise ``message`` and write it on ``topic`` at bag time ``t`` [s]."""
        rm = self._ros_messages()
        assert self._writer is not None
        connection = self._connections[topic]
        data = rm.typestore().serialize_cdr(message, connection.msgtype)
        try:
            self._writer.write(connection, rm.nanoseconds(t), data)
        except OSError as exc:  # the bag's own file: say so (other errors pass as they are)
            raise self._cannot_write(exc) from None


def _traffic_topics(rm: ModuleType) -> dict[type, Routes]:
    """The topics each kind of traffic item goes to, with its conversion."""
    by_name = {topic.name: topic for topic in TOPICS}

    def on(*pairs: tuple[str, Callable[[Any], object]]) -> Routes:
        return tuple((by_name[name], convert) for name, convert in pairs)

    return {
        NavSatFix: on(("/ublox_gps_node/fix", rm.nav_sat_fix)),
        PointStamped: on(("/local_xy", rm.local_xy)),
        HeadingStamped: on(
            ("/global_yaw", rm.global_yaw), ("/ublox_gps_node/navheading", rm.heading_orientation)
        ),
        Imu: on(("/imu/data", rm.imu)),
        WheelSpeed: on(("/wheel_speed", rm.wheel_speed)),
        ConeDetections: on(("/sorted_cones_time", rm.cone_array)),
        TransformStamped: on(("/tf", lambda transform: rm.tf_message([transform]))),
    }


def _latched_qos() -> Qos:
    """Reliable, transient-local, keep the last 1: a latched topic's offered QoS."""
    from rosbags.interfaces import (  # noqa: PLC0415
        Qos,
        QosDurability,
        QosHistory,
        QosLiveliness,
        QosReliability,
        QosTime,
    )

    default = QosTime(sec=0, nsec=0)
    return Qos(
        history=QosHistory.KEEP_LAST,
        depth=1,
        reliability=QosReliability.RELIABLE,
        durability=QosDurability.TRANSIENT_LOCAL,
        deadline=default,
        lifespan=default,
        liveliness=QosLiveliness.AUTOMATIC,
        liveliness_lease_duration=default,
        avoid_ros_namespace_conventions=False,
    )
