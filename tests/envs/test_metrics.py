"""The run's metrics from the loop's records: events as result.json lists them."""

from __future__ import annotations

import json
from dataclasses import asdict

import pytest

from conesim.core.pose import Pose2D
from conesim.envs.loop import ClosedLoop, EpisodeRules
from conesim.envs.metrics import RunMetrics
from conesim.envs.runner import run_scenario
from conesim.planner.messages import ControlCommand
from conesim.sim.world import WorldConfig
from conesim.tracks import load_track


def test_cone_events_name_the_cone_its_kind_and_place() -> None:
    """Down the acceleration lane's left cones: each hit and each knocked cone
    once, with its index, kind and surveyed position, in time order; the
    end where the loop stopped, at the CG."""
    track = load_track("acceleration")
    left = track.left_boundary
    start = Pose2D(float(left[0, 0]) - 3.0, float(left[0, 1]), 0.0)
    rules = EpisodeRules(end_on_off_track=False, time_limit=4.0)
    loop = ClosedLoop(track, WorldConfig(sensors="ideal"), rules=rules)
    metrics = RunMetrics(track)
    record = loop.reset(seed=0, start_pose=start)
    metrics.add(record)
    while record.end is None:
        record = loop.step(ControlCommand(record.t, 0.0, 3.0))
        metrics.add(record)
    ev = metrics.events
    assert len(ev.cones_hit) == record.truth.race.cones_hit >= 2
    assert len(ev.cones_down_or_out) == record.truth.race.cones_down_or_out >= 2
    for row in ev.cones_hit + ev.cones_down_or_out:
        assert row.kind == str(track.kinds[row.cone])
        assert (row.x, row.y) == tuple(track.cones[row.cone])
    assert [r.t for r in ev.cones_hit] == sorted(r.t for r in ev.cones_hit)
    assert ev.end is not None and ev.end.reason == "time_limit"
    assert ev.end.t == pytest.approx(4.0)
    assert (ev.end.x, ev.end.y) == (record.truth.state.x, record.truth.state.y)


def test_an_excursion_has_its_start_place_end_and_duration() -> None:
    """Full lock off the trackdrive start, off-track not ending the run: the
    first excursion's duration is its end minus its start, and one that is
    still under way at the end lasts to the end."""
    track = load_track("trackdrive")
    rules = EpisodeRules(end_on_off_track=False, end_on_stuck=False, time_limit=20.0)
    loop = ClosedLoop(track, WorldConfig(sensors="ideal"), rules=rules)
    metrics = RunMetrics(track)
    record = loop.reset(seed=0)
    metrics.add(record)
    while record.end is None:
        record = loop.step(ControlCommand(record.t, 0.47, 6.0))
        metrics.add(record)
    excursions = metrics.events.off_track
    assert excursions and record.truth.race.off_track_events == len(excursions)
    first = excursions[0]
    assert first.t_end is not None and first.duration_s == pytest.approx(
        first.t_end - first.t_start
    )
    for e in excursions:
        end = e.t_end if e.t_end is not None else record.t
        assert e.duration_s == pytest.approx(end - e.t_start)


def test_result_json_lists_laps_and_the_end() -> None:
    """A clean acceleration run: one lap, its time that of lap_times_s, the end
    with its reason; no cone events; all of it JSON."""
    result = run_scenario("acceleration", sensors="ideal")
    payload = json.loads(json.dumps(result.to_json()))
    events = payload["events"]
    assert [lap["lap"] for lap in events["laps"]] == [1]
    assert events["laps"][0]["time_s"] == result.lap_times_s[0]
    assert events["cones_hit"] == [] and events["off_track"] == []
    assert events["end"]["reason"] == "laps_completed" == result.end_reason
    assert events["end"]["t"] == result.sim_time_s
    assert payload["events"] == asdict(result.events)
