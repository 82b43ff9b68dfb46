"""Tests for envs.bag: a run recorded as a ROS 2 bag, read back with rosbags.

One 3 s run of trackdrive (rtk sensors, fused localization, seed 0) is
recorded once for the module; the tests read the bag back with rosbags'
``Reader`` and compare it against the profile's rates and the run's own
frame tree and autopilot.
"""

from __future__ import annotations

import json
import math
import os
import sys
from collections import defaultdict
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from numpy.testing import assert_allclose

pytest.importorskip("rosbags")

from gymnasium.error import DependencyNotInstalled
from rosbags.rosbag2 import Reader
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

from conesim.core.geodesy import gps_to_local_cartesian
from conesim.envs import bag as bag_module
from conesim.envs import runner
from conesim.envs.bag import TOPICS, BagError, BagRecorder
from conesim.envs.cli import main
from conesim.envs.loop import ClosedLoop
from conesim.envs.ros_messages import typestore
from conesim.envs.runner import TIMING_FIELDS, RunResult, run_scenario
from conesim.planner.autopilot import Autopilot
from conesim.sim.sensors import get_profile

DURATION = 3.0  # [s] simulated
NS = 1_000_000_000

Messages = dict[str, list[tuple[int, Any]]]


@dataclass
class Recorded:
    """The bag of one run, read back, and the run's own objects."""

    path: Path
    result: RunResult
    loop: ClosedLoop
    messages: Messages  # topic -> [(bag time [ns], message)]
    types: dict[str, str]  # topic -> type


def read_bag(path: Path) -> tuple[Messages, dict[str, str]]:
    """Every message of the bag, deserialised, by topic in bag order."""
    store = typestore()
    messages: Messages = defaultdict(list)
    with Reader(path) as reader:
        types = {c.topic: c.msgtype for c in reader.connections}
        for connection, timestamp, raw in reader.messages():
            msg = store.deserialize_cdr(raw, connection.msgtype)
            messages[connection.topic].append((timestamp, msg))
    return dict(messages), types


def record_run(path: Path, **kwargs: Any) -> tuple[RunResult, ClosedLoop]:
    """``run_scenario`` with a bag, keeping the loop it drove."""
    captured: list[ClosedLoop] = []
    real_drive = runner._drive

    def drive(loop: ClosedLoop, *args: Any, **kw: Any) -> RunResult:
        captured.append(loop)
        return real_drive(loop, *args, **kw)

    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(runner, "_drive", drive)
        result = run_scenario(bag=path, **kwargs)
    return result, captured[0]


RUN: dict[str, Any] = {"track": "trackdrive", "seed": 0, "time_limit": DURATION}


@pytest.fixture(scope="module")
def recorded(tmp_path_factory: pytest.TempPathFactory) -> Recorded:
    """The 3 s trackdrive run's bag."""
    path = tmp_path_factory.mktemp("bag") / "run"
    result, loop = record_run(path, **RUN)
    messages, types = read_bag(path)
    return Recorded(path, result, loop, messages, types)


def stamp_ns(msg: Any) -> int:
    """A message's header stamp [ns]."""
    return int(msg.header.stamp.sec) * NS + int(msg.header.stamp.nanosec)


def autopilot(recorded: Recorded) -> Autopilot:
    """The autopilot that drove the run (the loop's driver)."""
    driver = recorded.loop.driver
    assert isinstance(driver, Autopilot)
    return driver


def test_bag_directory_holds_metadata_and_one_mcap_file(recorded: Recorded) -> None:
    """rosbag2's layout: metadata.yaml and DIR.mcap, nothing else, nothing left beside it."""
    assert sorted(p.name for p in recorded.path.iterdir()) == ["metadata.yaml", "run.mcap"]
    assert [p.name for p in recorded.path.parent.iterdir()] == ["run"]
    meta = (recorded.path / "metadata.yaml").read_text()
    assert "storage_identifier: mcap" in meta and "version: 8" in meta
    assert "conesim.track: trackdrive" in meta


def test_topics_and_types(recorded: Recorded) -> None:
    """Every topic of the table, with the ROS pipeline's names and standard types."""
    assert recorded.types == {t.name: t.msgtype for t in TOPICS}
    assert recorded.types["/ublox_gps_node/fix"] == "sensor_msgs/msg/NavSatFix"
    assert recorded.types["/tf"] == "tf2_msgs/msg/TFMessage"
    assert recorded.types["/local_planned_path"] == "nav_msgs/msg/Path"
    assert set(recorded.messages) == set(recorded.types)  # every topic has messages


def delivered(rate: float, latency: float, duration: float) -> int:
    """Captures at k / rate (k = 0, 1, ...) delivered by ``duration``, latency later."""
    return math.floor((duration - latency) * rate + 1e-9) + 1


def test_counts_match_the_sensor_rates(recorded: Recorded) -> None:
    """rtk over 3 s: GPS 10 Hz + 50 ms -> 30, heading 20 Hz + 50 ms -> 60, IMU 100 Hz
    -> 301, wheel speed 50 Hz -> 151, cones 10 Hz + 0.2 s -> 29; one truth odom per
    control step (50 Hz, and t = 0) -> 151."""
    p = get_profile("rtk")
    counts = {topic: len(msgs) for topic, msgs in recorded.messages.items()}
    expected = {
        "/ublox_gps_node/fix": delivered(p.gps.rate, p.gps.latency, DURATION),
        "/local_xy": delivered(p.gps.rate, p.gps.latency, DURATION),
        "/global_yaw": delivered(p.heading.rate, p.heading.latency, DURATION),
        "/ublox_gps_node/navheading": delivered(p.heading.rate, p.heading.latency, DURATION),
        "/imu/data": delivered(p.imu.rate, p.imu.latency, DURATION),
        "/wheel_speed": delivered(p.wheel_speed.rate, p.wheel_speed.latency, DURATION),
        "/sorted_cones_time": delivered(p.cones.rate, p.cones.latency, DURATION),
        "/ground_truth/odom": round(DURATION * 50) + 1,
        "/tf_static": 1,
        "/global_path_marker": 1,
    }
    assert {k: counts[k] for k in expected} == expected
    assert [expected[k] for k in ("/ublox_gps_node/fix", "/global_yaw", "/imu/data")] == [
        30,
        60,
        301,
    ]
    assert [expected[k] for k in ("/wheel_speed", "/sorted_cones_time")] == [151, 29]
    # One /tf per broadcast into the frame tree, 20 Hz apart.
    tf_ns = [t for t, _ in recorded.messages["/tf"]]
    assert len(tf_ns) == len(recorded.result.trace.loc_t)
    assert set(np.diff(tf_ns).tolist()) == {50_000_000}
    # One set of planner topics per plan: every detection was planned.
    plans = autopilot(recorded).plan_count
    assert plans == counts["/sorted_cones_time"]
    for topic in ("/left_cone_marker", "/local_planned_path", "/waypoint_speed_bars"):
        assert counts[topic] == plans


def test_bag_time_is_delivery_and_header_is_capture(recorded: Recorded) -> None:
    """Bag time - header stamp is each sensor's latency (rtk: GPS, heading 50 ms; IMU,
    wheel speed 0; cones 0.2 s); /tf is stamped at its broadcast; /local_xy carries its
    fix's stamp at its fix's bag time."""
    lag = {
        "/ublox_gps_node/fix": 50_000_000,
        "/ublox_gps_node/navheading": 50_000_000,
        "/imu/data": 0,
        "/wheel_speed": 0,
        "/sorted_cones_time": 200_000_000,
        "/tf": 0,
        "/local_xy": 50_000_000,
        "/ground_truth/odom": 0,
    }
    for topic, latency in lag.items():
        msgs = recorded.messages[topic]
        stamps = [stamp_ns(m.transforms[0]) if topic == "/tf" else stamp_ns(m) for _, m in msgs]
        assert [t for t, _ in msgs] == [s + latency for s in stamps], topic
    fixes = recorded.messages["/ublox_gps_node/fix"]
    points = recorded.messages["/local_xy"]
    assert [(t, stamp_ns(m)) for t, m in fixes] == [(t, stamp_ns(m)) for t, m in points]


def test_timestamps_are_monotonic_per_topic(recorded: Recorded) -> None:
    """Bag times never go back on a topic, start at 0 and end at the run's 3 s."""
    for topic, msgs in recorded.messages.items():
        times = [t for t, _ in msgs]
        assert times == sorted(times), topic
    every = [t for msgs in recorded.messages.values() for t, _ in msgs]
    assert min(every) == 0 and max(every) == round(DURATION * NS)


def test_navsatfix_round_trips_to_the_frame_tree(recorded: Recorded) -> None:
    """Each fix, projected with the ROS pipeline's geodesy, is within 0.15 m (about 4 sigma of
    rtk's 2.5 cm per axis plus the EKF's ~1 cm) of gps_antenna in the frame tree at
    the fix's stamp, and is the /local_xy point to 1e-9 m."""
    loop = recorded.loop
    points = recorded.messages["/local_xy"]
    checked = 0
    for (_, fix), (_, point) in zip(recorded.messages["/ublox_gps_node/fix"], points, strict=True):
        x, y = gps_to_local_cartesian(fix.latitude, fix.longitude, loop.world_config.origin)
        assert_allclose([x, y], [point.point.x, point.point.y], atol=1e-9)
        stamp = stamp_ns(fix) / NS
        assert fix.header.frame_id == "gps_antenna" and point.header.frame_id == "reference"
        assert fix.position_covariance_type == 3
        assert_allclose(fix.position_covariance[[0, 4]], 0.025**2)
        if stamp == 0.0 or not loop.localizer.frames.can_transform(
            "reference", "gps_antenna", stamp
        ):
            continue  # 0 means "latest" to the frame tree; before the first broadcast
        pose = loop.localizer.frames.lookup_pose2d("reference", "gps_antenna", stamp)
        assert math.hypot(float(x) - pose.x, float(y) - pose.y) < 0.15
        checked += 1
    assert checked >= 25


def test_tf_equals_the_frame_tree(recorded: Recorded) -> None:
    """Every /tf transform is the frame tree's reference -> gps_antenna at its stamp;
    /tf_static is gps_antenna -> os_sensor, 0.1 m down, stamped 0."""
    buffer = recorded.loop.localizer.frames
    for t, msg in recorded.messages["/tf"]:
        (tf,) = msg.transforms
        assert (tf.header.frame_id, tf.child_frame_id) == ("reference", "gps_antenna")
        tree = buffer.lookup_transform("reference", "gps_antenna", t / NS)
        got = tf.transform
        assert_allclose([got.translation.x, got.translation.y, got.translation.z],
                        tree.translation, rtol=0, atol=1e-12)  # fmt: skip
        assert_allclose([got.rotation.x, got.rotation.y, got.rotation.z, got.rotation.w],
                        tree.rotation, rtol=0, atol=1e-12)  # fmt: skip
    ((t0, static),) = recorded.messages["/tf_static"]
    (tf,) = static.transforms
    assert t0 == 0 and stamp_ns(tf) == 0
    assert (tf.header.frame_id, tf.child_frame_id) == ("gps_antenna", "os_sensor")
    assert (tf.transform.translation.z, tf.transform.rotation.w) == (-0.1, 1.0)


def test_path_is_in_os_sensor_and_is_the_plan(recorded: Recorded) -> None:
    """/local_planned_path is in os_sensor (path and poses); the last one is the
    autopilot's last plan, point for point; the cone markers are in reference."""
    for _, path in recorded.messages["/local_planned_path"]:
        assert path.header.frame_id == "os_sensor"
        assert all(p.header.frame_id == "os_sensor" for p in path.poses)
    _, last = recorded.messages["/local_planned_path"][-1]
    plan = autopilot(recorded).plan
    assert plan is not None and len(plan.path) > 2
    assert_allclose([[p.pose.position.x, p.pose.position.y] for p in last.poses], plan.path)
    assert stamp_ns(last) == round(plan.header.stamp * NS)
    # Along the path: each pose faces the next point.
    yaw = [2.0 * math.atan2(p.pose.orientation.z, p.pose.orientation.w) for p in last.poses]
    d = np.diff(plan.path, axis=0)
    assert_allclose(np.cos(yaw[:-1]), d[:, 0] / np.hypot(d[:, 0], d[:, 1]), atol=1e-9)
    for topic in ("/left_cone_marker", "/right_cone_marker", "/global_path_marker"):
        assert all(m.header.frame_id == "reference" for _, m in recorded.messages[topic])
    _, speed_bars = recorded.messages["/waypoint_speed_bars"][-1]
    tops = [p.z for p in speed_bars.markers[0].points[1::2]]
    assert_allclose(tops, 0.1 * plan.speeds, atol=1e-12)


def test_cone_type_decodes_from_the_bags_own_definition(recorded: Recorded) -> None:
    """A reader without conesim's code (an empty typestore fed only the definitions the
    bag carries) decodes /sorted_cones_time: (n, 3) cones in os_sensor, nearest first."""
    with Reader(recorded.path) as reader:
        (connection,) = [c for c in reader.connections if c.topic == "/sorted_cones_time"]
        definition = connection.msgdef.data
        assert connection.msgtype == "conesim_msgs/msg/ModifiedFloat32MultiArray"
        assert definition.startswith(
            "std_msgs/Header header\nstd_msgs/MultiArrayLayout layout\nfloat32[] data\n"
        )
        store = get_typestore(Stores.EMPTY)
        store.register(get_types_from_msg(definition, connection.msgtype))
        decoded: list[Any] = [
            store.deserialize_cdr(raw, connection.msgtype)
            for _, _, raw in reader.messages(connections=[connection])
        ]
    ours = [m for _, m in recorded.messages["/sorted_cones_time"]]
    assert len(decoded) == len(ours) == 29
    for theirs, mine in zip(decoded, ours, strict=True):
        n = theirs.layout.dim[0].size
        assert [(d.label, d.size, d.stride) for d in theirs.layout.dim] == [
            ("cones", n, 3 * n),
            ("xyz", 3, 3),
        ]
        cones = theirs.data.reshape(n, 3)
        assert theirs.header.frame_id == "os_sensor"
        assert_allclose(cones, mine.data.reshape(-1, 3))
        assert np.all(np.diff(np.linalg.norm(cones.astype(float), axis=1)) >= -1e-5)
    # The MCAP file alone (what Foxglove opens) holds the schema too.
    mcap = (recorded.path / "run.mcap").read_bytes()
    assert b"conesim_msgs/msg/ModifiedFloat32MultiArray" in mcap
    assert b"MSG: std_msgs/MultiArrayLayout" in mcap


def test_latched_topics_are_offered_transient_local(recorded: Recorded) -> None:
    """/tf_static and /global_path_marker reach late subscribers on `ros2 bag play`."""
    with Reader(recorded.path) as reader:
        offered = {c.topic: c.ext.offered_qos_profiles for c in reader.connections}
    for topic in ("/tf_static", "/global_path_marker"):
        (qos,) = offered[topic]
        assert (qos.durability.name, qos.depth) == ("TRANSIENT_LOCAL", 1)
    assert offered["/tf"] == []


def test_recording_does_not_change_the_run(recorded: Recorded) -> None:
    """The result with and without the bag is the same apart from the wall time."""
    plain = run_scenario(**RUN).to_json()
    with_bag = recorded.result.to_json()
    for key in TIMING_FIELDS:
        plain.pop(key)
        with_bag.pop(key)
    assert with_bag == plain


# -- the command line and the error cases ---------------------------------------------------


def test_cli_bag_into_an_empty_directory_and_same_result_json(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """`conesim run --bag DIR` fills an existing empty DIR; result.json is the one
    without --bag apart from the wall time."""
    (tmp_path / "bag").mkdir()
    base = ["run", "--track", "acceleration", "--sensors", "ideal", "--json"]
    assert main([*base, "--out", str(tmp_path / "a"), "--bag", str(tmp_path / "bag")]) == 0
    capsys.readouterr()
    assert main([*base, "--out", str(tmp_path / "b")]) == 0
    a, b = (json.loads((tmp_path / d / "result.json").read_text()) for d in ("a", "b"))
    for result in (a, b):
        for key in TIMING_FIELDS:
            del result[key]
    assert a == b
    assert sorted(p.name for p in (tmp_path / "bag").iterdir()) == ["bag.mcap", "metadata.yaml"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a", "b", "bag"]
    messages, _ = read_bag(tmp_path / "bag")
    assert max(t for t, _ in messages["/ground_truth/odom"]) == round(a["sim_time_s"] * NS)


def no_simulation(*args: object, **kwargs: object) -> None:
    """Stands in for the run in tests of input errors."""
    raise AssertionError("simulated despite a bad --bag")


def non_empty_directory(tmp_path: Path) -> str:
    (tmp_path / "bag").mkdir()
    (tmp_path / "bag" / "x.txt").write_text("x")
    return str(tmp_path / "bag")


def a_file(tmp_path: Path) -> str:
    (tmp_path / "bag").write_text("a file")
    return str(tmp_path / "bag")


def under_a_file(tmp_path: Path) -> str:
    (tmp_path / "FILE").write_text("a file")
    return str(tmp_path / "FILE" / "sub" / "bag")


def no_name(tmp_path: Path) -> str:
    return ""


@pytest.mark.parametrize(
    ("make", "message"),
    [
        (non_empty_directory, "exists and is not empty"),
        (a_file, "exists and is not a directory"),
        (under_a_file, "FILE is not a directory"),
        (no_name, "(empty name)"),
    ],
)
def test_cli_refuses_a_bad_bag_path(
    make: Any,
    message: str,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """An existing non-empty directory, a file, a path under a file, no name: exit 2
    before simulating, one line naming --bag and the path, nothing touched."""
    monkeypatch.setattr(runner, "_drive", no_simulation)
    bag = make(tmp_path)
    before = sorted(tmp_path.rglob("*"))
    code = main(["run", "--out", str(tmp_path / "out"), "--bag", bag])
    err = capsys.readouterr().err
    assert code == 2 and len(err.strip().splitlines()) == 1
    assert f"--bag {bag}" in err and message in err
    assert sorted(tmp_path.rglob("*")) == before


def test_without_the_ros_extra(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """No rosbags: run_scenario raises DependencyNotInstalled and the CLI exits 2, both
    naming `pip install "conesim[ros]"`, before any simulation."""
    monkeypatch.setitem(sys.modules, "rosbags", None)
    monkeypatch.setattr(runner, "_drive", no_simulation)
    with pytest.raises(DependencyNotInstalled, match=r'pip install "conesim\[ros\]"'):
        run_scenario("acceleration", bag=tmp_path / "bag")
    code = main(["run", "--out", str(tmp_path / "out"), "--bag", str(tmp_path / "bag")])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1 and 'pip install "conesim[ros]"' in err
    assert list(tmp_path.iterdir()) == []


def test_a_failed_run_leaves_no_bag(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """An error during the run removes the unfinished bag and its temporary directory."""
    calls = []
    real_record = BagRecorder.record

    def record(self: BagRecorder, *args: Any) -> None:
        calls.append(1)
        if len(calls) == 20:
            raise RuntimeError("stop")
        real_record(self, *args)

    monkeypatch.setattr(BagRecorder, "record", record)
    target = tmp_path / "new" / "bag"
    with pytest.raises(RuntimeError, match="stop"):
        run_scenario("acceleration", bag=target)
    assert list(tmp_path.iterdir()) == []


def test_a_failed_move_into_place_leaves_nothing(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """When the finished bag cannot be moved into place: BagError naming the path, and
    neither the bag, its temporary directory nor the parents made for it remain."""

    target = tmp_path / "new" / "bag"
    real_replace = os.replace

    def replace(src: Path, dst: Path) -> None:
        if Path(dst) == target:
            raise PermissionError(13, "Permission denied", str(dst))
        real_replace(src, dst)

    monkeypatch.setattr(os, "replace", replace)
    with pytest.raises(BagError, match=r"new/bag: cannot write the bag \(Permission denied\)"):
        run_scenario("acceleration", bag=target, time_limit=0.5)
    assert list(tmp_path.iterdir()) == []


def test_check_bag_target_creates_nothing(tmp_path: Path) -> None:
    """The check before the run makes no directory, not even missing parents."""
    target = bag_module.check_bag_target(tmp_path / "a" / "b" / "bag")
    assert target == tmp_path / "a" / "b" / "bag" and list(tmp_path.iterdir()) == []
    with pytest.raises(BagError, match="exists and is not empty"):
        bag_module.check_bag_target(tmp_path.parent)


def test_a_symlink_to_an_empty_directory_gets_the_bag(tmp_path: Path) -> None:
    """An existing empty target (here a symlink to one; a mount point is alike)
    gets the bag's files moved into it: the unfinished bag is written inside it,
    not beside it, so the move cannot fail after the run."""
    (tmp_path / "real").mkdir()
    (tmp_path / "link").symlink_to(tmp_path / "real", target_is_directory=True)
    run_scenario("acceleration", bag=tmp_path / "link", time_limit=0.5)
    assert sorted(p.name for p in (tmp_path / "real").iterdir()) == ["link.mcap", "metadata.yaml"]
    assert (tmp_path / "link").is_symlink()
    messages, _ = read_bag(tmp_path / "real")
    assert len(messages["/ground_truth/odom"]) == 26  # t = 0 and 25 control steps of 20 ms


@pytest.mark.parametrize("existed", [True, False])
def test_results_that_cannot_be_written_take_only_what_the_bag_made(
    existed: bool,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """When result.json and run.png cannot be written the bag goes too (half a run),
    but an empty directory the user made stays, and only the parents made for
    the bag are removed."""
    from conesim.envs import cli

    def cannot_write(*args: object) -> None:
        raise cli.CliError("--out: cannot write there (disk full)")

    monkeypatch.setattr(cli, "_write_outputs", cannot_write)
    bag = tmp_path / "mine" if existed else tmp_path / "new" / "deeper" / "bag"
    if existed:
        bag.mkdir()
    args = ["run", "--track", "acceleration", "--sensors", "ideal", "--out", str(tmp_path / "o")]
    assert main([*args, "--bag", str(bag)]) == 2
    assert "disk full" in capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.iterdir()) == (["mine"] if existed else [])
    if existed:
        assert list(bag.iterdir()) == []
