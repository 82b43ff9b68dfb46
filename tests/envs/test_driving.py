"""Clean driving on tracks the planner was not tuned on (issue 15 part 4), in closed loop.

Cheap runs: one lap each, rtk sensors, fused localization. The figures over
many tracks and faults are ``benchmarks/bench_driving.py``'s.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from conesim.envs.runner import RunResult, run_scenario
from conesim.envs.scenario import Scenario
from conesim.tracks import Track, load_track, write_track
from conesim.tracks.generate import GeneratedTrack, Size, TrackSpec
from conesim.tracks.generate.hard import hairpin_loop, hard_loop
from conesim.tracks.survey import PathSurvey


def clean(r: RunResult) -> bool:
    """All laps, no cone down or out, no off-track event."""
    return r.finished and r.cones_down_or_out == 0 and r.off_track_events == 0


def written(track: Track, tmp_path: Path) -> str:
    """The track as a file."""
    return str(write_track(track, tmp_path / f"{track.name}.yaml"))


def test_hairpins_of_3_m_lane_centre_radius_behind_a_wide_gate(tmp_path: Path) -> None:
    """Two hairpins of 3 m lane-centre radius (3.5 m lane: 9.5 m outside diameter),
    an S-bend, and a start gate 0.5 m wider than the lane each side: a clean lap
    from standstill. At full lock (rear axle on 3.0 m) the front corner runs on
    sqrt(3.7^2 + 2.28^2) = 4.35 m, inside the outer cones' 4.75 m."""
    track = hairpin_loop(3.0, width=3.5, gate_offset=0.5)
    r = run_scenario(written(track, tmp_path), laps=1, seed=0)
    assert clean(r), (r.end_reason, r.events.cones_down_or_out)
    assert r.cones_hit == 0


@pytest.mark.parametrize("track", ["trackdrive", "autocross"])
def test_a_surveyed_global_path_is_enough(track: str) -> None:
    """A global path with 0.2 m of noise per point and a 0.3 m bias: still clean."""
    survey = PathSurvey(noise=0.2, bias=0.3, seed=1)
    r = run_scenario(Scenario(track=track, laps=1, seed=0, global_path=survey))
    assert clean(r), (r.end_reason, r.events.cones_down_or_out)


@pytest.mark.parametrize("seed", [1, 17])
def test_hard_loops_with_a_gate_wider_than_the_lane(seed: int, tmp_path: Path) -> None:
    """Hard loops (``tracks.generate.hard``) 3.3 and 3.16 m wide whose big orange
    cones stand 0.6 m outside the lane: a clean lap from standstill."""
    track = hard_loop(seed)
    assert "gate 0.6 m" in track.description
    r = run_scenario(written(track, tmp_path), laps=1, seed=0)
    assert clean(r), (r.end_reason, r.events.cones_down_or_out)


def gate_offset(track: Track) -> float:
    """How far the big orange gate cones stand outside the lane's edges [m]."""
    big = track.cones[[str(k) == "big_orange" for k in track.kinds]]
    start = track.centreline[0]
    half = 0.5 * float(track.widths[0])
    return float(np.linalg.norm(big - start, axis=1).min()) - half


@pytest.mark.parametrize(("seed", "size"), [(3, "small"), (4, "medium"), (5, "large")])
def test_generated_tracks_with_a_gate_wider_than_the_lane(seed: int, size: Size) -> None:
    """Generated tracks of each size (``tracks.generate``; the benchmark's seeds
    are 5000 on), whose big orange gate cones stand 0.5-1.2 m outside the lane:
    a clean lap from standstill."""
    generated = GeneratedTrack(seed, TrackSpec(size=size))
    assert gate_offset(load_track(generated)) > 0.4
    r = run_scenario(Scenario(track=generated, laps=1, seed=0))
    assert clean(r), (r.end_reason, r.events.cones_down_or_out)


@pytest.mark.parametrize("seed", [1, 2])
def test_generated_hairpins_of_3_m_lane_centre_radius(seed: int) -> None:
    """Two hairpins of 3.0 m lane-centre radius, tighter than the generator's
    4.5 m (a 9 m diameter at the lane's centre), in a 3.5 m lane: a clean lap.
    In a 3.0 m lane the same hairpin leaves the car's front corner (4.35 m at
    full lock) 4 cm from the outer cones' inner edge, and it touches them."""
    spec = TrackSpec(size="small", width=(3.5, 3.5), hairpin_radius=(3.0, 3.0), hairpins=(2, 2))
    r = run_scenario(Scenario(track=GeneratedTrack(seed, spec), laps=1, seed=0))
    assert clean(r), (r.end_reason, r.events.cones_down_or_out)
    assert r.cones_hit == 0
