"""Headless scenario runs: the closed loop, driven by the autopilot, measured.

``run_scenario`` is what ``conesim run``, the lap-completion tests and the
benchmarks call: one episode of a scenario's closed loop
(``envs.scenario.Scenario.closed_loop``) with the autopilot as its driver.
It takes a whole ``Scenario``, or a track and the parts to change (the
keywords it always took, and the parts of a scenario: sensors, faults,
ekf, vehicle). Every step's record goes to the metrics (``envs.metrics``),
and to the bag recorder and the window when asked for; the result, a
``RunResult``, is ``result.json`` (``to_json()``), with the resolved
scenario embedded so that the run can be reproduced from it.
"""

from __future__ import annotations

import dataclasses
import functools
import os
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager, nullcontext
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from conesim.core.geodesy import GeodesyError
from conesim.envs.bag import BagRecorder
from conesim.envs.limit_lap import track_lap_limit
from conesim.envs.loop import ClosedLoop, StepRecord, world_seed
from conesim.envs.map_quality import MapRecorder, MapSnapshot
from conesim.envs.metrics import RunEvents, RunMetrics, RunTrace
from conesim.envs.render import Renderer, SceneKeeper
from conesim.envs.scenario import Scenario
from conesim.envs.scenario_file import scenario_to_mapping
from conesim.localization.ekf import EkfConfig
from conesim.planner import Autopilot, AutopilotConfig
from conesim.sim.sensors import Faults, SensorProfile, get_profile
from conesim.sim.vehicle_params import VehicleParams
from conesim.tracks import (
    DEFAULT_TRACK,
    GeneratedTrack,
    TrackFormatError,
    TrackSource,
    load_track,
    track_label,
)

FloatArray = NDArray[np.float64]

TIMING_FIELDS = ("wall_time_s", "real_time_factor", "setup_time_s")
"""The fields of ``result.json`` that depend on the machine, not on the run:
the same seed gives the same result apart from them."""


@dataclass
class RunResult:
    """What a run reports (``result.json``); ``scenario`` is the resolved scenario
    (``envs.scenario_file.scenario_to_mapping``), from which the run can be made again.
    ``trace`` and ``racing_line`` ((k, 2) [m], the line of ``limit_lap_time_s``, None on
    an open lane; ``envs.limit_lap.LapLimit``) are for ``run.png``, not in the JSON."""

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
    centreline_lap_time_s: float
    lap_time_ratio: float | None
    events: RunEvents = field(default_factory=RunEvents)
    cone_associations: dict[str, float] | None = None
    landmarks: dict[str, int | bool] | None = None
    map_quality: dict[str, float] | None = None
    map_quality_lap: int | None = None
    trace: RunTrace = field(repr=False, default_factory=RunTrace)
    scenario: dict[str, Any] = field(repr=False, default_factory=dict)
    racing_line: FloatArray | None = field(repr=False, default=None)
    slam_map: MapSnapshot | None = field(repr=False, default=None)

    @property
    def clean(self) -> bool:
        """Every lap completed, no cone down or out, no excursion off the track."""
        return self.finished and self.cones_down_or_out == 0 and self.off_track_events == 0

    def to_json(self) -> dict[str, Any]:
        """The JSON-able result (the trace and the racing line left out; ``clean`` added)."""
        out = asdict(self)
        out.pop("trace")
        out.pop("racing_line")
        out.pop("slam_map")
        out["clean"] = self.clean
        return out


def run_scenario(
    track: Scenario | TrackSource = DEFAULT_TRACK,
    *,
    laps: int | None = None,
    seed: int | None = None,
    sensors: SensorProfile | str | None = None,
    localization: str | None = None,
    render: bool = False,
    progress: Callable[[float, float], None] | None = None,
    bag: str | os.PathLike[str] | None = None,
    autopilot: AutopilotConfig | None = None,
    time_limit: float | None = None,
    control_rate: float | None = None,
    physics_rate: float | None = None,
    faults: Faults | None = None,
    ekf: EkfConfig | None = None,
    vehicle: VehicleParams | None = None,
) -> RunResult:
    """Run one episode of a scenario with the autopilot.

    Args:
        track: a whole ``Scenario``, or a shipped track's name, a track file
            or a ``GeneratedTrack`` (then a ``Scenario`` with its defaults:
            ``conesim run``'s).
        laps, seed, localization, autopilot, time_limit, control_rate,
        physics_rate, faults, ekf, vehicle: replace the scenario's field of
            the same name when given (None: the scenario's). ``seed`` gives
            the same episode as ``env.reset(seed=seed)``.
        sensors: replaces the scenario's sensors: a ``SensorProfile`` or a
            shipped profile's name.
        render: show a window (the ``render`` extra).
        progress: called as ``progress(sim_time, time_limit)`` every control step.
        bag: record the run into a new rosbag2 directory there (``envs.bag``;
            the ``ros`` extra). The run is the same with and without it.

    Raises:
        TrackFormatError: the track cannot be read, or the world cannot be
            built on it (the message names the track and its start pose).
        ValueError: a setting out of range.
        BagError: ``bag`` exists and is not an empty directory, or cannot be
            written (checked before the run; nothing is left half written).
        gymnasium.error.DependencyNotInstalled: ``bag`` without the ``ros`` extra.
    """
    scenario = _scenario(
        track, laps=laps, seed=seed, sensors=sensors, localization=localization,
        autopilot=autopilot, time_limit=time_limit, control_rate=control_rate,
        physics_rate=physics_rate, faults=faults, ekf=ekf, vehicle=vehicle,
    )  # fmt: skip
    recorder = None
    if bag is not None:
        recorder = BagRecorder(
            bag,
            {"conesim.track": scenario.track_name, "conesim.seed": str(scenario.seed),
             "conesim.sensors": scenario.sensors.name,
             "conesim.localization": scenario.localization},
        )  # fmt: skip
    setup0 = time.perf_counter()  # building the loop loads (or compiles) the kernels
    config = scenario.autopilot_config()
    with _world_build_errors(scenario.track):
        the_track = load_track(scenario.track)
        loop = scenario.closed_loop(the_track, functools.partial(Autopilot, config=config))
        first = loop.reset(world_seed(np.random.default_rng(scenario.seed)))
    window = _Window(loop) if render else None
    try:
        with recorder or nullcontext():
            result = _drive(
                loop, first, seed=scenario.seed, progress=progress, recorder=recorder,
                window=window, setup0=setup0,
            )  # fmt: skip
    finally:
        if window is not None:
            window.close()
    result.scenario = scenario_to_mapping(scenario)
    return result


def _scenario(track: Scenario | TrackSource, **given: Any) -> Scenario:
    """``track`` as a scenario, with the fields ``given`` (not None) replaced."""
    if isinstance(track, Scenario):
        scenario = track
    else:
        scenario = Scenario(track=track if isinstance(track, GeneratedTrack) else os.fspath(track))
    changes = {name: value for name, value in given.items() if value is not None}
    if isinstance(changes.get("sensors"), str):
        changes["sensors"] = get_profile(changes["sensors"])
    return dataclasses.replace(scenario, **changes) if changes else scenario


@contextmanager
def _world_build_errors(track: TrackSource) -> Iterator[None]:
    """Name the track and its start pose when the world cannot be built on it.

    Such a failure (the start pose out of the geodesy's range) is the track
    file's fault, so it becomes a `TrackFormatError` naming the file.
    """
    try:
        yield
    except GeodesyError as exc:
        pose = load_track(track).start_pose
        raise TrackFormatError(
            f"cannot build the world at the start pose ({pose.x:g}, {pose.y:g}): {exc}",
            track_label(track),
        ) from None


class _Window:
    """``render=True``: each record drawn in a window, at the loop's rate."""

    def __init__(self, loop: ClosedLoop) -> None:
        self.loop = loop
        p = loop.world_config.vehicle
        self.scenes = SceneKeeper(tuple(str(k) for k in loop.track.kinds), p.length, p.width)
        self.renderer = Renderer(loop.global_path)

    def show(self, record: StepRecord) -> None:
        """Draw the record."""
        self.scenes.update(record)
        loc = self.loop.localizer
        frame = self.renderer.rgb_array(self.scenes.scene(loc.frames, loc.estimate(record.t)))
        self.renderer.show(frame, self.loop.control_rate)

    def close(self) -> None:
        """Close the window."""
        self.renderer.close()


def _drive(
    loop: ClosedLoop,
    record: StepRecord,
    *,
    seed: int,
    progress: Callable[[float, float], None] | None,
    recorder: BagRecorder | None,
    window: _Window | None,
    setup0: float,
) -> RunResult:
    """Drive the episode from its first record; ``setup0``: when building began (perf_counter)."""
    metrics = RunMetrics(loop.track)
    mapped = MapRecorder()
    if recorder is not None:
        recorder.start(loop)
    limit = loop.rules.time_limit_s
    # The loop's clock starts here: building the world, localization and the
    # autopilot (loading the compiled kernels, or compiling them on a cold
    # cache) is the setup, reported apart.
    wall0 = time.perf_counter()
    setup = wall0 - setup0
    while True:
        metrics.add(record)
        mapped.observe(loop, record)
        if recorder is not None:
            recorder.record(record)
        if window is not None:
            window.show(record)
        if record.end is not None:
            break
        record = loop.step()
        if progress is not None:
            progress(record.t, limit)
    wall = time.perf_counter() - wall0
    mapped.finish(loop, record)
    result = _result(loop, record, metrics, seed=seed, wall=wall, setup=setup)
    snap = mapped.snapshot
    if snap is not None:
        result.slam_map = snap
        result.map_quality = snap.quality.as_dict()
        result.map_quality_lap = snap.lap
    return result


def _result(
    loop: ClosedLoop, last: StepRecord, metrics: RunMetrics, *, seed: int, wall: float, setup: float
) -> RunResult:
    race = last.truth.race
    lap_times = [float(v) for v in race.lap_times]
    limit = track_lap_limit(loop.track, loop.world_config.vehicle)
    best = min(lap_times) if lap_times else None
    return RunResult(
        track=loop.track.name,
        seed=seed,
        sensors=loop.world_config.sensor_profile.name,
        localization=loop.localization,
        laps=loop.laps_to_drive,
        finished=race.laps_completed >= loop.laps_to_drive,
        end_reason=str(last.end),
        laps_completed=race.laps_completed,
        lap_times_s=lap_times,
        best_lap_s=best,
        cones_hit=race.cones_hit,
        cones_down_or_out=race.cones_down_or_out,
        off_track_events=race.off_track_events,
        sim_time_s=last.t,
        wall_time_s=wall,
        real_time_factor=last.t / wall if wall > 0 else float("inf"),
        setup_time_s=setup,
        localization_pos_rmse_m=metrics.localization_pos_rmse_m,
        localization_yaw_rmse_deg=metrics.localization_yaw_rmse_deg,
        midline_rmse_m=metrics.midline_rmse_m,
        planner_fallbacks=metrics.fallbacks,
        limit_lap_time_s=limit.limit_s,
        centreline_lap_time_s=limit.centreline_s,
        lap_time_ratio=None if best is None else best / limit.limit_s,
        events=metrics.events,
        cone_associations=_cone_associations(loop),
        landmarks=_landmarks(loop),
        trace=metrics.trace,
        racing_line=limit.racing_line,
    )


def _cone_associations(loop: ClosedLoop) -> dict[str, float] | None:
    """The filter's cone association counts (``cones``, ``slam`` localization), else None."""
    ekf = loop.localizer.ekf
    if loop.localization not in ("cones", "slam") or ekf is None:
        return None
    return ekf.health.cones.as_dict()


def _landmarks(loop: ClosedLoop) -> dict[str, int | bool] | None:
    """The map's landmark counts at the end (``slam`` localization), else None."""
    ekf = loop.localizer.ekf
    counts = None if ekf is None else ekf.health.landmarks
    return None if counts is None else counts.as_dict()
