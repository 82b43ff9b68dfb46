"""Tests for World.reset: a reset world runs the episode of a new one, bit for bit."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import astuple

import numpy as np

from conesim.core.pose import Pose2D
from conesim.sim.world import World, WorldConfig
from conesim.tracks import Track, load_track

Command = Callable[[int], tuple[float, float]]


def straight(accel: float, steer: float = 0.0) -> Command:
    """A held command: ``steer`` [rad], ``accel`` [m/s^2]."""
    return lambda k: (steer, accel)


def weave(k: int) -> tuple[float, float]:
    """A lap-like drive: a slow weave at 2 m/s^2."""
    return 0.2 * math.sin(k / 50), 2.0


def episode(world: World, first: list[object], command: Command, steps: int) -> list[object]:
    """Everything an episode shows, as plain values: the t = 0 messages, then
    each step's messages, events and true state, then the cones at the end."""
    out: list[object] = [flat(first)]
    for k in range(steps):
        world.set_command(*command(k))
        step = world.step()
        out += [step.t, flat(step.messages), step.events, world.state]
    cones = world.cones
    out += [cones.positions.tobytes(), sorted(cones.hit_ids), cones.hit_events, cones.doo_events]
    out += [world.standing(), world.race_state.progress_m]
    return out


def flat(messages: list[object]) -> list[tuple[object, ...]]:
    """Messages as tuples of numbers, arrays as bytes (exact comparison)."""
    return [
        tuple(v.tobytes() if isinstance(v, np.ndarray) else v for v in astuple(m))  # type: ignore[call-overload]
        for m in messages
    ]


def fresh(
    track: Track, config: WorldConfig, seed: int, pose: Pose2D | None, drive: tuple[Command, int]
) -> list[object]:
    """The episode in a new world: ``drive`` is the command and the steps."""
    world = World(track, config, seed, pose)
    return episode(world, world.initial_messages, *drive)


def into_the_cones(track: Track, k: int) -> Pose2D:
    """A start 3 m behind the ``k``-th cone of the left line, heading along +x, a
    little to its right: full throttle pushes cones into each other."""
    left = track.left_boundary
    return Pose2D(float(left[k, 0]) - 3.0, float(left[k, 1]) - 0.1 * k, 0.02 * k)


def test_reset_runs_a_new_worlds_episode_after_cones_were_knocked() -> None:
    """Consecutive resets of one world with other seeds and start poses, each
    after an episode that knocked cones and ended with cones still sliding
    and the car against them: each episode is a new world's, bit for bit."""
    track = load_track("acceleration")
    for sensors in ("ideal", "rtk"):
        config = WorldConfig(sensors=sensors)
        world = World(track, config, seed=50)
        for seed, (k, steps) in enumerate([(0, 700), (2, 500), (4, 600), (1, 650)]):
            pose = into_the_cones(track, k)
            # Knock cones, and stop while they move and the car pushes them.
            world.reset(seed + 100, pose)
            episode(world, [], straight(6.0), 300 + 40 * k)
            assert world.cones.awake_count > 0 and world.cones.hit_ids
            got = episode(world, world.reset(seed, pose), straight(3.0), steps)
            assert world.cones.hit_ids, "the test drives into the cones"
            assert got == fresh(track, config, seed, pose, (straight(3.0), steps))


def test_reset_after_a_drive_that_touched_nothing() -> None:
    """The car joins the new space where a new car does (Chipmunk indexes a
    shape where it joins; the index shapes later contacts): after a short
    drive that touched no cone, the next episode's impacts are a new world's."""
    track = load_track("acceleration")
    config = WorldConfig(sensors="ideal")
    pose = into_the_cones(track, 0)
    world = World(track, config, seed=99)
    want = fresh(track, config, 1, pose, (straight(3.0), 300))
    for steps in (9, 37):
        world.reset(101, pose)
        episode(world, [], straight(3.0), steps)
        assert not world.cones.hit_ids
        got = episode(world, world.reset(1, pose), straight(3.0), 300)
        assert world.cones.hit_ids
        assert got == want


def test_reset_after_a_start_on_a_cone() -> None:
    """A start pose on a cone: Chipmunk's solver pushes the car and the cone
    apart with bias velocities that pymunk cannot reset; an episode reset
    right after it (or after a few steps) is still a new world's."""
    track = load_track("acceleration")
    config = WorldConfig(sensors="ideal")
    cone = track.cones[0]
    on_cone = Pose2D(float(cone[0]) + 0.5, float(cone[1]) - 0.3, 0.3)
    world = World(track, config, seed=5)
    for seed, (pose, before) in enumerate([(into_the_cones(track, 0), 0), (on_cone, 3)]):
        world.reset(seed + 10, on_cone)
        assert world.cones.hit_ids  # the car stands on the cone
        episode(world, [], straight(3.0), before)
        got = episode(world, world.reset(seed, pose), straight(3.0), 300)
        assert got == fresh(track, config, seed, pose, (straight(3.0), 300))


def test_reset_runs_a_new_worlds_lap_segment() -> None:
    """Trackdrive from its start and from another pose, rtk sensors: the same
    seeds give a new world's episodes, also after a reset to another start."""
    track = load_track("trackdrive")
    config = WorldConfig()
    start = track.start_pose
    other = Pose2D(start.x + 4.0, start.y + 0.3, start.yaw + 0.05)
    world = World(track, config, seed=3)
    for seed, pose in [(3, None), (8, other), (3, None), (11, start)]:
        got = episode(world, world.reset(seed, pose), weave, 900)
        assert got == fresh(track, config, seed, pose, (weave, 900))


def test_reset_keeps_the_bodies_in_a_new_space() -> None:
    """A reset moves the same car and cone bodies into a new space; the old
    space is left empty."""
    world = World(load_track("acceleration"), WorldConfig(sensors="ideal"))
    space, body, cones = world.space, world.vehicle.body, list(world.cones.bodies)
    world.reset(1)
    assert world.space is not space and not space.bodies and not space.shapes
    assert world.vehicle.body is body and world.cones.bodies == cones
    assert len(world.space.bodies) == 1 + len(cones)
