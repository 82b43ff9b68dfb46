"""The closed loop: one step's data path, its records, events and end, its driver."""

from __future__ import annotations

import dataclasses
import functools

import numpy as np
import pytest

from conesim.core.messages import ConeDetections, Imu, NavSatFix, PointStamped, WheelSpeed
from conesim.core.pose import Pose2D
from conesim.envs.loop import ClosedLoop, EndReason, EpisodeRules, world_seed
from conesim.planner import Autopilot, AutopilotConfig
from conesim.planner.messages import ControlCommand
from conesim.sim.events import BackOnTrack, ConeDown, ConeHit, LapCompleted, OffTrack
from conesim.sim.world import WorldConfig
from conesim.tracks import load_track


def test_a_step_is_one_control_period_of_physics_localization_and_command() -> None:
    """rtk sensors, 200 Hz physics, 50 Hz control: each step advances 0.02 s
    over 4 physics steps; the IMU (100 Hz) delivers 2 samples and the wheel
    encoders (50 Hz) 1, at physics step times; the broadcaster's 20 Hz grid
    gives 5 broadcasts in 0.26 s (t = 0.05, ..., 0.25) after the reset's."""
    loop = ClosedLoop(load_track("acceleration"), WorldConfig(sensors="rtk"), localization="truth")
    assert loop.substeps == 4
    first = loop.reset(seed=0)
    assert first.t == 0.0 and first.end is None
    assert [b.t for b in first.broadcasts] == [0.0]
    records = [loop.step(ControlCommand(0.0, 0.0, 2.0)) for _ in range(13)]
    assert [r.t for r in records] == pytest.approx(np.arange(1, 14) * 0.02)
    for record in records[1:]:  # the IMU's first sample comes at 0.01 s
        kinds = [type(d.message) for d in record.deliveries]
        assert kinds.count(Imu) == 2 and kinds.count(WheelSpeed) == 1
        assert all(record.t - 0.02 < d.t <= record.t + 1e-12 for d in record.deliveries)
    broadcasts = [b.t for r in records for b in r.broadcasts]
    assert broadcasts == pytest.approx([0.05, 0.10, 0.15, 0.20, 0.25])
    # truth mode: the published pose is the true one, exactly
    assert all(
        b.position_error == 0.0 and b.yaw_error == 0.0 for r in records for b in r.broadcasts
    )
    assert records[-1].command == ControlCommand(0.0, 0.0, 2.0)  # held by the world
    assert records[-1].truth.state.vx > 0.5  # 2 m/s^2 for 0.26 s, less the actuator's lag


def test_each_fix_becomes_a_local_xy_point_at_its_delivery() -> None:
    """Every fix delivered is converted once, at the same delivery time."""
    loop = ClosedLoop(load_track("acceleration"), WorldConfig(sensors="rtk"), localization="raw")
    records = [loop.reset(seed=1)] + [loop.step(ControlCommand(0.0, 0.0, 0.0)) for _ in range(30)]
    fixes = [(d.t, d.message) for r in records for d in r.deliveries]
    fixes = [(t, m) for t, m in fixes if isinstance(m, NavSatFix)]
    points = [(d.t, d.message) for r in records for d in r.local_xy]
    assert len(fixes) == len(points) >= 5  # 10 Hz for 0.6 s
    for (t_fix, fix), (t_point, point) in zip(fixes, points, strict=True):
        assert t_fix == t_point and isinstance(point, PointStamped)
        assert point.header.stamp == fix.header.stamp and point.header.frame_id == "reference"


def test_driving_into_the_cones_reports_each_hit_and_knock_once() -> None:
    """Down the acceleration lane's left cone line at 3 m/s^2 for 4 s: every
    cone hit is one ConeHit (at its place), every cone knocked one ConeDown,
    and the standing counts them the same."""
    track = load_track("acceleration")
    left = track.left_boundary
    start = Pose2D(float(left[0, 0]) - 3.0, float(left[0, 1]), 0.0)
    loop = ClosedLoop(
        track, WorldConfig(sensors="ideal"), rules=EpisodeRules(end_on_off_track=False)
    )
    loop.reset(seed=0, start_pose=start)
    events = []
    moved = 0
    for _ in range(200):
        record = loop.step(ControlCommand(0.0, 0.0, 3.0))
        events += record.events
        moved += record.truth.cones_moved
    hits = [e for e in events if isinstance(e, ConeHit)]
    downs = [e for e in events if isinstance(e, ConeDown)]
    assert {0, 1} <= {e.cone for e in hits}
    assert len({e.cone for e in hits}) == len(hits) == record.truth.race.cones_hit
    assert len({e.cone for e in downs}) == len(downs) == record.truth.race.cones_down_or_out
    assert {0, 1} <= {e.cone for e in downs}
    for e in hits:
        assert (e.x, e.y) == tuple(track.cones[e.cone])
    assert moved and not np.array_equal(record.truth.cones, track.cones)


def test_leaving_the_track_is_an_event_and_by_default_the_end() -> None:
    """Full lock at 6 m/s^2 off the trackdrive start: an OffTrack event, and
    the episode ends off_track (terminal); without that rule the car's return
    is a BackOnTrack event later."""
    track = load_track("trackdrive")
    command = ControlCommand(0.0, 0.47, 6.0)
    loop = ClosedLoop(track, WorldConfig(sensors="ideal"))
    loop.reset(seed=0)
    record = loop.step(command)
    while record.end is None:
        record = loop.step()
    assert record.end is EndReason.OFF_TRACK and not record.end.truncated
    (off,) = [e for e in record.events if isinstance(e, OffTrack)]
    assert off.t == pytest.approx(record.t, abs=0.02)
    rules = EpisodeRules(end_on_stuck=False, end_on_off_track=False, time_limit=30.0)
    loose = ClosedLoop(track, WorldConfig(sensors="ideal"), rules=rules)
    loose.reset(seed=0)
    kinds = []
    record = loose.step(command)
    while record.end is None:
        kinds += [type(e) for e in record.events if isinstance(e, OffTrack | BackOnTrack)]
        record = loose.step()
    assert kinds[:2] == [OffTrack, BackOnTrack]
    assert record.end is EndReason.TIME_LIMIT and record.end.truncated
    assert record.t == pytest.approx(30.0)


def test_the_autopilot_drives_the_loop_to_a_lap() -> None:
    """The autopilot as the loop's driver finishes the acceleration run: one
    LapCompleted event whose lap time is the standing's; the driver was built
    on the episode's frame tree and global path, at the loop's rate."""
    built = []

    def factory(frames, global_path, *, control_rate):  # type: ignore[no-untyped-def]
        built.append((frames, global_path, control_rate))
        return Autopilot(frames, global_path, AutopilotConfig(), control_rate=control_rate)

    loop = ClosedLoop(load_track("acceleration"), WorldConfig(sensors="ideal"), driver=factory)
    record = loop.reset(seed=world_seed(np.random.default_rng(0)))
    assert built == [(loop.localizer.frames, loop.global_path, 50.0)]
    assert record.driver is not None and record.command == record.driver.command
    laps = []
    while record.end is None:
        record = loop.step()
        laps += [e for e in record.events if isinstance(e, LapCompleted)]
    assert record.end is EndReason.LAPS_COMPLETED
    ((lap,),) = (laps,)
    assert lap.lap == 1 and (lap.lap_time,) == record.truth.race.lap_times
    assert 5.0 < lap.lap_time < 8.0  # 75 m from rest


def test_same_seed_same_records() -> None:
    """Two loops, one seed: the same states, messages and commands, bit for bit."""

    def run() -> list[tuple[float, ...]]:
        loop = ClosedLoop(
            load_track("skidpad"),
            WorldConfig(sensors="rtk"),
            driver=functools.partial(Autopilot, config=AutopilotConfig()),
        )
        record = loop.reset(seed=7)
        out = []
        for _ in range(100):
            record = loop.step()
            s = record.truth.state
            detections = [d.message for d in record.deliveries]
            n = sum(len(m) for m in detections if isinstance(m, ConeDetections))
            out.append((s.x, s.y, s.yaw, record.command.steering, record.command.acceleration, n))
        return out

    assert run() == run()


def test_bad_settings_and_order() -> None:
    """A rate that does not divide the physics rate, and a step before reset, are refused."""
    track = load_track("acceleration")
    with pytest.raises(ValueError, match="whole multiple"):
        ClosedLoop(track, control_rate=30.0)
    with pytest.raises(ValueError, match=r"EpisodeRules\.laps"):
        EpisodeRules(laps=0)
    with pytest.raises(RuntimeError, match="before reset"):
        ClosedLoop(track).step()


def exact(message: object) -> tuple[object, ...]:
    """A message's fields, arrays as bytes: for comparison bit for bit."""
    values = dataclasses.astuple(message)  # type: ignore[call-overload]
    return tuple(v.tobytes() if isinstance(v, np.ndarray) else v for v in values)


def test_a_reset_loop_runs_a_new_loops_episode_on_the_same_world() -> None:
    """Resets of one loop with other seeds and starts, after episodes that
    knocked cones: the same world object, and each episode's records are a
    new loop's, bit for bit."""
    track = load_track("acceleration")
    left = track.left_boundary
    rules = EpisodeRules(end_on_off_track=False)

    def run(loop: ClosedLoop, seed: int, start: Pose2D | None) -> list[object]:
        records = [loop.reset(seed=seed, start_pose=start)]
        records += [loop.step(ControlCommand(0.0, 0.02, 4.0)) for _ in range(120)]
        return [(r.t, [exact(m) for m in r.messages], r.events, r.truth.state,
                 r.truth.cones.tobytes(), r.truth.race, r.command, r.end)
                for r in records]  # fmt: skip

    loop = ClosedLoop(track, WorldConfig(sensors="rtk"), localization="fused", rules=rules)
    starts = [Pose2D(float(left[k, 0]) - 3.0, float(left[k, 1]) - 0.2, 0.0) for k in (0, 2)]
    world = None
    for seed, start in [(1, starts[0]), (2, None), (3, starts[1]), (1, starts[0])]:
        got = run(loop, seed, start)
        assert world is None or loop.world is world
        world = loop.world
        new = ClosedLoop(track, WorldConfig(sensors="rtk"), localization="fused", rules=rules)
        assert got == run(new, seed, start)
    assert loop.world.cones.hit_ids  # the last episode knocked cones
