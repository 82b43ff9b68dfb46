"""The per-step fast paths of the world give the answers of the plain ones, bit for bit."""

from __future__ import annotations

import math
from dataclasses import astuple, fields

import numpy as np
import pytest

from conesim.core.messages import ConeDetections, Header
from conesim.core.polyline import Polyline
from conesim.core.pose import Pose2D
from conesim.envs.observation import SensorMemory, build_dict, build_vector
from conesim.sim import progress
from conesim.sim.progress import PolylineProgress
from conesim.sim.sensors.profiles import get_profile
from conesim.sim.sensors.suite import SensorSuite
from conesim.sim.sensors.truth import TruthSample
from conesim.sim.world import World, WorldConfig
from conesim.tracks import load_track
from tests.sim import progress_reference


def _wiggle(n: int, rng: np.random.Generator) -> np.ndarray:
    """A random walk of n points [m], steps of a few centimetres."""
    return np.cumsum(rng.normal(0.0, 0.2, (n, 2)) + np.array([0.3, 0.0]), axis=0)


def test_project_xy_is_project() -> None:
    """``project_xy`` answers ``project``'s station, segment and tangent bit for bit,
    and its lateral offset to rounding, walking a circle and off an open arc's end."""
    rng = np.random.default_rng(4)
    theta = np.linspace(0.0, 2 * math.pi, 80, endpoint=False)
    circle = 20.0 * np.column_stack([np.cos(theta), np.sin(theta)])
    for points, closed in ((circle, True), (circle[:50], False)):
        line = Polyline(points, closed)
        a, b = PolylineProgress(line), PolylineProgress(line)
        path = 20.0 * np.column_stack([np.cos(theta), np.sin(theta)])
        path = np.vstack([path, _wiggle(200, rng) + path[-1]])
        for x, y in path:
            proj = a.project((float(x), float(y)))
            got = b.project_xy(float(x), float(y))
            s, lateral, index, tx, ty = got
            assert (s, index, tx, ty) == (proj.station[0], proj.segment[0], *proj.tangent[0])
            assert lateral == pytest.approx(proj.lateral[0], abs=1e-12)


def test_world_state_and_truth_match_the_vehicle_state() -> None:
    world = World(load_track("autocross"), WorldConfig(sensors="rtk"), seed=2)
    world.set_command(0.3, 3.0)
    truths: list[TruthSample] = []
    suite_step = world.sensors.step

    def spy(truth: TruthSample) -> list:
        truths.append(truth)
        return suite_step(truth)

    world.sensors.step = spy  # type: ignore[method-assign]
    for _ in range(300):
        world.step()
        state = world.vehicle.state
        assert astuple(world.state) == astuple(state)
        assert world.pose == state.pose
        assert world.antenna_pose == state.antenna_pose()
        assert world.vehicle.kinematics() == (
            state.x,
            state.y,
            state.yaw,
            state.vx,
            state.vy,
            state.yaw_rate,
            state.ax,
            state.ay,
            state.yaw_accel,
        )
    last = truths[-1]
    checked = TruthSample(**{f.name: getattr(last, f.name) for f in fields(TruthSample)})
    for f in fields(TruthSample):
        assert getattr(checked, f.name) is getattr(last, f.name)
    assert last.cone_positions.shape == (len(last.cone_kinds), 2)


def _circle_truth(t: float) -> TruthSample:
    theta = t / 3.0
    pose = Pose2D(30.0 * math.cos(theta), 30.0 * math.sin(theta), theta + math.pi / 2)
    angles = np.linspace(0.0, 2 * math.pi, 100, endpoint=False)
    cones = np.vstack([r * np.column_stack([np.cos(angles), np.sin(angles)]) for r in (28.0, 32.0)])
    return TruthSample(t, pose, 10.0, 1 / 3.0, 0.0, 10.0 / 3.0, cones, ("blue",) * 200)


def test_suite_early_return_changes_nothing() -> None:
    profile = get_profile("consumer")
    fast, slow = SensorSuite(profile, seed=3), SensorSuite(profile, seed=3)
    for k in range(1, 801):
        truth = _circle_truth(k / 200.0)
        slow._next_capture = -math.inf  # never take the early return
        got, want = fast.step(truth), slow.step(truth)
        assert [repr(m) for m in got] == [repr(m) for m in want]


def test_observation_cone_block_follows_the_detection() -> None:
    """The cached cone blocks of both modes follow the detection and are not
    changed through what a caller was handed (vector mode: / 10 m, blue +1)."""
    memory = SensorMemory()
    command = (0.0, 0.0)
    empty = build_vector(memory, None, command, 4, 10.0, pose_valid=False, now=1.0)
    det = ConeDetections(
        Header(0.1, "os_sensor"), np.array([[1.0, 2.0, 0.0], [3.0, -1.0, 0.0]]), ("blue", "yellow")
    )
    memory.update([det])
    first = build_dict(memory, None, command, 4, now=1.0)
    assert first["cone_mask"].tolist() == [1.0, 1.0, 0.0, 0.0]
    first["cones"][:] = 99.0  # the caller's copy, not the cached block
    again = build_dict(memory, None, command, 4, now=1.0)
    assert again["cones"][:2].tolist() == [[1.0, 2.0], [3.0, -1.0]]
    vec = build_vector(memory, None, command, 4, 10.0, pose_valid=False, now=1.0)
    expected = [0.1, 0.2, 1.0, 1.0, 0.0, 0.3, -0.1, 1.0, -1.0, 0.0]
    assert vec[8:18].tolist() == pytest.approx(expected)
    vec[8:] = 99.0
    assert build_vector(memory, None, command, 4, 10.0, pose_valid=False, now=1.0)[8] != 99.0
    memory.update([ConeDetections(Header(0.2, "os_sensor"), np.zeros((0, 3)), ())])
    later = build_vector(memory, None, command, 4, 10.0, pose_valid=False, now=1.0)
    assert later[8:].tolist() == empty[8:].tolist()


def test_gps_scalar_conversion_is_the_library_one() -> None:
    from conesim.core.geodesy import GeodesyError, local_cartesian_to_gps
    from conesim.sim.sensors.gps import GpsReceiver

    gps = GpsReceiver(get_profile("rtk").gps, 0)
    rng = np.random.default_rng(7)
    for x, y in rng.uniform(-5e4, 5e4, (2000, 2)).tolist():
        lat, lon = local_cartesian_to_gps(x, y, gps.origin)
        assert gps._to_gps(x, y) == (float(lat), float(lon))
    for bad in (math.nan, math.inf, 1e9):
        with pytest.raises(GeodesyError):
            gps._to_gps(0.0, bad)


def test_the_walk_kernel_is_the_python_walk() -> None:
    """The compiled walk and offset give the plain-Python formulation's numbers,
    bit for bit, on a closed circle and off both ends of an open arc."""
    rng = np.random.default_rng(9)
    theta = np.linspace(0.0, 2 * math.pi, 80, endpoint=False)
    circle = 20.0 * np.column_stack([np.cos(theta), np.sin(theta)])
    for points, closed in ((circle, True), (circle[:50], False)):
        tracker = PolylineProgress(Polyline(points, closed))
        segments = [tuple(float(v) for v in row) for row in tracker._segments]
        i = 0
        path = np.vstack([circle * rng.uniform(0.9, 1.1, (80, 1)), _wiggle(200, rng) + circle[0]])
        for x, y in path:
            want = progress_reference.walk(segments, closed, float(x), float(y), i)
            assert tracker._walk(float(x), float(y), i) == want
            j, d2, u, lateral = want
            assert progress._offset(lateral, d2, u, segments[j][4]) == (
                progress_reference.offset(lateral, d2, u, segments[j][4])
            )
            i = j


def test_the_search_kernel_is_the_numpy_search() -> None:
    """The compiled whole-line search gives the numpy formulation's numbers, bit for
    bit, on a closed circle, an open arc (off both ends) and a window wider than the loop."""
    rng = np.random.default_rng(10)
    theta = np.linspace(0.0, 2 * math.pi, 80, endpoint=False)
    circle = 20.0 * np.column_stack([np.cos(theta), np.sin(theta)])
    for points, closed, window_m in ((circle, True, 15.0), (circle[:50], False, 15.0),
                                     (circle, True, 200.0)):  # fmt: skip
        tracker = PolylineProgress(Polyline(points, closed), window_m=window_m)
        vertices = np.ascontiguousarray(points, dtype=float)
        for x, y in rng.uniform(-30.0, 30.0, (300, 2)):
            want = progress_reference.search(
                vertices, tracker._segments, float(x), float(y),
                window=tracker._window, closed=closed,
            )  # fmt: skip
            assert tracker._search(float(x), float(y)) == want
