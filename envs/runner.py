"""Headless scenario runs: the env, driven by the autopilot, measured.

``run_scenario`` is what ``conesim run``, the lap-completion tests and the
benchmarks call: one episode of ``ConeTrack-v0`` with the ``AutopilotPolicy``,
recording what the result needs (trajectory, localization error at every
broadcast, the planner's midline error, speeds) and returning a
``RunResult`` whose ``to_json()`` is ``result.json``.
"""

from __future__ import annotations

import math
import os
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager, nullcontext
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np
from scipy.spatial import cKDTree

from conesim.core.geodesy import GeodesyError
from conesim.envs.autopilot_policy import AutopilotPolicy
from conesim.envs.bag import BagRecorder
from conesim.envs.cone_track_env import ConeTrackEnv
from conesim.envs.limit_lap import limit_lap_time
from conesim.sim.progress import PolylineProgress
from conesim.sim.race_control import line_crossings_along
from conesim.tracks import Track, TrackFormatError, load_track

MIDLINE_SAMPLE_M = 0.05  # [m] spacing of the densified true centreline


@dataclass
class RunTrace:
    """Per control step samples for the run picture."""

    t: list[float] = field(default_factory=list)
    x: list[float] = field(default_factory=list)
    y: list[float] = field(default_factory=list)
    speed: list[float] = field(default_factory=list)
    target_speed: list[float] = field(default_factory=list)
    loc_t: list[float] = field(default_factory=list)
    loc_pos_err: list[float] = field(default_factory=list)
    loc_yaw_err: list[float] = field(default_factory=list)


TIMING_FIELDS = ("wall_time_s", "real_time_factor", "setup_time_s")
"""The fields of ``result.json`` that depend on the machine, not on the run:
the same seed gives the same result apart from them."""


@dataclass
class RunResult:
    """What a run reports (``result.json``)."""

    track: str
    seed: int
    sensors: str
    localization: str
    laps: int
    finished: bool
    end_reason: str
    laps_completed: int
    lap_times_s: list[float]
    best_lap_s: float | None
    cones_hit: int
    cones_down_or_out: int
    off_track_events: int
    sim_time_s: float
    wall_time_s: float
    real_time_factor: float
    setup_time_s: float
    localization_pos_rmse_m: float | None
    localization_yaw_rmse_deg: float | None
    midline_rmse_m: float | None
    planner_fallbacks: int
    limit_lap_time_s: float
    lap_time_ratio: float | None
    trace: RunTrace = field(repr=False, default_factory=RunTrace)

    def to_json(self) -> dict[str, Any]:
        """The JSON-able result (the trace left out)."""
        out = asdict(self)
        out.pop("trace")
        return out


def timed_limit_lap(track: Track) -> float:
    """The friction-limited lap time for the track's timed lap [s].

    A loop: a flying lap of the centreline. The skidpad: one flying circle
    (the centreline between its first two crossings of the timing line). An
    open lane: from rest at the car's start, timed from the start line to the
    finish line, as race control times the simulated run.
    """
    centre = np.asarray(track.centreline)
    if track.layout == "closed":
        return limit_lap_time(centre, True)
    seg = np.hypot(*np.diff(centre, axis=0).T)
    s = np.concatenate([[0.0], np.cumsum(seg)])
    finishes = line_crossings_along(centre, False, np.asarray(track.finish_line))
    if track.layout == "skidpad" and len(finishes) >= 2:
        mask = (s >= finishes[0]) & (s < finishes[1])
        return limit_lap_time(centre[mask], True)
    starts = line_crossings_along(centre, False, np.asarray(track.start_finish))
    start_s = PolylineProgress(centre, False).project(track.start_pose.xy).s
    return limit_lap_time(
        centre,
        False,
        start_s=start_s,
        timed_from_s=starts[0] if starts else start_s,
        timed_to_s=finishes[0] if finishes else None,
    )


def run_scenario(
    track: str = "trackdrive",
    *,
    laps: int = 1,
    seed: int = 0,
    sensors: str = "rtk",
    localization: str = "fused",
    render: bool = False,
    progress: Callable[[float, float], None] | None = None,
    env_options: dict[str, Any] | None = None,
    bag: str | os.PathLike[str] | None = None,
) -> RunResult:
    """Run one episode with the autopilot.

    Args:
        track: shipped track name or a track file.
        laps: laps to drive.
        seed: episode seed.
        sensors: sensor profile.
        localization: ``fused``, ``raw`` or ``truth``.
        render: show a window (the ``render`` extra).
        progress: called as ``progress(sim_time, time_limit)`` every control step.
        env_options: further ``EnvConfig`` fields (not the ones named above).
        bag: record the run into a new rosbag2 directory there (``envs.bag``;
            the ``ros`` extra). The run is the same with and without it.

    Raises:
        TrackFormatError: the track cannot be read, or the world cannot be
            built on it (the message names the track and its start pose).
        ValueError: ``env_options`` repeats an argument of this function, or
            ``EnvConfig`` refuses a field.
        BagError: ``bag`` exists and is not an empty directory, or cannot be
            written (checked before the run; nothing is left half written).
        gymnasium.error.DependencyNotInstalled: ``bag`` without the ``ros`` extra.
    """
    # env_options keys that run_scenario sets itself, and the keyword to use instead
    own = {
        "track": "track",
        "laps": "laps",
        "sensors": "sensors",
        "localization": "localization",
        "render_mode": "render",
    }
    repeated = sorted(own.keys() & (env_options or {}).keys())
    if repeated:
        instead = ", ".join(f"{own[k]}=" for k in repeated)
        raise ValueError(
            f"run_scenario: env_options {repeated} repeat arguments of run_scenario; "
            f"pass {instead} instead"
        )
    recorder = None
    if bag is not None:
        recorder = BagRecorder(
            bag,
            {"conesim.track": track, "conesim.seed": str(seed), "conesim.sensors": sensors,
             "conesim.localization": localization},
        )  # fmt: skip
    setup0 = time.perf_counter()  # building the env loads (or compiles) the EKF's kernels
    with _world_build_errors(track):
        env = ConeTrackEnv(
            render_mode="human" if render else None,
            track=track,
            laps=laps,
            sensors=sensors,
            localization=localization,
            **(env_options or {}),
        )
    try:
        with recorder or nullcontext():
            return _drive(env, seed, progress, recorder, setup0)
    finally:
        env.close()


@contextmanager
def _world_build_errors(track: str) -> Iterator[None]:
    """Name the track and its start pose when the world cannot be built on it.

    Such a failure (the start pose out of the geodesy's range) is the track
    file's fault, so it becomes a `TrackFormatError` naming the file.
    """
    try:
        yield
    except GeodesyError as exc:
        pose = load_track(track).start_pose
        raise TrackFormatError(
            f"cannot build the world at the start pose ({pose.x:g}, {pose.y:g}): {exc}", track
        ) from None


def _drive(
    env: ConeTrackEnv,
    seed: int,
    progress: Callable[[float, float], None] | None,
    recorder: BagRecorder | None,
    setup0: float,
) -> RunResult:
    """Drive one episode; ``setup0``: when building the env began (perf_counter)."""
    cfg = env.config
    with _world_build_errors(cfg.track):
        _, info = env.reset(seed=seed)
    policy = AutopilotPolicy(env)
    action = policy.reset(info)
    if recorder is not None:
        recorder.start(env.stack, policy.autopilot)
    track = env.stack.track
    centre_tree = _dense_centreline_tree(track)
    trace = RunTrace()
    midline_sq: list[float] = []
    last_plan = None
    limit = cfg.episode_time_limit
    # The loop's clock starts here: building the world, the stack and the
    # autopilot (loading the compiled kernels, or compiling them on a cold
    # cache) is the setup, reported apart.
    wall0 = time.perf_counter()
    setup = wall0 - setup0
    while True:
        _, _, terminated, truncated, info = env.step(action)
        action = policy(info)
        _record(env, policy, trace)
        if recorder is not None:
            recorder.record(env.stack, policy.autopilot)
        plan = policy.autopilot.plan
        if plan is not None and plan is not last_plan and len(policy.autopilot.path_reference):
            dist, _ = centre_tree.query(policy.autopilot.path_reference)
            midline_sq.extend((dist**2).tolist())
            last_plan = plan
        if progress is not None:
            progress(env.stack.time, limit)
        if terminated or truncated:
            break
    wall = time.perf_counter() - wall0
    _localization_trace(env, trace)
    return _result(
        env, policy, info=info, trace=trace, midline_sq=midline_sq, seed=seed,
        wall=wall, setup=setup,
    )  # fmt: skip


def _dense_centreline_tree(track: Track) -> cKDTree:
    centre = np.asarray(track.centreline)
    if track.layout == "closed":
        centre = np.vstack([centre, centre[:1]])
    seg = np.hypot(*np.diff(centre, axis=0).T)
    s = np.concatenate([[0.0], np.cumsum(seg)])
    fine = np.arange(0.0, s[-1], MIDLINE_SAMPLE_M)
    return cKDTree(
        np.column_stack([np.interp(fine, s, centre[:, 0]), np.interp(fine, s, centre[:, 1])])
    )


def _record(env: ConeTrackEnv, policy: AutopilotPolicy, trace: RunTrace) -> None:
    world = env.stack.world
    t = world.time
    state = world.state
    trace.t.append(t)
    trace.x.append(state.x)
    trace.y.append(state.y)
    trace.speed.append(state.speed)
    trace.target_speed.append(policy.autopilot.target_speed)


def _localization_trace(env: ConeTrackEnv, trace: RunTrace) -> None:
    """The published pose against truth at every TF broadcast (all three modes)."""
    for sample in env.stack.localization_samples:
        trace.loc_t.append(sample.t)
        trace.loc_pos_err.append(sample.position_error)
        trace.loc_yaw_err.append(sample.yaw_error)


def _rms(values: list[float]) -> float | None:
    return float(math.sqrt(np.mean(np.square(values)))) if values else None


def _result(
    env: ConeTrackEnv,
    policy: AutopilotPolicy,
    *,
    info: dict[str, Any],
    trace: RunTrace,
    midline_sq: list[float],
    wall: float,
    setup: float,
    seed: int,
) -> RunResult:
    world = env.stack.world
    lap_times = [float(v) for v in info["lap_times"]]
    limit = timed_limit_lap(env.stack.track)
    best = min(lap_times) if lap_times else None
    yaw_rmse = _rms(trace.loc_yaw_err)
    return RunResult(
        track=env.stack.track.name,
        seed=seed,
        sensors=env.stack.world_config.sensor_profile.name,
        localization=env.stack.localization,
        laps=env.laps_to_drive,
        finished=info["laps_completed"] >= env.laps_to_drive,
        end_reason=info["end_reason"],
        laps_completed=int(info["laps_completed"]),
        lap_times_s=lap_times,
        best_lap_s=best,
        cones_hit=int(info["cones_hit"]),
        cones_down_or_out=int(info["cones_down_or_out"]),
        off_track_events=int(info["off_track_events"]),
        sim_time_s=world.time,
        wall_time_s=wall,
        real_time_factor=world.time / wall if wall > 0 else math.inf,
        setup_time_s=setup,
        localization_pos_rmse_m=_rms(trace.loc_pos_err),
        localization_yaw_rmse_deg=None if yaw_rmse is None else math.degrees(yaw_rmse),
        midline_rmse_m=float(math.sqrt(np.mean(midline_sq))) if midline_sq else None,
        planner_fallbacks=policy.autopilot.fallback_count,
        limit_lap_time_s=limit,
        lap_time_ratio=None if best is None else best / limit,
        trace=trace,
    )
